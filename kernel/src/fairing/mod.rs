//! Fairing (paper 004 §3–7).
pub mod eigen3;
