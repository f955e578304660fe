//! # radlab-wavelet
//!
//! Wavelet (higher-order Galerkin) radiosity.
#![doc = "wip"]

pub mod basis;
