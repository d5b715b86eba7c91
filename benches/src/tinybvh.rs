//! tinybvh's BVH8_CPU (8-wide, AVX2 + FMA) as a benchmark peer, through the
//! C shim in `tinybvh/shim.cpp` that `build.rs` compiles when the host allows
//! it. [`TinyBvh8::build`] says why not when it was not compiled.
//!
//! Besides `embree`, this is the crate's only `unsafe`: calls into that shim,
//! whose signatures are declared here.

use glam::Vec3;
use glint::accel::Ray;

#[cfg(tinybvh)]
unsafe extern "C" {
    fn glint_tbvh8_build(verts: *const f32, tri_count: u32) -> *mut std::ffi::c_void;
    fn glint_tbvh8_free(bvh: *mut std::ffi::c_void);
    fn glint_tbvh8_bytes(bvh: *const std::ffi::c_void) -> u64;
    fn glint_tbvh8_intersect(
        bvh: *const std::ffi::c_void,
        o: *const f32,
        d: *const f32,
        t: *mut f32,
        prim: *mut u32,
    ) -> i32;
    fn glint_tbvh8_occluded(
        bvh: *const std::ffi::c_void,
        o: *const f32,
        d: *const f32,
        t_max: f32,
    ) -> i32;
}

/// A BVH8_CPU over a triangle soup, with the vertices it points at.
pub struct TinyBvh8 {
    #[cfg(tinybvh)]
    bvh: *mut std::ffi::c_void,
    #[cfg(tinybvh)]
    _verts: Vec<[f32; 4]>,
}

impl TinyBvh8 {
    /// Builds (tinybvh's default SAH build, one thread) over `tris`; Err
    /// says why tinybvh is not available in this build.
    pub fn build(tris: &[[Vec3; 3]]) -> Result<TinyBvh8, String> {
        #[cfg(tinybvh)]
        {
            let verts: Vec<[f32; 4]> = tris
                .iter()
                .flatten()
                .map(|p| p.extend(0.0).to_array())
                .collect();
            let n = u32::try_from(tris.len()).map_err(|e| e.to_string())?;
            // SAFETY: `verts` holds 3 xyzw vertices per triangle and lives as long as the BVH.
            let bvh = unsafe { glint_tbvh8_build(verts.as_ptr().cast(), n) };
            Ok(TinyBvh8 { bvh, _verts: verts })
        }
        #[cfg(not(tinybvh))]
        {
            let _ = tris;
            Err(format!(
                "tinybvh was not compiled: {}",
                option_env!("TINYBVH_SKIP").unwrap_or("unknown reason")
            ))
        }
    }

    /// Bytes of the node and triangle blocks traversal reads (tinybvh also
    /// keeps the binary and 8-wide build trees it converted from).
    pub fn bytes(&self) -> usize {
        #[cfg(tinybvh)]
        // SAFETY: a live BVH from glint_tbvh8_build.
        return unsafe { glint_tbvh8_bytes(self.bvh) } as usize;
        #[cfg(not(tinybvh))]
        0
    }

    /// Closest hit (triangle index, t) with `BVH8_CPU::Intersect`.
    #[inline]
    pub fn closest(&self, ray: &Ray) -> Option<(u32, f32)> {
        #[cfg(tinybvh)]
        {
            let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
            let (mut t, mut prim) = (0.0f32, 0u32);
            // SAFETY: a live BVH; o and d are 3 floats; t and prim are written on a hit.
            let hit = unsafe {
                glint_tbvh8_intersect(self.bvh, o.as_ptr(), d.as_ptr(), &mut t, &mut prim)
            };
            (hit != 0).then_some((prim, t))
        }
        #[cfg(not(tinybvh))]
        {
            let _ = ray;
            None
        }
    }

    /// Any hit with t in (0, `t_max`) with `BVH8_CPU::IsOccluded`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        #[cfg(tinybvh)]
        {
            let (o, d) = (ray.origin.to_array(), ray.dir.to_array());
            // SAFETY: a live BVH; o and d are 3 floats.
            unsafe { glint_tbvh8_occluded(self.bvh, o.as_ptr(), d.as_ptr(), t_max) != 0 }
        }
        #[cfg(not(tinybvh))]
        {
            let _ = (ray, t_max);
            false
        }
    }
}

#[cfg(tinybvh)]
impl Drop for TinyBvh8 {
    fn drop(&mut self) {
        // SAFETY: built by glint_tbvh8_build, freed once.
        unsafe { glint_tbvh8_free(self.bvh) }
    }
}
