//! Form factors: the exact point-to-polygon kernel, area-to-area quadrature with sampled visibility, the cheap
//! estimate refinement oracles use, and Howell's closed forms to test them against.

mod estimate;
mod point_polygon;

pub use estimate::form_factor_estimate;
pub use point_polygon::{point_polygon, point_polygon_unclipped};
