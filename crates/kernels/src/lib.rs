//! # radlab-kernels
//!
//! The transport kernels radlab's finite-element methods integrate: the form factor
//! F_{i→j} = (1/A_i) ∫_{A_i} ∫_{A_j} V(x, y) cos θ_x cos θ_y / (π r²) dA_y dA_x, exactly from a point to a
//! polygon (Lambert's formula), by Gauss-Legendre quadrature with sampled visibility between polygons, as the
//! cheap estimate refinement oracles use, and in Howell's closed forms to test them against; and the open
//! fraction of a face (the share of its hemisphere not blocked by touching geometry). Nothing in this crate
//! prints or writes files.

pub mod form_factor;
pub mod open_fraction;
