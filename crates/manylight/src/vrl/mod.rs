//! Virtual ray lights.
