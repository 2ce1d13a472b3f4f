//! vsculpt-kernel: geometry and solver, no I/O.
