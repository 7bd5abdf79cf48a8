//! The CPU anchor of `bench lbvh` (cargo feature `embree`): Intel Embree 3 (Debian's
//! `libembree-dev`, through the `embree` crate's raw bindings) building and tracing
//! the same triangles and rays on this machine's CPU threads, so that a run shows
//! "this device against the best CPU tracer" as ratios.
//!
//! Builds: `LOW` quality with the dynamic-scene flag (Embree's Morton builder, the
//! LBVH family; TOOLCHAIN.md: with the geometry's quality left at `MEDIUM` a dynamic
//! scene silently takes the binned-SAH builder) and `MEDIUM` (its default binned SAH).
//! Only `rtcCommitScene` is timed. Traversal: `rtcIntersect1` per ray, the rays split
//! into one contiguous chunk per thread.

use super::anchor::{AnchorRuns, AnchorSet, QualityRuns};
use crate::error::{Error, Result};
use crate::gpu_types::{GpuVertex, Hit, Ray};
use crate::report::Stat;
use crate::shader_defines::BVH_INVALID;
use embree::sys::*;
use serde::Serialize;
use std::ffi::CString;

/// An Embree build quality.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Quality {
    /// The Morton builder (with `RTC_SCENE_FLAG_DYNAMIC`).
    Low,
    /// The default binned-SAH builder.
    Medium,
}

impl Quality {
    pub const ALL: [Quality; 2] = [Quality::Low, Quality::Medium];

    pub fn name(self) -> &'static str {
        match self {
            Quality::Low => "low",
            Quality::Medium => "medium",
        }
    }
}

/// An Embree device limited to `threads` threads.
pub struct Anchor {
    device: RTCDevice,
    pub threads: usize,
}

// Embree devices and committed scenes may be used from any thread (Embree's API
// documentation: ray queries on a committed scene are thread safe).
// SAFETY: see above; the device handle is freed once, on drop.
unsafe impl Send for Anchor {}
// SAFETY: as for `Send`: Embree's device calls may come from any thread.
unsafe impl Sync for Anchor {}

impl Anchor {
    /// A device with as many threads as this machine runs at once (the GPU bench's CPU
    /// driver gets the same cores).
    pub fn new() -> Result<Self> {
        let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
        let config = CString::new(format!("threads={threads}")).expect("no NUL");
        // SAFETY: a NUL-terminated configuration string that outlives the call.
        let device = unsafe { rtcNewDevice(config.as_ptr()) };
        if device.is_null() {
            return Err(Error::Bvh("Embree: rtcNewDevice failed".into()));
        }
        Ok(Self { device, threads })
    }

    fn check(&self, what: &str) -> Result<()> {
        // SAFETY: the device is live (freed only on drop).
        let e = unsafe { rtcGetDeviceError(self.device) };
        if e == RTCError::NONE {
            Ok(())
        } else {
            Err(Error::Bvh(format!("Embree: {what}: {e:?}")))
        }
    }

    /// Builds a scene of the triangles at `quality`; returns it and the milliseconds
    /// `rtcCommitScene` took.
    pub fn build(&self, vertices: &[GpuVertex], indices: &[u32], quality: Quality) -> Result<(Scene<'_>, f64)> {
        let tris = indices.len() / 3;
        // SAFETY: the device is live; the geometry buffers Embree returns are checked
        // for null and written within the sizes asked for (3 floats a vertex, 3 indices a
        // triangle); the scene keeps the geometry and borrows the anchor.
        unsafe {
            let geom = rtcNewGeometry(self.device, RTCGeometryType::TRIANGLE);
            let vb = rtcSetNewGeometryBuffer(geom, RTCBufferType::VERTEX, 0, RTCFormat::FLOAT3, 12, vertices.len())
                as *mut f32;
            let ib = rtcSetNewGeometryBuffer(geom, RTCBufferType::INDEX, 0, RTCFormat::UINT3, 12, tris) as *mut u32;
            if vb.is_null() || ib.is_null() {
                rtcReleaseGeometry(geom);
                self.check("geometry buffers")?;
                return Err(Error::Bvh("Embree: no geometry buffers".into()));
            }
            let vs = std::slice::from_raw_parts_mut(vb, vertices.len() * 3);
            for (k, v) in vertices.iter().enumerate() {
                vs[3 * k..3 * k + 3].copy_from_slice(&v.position);
            }
            std::slice::from_raw_parts_mut(ib, tris * 3).copy_from_slice(&indices[..tris * 3]);
            let q = match quality {
                Quality::Low => RTCBuildQuality::LOW,
                Quality::Medium => RTCBuildQuality::MEDIUM,
            };
            rtcSetGeometryBuildQuality(geom, q);
            rtcCommitGeometry(geom);
            let scene = rtcNewScene(self.device);
            rtcAttachGeometry(scene, geom);
            rtcReleaseGeometry(geom); // the scene holds it
            rtcSetSceneBuildQuality(scene, q);
            if quality == Quality::Low {
                rtcSetSceneFlags(scene, RTCSceneFlags(1)); // RTC_SCENE_FLAG_DYNAMIC
            }
            let t0 = std::time::Instant::now();
            rtcCommitScene(scene);
            let ms = t0.elapsed().as_secs_f64() * 1e3;
            let built = Scene { scene, anchor: self };
            self.check("rtcCommitScene")?;
            Ok((built, ms))
        }
    }
}

impl Drop for Anchor {
    fn drop(&mut self) {
        // SAFETY: the device's one release; every scene borrowing it is gone.
        unsafe { rtcReleaseDevice(self.device) };
    }
}

/// A committed Embree scene.
pub struct Scene<'a> {
    scene: RTCScene,
    anchor: &'a Anchor,
}

// SAFETY: a committed scene's queries are thread safe (as for `Anchor`); it is
// released once, on drop.
unsafe impl Send for Scene<'_> {}
// SAFETY: as for `Send`: queries on a committed scene may run side by side.
unsafe impl Sync for Scene<'_> {}

impl Scene<'_> {
    /// Closest hits of `rays` with `rtcIntersect1` on the anchor's threads, in
    /// Speculum's `Hit` form (a miss: `t = tmax`, `BVH_INVALID`), and the wall-clock
    /// milliseconds.
    pub fn trace(&self, rays: &[Ray], coherent: bool) -> (Vec<Hit>, f64) {
        let mut hits = vec![Hit::default(); rays.len()];
        let chunk = rays.len().div_ceil(self.anchor.threads).max(1);
        let flags = if coherent {
            RTCIntersectContextFlags::COHERENT
        } else {
            RTCIntersectContextFlags::INCOHERENT
        };
        let t0 = std::time::Instant::now();
        std::thread::scope(|s| {
            for (rs, hs) in rays.chunks(chunk).zip(hits.chunks_mut(chunk)) {
                s.spawn(move || {
                    let mut ctx = RTCIntersectContext {
                        flags,
                        filter: None,
                        instID: [u32::MAX],
                    };
                    for (r, h) in rs.iter().zip(hs.iter_mut()) {
                        *h = self.intersect(&mut ctx, r);
                    }
                });
            }
        });
        (hits, t0.elapsed().as_secs_f64() * 1e3)
    }

    fn intersect(&self, ctx: &mut RTCIntersectContext, r: &Ray) -> Hit {
        let mut rh = RTCRayHit {
            ray: RTCRay {
                org_x: r.origin[0],
                org_y: r.origin[1],
                org_z: r.origin[2],
                tnear: r.tmin,
                dir_x: r.dir[0],
                dir_y: r.dir[1],
                dir_z: r.dir[2],
                time: 0.0,
                tfar: r.tmax,
                mask: u32::MAX,
                id: 0,
                flags: 0,
            },
            hit: RTCHit {
                Ng_x: 0.0,
                Ng_y: 0.0,
                Ng_z: 0.0,
                u: 0.0,
                v: 0.0,
                primID: u32::MAX,
                geomID: u32::MAX,
                instID: [u32::MAX],
            },
        };
        // SAFETY: a committed, live scene; `ctx` and `rh` are initialised locals.
        unsafe { rtcIntersect1(self.scene, ctx, &mut rh) };
        if rh.hit.geomID == u32::MAX {
            Hit {
                t: r.tmax,
                prim: BVH_INVALID,
                u: 0.0,
                v: 0.0,
            }
        } else {
            Hit {
                t: rh.ray.tfar,
                prim: rh.hit.primID,
                u: rh.hit.u,
                v: rh.hit.v,
            }
        }
    }
}

impl Drop for Scene<'_> {
    fn drop(&mut self) {
        // SAFETY: the scene's one release.
        unsafe { rtcReleaseScene(self.scene) };
    }
}

/// Embree LOW and MEDIUM on case `case`: each built `repeats` times after a warm-up,
/// each of `sets` (coherent, incoherent, the file's; `None` where absent) traced
/// `repeats` times after a warm-up; `AnchorRuns::report` compares them with each
/// builder's and layout's.
pub fn anchor_runs(
    case: &str,
    (vertices, indices): (&[GpuVertex], &[u32]),
    sets: &[Option<AnchorSet<'_>>; 3],
    repeats: u32,
) -> Result<AnchorRuns> {
    let anchor = Anchor::new()?;
    let mut qualities = Vec::new();
    for quality in Quality::ALL {
        let (scene, build_ms) = repeated(repeats, || anchor.build(vertices, indices, quality))?;
        let mut traced = Vec::new();
        for set in sets {
            traced.push(match *set {
                Some((rays, _, _, coherent)) => Some(repeated(repeats, || Ok(scene.trace(rays, coherent)))?),
                None => None,
            });
        }
        qualities.push(QualityRuns {
            quality: quality.name(),
            threads: anchor.threads as u32,
            build_ms,
            sets: traced.try_into().expect("three sets"),
        });
    }
    let counts = sets.each_ref().map(|s| s.as_ref().map(|s| s.0.len()));
    Ok(AnchorRuns {
        case: (case.to_string(), counts),
        qualities,
    })
}

/// `run` once to warm up, then `repeats` times timed: the last run's output and the
/// statistic of the timed runs' milliseconds.
fn repeated<T>(repeats: u32, mut run: impl FnMut() -> Result<(T, f64)>) -> Result<(T, Stat)> {
    let (mut out, _) = run()?;
    let mut times = Vec::new();
    for _ in 0..repeats {
        let (o, ms) = run()?;
        times.push(ms);
        out = o;
    }
    Ok((out, Stat::of(&times).expect("repeats > 0")))
}
