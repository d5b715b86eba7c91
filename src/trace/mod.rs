//! Tracing: the scene's geometry and its queries, the material and light tables, the
//! render plan, and the wavefront systems of one depth level.

pub mod geometry;
pub mod lights;
pub mod materials;
pub mod plan;
pub mod surface;
pub mod wavefront;
