//! The radiosity texture's parameters: the particle budget and its passes, Heckbert's (1990) adaptive split
//! rule for the per-face quadtrees (a particle count per leaf and a smallest cell), an optional contrast test
//! on the split, and how points are answered (radlab-answer's reconstructions).

use radlab_answer::{AnswerParams, Reconstruction};
use radlab_method::{MethodParams, SolveError};
use radlab_pathtrace::DEFAULT_MAX_DEPTH;
use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// The default smallest cell as a fraction of the scene's bounding-box diagonal (1/256: about 7 mm in a 1 m
/// room's 1.7 m diagonal).
pub const DEFAULT_MIN_CELL_REL: f64 = 1.0 / 256.0;

/// When a leaf of a face's quadtree splits into four.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum SplitRule {
    /// Heckbert's rule: a leaf holding more than `split_threshold` particles splits (while its children are no
    /// smaller than `min_cell`). Cells end up small where light is dense, each with about the same count, so
    /// the relative noise per leaf is about 1/√split_threshold everywhere. The default.
    #[default]
    Count,
    /// As `count`, and the four children's particle densities must also differ: Pearson's χ² of their counts
    /// against counts proportional to their areas exceeds 16.27 (3 degrees of freedom, p = 0.001). Uniformly
    /// lit regions keep large leaves (and little noise); leaves are small only where the density changes,
    /// such as at shadow edges.
    Contrast,
}

impl SplitRule {
    /// The name as in parameters.
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Count => "count",
            Self::Contrast => "contrast",
        }
    }
}

/// Parameters of the radiosity texture. Each field is declared once: its doc comment's first paragraph is the
/// help `radlab methods` prints, its `schemars` attribute the accepted range, and its default is in
/// `impl Default`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(default, deny_unknown_fields)]
pub struct RadiosityTextureParams {
    /// Particle landings deposited in all, over all passes (emission goes on in chunks of 256 until each pass
    /// holds its share); more give smaller leaves and less noise.
    #[schemars(range(min = 1))]
    pub particles: u64,
    /// Passes (one per step), each depositing particles/passes more landings; the textures after a pass
    /// estimate over every particle so far.
    #[schemars(range(min = 1))]
    pub passes: u32,
    /// A leaf holding more than this many particles splits into four: the noise per leaf (about
    /// 1/√split_threshold relative) against its size (bias where the radiosity varies).
    #[schemars(range(min = 1))]
    pub split_threshold: u32,
    /// When a leaf splits: `count` (Heckbert's particle count) or `contrast` (the count, and the children's
    /// densities must differ).
    pub split: SplitRule,
    /// Smallest leaf size in scene units: a leaf splits only while half its longest edge is at least this;
    /// unset: 1/256 of the scene's bounding diagonal.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub min_cell: Option<f64>,
    /// Cap on a particle's reflections (Russian roulette ends them).
    #[schemars(range(min = 1))]
    pub max_depth: u32,
    /// How points are answered: reconstruction and gather_opening, declared once in radlab-answer.
    #[serde(flatten)]
    pub answer: AnswerParams,
}

impl Default for RadiosityTextureParams {
    fn default() -> Self {
        Self {
            particles: 1_000_000,
            passes: 4,
            split_threshold: 100,
            split: SplitRule::Count,
            min_cell: None,
            max_depth: DEFAULT_MAX_DEPTH,
            // Gouraud: vertex values fitted to the leaves of each face, bilinear within a leaf.
            answer: AnswerParams {
                reconstruction: Reconstruction::Gouraud,
                ..AnswerParams::default()
            },
        }
    }
}

impl MethodParams for RadiosityTextureParams {
    fn check_combination(&self) -> Result<(), SolveError> {
        if self.particles < self.passes as u64 {
            return Err(SolveError::param(
                "particles",
                format!(
                    "{} particles cannot be shared among {} passes; set particles to at least passes",
                    self.particles, self.passes
                ),
            ));
        }
        self.answer.check(&Self::default().answer)
    }
}
