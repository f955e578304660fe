//! The cluster hierarchy above the input faces: Christensen's loose octree (Christensen, Lischinski, Stollnitz
//! & Salesin 1997; as RenderPark builds it), top down. A cluster's box is split at its centre; a face moves to
//! the octant holding its box centre only if its extent is at most half the box's on every axis, otherwise it
//! stays a direct child of the cluster. Empty octants are dropped, an octant holding a single face gives that
//! face to the cluster directly, child boxes are recomputed from their contents (so they may overlap), and a
//! cluster of three faces or fewer is not split. Each level partitions its faces, so the build is O(k log k) for
//! k faces (O(k · depth)); it depends only on the scene, so it is deterministic.
//!
//! Faces are permuted so that every cluster's faces (its direct faces, then its children's) are one contiguous
//! range of [`ClusterTree::face_order`]; the prefix sums of their areas let any cluster pick a face in
//! proportion to area in O(log k), which is how visibility rays find sample points on a cluster's contents.

use glam::DVec3;
use radlab_scene::{FaceId, Rgb, Scene};

use crate::normal_cone::NormalCone;

/// One cluster.
#[derive(Clone, Debug)]
pub struct Cluster {
    /// Lower corner of the box around its faces.
    pub lo: DVec3,
    /// Upper corner.
    pub hi: DVec3,
    /// Area-weighted centroid of its faces.
    pub centroid: DVec3,
    /// Total area of its faces.
    pub area: f64,
    /// Area-mean reflectance.
    pub reflectance: Rgb,
    /// Area-mean emission.
    pub emission: Rgb,
    /// Child clusters.
    pub children: Vec<u32>,
    /// Its faces: `face_order[start..end]`, the first `direct` of them its direct children.
    pub start: u32,
    /// End of its face range.
    pub end: u32,
    /// Number of direct face children.
    pub direct: u32,
    /// The cone of its faces' normals ([`NormalCone::UNKNOWN`] for items that are not faces).
    pub cone: NormalCone,
}

/// The hierarchy: clusters (the root is 0) and the face permutation.
#[derive(Clone, Debug)]
pub struct ClusterTree {
    /// Clusters, parents before children.
    pub clusters: Vec<Cluster>,
    /// Faces in cluster order.
    pub face_order: Vec<FaceId>,
    /// Prefix sums of face areas along `face_order` (length k + 1).
    pub area_prefix: Vec<f64>,
}

/// A face's bounding box.
fn face_box(scene: &Scene, f: FaceId) -> (DVec3, DVec3) {
    let p = scene.polygon(f);
    p.vertices()
        .iter()
        .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(*v), hi.max(*v))
        })
}

/// What the octree clusters: an axis-aligned box with the surface it holds (an input face, or any group of
/// faces, such as a face-cluster root).
#[derive(Clone, Copy, Debug)]
pub struct OctreeItem {
    /// Lower corner of its box.
    pub lo: DVec3,
    /// Upper corner.
    pub hi: DVec3,
    /// Its area.
    pub area: f64,
    /// Its area-weighted centroid.
    pub centroid: DVec3,
    /// Its area-mean reflectance.
    pub reflectance: Rgb,
    /// Its area-mean emission.
    pub emission: Rgb,
}

impl ClusterTree {
    /// Builds the loose octree over every face of `scene` (at least one face).
    pub fn build(scene: &Scene) -> Self {
        Self::build_over(scene, (0..scene.face_count()).collect())
    }

    /// Builds the loose octree over the given faces of `scene` (at least one), with every cluster's normal
    /// cone.
    pub fn build_over(scene: &Scene, all: Vec<FaceId>) -> Self {
        let items: Vec<OctreeItem> = (0..scene.face_count())
            .map(|f| {
                let (lo, hi) = face_box(scene, f);
                let face = &scene.faces[f];
                OctreeItem {
                    lo,
                    hi,
                    area: face.area,
                    centroid: face.centroid,
                    reflectance: scene.reflectance(f),
                    emission: scene.emission(f),
                }
            })
            .collect();
        let mut tree = Self::build_over_items(&items, all);
        for i in 0..tree.clusters.len() {
            let faces = tree.faces(i as u32);
            let cone = NormalCone::of(
                faces
                    .iter()
                    .map(|&f| (scene.faces[f].area, scene.faces[f].normal)),
            );
            tree.clusters[i].cone = cone;
        }
        tree
    }

    /// Builds the loose octree over `all` (at least one index into `items`): the same tree as
    /// [`ClusterTree::build_over`] for items that are not faces (a face-cluster method clusters its roots).
    /// "Faces" of the tree are then item indices.
    pub fn build_over_items(items: &[OctreeItem], all: Vec<FaceId>) -> Self {
        let mut tree = Self {
            clusters: Vec::new(),
            face_order: Vec::with_capacity(all.len()),
            area_prefix: Vec::new(),
        };
        tree.build_cluster(items, all);
        let mut prefix = Vec::with_capacity(tree.face_order.len() + 1);
        let mut acc = 0.0;
        prefix.push(0.0);
        for &f in &tree.face_order {
            acc += items[f].area;
            prefix.push(acc);
        }
        tree.area_prefix = prefix;
        tree
    }

    /// Builds the cluster over `faces` and its subtree; returns its id.
    fn build_cluster(&mut self, items: &[OctreeItem], faces: Vec<FaceId>) -> u32 {
        let (lo, hi) = faces
            .iter()
            .fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), &f| {
                (lo.min(items[f].lo), hi.max(items[f].hi))
            });
        let id = self.clusters.len() as u32;
        let start = self.face_order.len() as u32;
        self.clusters.push(Cluster {
            lo,
            hi,
            centroid: DVec3::ZERO,
            area: 0.0,
            reflectance: Rgb::ZERO,
            emission: Rgb::ZERO,
            children: Vec::new(),
            start,
            end: start,
            direct: 0,
            cone: NormalCone::UNKNOWN,
        });
        let (direct, groups) = partition(items, faces, lo, hi);
        self.clusters[id as usize].direct = direct.len() as u32;
        self.face_order.extend_from_slice(&direct);
        let mut children = Vec::with_capacity(groups.len());
        for g in groups {
            children.push(self.build_cluster(items, g));
        }
        let end = self.face_order.len() as u32;
        // Sums over the face range.
        let (mut area, mut c, mut rho, mut e) = (0.0, DVec3::ZERO, Rgb::ZERO, Rgb::ZERO);
        for &f in &self.face_order[start as usize..end as usize] {
            let it = &items[f];
            area += it.area;
            c += it.area * it.centroid;
            rho += it.area * it.reflectance;
            e += it.area * it.emission;
        }
        let cl = &mut self.clusters[id as usize];
        cl.children = children;
        cl.end = end;
        cl.area = area;
        if area > 0.0 {
            cl.centroid = c / area;
            cl.reflectance = rho / area;
            cl.emission = e / area;
        } else {
            cl.centroid = 0.5 * (lo + hi);
        }
        id
    }

    /// The cluster's faces (direct ones first).
    pub fn faces(&self, id: u32) -> &[FaceId] {
        let c = &self.clusters[id as usize];
        &self.face_order[c.start as usize..c.end as usize]
    }

    /// The face of cluster `id` at area fraction `u` ∈ [0, 1) of its faces (area-proportional choice).
    pub fn face_at(&self, id: u32, u: f64) -> FaceId {
        let c = &self.clusters[id as usize];
        let (s, e) = (c.start as usize, c.end as usize);
        let target = self.area_prefix[s] + u * (self.area_prefix[e] - self.area_prefix[s]);
        // First position in [s, e) whose prefix end exceeds the target.
        let k = self.area_prefix[s + 1..=e].partition_point(|&p| p <= target);
        self.face_order[s + k.min(e - s - 1)]
    }

    /// Bytes held.
    pub fn bytes(&self) -> u64 {
        let children: usize = self
            .clusters
            .iter()
            .map(|c| c.children.capacity() * 4)
            .sum();
        (self.clusters.capacity() * size_of::<Cluster>()
            + children
            + self.face_order.capacity() * size_of::<FaceId>()
            + self.area_prefix.capacity() * 8) as u64
    }
}

/// Splits `faces` (box `lo`..`hi`) into the faces that stay at this level and the groups of the non-empty
/// octants (in octant order). Three faces or fewer stay; so do all of them when the split makes no progress
/// (every face in one octant, whose box is then this box: coincident faces, or extents of exactly half).
fn partition(
    items: &[OctreeItem],
    faces: Vec<FaceId>,
    lo: DVec3,
    hi: DVec3,
) -> (Vec<FaceId>, Vec<Vec<FaceId>>) {
    if faces.len() <= 3 {
        return (faces, Vec::new());
    }
    let centre = 0.5 * (lo + hi);
    let half = 0.5 * (hi - lo);
    let mut stay = Vec::new();
    let mut octants: [Vec<FaceId>; 8] = Default::default();
    for &f in &faces {
        let (flo, fhi) = (items[f].lo, items[f].hi);
        let ext = fhi - flo;
        if ext.x <= half.x && ext.y <= half.y && ext.z <= half.z {
            let c = 0.5 * (flo + fhi);
            let o = (c.x > centre.x) as usize
                | ((c.y > centre.y) as usize) << 1
                | ((c.z > centre.z) as usize) << 2;
            octants[o].push(f);
        } else {
            stay.push(f);
        }
    }
    let mut groups = Vec::new();
    for o in octants {
        match o.len() {
            0 => {}
            1 => stay.push(o[0]),
            _ => groups.push(o),
        }
    }
    if stay.is_empty() && groups.len() == 1 {
        // Every face in one octant: that group's box is this box, so splitting makes no progress.
        return (faces, Vec::new());
    }
    stay.sort_unstable();
    (stay, groups)
}
