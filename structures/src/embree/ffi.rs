//! The part of Embree 3's C API the `embree` row uses, loaded from the shared library at run time
//! with `libloading`, and safe wrappers around it. This file is the workspace's only foreign code;
//! every `unsafe` block carries its soundness argument.
//!
//! Why at run time: the row must appear in a plain `cargo run -p harness` wherever the library is
//! installed (Debian: `apt-get install libembree3-3`), and the workspace must build and run where
//! it is not — no cargo feature, no link-time dependency, no C headers at build time.
//!
//! The declarations below transcribe Embree 3.13's headers (`rtcore_*.h`). The layouts that matter
//! are `RTCRayHit` and `RTCRayHitN`, and `RTCIntersectContext`; they are fixed across Embree 3
//! for the library's default configuration, `RTC_MAX_INSTANCE_LEVEL_COUNT = 1` (the Debian package
//! and Intel's binaries). `Api::load` refuses any major version but 3. A library built with more
//! instance levels writes a longer `instID` array at the end of the hit: the structures below
//! carry spare words after it, so such a write stays inside our memory.

#![allow(unsafe_code)]

use std::ffi::{CStr, CString, c_char, c_int, c_uint, c_void};
use std::sync::atomic::{AtomicI64, Ordering};
use std::sync::{Mutex, OnceLock};

use libloading::Library;

/// Environment variable: the path of the Embree 3 library to load instead of the default names.
pub const LIBRARY_ENV: &str = "ACCEL_BENCH_EMBREE";
/// Environment variable: `1` turns a missing Embree from a skip into a failure in the tests (CI sets it).
pub const REQUIRE_ENV: &str = "ACCEL_BENCH_REQUIRE_EMBREE";

/// File names tried in order when [`LIBRARY_ENV`] is not set.
const LIBRARY_NAMES: &[&str] =
    &["libembree3.so.3", "libembree3.so", "libembree3.3.dylib", "libembree3.dylib", "embree3.dll"];

/// What to tell a user whose machine has no Embree.
pub const INSTALL_HINT: &str = "install Embree 3 (Debian/Ubuntu: `apt-get install libembree3-3`; elsewhere Intel's \
     release from github.com/embree/embree, v3.x) or point ACCEL_BENCH_EMBREE at libembree3";

type Device = *mut c_void;
type Scene = *mut c_void;
type Geometry = *mut c_void;

type ErrorFn = extern "C" fn(user: *mut c_void, code: c_int, message: *const c_char);
type MonitorFn = extern "C" fn(user: *mut c_void, bytes: isize, post: bool) -> bool;

// Enum values of rtcore_*.h (C enums are `int`).
const RTC_DEVICE_PROPERTY_VERSION: c_int = 0;
const RTC_GEOMETRY_TYPE_TRIANGLE: c_int = 0;
const RTC_BUFFER_TYPE_INDEX: c_int = 0;
const RTC_BUFFER_TYPE_VERTEX: c_int = 1;
const RTC_FORMAT_UINT3: c_int = 0x5003;
const RTC_FORMAT_FLOAT3: c_int = 0x9003;
const RTC_SCENE_FLAG_ROBUST: c_int = 1 << 2;
const RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT: c_int = 0;
const RTC_INTERSECT_CONTEXT_FLAG_COHERENT: c_int = 1;
const RTC_INVALID_GEOMETRY_ID: u32 = u32::MAX;

/// Spare words after each hit record (see the module comment).
const SPARE: usize = 16;

/// `struct RTCIntersectContext` with one instance level.
#[repr(C)]
struct IntersectContext {
    flags: c_int,
    filter: *const c_void,
    inst_id: [u32; 1],
}

/// `struct RTCRayHit`: `RTCRay` (48 bytes) and `RTCHit` (32 bytes), both 16-byte aligned.
#[repr(C, align(16))]
struct RayHit1 {
    org: [f32; 3],
    tnear: f32,
    dir: [f32; 3],
    time: f32,
    tfar: f32,
    mask: u32,
    id: u32,
    flags: u32,
    ng: [f32; 3],
    u: f32,
    v: f32,
    prim_id: u32,
    geom_id: u32,
    inst_id: [u32; 1],
    spare: [u32; SPARE],
}

/// `struct RTCRayHit8` / `RTCRayHit16`: structure-of-arrays, 32- / 64-byte aligned (64 serves both).
#[repr(C, align(64))]
struct RayHitN<const N: usize> {
    org_x: [f32; N],
    org_y: [f32; N],
    org_z: [f32; N],
    tnear: [f32; N],
    dir_x: [f32; N],
    dir_y: [f32; N],
    dir_z: [f32; N],
    time: [f32; N],
    tfar: [f32; N],
    mask: [u32; N],
    id: [u32; N],
    flags: [u32; N],
    ng_x: [f32; N],
    ng_y: [f32; N],
    ng_z: [f32; N],
    u: [f32; N],
    v: [f32; N],
    prim_id: [u32; N],
    geom_id: [u32; N],
    inst_id: [u32; N],
    spare: [u32; SPARE],
}

/// The `valid` lane mask of `rtcIntersect8/16`, aligned like the packet.
#[repr(C, align(64))]
struct ValidMask<const N: usize>([c_int; N]);

/// The entry points, resolved once per process.
struct Api {
    new_device: unsafe extern "C" fn(*const c_char) -> Device,
    release_device: unsafe extern "C" fn(Device),
    device_property: unsafe extern "C" fn(Device, c_int) -> isize,
    device_error: unsafe extern "C" fn(Device) -> c_int,
    set_error_function: unsafe extern "C" fn(Device, Option<ErrorFn>, *mut c_void),
    set_memory_monitor: unsafe extern "C" fn(Device, Option<MonitorFn>, *mut c_void),
    new_scene: unsafe extern "C" fn(Device) -> Scene,
    release_scene: unsafe extern "C" fn(Scene),
    set_scene_flags: unsafe extern "C" fn(Scene, c_int),
    set_scene_build_quality: unsafe extern "C" fn(Scene, c_int),
    commit_scene: unsafe extern "C" fn(Scene),
    new_geometry: unsafe extern "C" fn(Device, c_int) -> Geometry,
    set_new_geometry_buffer: unsafe extern "C" fn(Geometry, c_int, c_uint, c_int, usize, usize) -> *mut c_void,
    commit_geometry: unsafe extern "C" fn(Geometry),
    attach_geometry: unsafe extern "C" fn(Scene, Geometry) -> c_uint,
    release_geometry: unsafe extern "C" fn(Geometry),
    intersect1: unsafe extern "C" fn(Scene, *mut IntersectContext, *mut RayHit1),
    intersect8: unsafe extern "C" fn(*const c_int, Scene, *mut IntersectContext, *mut RayHitN<8>),
    intersect16: unsafe extern "C" fn(*const c_int, Scene, *mut IntersectContext, *mut RayHitN<16>),
    /// The library the function pointers point into; never unloaded while they live (it lives in
    /// a process-wide `OnceLock`).
    _library: Library,
    /// Where it was loaded from, and its version (e.g. 31305).
    source: String,
    version: i64,
}

static API: OnceLock<Result<Api, String>> = OnceLock::new();

impl Api {
    fn get() -> Result<&'static Api, String> {
        API.get_or_init(Api::load).as_ref().map_err(Clone::clone)
    }

    fn load() -> Result<Api, String> {
        let candidates: Vec<String> = match std::env::var(LIBRARY_ENV) {
            Ok(path) if !path.is_empty() => vec![path],
            _ => LIBRARY_NAMES.iter().map(|s| s.to_string()).collect(),
        };
        let mut errors = Vec::new();
        for name in &candidates {
            // SAFETY: loading a library runs its initialisers. We load only Embree 3 by its file
            // name (or the user's explicit path), whose initialisers set up its own state only.
            match unsafe { Library::new(name) } {
                Ok(library) => return Api::resolve(library, name),
                Err(e) => errors.push(e.to_string()),
            }
        }
        Err(format!("Embree 3 not found ({}); {INSTALL_HINT}", errors.join("; ")))
    }

    fn resolve(library: Library, source: &str) -> Result<Api, String> {
        macro_rules! sym {
            ($name:literal) => {
                // SAFETY: each symbol is given the exact signature of its declaration in Embree 3's
                // headers (transcribed above; pointer types as `*mut c_void`, enums as `c_int`),
                // and the pointer is used only while `library` is alive (both live in `Api`).
                *unsafe { library.get(concat!($name, "\0").as_bytes()) }
                    .map_err(|e| format!("{source}: no symbol {}: {e}", $name))?
            };
        }
        let mut api = Api {
            new_device: sym!("rtcNewDevice"),
            release_device: sym!("rtcReleaseDevice"),
            device_property: sym!("rtcGetDeviceProperty"),
            device_error: sym!("rtcGetDeviceError"),
            set_error_function: sym!("rtcSetDeviceErrorFunction"),
            set_memory_monitor: sym!("rtcSetDeviceMemoryMonitorFunction"),
            new_scene: sym!("rtcNewScene"),
            release_scene: sym!("rtcReleaseScene"),
            set_scene_flags: sym!("rtcSetSceneFlags"),
            set_scene_build_quality: sym!("rtcSetSceneBuildQuality"),
            commit_scene: sym!("rtcCommitScene"),
            new_geometry: sym!("rtcNewGeometry"),
            set_new_geometry_buffer: sym!("rtcSetNewGeometryBuffer"),
            commit_geometry: sym!("rtcCommitGeometry"),
            attach_geometry: sym!("rtcAttachGeometry"),
            release_geometry: sym!("rtcReleaseGeometry"),
            intersect1: sym!("rtcIntersect1"),
            intersect8: sym!("rtcIntersect8"),
            intersect16: sym!("rtcIntersect16"),
            _library: library,
            source: source.to_string(),
            version: 0,
        };
        // SAFETY: a null config asks for the default device; the device is released before return.
        let device = unsafe { (api.new_device)(std::ptr::null()) };
        if device.is_null() {
            return Err(format!("{source}: rtcNewDevice failed (unsupported CPU?)"));
        }
        // SAFETY: `device` is a live device; the property id is a valid `RTCDeviceProperty`.
        api.version = unsafe { (api.device_property)(device, RTC_DEVICE_PROPERTY_VERSION) } as i64;
        // SAFETY: `device` was created above and is released once.
        unsafe { (api.release_device)(device) };
        if !(30000..40000).contains(&api.version) {
            return Err(format!("{source} is Embree version {}, not 3.x; {INSTALL_HINT}", api.version));
        }
        Ok(api)
    }
}

/// Where Embree was loaded from and its version, or why it cannot be.
pub fn library() -> Result<(String, String), String> {
    Api::get().map(|api| {
        let v = api.version;
        (api.source.clone(), format!("{}.{}.{}", v / 10000, v / 100 % 100, v % 100))
    })
}

/// What the device's callbacks write: bytes Embree holds, and its last error message.
#[derive(Default)]
struct DeviceState {
    bytes: AtomicI64,
    peak: AtomicI64,
    last_error: Mutex<String>,
}

extern "C" fn on_memory(user: *mut c_void, bytes: isize, _post: bool) -> bool {
    // SAFETY: `user` is the `DeviceState` registered with this callback, boxed in the
    // `CommittedScene` that owns the device and dropped only after the device is released, so
    // it outlives every call. Only atomics are touched: Embree calls this from its build threads.
    let state = unsafe { &*(user as *const DeviceState) };
    let now = state.bytes.fetch_add(bytes as i64, Ordering::Relaxed) + bytes as i64;
    state.peak.fetch_max(now, Ordering::Relaxed);
    true
}

extern "C" fn on_error(user: *mut c_void, code: c_int, message: *const c_char) {
    // SAFETY: as in `on_memory`; `message` is null or a NUL-terminated string valid for the call.
    let state = unsafe { &*(user as *const DeviceState) };
    let text = if message.is_null() {
        String::new()
    } else {
        unsafe { CStr::from_ptr(message) }.to_string_lossy().into_owned()
    };
    if let Ok(mut last) = state.last_error.lock() {
        *last = format!("error {code}: {text}");
    }
}

/// How to build the scene.
#[derive(Clone, Copy, Debug)]
pub struct SceneOptions {
    /// `RTC_SCENE_FLAG_ROBUST`: slower traversal that avoids optimisations reducing arithmetic accuracy.
    pub robust: bool,
    /// `RTCBuildQuality`: 0 low, 1 medium (Embree's default), 2 high.
    pub quality: i32,
    /// Build threads (`threads=` in the device config); 0 lets Embree use every core.
    pub threads: usize,
}

/// A committed Embree scene over one triangle mesh, ready for concurrent queries.
pub struct CommittedScene {
    api: &'static Api,
    device: Device,
    scene: Scene,
    state: Box<DeviceState>,
    /// Bytes the memory monitor saw: after the vertex and index buffers were made, and in all
    /// once the scene was committed (the BVH is the difference); and the peak during the build.
    pub buffer_bytes: i64,
    pub total_bytes: i64,
    pub peak_bytes: i64,
}

// SAFETY: Embree documents that a committed scene may be traversed (`rtcIntersect*`) from any
// number of threads at once; after `build` returns nothing mutates the scene or device until
// `drop`, which takes `&mut self`, so no query can run concurrently with the release.
unsafe impl Send for CommittedScene {}
unsafe impl Sync for CommittedScene {}

impl CommittedScene {
    /// Copies `vertices` (three per triangle) into a new device's triangle geometry, commits it.
    pub fn build(vertices: &[[f32; 3]], options: SceneOptions) -> Result<CommittedScene, String> {
        let api = Api::get()?;
        let triangles = vertices.len() / 3;
        let config =
            CString::new(if options.threads > 0 { format!("threads={}", options.threads) } else { String::new() })
                .map_err(|e| e.to_string())?;
        // SAFETY: `config` is a valid NUL-terminated string for the duration of the call.
        let device = unsafe { (api.new_device)(config.as_ptr()) };
        if device.is_null() {
            return Err("rtcNewDevice failed".into());
        }
        let state = Box::<DeviceState>::default();
        let user = &*state as *const DeviceState as *mut c_void;
        let mut out = CommittedScene {
            api,
            device,
            scene: std::ptr::null_mut(),
            state,
            buffer_bytes: 0,
            total_bytes: 0,
            peak_bytes: 0,
        };
        // SAFETY: `device` is live; `user` points to the boxed state, which `out` keeps alive
        // until after the device is released (see `Drop`); the callbacks match Embree's types.
        unsafe {
            (api.set_error_function)(device, Some(on_error), user);
            (api.set_memory_monitor)(device, Some(on_memory), user);
        }
        // SAFETY: `device` is live. The scene handle is stored in `out` at once, so `Drop`
        // releases it on every path below.
        out.scene = unsafe { (api.new_scene)(device) };
        if out.scene.is_null() {
            return Err(out.error("rtcNewScene"));
        }
        // SAFETY: `out.scene` is live; the flag and quality values are valid enum values
        // (quality checked by the caller to be 0..=2).
        unsafe {
            (api.set_scene_flags)(out.scene, if options.robust { RTC_SCENE_FLAG_ROBUST } else { 0 });
            (api.set_scene_build_quality)(out.scene, options.quality.clamp(0, 2));
        }
        if triangles > 0 {
            // SAFETY: `device` is live; released below after attaching (the scene keeps its own reference).
            let geometry = unsafe { (api.new_geometry)(device, RTC_GEOMETRY_TYPE_TRIANGLE) };
            if geometry.is_null() {
                return Err(out.error("rtcNewGeometry"));
            }
            // SAFETY: `geometry` is live. Embree allocates each buffer with room for
            // `count` items of `stride` bytes (plus its own padding) and returns it, or null
            // on failure; we write exactly `count` items into a non-null one.
            let filled = unsafe {
                let v = (api.set_new_geometry_buffer)(
                    geometry,
                    RTC_BUFFER_TYPE_VERTEX,
                    0,
                    RTC_FORMAT_FLOAT3,
                    12,
                    vertices.len(),
                ) as *mut [f32; 3];
                let i =
                    (api.set_new_geometry_buffer)(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 12, triangles)
                        as *mut [u32; 3];
                if !v.is_null() && !i.is_null() {
                    std::ptr::copy_nonoverlapping(vertices.as_ptr(), v, vertices.len());
                    let indices = std::slice::from_raw_parts_mut(i, triangles);
                    for (k, tri) in indices.iter_mut().enumerate() {
                        let base = 3 * k as u32;
                        *tri = [base, base + 1, base + 2];
                    }
                }
                !v.is_null() && !i.is_null()
            };
            if !filled {
                // SAFETY: `geometry` is live and released once.
                unsafe { (api.release_geometry)(geometry) };
                return Err(out.error("rtcSetNewGeometryBuffer"));
            }
            // SAFETY: `geometry` is live with both buffers set; attaching makes the scene hold a
            // reference, so releasing ours afterwards leaves it alive.
            unsafe {
                (api.commit_geometry)(geometry);
                (api.attach_geometry)(out.scene, geometry);
                (api.release_geometry)(geometry);
            }
        }
        out.buffer_bytes = out.state.bytes.load(Ordering::Relaxed);
        // SAFETY: `out.scene` is live; the commit builds the BVH (on Embree's own threads).
        unsafe { (api.commit_scene)(out.scene) };
        // SAFETY: `device` is live.
        if unsafe { (api.device_error)(device) } != 0 {
            return Err(out.error("rtcCommitScene"));
        }
        out.total_bytes = out.state.bytes.load(Ordering::Relaxed);
        out.peak_bytes = out.state.peak.load(Ordering::Relaxed);
        Ok(out)
    }

    fn error(&self, call: &str) -> String {
        let last = self.state.last_error.lock().map(|s| s.clone()).unwrap_or_default();
        if last.is_empty() { format!("{call} failed") } else { format!("{call} failed: {last}") }
    }

    /// The nearest hit in `[t_min, t_max]` of one ray.
    #[inline]
    pub fn intersect1(&self, origin: [f32; 3], dir: [f32; 3], t_min: f32, t_max: f32) -> Option<EmbreeHit> {
        let mut context = context(RTC_INTERSECT_CONTEXT_FLAG_INCOHERENT);
        let mut rh = RayHit1 {
            org: origin,
            tnear: t_min,
            dir,
            time: 0.0,
            tfar: t_max,
            mask: u32::MAX,
            id: 0,
            flags: 0,
            ng: [0.0; 3],
            u: 0.0,
            v: 0.0,
            prim_id: RTC_INVALID_GEOMETRY_ID,
            geom_id: RTC_INVALID_GEOMETRY_ID,
            inst_id: [RTC_INVALID_GEOMETRY_ID],
            spare: [0; SPARE],
        };
        // SAFETY: the scene is committed and live (see the Send/Sync argument); `context` and
        // `rh` are initialised, correctly laid out and aligned, and live for the call.
        unsafe { (self.api.intersect1)(self.scene, &mut context, &mut rh) };
        (rh.geom_id != RTC_INVALID_GEOMETRY_ID).then_some(EmbreeHit { t: rh.tfar, prim: rh.prim_id, ng: rh.ng })
    }

    /// The nearest hits of up to `N` (8 or 16) rays traced as one packet, in order; unused lanes
    /// (`rays.len() < N`) are masked off.
    #[inline]
    pub fn intersect_packet<const N: usize>(&self, rays: &[PacketRay], out: &mut [Option<EmbreeHit>]) {
        assert!(N == 8 || N == 16, "Embree packets are 8 or 16 rays");
        assert!(rays.len() <= N && out.len() >= rays.len(), "at most one packet");
        let mut context = context(RTC_INTERSECT_CONTEXT_FLAG_COHERENT);
        // Embree loads the mask as one vector: aligned like the packet.
        let mut valid = ValidMask([0 as c_int; N]);
        let mut p = RayHitN::<N> {
            org_x: [0.0; N],
            org_y: [0.0; N],
            org_z: [0.0; N],
            tnear: [0.0; N],
            dir_x: [0.0; N],
            dir_y: [0.0; N],
            dir_z: [1.0; N],
            time: [0.0; N],
            tfar: [0.0; N],
            mask: [u32::MAX; N],
            id: [0; N],
            flags: [0; N],
            ng_x: [0.0; N],
            ng_y: [0.0; N],
            ng_z: [0.0; N],
            u: [0.0; N],
            v: [0.0; N],
            prim_id: [RTC_INVALID_GEOMETRY_ID; N],
            geom_id: [RTC_INVALID_GEOMETRY_ID; N],
            inst_id: [RTC_INVALID_GEOMETRY_ID; N],
            spare: [0; SPARE],
        };
        for (k, r) in rays.iter().enumerate() {
            valid.0[k] = -1;
            [p.org_x[k], p.org_y[k], p.org_z[k]] = r.origin;
            [p.dir_x[k], p.dir_y[k], p.dir_z[k]] = r.dir;
            p.tnear[k] = r.t_min;
            p.tfar[k] = r.t_max;
        }
        // SAFETY: as in `intersect1`; `valid` holds N ints aligned to 64 bytes, `p` is the N-wide layout with the
        // alignment Embree requires (64 ≥ 32 for 8 rays, = 64 for 16), and N is 8 or 16
        // (asserted), so the pointer casts name the very type the called function takes.
        unsafe {
            match N {
                8 => (self.api.intersect8)(
                    valid.0.as_ptr(),
                    self.scene,
                    &mut context,
                    (&mut p as *mut RayHitN<N>).cast(),
                ),
                _ => (self.api.intersect16)(
                    valid.0.as_ptr(),
                    self.scene,
                    &mut context,
                    (&mut p as *mut RayHitN<N>).cast(),
                ),
            }
        }
        for (k, o) in out.iter_mut().enumerate().take(rays.len()) {
            *o = (p.geom_id[k] != RTC_INVALID_GEOMETRY_ID).then_some(EmbreeHit {
                t: p.tfar[k],
                prim: p.prim_id[k],
                ng: [p.ng_x[k], p.ng_y[k], p.ng_z[k]],
            });
        }
    }
}

/// What Embree reports of a hit: distance, triangle, and its unnormalised geometric normal `Ng`
/// (oriented as (v1 − v0) × (v2 − v0), checked by the tests below and in tests/tests/references.rs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmbreeHit {
    pub t: f32,
    pub prim: u32,
    pub ng: [f32; 3],
}

/// One lane of a packet.
#[derive(Clone, Copy, Debug)]
pub struct PacketRay {
    pub origin: [f32; 3],
    pub dir: [f32; 3],
    pub t_min: f32,
    pub t_max: f32,
}

/// `rtcInitIntersectContext` (an inline function in the header, so written out here).
fn context(flags: c_int) -> IntersectContext {
    IntersectContext { flags, filter: std::ptr::null(), inst_id: [RTC_INVALID_GEOMETRY_ID] }
}

impl Drop for CommittedScene {
    fn drop(&mut self) {
        // SAFETY: the scene (if made) and the device are live and released exactly once, scene
        // first; `&mut self` means no query is running. `state` is dropped after this, once no
        // callback can run any more.
        unsafe {
            if !self.scene.is_null() {
                (self.api.release_scene)(self.scene);
            }
            (self.api.release_device)(self.device);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The layouts Embree 3.13's headers define (sizes from `sizeof` of the C structs).
    #[test]
    fn layouts_match_the_headers() {
        use std::mem::{align_of, offset_of};
        assert_eq!(offset_of!(RayHit1, tfar), 32);
        assert_eq!(offset_of!(RayHit1, ng), 48);
        assert_eq!(offset_of!(RayHit1, prim_id), 68);
        assert_eq!(offset_of!(RayHit1, spare), 80, "sizeof(RTCRayHit) = 80");
        assert_eq!(align_of::<RayHit1>(), 16);
        assert_eq!(offset_of!(RayHitN<8>, tfar), 8 * 4 * 8);
        assert_eq!(offset_of!(RayHitN<8>, ng_x), 12 * 4 * 8, "sizeof(RTCRay8) = 384");
        assert_eq!(offset_of!(RayHitN<8>, spare), 20 * 4 * 8, "sizeof(RTCRayHit8) = 640");
        assert_eq!(offset_of!(RayHitN<16>, spare), 20 * 4 * 16, "sizeof(RTCRayHit16) = 1280");
        assert!(align_of::<RayHitN<16>>() >= 64);
        assert_eq!(offset_of!(IntersectContext, inst_id), 16);
    }

    /// Every wrapper against a mesh whose answers are known: a unit square at z = 2 split into two
    /// triangles, rays down +z through a grid of points on and off it, one at a time and in
    /// packets of 8 and 16 (with a partly filled packet), and the memory monitor's counts.
    #[test]
    fn wrappers_answer_like_the_geometry() {
        if let Err(why) = library() {
            assert_ne!(std::env::var(REQUIRE_ENV).as_deref(), Ok("1"), "{why}");
            eprintln!("skipped: {why}");
            return;
        }
        let square =
            [[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [1.0, 1.0, 2.0], [0.0, 0.0, 2.0], [1.0, 1.0, 2.0], [0.0, 1.0, 2.0]];
        for robust in [false, true] {
            let scene =
                CommittedScene::build(&square, SceneOptions { robust, quality: 1, threads: 1 }).expect("builds");
            assert!(scene.buffer_bytes >= 6 * 12 + 2 * 12, "buffers counted: {}", scene.buffer_bytes);
            assert!(scene.total_bytes > scene.buffer_bytes, "a BVH beyond the buffers: {}", scene.total_bytes);
            let mut rays = Vec::new();
            let mut expected = Vec::new();
            for i in 0..23 {
                let (x, y) = (-0.3 + 0.07 * i as f32, 0.05 + 0.041 * i as f32);
                rays.push(PacketRay { origin: [x, y, 0.0], dir: [0.0, 0.0, 1.0], t_min: 0.0, t_max: f32::INFINITY });
                let inside = (0.0..=1.0).contains(&x) && (0.0..=1.0).contains(&y);
                // Triangle 0 is below the diagonal (y < x), triangle 1 above it.
                expected.push(inside.then_some((2.0, u32::from(y > x))));
            }
            // A span that ends before the square, and one that starts after it: misses.
            rays.push(PacketRay { origin: [0.5, 0.2, 0.0], dir: [0.0, 0.0, 1.0], t_min: 0.0, t_max: 1.5 });
            expected.push(None);
            rays.push(PacketRay { origin: [0.5, 0.2, 0.0], dir: [0.0, 0.0, 1.0], t_min: 2.5, t_max: f32::INFINITY });
            expected.push(None);
            let single: Vec<_> = rays
                .iter()
                .map(|r| {
                    scene.intersect1(r.origin, r.dir, r.t_min, r.t_max).map(|h| {
                        // Both triangles lie in z = 2, wound counter-clockwise seen from +z:
                        // (v1 − v0) × (v2 − v0) points to +z, and so does Embree's Ng.
                        assert!(h.ng[0] == 0.0 && h.ng[1] == 0.0 && h.ng[2] > 0.0, "Ng {:?}", h.ng);
                        (h.t, h.prim)
                    })
                })
                .collect();
            assert_eq!(single, expected, "rtcIntersect1, robust {robust}");
            for width in [8, 16] {
                let mut packed = vec![None; rays.len()];
                for (chunk, out) in rays.chunks(width).zip(packed.chunks_mut(width)) {
                    let mut lanes = [None; 16];
                    match width {
                        8 => scene.intersect_packet::<8>(chunk, &mut lanes),
                        _ => scene.intersect_packet::<16>(chunk, &mut lanes),
                    }
                    for (o, lane) in out.iter_mut().zip(&lanes) {
                        *o = lane.map(|h| (h.t, h.prim));
                    }
                }
                assert_eq!(packed, expected, "rtcIntersect{width}, robust {robust}");
            }
        }
    }

    /// An empty scene commits and misses.
    #[test]
    fn an_empty_scene_misses() {
        if library().is_err() {
            return;
        }
        let scene = CommittedScene::build(&[], SceneOptions { robust: false, quality: 1, threads: 1 }).expect("builds");
        assert!(scene.intersect1([0.0; 3], [0.0, 0.0, 1.0], 0.0, f32::INFINITY).is_none());
    }
}
