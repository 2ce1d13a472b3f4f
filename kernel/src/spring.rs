//! The spring model: a drag of Δx becomes a force f = k Δx with adaptive stiffness.
