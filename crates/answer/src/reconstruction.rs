//! How a finite-element solution answers radiosity at a point: the `reconstruction` parameter shared by
//! matrix, progressive and mesh Monte Carlo radiosity.
//!
//! - `constant`: B of the element containing the point (the piecewise-constant solution itself);
//! - `gouraud`: vertex values interpolated over each input face's elements ([`crate::gouraud`]; Gouraud 1971,
//!   as Cohen & Greenberg 1985 display radiosity), continuous within a face;
//! - `final-gather`: B(x) = E(x) + ρ(x) Σ_j F_{x→j} V_xj B_j over the elements ([`crate::final_gather`]).
//!
//! [`Reconstructor`] builds the interpolation or gather data once per solution (lazily, at the first query
//! after the solution changed) so a method only has to list its elements and locate a point's element.

use std::sync::OnceLock;

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::final_gather::{FinalGather, GatherSettings};
use crate::gouraud::{ElementValue, GouraudField};
use radlab_scene::{FaceId, Rgb, Scene};
use radlab_visibility::Accel;

/// How point answers are reconstructed from element values.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum Reconstruction {
    /// The element's constant value.
    #[default]
    Constant,
    /// Vertex values interpolated over the elements of each input face.
    Gouraud,
    /// One more gather from every element, with the exact point-to-polygon factor and visibility rays.
    FinalGather,
}

impl Reconstruction {
    /// The name as in parameters (`constant`, `gouraud`, `final-gather`).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Constant => "constant",
            Self::Gouraud => "gouraud",
            Self::FinalGather => "final-gather",
        }
    }
}

#[derive(Debug)]
enum Built {
    Gouraud(GouraudField),
    Gather(FinalGather),
}

/// The output side of an element solution: the chosen reconstruction and its data, built at the first query
/// after [`Reconstructor::invalidate`].
#[derive(Debug)]
pub struct Reconstructor {
    kind: Reconstruction,
    settings: GatherSettings,
    /// A final gather's opening ([`FinalGather::with_opening`]; 0: every element).
    opening: f64,
    built: OnceLock<Built>,
    /// Gather work of solutions already invalidated (so the totals survive a rebuild).
    past: (u64, u64),
}

impl Reconstructor {
    /// A reconstructor of `kind`; a final gather draws its visibility rays from `seed`.
    pub fn new(kind: Reconstruction, seed: u64) -> Self {
        Self {
            kind,
            settings: GatherSettings::with_seed(seed),
            opening: 0.0,
            built: OnceLock::new(),
            past: (0, 0),
        }
    }

    /// The same with a final gather at opening `opening` ([`FinalGather::with_opening`]: far groups of
    /// elements through one drawn element each; 0, the default, gathers every element).
    pub fn with_opening(mut self, opening: f64) -> Self {
        self.opening = opening;
        self
    }

    /// Which reconstruction.
    pub fn kind(&self) -> Reconstruction {
        self.kind
    }

    /// Forgets the data built from the previous solution (call whenever the element values change).
    pub fn invalidate(&mut self) {
        if let Some(Built::Gather(g)) = self.built.take() {
            self.past.0 += g.rays();
            self.past.1 += g.kernel_evaluations();
        }
    }

    /// Rays and kernel evaluations the final gather has spent answering queries so far (zeros otherwise).
    pub fn gather_work(&self) -> (u64, u64) {
        match self.built.get() {
            Some(Built::Gather(g)) => {
                (self.past.0 + g.rays(), self.past.1 + g.kernel_evaluations())
            }
            _ => self.past,
        }
    }

    /// Approximate heap bytes of the built data.
    pub fn bytes(&self) -> usize {
        match self.built.get() {
            Some(Built::Gouraud(g)) => g.bytes(),
            Some(Built::Gather(g)) => g.bytes(),
            None => 0,
        }
    }

    /// The radiosity at `point` on `face`. `constant` is the value of the element containing it, `element`
    /// locates that element's index in the order of `elements()`, which lists every element of the solution
    /// (called once per solution).
    #[allow(clippy::too_many_arguments)]
    pub fn radiosity_at(
        &self,
        scene: &Scene,
        accel: &Accel,
        face: FaceId,
        point: DVec3,
        constant: impl FnOnce() -> Rgb,
        element: impl FnOnce() -> Option<usize>,
        elements: impl FnOnce() -> Vec<ElementValue>,
    ) -> Rgb {
        match self.kind {
            Reconstruction::Constant => constant(),
            Reconstruction::Gouraud => {
                let built = self
                    .built
                    .get_or_init(|| Built::Gouraud(GouraudField::new(&elements())));
                match (built, element()) {
                    (Built::Gouraud(g), Some(e)) if e < g.len() => g.at(e, point),
                    _ => constant(),
                }
            }
            Reconstruction::FinalGather => {
                let built = self.built.get_or_init(|| {
                    Built::Gather(
                        FinalGather::new(scene, &elements(), self.settings)
                            .with_opening(self.opening),
                    )
                });
                match built {
                    Built::Gather(g) => g.radiosity_at(scene, accel, face, point),
                    Built::Gouraud(_) => constant(),
                }
            }
        }
    }
}

impl Clone for Reconstructor {
    fn clone(&self) -> Self {
        Self {
            kind: self.kind,
            settings: self.settings,
            opening: self.opening,
            built: OnceLock::new(),
            past: self.gather_work(),
        }
    }
}
