//! Test support shared by every crate's tests (in the spirit of Mitsuba 3's `chi2` module): a
//! chi-square test for direction sampling, a per-pixel z-test of a rendered image against a
//! reference, adaptive Gauss-Kronrod quadrature for exact integrals, and the location of the
//! test data (`data`). Only tests depend on this crate.

pub mod chi2;
pub mod data;
pub mod quadrature;
pub mod ztest;
