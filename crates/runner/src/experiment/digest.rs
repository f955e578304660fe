//! Stable content digests for cache keys and skip checks: 64-bit FNV-1a (Fowler, Noll & Vo), twice with
//! different offsets for 128 bits, as hex. Not cryptographic; stable across platforms and releases.

/// 32 hex digits of the digest of `bytes`.
pub fn hex(bytes: &[u8]) -> String {
    let h = |offset: u64| {
        bytes.iter().fold(offset, |h, &b| {
            (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01B3)
        })
    };
    format!(
        "{:016x}{:016x}",
        h(0xcbf2_9ce4_8422_2325),
        h(0x6c62_272e_07bb_0142)
    )
}

/// Digest of a scene's content: vertices, faces, materials (bit patterns), so any change to geometry or
/// materials gives a new key.
pub fn scene(scene: &radlab_scene::Scene) -> String {
    let mut b = Vec::with_capacity(scene.faces.len() * 64);
    for f in 0..scene.faces.len() {
        for v in scene.polygon(f).vertices() {
            for x in v.to_array() {
                b.extend_from_slice(&x.to_bits().to_le_bytes());
            }
        }
        let m = scene.material(f);
        for x in m
            .reflectance
            .to_array()
            .into_iter()
            .chain(m.emission.to_array())
        {
            b.extend_from_slice(&x.to_bits().to_le_bytes());
        }
    }
    hex(&b)
}

#[cfg(test)]
mod tests {
    #[test]
    fn known_value_and_sensitivity() {
        // FNV-1a 64 of the empty input is its offset basis.
        assert!(super::hex(b"").starts_with("cbf29ce484222325"));
        assert_ne!(super::hex(b"a"), super::hex(b"b"));
    }
}
