//! The hierarchy's cache format and its key. The key is a BLAKE3 digest (O'Connor et al. 2020) of the mesh
//! content (vertex positions, faces' vertex indices and materials, every material's reflectance and
//! emission, all as exact bits) and the build parameters, so a cached hierarchy is reused only for the very
//! mesh and parameters it was built from. The bytes are a header (magic, format version, digest) and the
//! tree in postcard's encoding, which writes every f64 as its 8 bytes: a round trip is bit-identical.
//!
//! The library only makes bytes and reads them back; the caller (the runner) chooses the file, typically
//! named by [`digest_hex`], and times the build.

use std::io::{Read, Write};

use radlab_scene::Scene;

use crate::{FaceClusterError, FaceClusterParams, FaceClusterTree};

/// A 32-byte BLAKE3 digest.
pub type Digest = [u8; 32];

/// First bytes of every cache.
pub const CACHE_MAGIC: &[u8; 8] = b"RLFCTREE";

/// Version of the cache format and of the build algorithm: part of the digest, so a change to either
/// invalidates old caches.
pub const CACHE_VERSION: u32 = 3;

const HEADER_LEN: usize = 8 + 4 + 32;

/// The digest of the scene's mesh and the build parameters.
pub fn digest(scene: &Scene, params: &FaceClusterParams) -> Digest {
    let mut h = blake3::Hasher::new();
    h.update(CACHE_MAGIC);
    h.update(&CACHE_VERSION.to_le_bytes());
    // The parameters in a fixed binary form (postcard of plain fields cannot fail).
    let p = postcard::to_stdvec(params).unwrap_or_default();
    h.update(&(p.len() as u64).to_le_bytes());
    h.update(&p);
    let mut buf: Vec<u8> = Vec::with_capacity(1 << 16);
    let flush = |h: &mut blake3::Hasher, buf: &mut Vec<u8>, force: bool| {
        if force || buf.len() >= (1 << 16) - 64 {
            h.update(buf);
            buf.clear();
        }
    };
    buf.extend_from_slice(&(scene.vertices.len() as u64).to_le_bytes());
    for v in &scene.vertices {
        for c in v.to_array() {
            buf.extend_from_slice(&c.to_bits().to_le_bytes());
        }
        flush(&mut h, &mut buf, false);
    }
    buf.extend_from_slice(&(scene.faces.len() as u64).to_le_bytes());
    for f in &scene.faces {
        for i in f.indices {
            buf.extend_from_slice(&i.to_le_bytes());
        }
        buf.extend_from_slice(&f.material.to_le_bytes());
        flush(&mut h, &mut buf, false);
    }
    buf.extend_from_slice(&(scene.materials.len() as u64).to_le_bytes());
    for m in &scene.materials {
        for c in m
            .reflectance
            .to_array()
            .into_iter()
            .chain(m.emission.to_array())
        {
            buf.extend_from_slice(&c.to_bits().to_le_bytes());
        }
        flush(&mut h, &mut buf, false);
    }
    flush(&mut h, &mut buf, true);
    *h.finalize().as_bytes()
}

/// A digest as 64 lowercase hex digits (for file names).
pub fn digest_hex(d: &Digest) -> String {
    d.iter().map(|b| format!("{b:02x}")).collect()
}

impl FaceClusterTree {
    /// The cache bytes: header (magic, version, digest) and the tree.
    pub fn to_bytes(&self) -> Result<Vec<u8>, FaceClusterError> {
        let mut out = Vec::with_capacity(HEADER_LEN + self.bytes());
        out.extend_from_slice(CACHE_MAGIC);
        out.extend_from_slice(&CACHE_VERSION.to_le_bytes());
        out.extend_from_slice(&self.digest);
        postcard::to_io(self, &mut out).map_err(|e| FaceClusterError::CacheFormat {
            message: format!("cannot encode the hierarchy: {e}"),
        })?;
        Ok(out)
    }

    /// Reads cache bytes back. With `expected` (the digest of the scene and parameters at hand, see
    /// [`digest`]), a cache of another mesh or other parameters is refused.
    pub fn from_bytes(bytes: &[u8], expected: Option<&Digest>) -> Result<Self, FaceClusterError> {
        let format = |message: String| FaceClusterError::CacheFormat { message };
        if bytes.len() < HEADER_LEN || &bytes[..8] != CACHE_MAGIC {
            return Err(format(
                "it does not start with the face-cluster cache header".into(),
            ));
        }
        let version = u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]);
        if version != CACHE_VERSION {
            return Err(format(format!(
                "format version {version}, this radlab reads version {CACHE_VERSION}"
            )));
        }
        let mut found: Digest = [0; 32];
        found.copy_from_slice(&bytes[12..HEADER_LEN]);
        if let Some(want) = expected.filter(|w| **w != found) {
            return Err(FaceClusterError::CacheStale {
                found: digest_hex(&found),
                expected: digest_hex(want),
            });
        }
        let tree: Self = postcard::from_bytes(&bytes[HEADER_LEN..])
            .map_err(|e| format(format!("the hierarchy does not decode: {e}")))?;
        if tree.digest != found {
            return Err(format(
                "the header's digest differs from the hierarchy's".into(),
            ));
        }
        tree.check_layout().map_err(format)?;
        Ok(tree)
    }

    /// Writes the cache bytes.
    pub fn write_to(&self, w: &mut impl Write) -> Result<(), FaceClusterError> {
        w.write_all(&self.to_bytes()?)?;
        Ok(())
    }

    /// Reads cache bytes from a reader (see [`FaceClusterTree::from_bytes`]).
    pub fn read_from(
        r: &mut impl Read,
        expected: Option<&Digest>,
    ) -> Result<Self, FaceClusterError> {
        let mut bytes = Vec::new();
        r.read_to_end(&mut bytes)?;
        Self::from_bytes(&bytes, expected)
    }

    /// Checks the indices a decoded tree uses, so a damaged cache is an error rather than a panic later.
    fn check_layout(&self) -> Result<(), String> {
        let (n, k) = (self.nodes.len(), self.face_order.len());
        let s = self.params.samples_per_node;
        if self.params.validate().is_err()
            || self.samples.len() != n * s
            || self.sample_normals.len() != n * s
            || self.leaf_of_face.len() != k
        {
            return Err("array lengths do not match".into());
        }
        if self.root_count as usize > n {
            return Err("more roots than nodes".into());
        }
        for (i, node) in self.nodes.iter().enumerate() {
            let (c_end, f_end) = node.raw_ends();
            if c_end > n as u64 || f_end > k as u64 {
                return Err(format!("node {i} points outside the tree"));
            }
            let c = node.children();
            let f = node.faces();
            let parent_ok = node.parent().is_none_or(|p| p < i);
            if c.end > n || (!c.is_empty() && c.start <= i) || f.end > k || !parent_ok {
                return Err(format!("node {i} points outside the tree"));
            }
        }
        if self.face_order.iter().any(|&f| f as usize >= k)
            || self.leaf_of_face.iter().any(|&l| l as usize >= n)
        {
            return Err("a face index is out of range".into());
        }
        Ok(())
    }
}
