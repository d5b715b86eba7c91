//! Linear colour gradients as settings hold them (SPEC "Linear gradient"): sorted
//! `(t, colour)` components. Sampling is shading: `shade::gradient`.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// A list of `(t, colour)` components, kept sorted by `t`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(from = "Vec<(f32, Vec3)>", into = "Vec<(f32, Vec3)>")]
pub struct Gradient {
    components: Vec<(f32, Vec3)>,
}

impl From<Vec<(f32, Vec3)>> for Gradient {
    fn from(components: Vec<(f32, Vec3)>) -> Self {
        Self::new(components)
    }
}

impl From<Gradient> for Vec<(f32, Vec3)> {
    fn from(g: Gradient) -> Self {
        g.components
    }
}

impl Gradient {
    /// Builds a gradient from components in any order (sorted here, once).
    pub fn new(mut components: Vec<(f32, Vec3)>) -> Self {
        components.sort_by(|a, b| a.0.total_cmp(&b.0));
        Self { components }
    }

    /// The components, sorted by `t`.
    pub fn components(&self) -> &[(f32, Vec3)] {
        &self.components
    }

    /// The default shading gradient: dark blue through orange to pale yellow.
    pub fn default_shading() -> Self {
        Self::new(vec![
            (0.0, Vec3::new(0.05, 0.05, 0.3)),
            (0.5, Vec3::new(0.9, 0.4, 0.1)),
            (1.0, Vec3::new(1.0, 1.0, 0.7)),
        ])
    }

    /// The default comparison gradient: red at -1, dark grey at 0, green at +1.
    pub fn default_comparison() -> Self {
        Self::new(vec![
            (-1.0, Vec3::new(1.0, 0.0, 0.0)),
            (0.0, Vec3::splat(0.1)),
            (1.0, Vec3::new(0.0, 1.0, 0.0)),
        ])
    }
}
