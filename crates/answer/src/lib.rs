//! # radlab-answer
//!
//! How a solved finite-element representation answers radiosity at a surface point: the element's constant
//! value, Gouraud interpolation of vertex values (or, for solutions holding an irradiance vector per face, of
//! irradiance carried to each face's normal), or a final gather B(x) = E(x) + ρ(x) Σ_j F_{x→j} V B_j with
//! exact point-to-polygon factors (and a finer gather of the elements next to x). Also element meshes over the
//! scene's faces, the locator that finds the element under a point, and primary-ray rendering of any
//! solution. Nothing in this crate prints or writes files.

pub mod elements;
pub mod final_gather;
pub mod gouraud;
pub mod irradiance_gouraud;
pub mod locate;
pub mod reconstruction;
pub mod render;
mod source_tree;

pub use elements::{
    DEFAULT_ELEMENT_SIZE_REL, Element, ElementMesh, default_element_size, element_size,
    element_size_or,
};
pub use locate::{ElementLocator, ElementTree};
pub use reconstruction::{
    AnswerParams, DEFAULT_GATHER_OPENING, NearValues, Reconstruction, Reconstructor,
};
pub use render::{Image, render_solution};
