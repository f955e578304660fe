//! How a finite-element solution answers radiosity at a point: the `reconstruction`, `gather_opening` and
//! `near_values` parameters ([`AnswerParams`]) every element method flattens into its own.
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
use radlab_method::SolveError;
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

/// What a final gather reads for the sources near the query point (parameter `near_values`).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, schemars::JsonSchema,
)]
#[serde(rename_all = "kebab-case")]
pub enum NearValues {
    /// Their values in the solution.
    #[default]
    Solution,
    /// Each gathered once more at its centroid, at its first use ([`crate::final_gather`], "Near values").
    Regathered,
}

impl NearValues {
    /// The name as in parameters (`solution`, `regathered`).
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Solution => "solution",
            Self::Regathered => "regathered",
        }
    }
}

/// How an element method answers at points, declared once for every method that flattens it into its
/// parameters (`#[serde(flatten)]`; each method sets its own defaults in its `impl Default`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, schemars::JsonSchema)]
#[serde(default)]
pub struct AnswerParams {
    /// How radiosity at a point is answered from the element values: constant (the element's value), gouraud
    /// (vertex values interpolated over each face's elements) or final-gather (one more gather from every
    /// element with exact point-to-polygon factors and visibility rays, charged to answering).
    ///
    /// A final gather costs a kernel per element and query (fewer at a positive `gather_opening`), so images
    /// of finely meshed solutions are slow; ask for constant to read the elements themselves.
    pub reconstruction: Reconstruction,
    /// Final-gather only: a group of elements whose bounding radius is below this times its distance from
    /// the query point is gathered whole, through one element drawn by its light (face clusters: a node of
    /// their tree, by its power vector); 0 gathers every element, a cost linear in the elements per point.
    ///
    /// Groups holding a light or an element along a contact are always opened, as is a group holding more
    /// than 1e-4 of the point's estimated light, and elements near the point keep their near field
    /// ([`crate::final_gather`] and its source tree; Barnes & Hut 1986, Yuksel 2019). Larger openings answer
    /// faster, with more noise.
    #[schemars(range(min = 0), extend("exclusiveMaximum" = 1))]
    pub gather_opening: f64,
    /// Final-gather only: what the gather reads for an element it takes one by one with a factor of at least
    /// [`crate::final_gather::NEAR_VALUES_MIN_FACTOR`] from the point (and sees): solution (its value in the
    /// solution) or regathered (its value gathered once more at its centroid, at its first use, charged to
    /// answering: the solution's error there reaches the point damped by one more bounce). Default regathered
    /// for volume and face clusters, whose cluster-made values left the floor under scanned meshes 19–27% off
    /// (13–14% with it), solution for the other methods, whose answers it moved by at most 0.03 points of mean
    /// for 1.8–3.1 times the answering time (docs/defaults.md, docs/methods.md "Near values").
    pub near_values: NearValues,
}

/// Default opening of the final gather (`gather_opening`) for every element method: far groups of elements
/// through one drawn element each ([`crate::final_gather`] over its source tree). On the 10⁵-face terrain volume
/// clusters' answering pass at 512 points took 118 s of one thread flat, and the method 183 s on two cores; at
/// 0.25 it takes 103 s for the same 0.28% / 3.6%. On the suite's small rooms matrix, progressive, hierarchical,
/// volume-cluster and mesh Monte Carlo answers move by at most 0.02 points of mean error, for 5–75% fewer
/// kernel evaluations; mesh Monte Carlo radiosity converges on the 52k-face elephant room within the suite's
/// time, where the flat gather's answering passes had it killed (docs/defaults.md).
pub const DEFAULT_GATHER_OPENING: f64 = 0.25;

impl AnswerParams {
    /// A final gather at opening `gather_opening` (0: over every element), reading near elements at their
    /// values in the solution.
    pub const fn final_gather(gather_opening: f64) -> Self {
        Self {
            reconstruction: Reconstruction::FinalGather,
            gather_opening,
            near_values: NearValues::Solution,
        }
    }

    /// The check across the three, for a method whose defaults are `default`: an opening or near values
    /// other than its defaults are refused under answers other than a final gather, where they would change
    /// nothing.
    pub fn check(&self, default: &AnswerParams) -> Result<(), SolveError> {
        if self.reconstruction != Reconstruction::FinalGather
            && self.near_values != default.near_values
        {
            return Err(SolveError::param(
                "near_values",
                format!(
                    "near_values = {} only applies to final-gather answers, and reconstruction is {}; set \
                     reconstruction = \"final-gather\" or remove near_values",
                    self.near_values.as_str(),
                    self.reconstruction.as_str()
                ),
            ));
        }
        if self.reconstruction != Reconstruction::FinalGather
            && self.gather_opening != default.gather_opening
        {
            return Err(SolveError::param(
                "gather_opening",
                format!(
                    "gather_opening = {} only applies to final-gather answers, and reconstruction is {}; set \
                     reconstruction = \"final-gather\" or remove gather_opening",
                    self.gather_opening,
                    self.reconstruction.as_str()
                ),
            ));
        }
        Ok(())
    }
}

impl Default for AnswerParams {
    /// A final gather at the default opening ([`DEFAULT_GATHER_OPENING`]).
    fn default() -> Self {
        Self::final_gather(DEFAULT_GATHER_OPENING)
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
    /// What a final gather reads for near elements ([`FinalGather::with_near_values`]).
    near_values: NearValues,
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
            near_values: NearValues::Solution,
            built: OnceLock::new(),
            past: (0, 0),
        }
    }

    /// A reconstructor as `params` ask: their reconstruction, and a final gather at their opening
    /// ([`FinalGather::with_opening`]: far groups of elements through one drawn element each; 0 gathers every
    /// element) reading near elements as they ask ([`FinalGather::with_near_values`]); a final gather draws its
    /// visibility rays from `seed`.
    pub fn of(params: &AnswerParams, seed: u64) -> Self {
        Self {
            opening: params.gather_opening,
            near_values: params.near_values,
            ..Self::new(params.reconstruction, seed)
        }
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
                    let gather = FinalGather::new(scene, &elements(), self.settings)
                        .with_opening(self.opening);
                    Built::Gather(gather.with_near_values(self.near_values))
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
            near_values: self.near_values,
            built: OnceLock::new(),
            past: self.gather_work(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_opening_or_near_values_other_than_the_defaults_are_refused_under_other_answers() {
        // A method whose defaults are a final gather at 0.25 regathering near values.
        let default = AnswerParams {
            near_values: NearValues::Regathered,
            ..AnswerParams::final_gather(0.25)
        };
        let gouraud = |gather_opening, near_values| AnswerParams {
            reconstruction: Reconstruction::Gouraud,
            gather_opening,
            near_values,
        };
        // Its defaults stay under Gouraud answers, where they change nothing.
        assert!(
            gouraud(0.25, NearValues::Regathered)
                .check(&default)
                .is_ok()
        );
        for (bad, key) in [
            (gouraud(0.3, NearValues::Regathered), "gather_opening"),
            (gouraud(0.25, NearValues::Solution), "near_values"),
        ] {
            let e = bad.check(&default).expect_err("refused").to_string();
            assert!(
                e.contains(key) && e.contains("final-gather"),
                "names the key and the fix: {e}"
            );
        }
        // Under a final gather any opening and near values go.
        assert!(AnswerParams::final_gather(0.3).check(&default).is_ok());
        // A method whose default reads near values at their solution values refuses regathered ones under
        // constant answers.
        let constant = AnswerParams {
            reconstruction: Reconstruction::Constant,
            ..default
        };
        assert!(constant.check(&AnswerParams::final_gather(0.25)).is_err());
    }
}
