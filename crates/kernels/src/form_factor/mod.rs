//! Form factors: the exact point-to-polygon kernel, area-to-area quadrature with sampled visibility, the cheap
//! estimate refinement oracles use, and Howell's closed forms to test them against.

mod area_area;
pub mod closed_form;
mod estimate;
pub mod gauss_legendre;
mod point_polygon;

pub use area_area::{
    VisibilitySampling, pair_kernel, polygon_polygon, polygon_polygon_unoccluded, receiver_points,
    visibility_fraction,
};
pub use estimate::form_factor_estimate;
pub use point_polygon::{point_polygon, point_polygon_unclipped, point_polygon_vector};
