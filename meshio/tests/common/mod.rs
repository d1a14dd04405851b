//! Support shared by meshio's integration tests.

pub mod quad;
