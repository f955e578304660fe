//! Loading a scene from the command line's SCENE argument: a path (TOML, OBJ, PLY, OFF, MGF) or
//! `builtin:NAME[?k=v&...]`, with errors that keep the scene crate's file/line/field detail, and the counted
//! warnings (dropped degenerate faces, default materials, clamped colours) reported on stderr.

use anyhow::Result;
use radlab_formats::{LoadNotes, load_scene_with_notes};
use radlab_scene::Scene;

/// Loads and validates a scene, quietly.
pub fn load(spec: &str) -> Result<Scene> {
    Ok(radlab_formats::load_scene(spec)?)
}

/// Loads and validates a scene, printing what was dropped or defaulted to stderr.
pub fn load_and_warn(spec: &str) -> Result<Scene> {
    let (scene, notes) = load_scene_with_notes(spec)?;
    for line in warning_lines(&scene, &notes) {
        eprintln!("warning: {spec}: {line}");
    }
    Ok(scene)
}

/// Human-readable lines for every non-zero counter.
pub fn warning_lines(scene: &Scene, notes: &LoadNotes) -> Vec<String> {
    let w = &scene.warnings;
    [
        (w.degenerate_faces, "degenerate (zero-area) face(s) dropped"),
        (
            w.nonplanar_faces,
            "non-planar or non-convex quad(s) split into triangles",
        ),
        (
            w.polygons_triangulated,
            "polygon(s) with more than 4 vertices fanned into triangles",
        ),
        (
            notes.default_material_faces,
            "face(s) without a material given the default grey",
        ),
        (
            notes.materials_without_kd,
            "material(s) without Kd given the default grey",
        ),
        (
            notes.clamped_colour_faces,
            "face colour(s) clamped to a valid reflectance",
        ),
        (
            notes.skipped_points_and_lines,
            "OBJ point/line element(s) skipped",
        ),
    ]
    .into_iter()
    .filter(|(n, _)| *n > 0)
    .map(|(n, what)| format!("{n} {what}"))
    .chain(notes.unsupported.iter().cloned())
    .collect()
}
