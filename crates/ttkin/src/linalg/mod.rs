//! Small dense linear algebra shared by the algorithms (nalgebra's `linalg/` keeps one
//! decomposition per file; so does this module). Allocation-free kernels on slices, so that hot
//! loops can run them on preallocated scratch space.

pub mod cholesky;
