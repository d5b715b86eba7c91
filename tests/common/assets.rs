//! Helpers of the model-import tests (tests/assets_*.rs): the project's fixture folder
//! and the shared third-party assets, which are skipped with a reason when absent.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use bevy_ecs::prelude::*;
use glam::Vec3;
use glint::scene::model::{ImportOptions, ImportReport, import_model};
use glint::{GlintError, Overrides, Renderer};

/// The repository root.
pub fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The committed glTF fixture's folder.
pub fn fixture_dir() -> PathBuf {
    repo().join("assets/fixture")
}

/// The shared assets folder, or `None` (with the reason printed) when it is absent.
pub fn shared_assets(test: &str) -> Option<PathBuf> {
    let dir = repo().join("../shared/assets");
    if dir.join("README.md").is_file() {
        Some(dir)
    } else {
        super::skip(
            test,
            &format!(
                "{} not found (third-party assets are not in the repository)",
                dir.display()
            ),
        );
        None
    }
}

/// Imports a model file into a fresh World.
pub fn import(path: &Path) -> Result<(World, ImportReport, Vec<String>), GlintError> {
    let mut world = World::new();
    let mut warnings = Vec::new();
    let report = import_model(&mut world, path, &ImportOptions::default(), &mut warnings)?;
    Ok((world, report, warnings))
}

/// 32x32 pixels, one sample each.
pub fn small() -> Overrides {
    Overrides {
        width: Some(32),
        height: Some(32),
        seed: None,
        set: vec![("pixel_samples".into(), "1".into())],
    }
}

/// Renders fully and returns the image.
pub fn render_image(mut r: Renderer) -> Vec<Vec3> {
    r.render(None, &mut |_| {}).expect("render");
    r.film().image()
}
/// Triangle counts per model folder from the assets README ("scene" counts).
pub fn readme_counts(assets: &Path) -> HashMap<String, u64> {
    let text = std::fs::read_to_string(assets.join("README.md")).unwrap();
    let mut counts = HashMap::new();
    for line in text.lines() {
        let cells: Vec<&str> = line.split('|').map(str::trim).collect();
        if cells.len() < 6 || cells[1] == "Folder" || cells[1].starts_with("---") {
            continue;
        }
        // "3,884 defs / 7,724 scene": the default-scene count is after the last '/'.
        let part = cells[4].rsplit('/').next().unwrap();
        let digits: String = part
            .trim()
            .chars()
            .take_while(|c| c.is_ascii_digit() || *c == ',')
            .filter(char::is_ascii_digit)
            .collect();
        if let Ok(n) = digits.parse() {
            counts.insert(cells[1].to_owned(), n);
        }
    }
    counts
}
