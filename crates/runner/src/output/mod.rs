//! Everything the runner writes: atomic files, EXR images, PLY meshes with radiosity, CSV tables.

pub mod atomic;
pub mod exr_image;
pub mod faces_csv;
pub mod ply_radiosity;
