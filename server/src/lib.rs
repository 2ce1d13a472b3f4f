//! vsculpt-server: the headless sculpting service (to be built, issue 3).
