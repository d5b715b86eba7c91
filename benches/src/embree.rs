//! Embree 4 as a benchmark peer, loaded at run time from the shared library
//! named by `GLINT_EMBREE_LIB` (e.g. the `libembree4.so.4` that the `embreex`
//! Python wheel ships: `pip download --no-deps embreex`, unzip, and point the
//! variable at `embreex.libs/libembree4-*.so.4`). Nothing is built or linked
//! at compile time, so the benchmarks build everywhere and skip Embree's rows
//! when the variable is unset.
//!
//! This module is the crate's only `unsafe`: calls through C function
//! pointers whose signatures and struct layouts are copied from Embree 4's
//! `rtcore_device.h`, `rtcore_scene.h`, `rtcore_geometry.h`, `rtcore_buffer.h`
//! and `rtcore_ray.h`.

use std::ffi::{CString, c_char, c_void};
use std::mem::ManuallyDrop;
use std::ptr::null_mut;
use std::sync::atomic::{AtomicIsize, Ordering};

use glam::Vec3;
use glint::accel::Ray;
use libloading::Library;

/// The environment variable that names the library.
pub const ENV_VAR: &str = "GLINT_EMBREE_LIB";

const RTC_GEOMETRY_TYPE_TRIANGLE: u32 = 0;
const RTC_BUFFER_TYPE_INDEX: u32 = 0;
const RTC_BUFFER_TYPE_VERTEX: u32 = 1;
const RTC_FORMAT_UINT3: u32 = 0x5003;
const RTC_FORMAT_FLOAT3: u32 = 0x9003;
const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;
const RTC_SCENE_FLAG_ROBUST: u32 = 1 << 2;

/// `RTCBuildQuality`: how much work a scene's build puts into its BVH.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub enum BuildQuality {
    /// Embree's default: binned SAH.
    Medium = 1,
    /// Binned SAH with spatial splits (Embree's SBVH builder for triangles).
    High = 2,
}

/// `RTCRay`.
#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct RtcRay {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: u32,
    id: u32,
    flags: u32,
}

/// `RTCHit` with one instance level; `inst_prim_id` exists when Embree was
/// built with instance arrays (4.3+ releases are) and pads it otherwise.
#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct RtcHit {
    ng: [f32; 3],
    u: f32,
    v: f32,
    prim_id: u32,
    geom_id: u32,
    inst_id: [u32; 1],
    inst_prim_id: [u32; 1],
}

/// `RTCRayHit`.
#[repr(C, align(16))]
#[derive(Clone, Copy)]
struct RtcRayHit {
    ray: RtcRay,
    hit: RtcHit,
}

/// `RTCRayHit16`: `RTCRay16` then `RTCHit16`, each a structure of 16-lane arrays.
/// `rest` covers the hit's instance fields (their count depends on how Embree was
/// built) with room to spare; nothing after `geom_id` is read.
#[repr(C, align(64))]
struct RtcRayHit16 {
    org: [[f32; 16]; 3],
    tnear: [f32; 16],
    dir: [[f32; 16]; 3],
    time: [f32; 16],
    tfar: [f32; 16],
    mask: [u32; 16],
    id: [u32; 16],
    flags: [u32; 16],
    ng: [[f32; 16]; 3],
    u: [f32; 16],
    v: [f32; 16],
    prim_id: [u32; 16],
    geom_id: [u32; 16],
    rest: [[u32; 16]; 8],
}

/// The `valid` argument of the 16-ray calls: -1 for a lane in use, 0 otherwise.
#[repr(C, align(64))]
struct Valid16([i32; 16]);

type Handle = *mut c_void;

/// The entry points used, resolved once.
struct Api {
    new_device: unsafe extern "C" fn(*const c_char) -> Handle,
    release_device: unsafe extern "C" fn(Handle),
    get_device_error: unsafe extern "C" fn(Handle) -> u32,
    new_scene: unsafe extern "C" fn(Handle) -> Handle,
    release_scene: unsafe extern "C" fn(Handle),
    commit_scene: unsafe extern "C" fn(Handle),
    set_scene_build_quality: unsafe extern "C" fn(Handle, u32),
    set_scene_flags: unsafe extern "C" fn(Handle, u32),
    new_geometry: unsafe extern "C" fn(Handle, u32) -> Handle,
    set_new_geometry_buffer: unsafe extern "C" fn(Handle, u32, u32, u32, usize, usize) -> Handle,
    commit_geometry: unsafe extern "C" fn(Handle),
    attach_geometry: unsafe extern "C" fn(Handle, Handle) -> u32,
    release_geometry: unsafe extern "C" fn(Handle),
    intersect1: unsafe extern "C" fn(Handle, *mut RtcRayHit, *mut c_void),
    occluded1: unsafe extern "C" fn(Handle, *mut RtcRay, *mut c_void),
    intersect16: unsafe extern "C" fn(*const Valid16, Handle, *mut RtcRayHit16, *mut c_void),
    // Takes an `RTCRay16`, the first part of an `RTCRayHit16`.
    occluded16: unsafe extern "C" fn(*const Valid16, Handle, *mut RtcRayHit16, *mut c_void),
    set_memory_monitor: unsafe extern "C" fn(Handle, MemoryMonitor, *mut c_void),
}

/// `RTCMemoryMonitorFunction`: Embree reports every allocation (positive)
/// and release (negative) of its device's memory.
type MemoryMonitor = unsafe extern "C" fn(*mut c_void, isize, bool) -> bool;

/// Bytes Embree's devices hold now, as their memory monitors report it.
static BYTES_IN_USE: AtomicIsize = AtomicIsize::new(0);

unsafe extern "C" fn count_bytes(_user: *mut c_void, bytes: isize, _post: bool) -> bool {
    BYTES_IN_USE.fetch_add(bytes, Ordering::Relaxed);
    true
}

/// A loaded Embree library and one device.
pub struct Embree {
    api: Api,
    device: Handle,
    // Never unloaded: the device's TBB worker threads outlive `rtcReleaseDevice`, and
    // unloading the library under them crashed the process at exit (SIGSEGV in about
    // one run of three of `anchors -- sponza`). The function pointers above point into it.
    _lib: ManuallyDrop<Library>,
}

/// A committed Embree scene of one triangle mesh.
pub struct EmbreeScene<'a> {
    embree: &'a Embree,
    scene: Handle,
}

impl Embree {
    /// Loads the library named by [`ENV_VAR`] and creates a device with
    /// Embree's `config` string (e.g. `"threads=1"`); Err says why not.
    pub fn load(config: &str) -> Result<Embree, String> {
        let path = std::env::var_os(ENV_VAR).ok_or_else(|| {
            format!(
                "{ENV_VAR} is not set (point it at libembree4.so.4, e.g. from the embreex wheel)"
            )
        })?;
        // SAFETY: loading runs the library's initialisers; Embree's are benign.
        let lib = unsafe { Library::new(&path) }
            .map_err(|e| format!("{}: {e}", path.to_string_lossy()))?;
        macro_rules! sym {
            ($name:literal) => {
                // SAFETY: the symbol's type is the signature in Embree's headers.
                *unsafe { lib.get(concat!($name, "\0").as_bytes()) }
                    .map_err(|e| format!("{}: {e}", path.to_string_lossy()))?
            };
        }
        let api = Api {
            new_device: sym!("rtcNewDevice"),
            release_device: sym!("rtcReleaseDevice"),
            get_device_error: sym!("rtcGetDeviceError"),
            new_scene: sym!("rtcNewScene"),
            release_scene: sym!("rtcReleaseScene"),
            commit_scene: sym!("rtcCommitScene"),
            set_scene_build_quality: sym!("rtcSetSceneBuildQuality"),
            set_scene_flags: sym!("rtcSetSceneFlags"),
            new_geometry: sym!("rtcNewGeometry"),
            set_new_geometry_buffer: sym!("rtcSetNewGeometryBuffer"),
            commit_geometry: sym!("rtcCommitGeometry"),
            attach_geometry: sym!("rtcAttachGeometry"),
            release_geometry: sym!("rtcReleaseGeometry"),
            intersect1: sym!("rtcIntersect1"),
            occluded1: sym!("rtcOccluded1"),
            intersect16: sym!("rtcIntersect16"),
            occluded16: sym!("rtcOccluded16"),
            set_memory_monitor: sym!("rtcSetDeviceMemoryMonitorFunction"),
        };
        let config = CString::new(config).map_err(|e| e.to_string())?;
        // SAFETY: a NUL-terminated config string; the device is released in Drop.
        let device = unsafe { (api.new_device)(config.as_ptr()) };
        if device.is_null() {
            return Err("rtcNewDevice failed".into());
        }
        // SAFETY: a live device and a callback with Embree's signature.
        unsafe { (api.set_memory_monitor)(device, count_bytes, null_mut()) };
        Ok(Embree {
            api,
            device,
            _lib: ManuallyDrop::new(lib),
        })
    }

    /// Bytes all loaded Embree devices hold now (buffers, BVHs, scratch).
    pub fn bytes_in_use() -> usize {
        BYTES_IN_USE.load(Ordering::Relaxed).max(0) as usize
    }

    /// Builds a scene (Embree's default, medium quality) over `tris`.
    pub fn scene(&self, tris: &[[Vec3; 3]]) -> Result<EmbreeScene<'_>, String> {
        self.scene_with(tris, BuildQuality::Medium, false)
    }

    /// Builds a scene of build quality `quality` over `tris`; `robust`: with
    /// `RTC_SCENE_FLAG_ROBUST` (robust traversal, no optimizations that reduce
    /// arithmetic accuracy: what glint's queries always do).
    pub fn scene_with(
        &self,
        tris: &[[Vec3; 3]],
        quality: BuildQuality,
        robust: bool,
    ) -> Result<EmbreeScene<'_>, String> {
        let a = &self.api;
        let n = tris.len();
        // SAFETY: Embree allocates both buffers with the sizes given here
        // (plus its own padding), and they are written within those sizes.
        unsafe {
            let scene = (a.new_scene)(self.device);
            if !scene.is_null() {
                (a.set_scene_build_quality)(scene, quality as u32);
                if robust {
                    (a.set_scene_flags)(scene, RTC_SCENE_FLAG_ROBUST);
                }
            }
            let geom = (a.new_geometry)(self.device, RTC_GEOMETRY_TYPE_TRIANGLE);
            let verts = (a.set_new_geometry_buffer)(
                geom,
                RTC_BUFFER_TYPE_VERTEX,
                0,
                RTC_FORMAT_FLOAT3,
                12,
                3 * n,
            ) as *mut f32;
            let index = (a.set_new_geometry_buffer)(
                geom,
                RTC_BUFFER_TYPE_INDEX,
                0,
                RTC_FORMAT_UINT3,
                12,
                n,
            ) as *mut u32;
            if scene.is_null() || geom.is_null() || verts.is_null() || index.is_null() {
                return Err(format!(
                    "Embree scene setup failed (error {})",
                    (a.get_device_error)(self.device)
                ));
            }
            let verts = std::slice::from_raw_parts_mut(verts, 9 * n);
            let index = std::slice::from_raw_parts_mut(index, 3 * n);
            for (i, t) in tris.iter().enumerate() {
                for (k, p) in t.iter().enumerate() {
                    verts[9 * i + 3 * k..9 * i + 3 * k + 3].copy_from_slice(&p.to_array());
                    index[3 * i + k] = (3 * i + k) as u32;
                }
            }
            (a.commit_geometry)(geom);
            (a.attach_geometry)(scene, geom);
            (a.release_geometry)(geom);
            (a.commit_scene)(scene);
            let err = (a.get_device_error)(self.device);
            if err != 0 {
                (a.release_scene)(scene);
                return Err(format!("Embree scene commit failed (error {err})"));
            }
            Ok(EmbreeScene {
                embree: self,
                scene,
            })
        }
    }
}

impl Drop for Embree {
    fn drop(&mut self) {
        // SAFETY: the device was created by rtcNewDevice and every scene borrowed it.
        unsafe { (self.api.release_device)(self.device) }
    }
}

impl Drop for EmbreeScene<'_> {
    fn drop(&mut self) {
        // SAFETY: the scene was created by rtcNewScene.
        unsafe { (self.embree.api.release_scene)(self.scene) }
    }
}

fn rtc_ray(ray: &Ray, t_max: f32) -> RtcRay {
    RtcRay {
        org: ray.origin.to_array(),
        tnear: 0.0,
        dir: ray.dir.to_array(),
        time: 0.0,
        tfar: t_max,
        mask: u32::MAX,
        id: 0,
        flags: 0,
    }
}

impl EmbreeScene<'_> {
    /// Closest hit (triangle index, t) with `rtcIntersect1`.
    #[inline]
    pub fn closest(&self, ray: &Ray) -> Option<(u32, f32)> {
        let mut rh = RtcRayHit {
            ray: rtc_ray(ray, f32::INFINITY),
            hit: RtcHit {
                ng: [0.0; 3],
                u: 0.0,
                v: 0.0,
                prim_id: 0,
                geom_id: RTC_INVALID_GEOMETRY_ID,
                inst_id: [RTC_INVALID_GEOMETRY_ID],
                inst_prim_id: [RTC_INVALID_GEOMETRY_ID],
            },
        };
        // SAFETY: a committed scene and an aligned RTCRayHit; NULL arguments mean defaults.
        unsafe { (self.embree.api.intersect1)(self.scene, &mut rh, null_mut()) };
        (rh.hit.geom_id != RTC_INVALID_GEOMETRY_ID).then_some((rh.hit.prim_id, rh.ray.tfar))
    }

    /// Any hit with t in (0, `t_max`) with `rtcOccluded1`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let mut r = rtc_ray(ray, t_max);
        // SAFETY: a committed scene and an aligned RTCRay; NULL arguments mean defaults.
        unsafe { (self.embree.api.occluded1)(self.scene, &mut r, null_mut()) };
        r.tfar == f32::NEG_INFINITY
    }

    /// Hits among up to 16 rays traced as one packet (`rtcIntersect16`, or
    /// `rtcOccluded16` up to `t_max` when `shadow`): Embree's packet kernels, which
    /// pay when the rays are coherent.
    pub fn hits16(&self, rays: &[Ray], shadow: bool, t_max: f32) -> u32 {
        assert!(rays.len() <= 16);
        // SAFETY: all-zero bits are valid for every field (plain numbers).
        let mut p: RtcRayHit16 = unsafe { std::mem::zeroed() };
        let mut valid = Valid16([0; 16]);
        for (i, r) in rays.iter().enumerate() {
            for a in 0..3 {
                p.org[a][i] = r.origin[a];
                p.dir[a][i] = r.dir[a];
            }
            p.tfar[i] = t_max;
            p.mask[i] = u32::MAX;
            p.geom_id[i] = RTC_INVALID_GEOMETRY_ID;
            valid.0[i] = -1;
        }
        // SAFETY: a committed scene, 64-byte aligned `valid` and packet (the packet with
        // room past the hit fields); NULL arguments mean defaults.
        unsafe {
            if shadow {
                (self.embree.api.occluded16)(&valid, self.scene, &mut p, null_mut());
            } else {
                (self.embree.api.intersect16)(&valid, self.scene, &mut p, null_mut());
            }
        }
        (0..rays.len())
            .filter(|&i| {
                if shadow {
                    p.tfar[i] == f32::NEG_INFINITY
                } else {
                    p.geom_id[i] != RTC_INVALID_GEOMETRY_ID
                }
            })
            .count() as u32
    }
}
