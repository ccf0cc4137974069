//! Statistical tests shared by every estimator's tests (in the spirit of Mitsuba 3's `chi2`
//! module): a chi-square test for direction sampling and a per-pixel z-test of a rendered image
//! against a reference. Only tests depend on this crate.

pub mod chi2;
pub mod ztest;
