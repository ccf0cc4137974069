//! Virtual point lights.
