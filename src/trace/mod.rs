//! Tracing: the scene's geometry and its queries, the material and light tables, the
//! render plan, the camera model, the wavefront systems of one depth level and their
//! optional trace log.

pub mod camera;
mod camera_samples;
mod crossings;
pub mod geometry;
mod lane_models;
pub mod lights;
pub mod log;
pub mod materials;
pub mod packet_hits;
pub mod plan;
mod shade_lanes;
pub mod shadow;
pub mod surface;
mod surface_lanes;
mod surface_queue;
pub mod wavefront;
