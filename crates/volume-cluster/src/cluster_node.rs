//! The node kind of volume-clustered hierarchical radiosity: a cluster of the loose octree
//! ([`crate::loose_octree`]) or a quadtree patch of an input face (Hanrahan, Salzman & Aupperle 1991). A
//! cluster has no one orientation; to the refinement it shows its direction-averaged projected area A/4 (the
//! mean of A max(0, n·d) over directions d is A/4 for any one-sided patch, so for any set of them; Sillion
//! 1995), and it splits into its child clusters and its direct faces, which are patches from then on.

use std::sync::Arc;

use glam::DVec3;
use radlab_hierarchical::{Bound, NodeKind, Patch};
use radlab_scene::{FaceId, Rgb, Scene, sampling};

use crate::loose_octree::ClusterTree;

/// A node: cluster or patch. Nodes live by value in the engine's arena, where most are patches, so the patch
/// is not boxed (a box would add an allocation per element to save space on the fewer clusters).
#[derive(Clone, Debug)]
#[allow(clippy::large_enum_variant)]
pub enum ClusterNode<'a> {
    /// A volume cluster.
    Cluster(ClusterRef<'a>),
    /// An input face or a piece of one.
    Patch(Patch),
}

/// A cluster of a shared tree.
#[derive(Clone, Debug)]
pub struct ClusterRef<'a> {
    /// The tree.
    pub tree: Arc<ClusterTree>,
    /// The scene the faces come from.
    pub scene: &'a Scene,
    /// Cluster id in the tree.
    pub id: u32,
}

impl ClusterRef<'_> {
    /// Its data.
    pub fn data(&self) -> &crate::loose_octree::Cluster {
        &self.tree.clusters[self.id as usize]
    }
}

impl<'a> ClusterNode<'a> {
    /// The root cluster of `tree`.
    pub fn root(tree: Arc<ClusterTree>, scene: &'a Scene) -> Self {
        Self::Cluster(ClusterRef { tree, scene, id: 0 })
    }

    /// Its bounding box.
    pub fn bbox(&self) -> (DVec3, DVec3) {
        match self {
            Self::Cluster(c) => (c.data().lo, c.data().hi),
            Self::Patch(p) => p
                .polygon
                .vertices()
                .iter()
                .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), v| {
                    (lo.min(*v), hi.max(*v))
                }),
        }
    }

    /// Area-weighted centroid: where a point approximation places the node.
    pub fn centroid(&self) -> DVec3 {
        match self {
            Self::Cluster(c) => c.data().centroid,
            Self::Patch(p) => p.centroid,
        }
    }

    /// The patch, if it is one.
    pub fn as_patch(&self) -> Option<&Patch> {
        match self {
            Self::Patch(p) => Some(p),
            Self::Cluster(_) => None,
        }
    }
}

impl NodeKind for ClusterNode<'_> {
    fn area(&self) -> f64 {
        match self {
            Self::Cluster(c) => c.data().area,
            Self::Patch(p) => p.area,
        }
    }

    fn bound(&self) -> Bound {
        match self {
            Self::Cluster(c) => {
                let d = c.data();
                Bound {
                    centre: 0.5 * (d.lo + d.hi),
                    radius: 0.5 * (d.hi - d.lo).length(),
                }
            }
            Self::Patch(p) => p.bound(),
        }
    }

    fn normal(&self) -> Option<DVec3> {
        self.as_patch().map(|p| p.normal)
    }

    fn projected_area(&self, dir: DVec3) -> f64 {
        match self {
            Self::Cluster(c) => c.data().area / 4.0,
            Self::Patch(p) => p.projected_area(dir),
        }
    }

    fn reflectance(&self) -> Rgb {
        match self {
            Self::Cluster(c) => c.data().reflectance,
            Self::Patch(p) => p.reflectance,
        }
    }

    fn emission(&self) -> Rgb {
        match self {
            Self::Cluster(c) => c.data().emission,
            Self::Patch(p) => p.emission,
        }
    }

    fn can_split(&self, min_size: f64) -> bool {
        match self {
            Self::Cluster(_) => true,
            Self::Patch(p) => p.can_split(min_size),
        }
    }

    fn split(&self) -> Vec<Self> {
        match self {
            Self::Cluster(c) => {
                let d = c.data();
                let mut kids: Vec<Self> = d
                    .children
                    .iter()
                    .map(|&id| {
                        Self::Cluster(ClusterRef {
                            tree: Arc::clone(&c.tree),
                            scene: c.scene,
                            id,
                        })
                    })
                    .collect();
                let direct = &c.tree.face_order[d.start as usize..(d.start + d.direct) as usize];
                kids.extend(direct.iter().map(|&f| Self::Patch(Patch::root(c.scene, f))));
                kids
            }
            Self::Patch(p) => p.split().into_iter().map(Self::Patch).collect(),
        }
    }

    fn face(&self) -> Option<FaceId> {
        self.as_patch().map(|p| p.face)
    }

    fn key(&self) -> u64 {
        match self {
            Self::Cluster(c) => sampling::mix64(0xC1A5_7E12_0000_0000 ^ c.id as u64),
            Self::Patch(p) => p.key(),
        }
    }

    fn patch(&self) -> Option<&Patch> {
        self.as_patch()
    }
}
