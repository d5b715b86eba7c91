//! Changes to a parsed scene for one run: image size, seed and `key=value` settings.

use super::format::SceneFile;
use crate::error::{GlintError, Result};

/// Changes to a scene for one run, applied to the parsed file before it is validated.
#[derive(Clone, Debug, Default)]
pub struct Overrides {
    /// Image width.
    pub width: Option<u32>,
    /// Image height.
    pub height: Option<u32>,
    /// Random seed.
    pub seed: Option<u64>,
    /// `key=value` settings, applied in order.
    pub set: Vec<(String, String)>,
}

impl Overrides {
    /// Applies the overrides to a parsed scene.
    pub fn apply(&self, file: &mut SceneFile) -> Result<()> {
        if let Some(w) = self.width {
            file.camera.width = w;
        }
        if let Some(h) = self.height {
            file.camera.height = h;
        }
        if let Some(seed) = self.seed {
            file.settings.seed = seed;
        }
        for (k, v) in &self.set {
            file.settings.set(k, v).map_err(GlintError::Setting)?;
        }
        Ok(())
    }
}
