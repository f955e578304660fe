//! # radlab-visibility
//!
//! The visibility engine every radlab method casts its rays through: [`Accel`], a compressed wide BVH
//! (obvhs's CwBvh, Ylitie et al. 2017) over the scene's faces, answering closest hits and point-to-point
//! visibility exactly in f64 behind a conservative f32 filter, and counting every ray it casts so methods report
//! rays the same way. Nothing in this crate prints or writes files.

pub mod accel;
mod cwbvh_convert;
mod wide_node_test;

pub use accel::{Accel, AccelPreset, Hit, NodeTestKind, PACKET_SEGMENTS, Segment, TraversalCost};
