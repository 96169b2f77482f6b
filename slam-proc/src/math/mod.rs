//! Numerical helpers: small symmetric positive definite solves and chi-square gates.

pub(crate) mod chi2;
#[cfg(test)]
pub(crate) mod finite_difference;
pub(crate) mod linalg;
