//! Numerical helpers: small symmetric positive definite solves and chi-square gates.

pub(crate) mod chi2;
pub(crate) mod linalg;
