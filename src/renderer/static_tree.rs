//! The static scene's tree, built once at load. With `static_ploc`, PLOC's, unless the
//! LBVH's tree of the same triangles walks this device's rays faster: both are built,
//! the same rays (from the scene's surfaces, in random directions: what reflection and
//! shadow rays are) traced through each in alternation, and the faster kept. A PLOC
//! tree has walked faster on lavapipe in every scene measured but one, and 4x slower
//! than the LBVH's on an NVIDIA H200 on a scanned statue (docs/lbvh.md); measuring on
//! the device at hand is what keeps it from ever walking slower. Both trees find the
//! same hits (the closest, equal distances to the smaller id), so the choice moves
//! time, never pixels.

use crate::error::Result;
use crate::gpu_types::{GpuVertex, Ray};
use crate::passes::rt_trace::{TracePass, NAME};
use crate::settings::Settings;
use crate::tracers::lbvh::{Bvh, BvhKind, Geometry, LbvhBuilder, MortonBits, StaticLayout};
use crate::tracers::{Lbvh, TraceScene, Traceable};
use crate::vk::Context;
use ash::vk;
use glam::Vec3;
use rand::{Rng, SeedableRng};
use serde::Serialize;
use std::sync::Arc;

/// Rays each tree walks per timed round: on a GPU enough to fill it; on a CPU device
/// (lavapipe walks 0.3-30 Mrays/s) few, so a load stays short.
const RAYS_GPU: u32 = 262_144;
const RAYS_CPU: u32 = 16_384;
/// Timed rounds of each tree, the two alternating, after one untimed round each.
const ROUNDS: usize = 3;
/// Tries of a round whose timestamps fail their self-check.
const TRIES: usize = 3;

/// How the static walk reads the static scene's BVH.
pub fn layout(settings: &Settings) -> StaticLayout {
    if settings.static_wide {
        StaticLayout::Wide
    } else {
        StaticLayout::Binary
    }
}

/// The builder asked for the static scene's BVH.
pub fn kind(settings: &Settings) -> BvhKind {
    if settings.static_ploc {
        BvhKind::Ploc
    } else {
        BvhKind::Lbvh
    }
}

/// What the measured choice of the static tree found (`static_ploc`).
#[derive(Clone, Debug, Serialize)]
pub struct StaticTreeChoice {
    /// The tree kept: `ploc`, or `lbvh` where it walked the rays faster.
    pub kept: &'static str,
    /// GPU milliseconds of the rays through each tree (`rt.trace`), medians of the
    /// timed rounds.
    pub ploc_ms: f64,
    pub lbvh_ms: f64,
    /// Rays a round.
    pub rays: u32,
}

impl StaticTreeChoice {
    /// One line of text: the tree kept and both prices.
    pub fn summary(&self) -> String {
        format!(
            "{} kept (PLOC {:.3} ms, LBVH {:.3} ms for {} rays from the surfaces)",
            self.kept, self.ploc_ms, self.lbvh_ms, self.rays
        )
    }
}

/// Rays for the choice on a device of `device_type`.
pub fn ray_count(device_type: vk::PhysicalDeviceType) -> u32 {
    if device_type == vk::PhysicalDeviceType::CPU {
        RAYS_CPU
    } else {
        RAYS_GPU
    }
}

/// `count` rays from points on the triangles of `vertices` and `indices` (each
/// triangle drawn by its area, a point uniform on it), less `origin` (the render
/// origin: the GPU's copy of the scene is relative to it), each in a direction uniform
/// over the hemisphere on a random side of its triangle; tmin a 1e-4 of the scene's
/// diagonal, so a ray does not stop at its own triangle. Reproducible by `seed`. None
/// for a scene without area.
pub fn surface_rays(vertices: &[GpuVertex], indices: &[u32], origin: Vec3, count: u32, seed: u64) -> Vec<Ray> {
    let corner = |t: usize, k: usize| Vec3::from(vertices[indices[3 * t + k] as usize].position);
    let tris = indices.len() / 3;
    let mut areas = Vec::with_capacity(tris);
    let (mut lo, mut hi, mut total) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN), 0.0f64);
    for t in 0..tris {
        let (a, b, c) = (corner(t, 0), corner(t, 1), corner(t, 2));
        lo = lo.min(a.min(b).min(c));
        hi = hi.max(a.max(b).max(c));
        total += 0.5 * f64::from((b - a).cross(c - a).length());
        areas.push(total);
    }
    if total.is_nan() || total <= 0.0 {
        return Vec::new();
    }
    let tmin = 1e-4 * (hi - lo).length();
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            let at = rng.random_range(0.0..total);
            let t = areas.partition_point(|&s| s <= at).min(tris - 1);
            let (a, b, c) = (corner(t, 0), corner(t, 1), corner(t, 2));
            let (r1, r2): (f32, f32) = (rng.random(), rng.random());
            let s = r1.sqrt();
            let p = a * (1.0 - s) + b * (s * (1.0 - r2)) + c * (s * r2);
            let n = (b - a).cross(c - a).normalize_or_zero();
            // Uniform on the sphere, then turned into n's hemisphere, whose side is random.
            let z: f32 = rng.random_range(-1.0..1.0);
            let phi: f32 = rng.random_range(0.0..std::f32::consts::TAU);
            let rho = (1.0 - z * z).max(0.0).sqrt();
            let mut d = Vec3::new(rho * phi.cos(), rho * phi.sin(), z);
            let side = if rng.random::<bool>() { 1.0 } else { -1.0 };
            if d.dot(n) * side < 0.0 {
                d = -d;
            }
            Ray {
                origin: (p - origin).to_array(),
                tmin,
                dir: d.to_array(),
                tmax: f32::MAX,
            }
        })
        .collect()
}

/// Builds the static scene's BVH over `geom` into `bvh` (`layout(settings)`) with the
/// settings' builder; with PLOC, also the LBVH's tree, and keeps the one that walks
/// `rays` faster (see the module). Returns the tree kept, its build's GPU milliseconds
/// per stage, and the choice (`None` when the LBVH was asked for, when the PLOC tree
/// was too deep for the walk and the LBVH was built instead, or without rays).
#[allow(clippy::type_complexity)]
pub fn build(
    ctx: &Arc<Context>,
    builder: &LbvhBuilder,
    geom: Geometry<'_>,
    bvh: Bvh,
    settings: &Settings,
    rays: &[Ray],
) -> Result<(Bvh, Vec<(&'static str, f64)>, Option<StaticTreeChoice>)> {
    let (scopes, built) = builder.build_now(geom, &bvh, kind(settings))?;
    if built != BvhKind::Ploc || rays.is_empty() {
        return Ok((bvh, scopes, None));
    }
    let lbvh = Bvh::new_static_in(ctx, geom.tri_count, MortonBits::Bits30, layout(settings))?;
    let (lbvh_scopes, _) = builder.build_now(geom, &lbvh, BvhKind::Lbvh)?;
    let tracer = TracePass::<Lbvh>::new(ctx)?;
    let time = |tree: &Bvh| -> Result<f64> {
        let scene = TraceScene {
            static_bvh: Some(Traceable {
                bvh: tree,
                geometry: geom,
            }),
            dynamic_bvh: None,
        };
        let mut ms = f64::NAN;
        for _ in 0..TRIES {
            let (_, readout) = tracer.trace(rays, scene, false)?;
            ms = readout.get(NAME).unwrap_or(f64::NAN);
            if readout.problem.is_none() {
                break;
            }
        }
        Ok(ms)
    };
    let (mut ploc_ms, mut lbvh_ms) = (Vec::new(), Vec::new());
    for round in 0..=ROUNDS {
        let (p, l) = (time(&bvh)?, time(&lbvh)?);
        if round > 0 {
            ploc_ms.push(p);
            lbvh_ms.push(l);
        }
    }
    let (ploc_ms, lbvh_ms) = (median(&mut ploc_ms), median(&mut lbvh_ms));
    let lbvh_faster = lbvh_ms < ploc_ms;
    let choice = StaticTreeChoice {
        kept: if lbvh_faster { "lbvh" } else { "ploc" },
        ploc_ms,
        lbvh_ms,
        rays: rays.len() as u32,
    };
    Ok(if lbvh_faster {
        (lbvh, lbvh_scopes, Some(choice))
    } else {
        (bvh, scopes, Some(choice))
    })
}

/// The median of `v` (not empty; NaN sorts last).
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rays start on the triangles, less the origin, and point away from their
    /// triangle's plane (on either side); the same seed gives the same rays; a scene
    /// of zero area gives none.
    #[test]
    fn surface_rays_start_on_the_surfaces() {
        let v = |x: f32, y: f32, z: f32| GpuVertex {
            position: [x, y, z],
            ..Default::default()
        };
        // A floor (z = 0, area 8) and a small wall (x = 5, area 0.5).
        let vertices = vec![
            v(0.0, 0.0, 0.0),
            v(4.0, 0.0, 0.0),
            v(0.0, 4.0, 0.0),
            v(5.0, 0.0, 0.0),
            v(5.0, 1.0, 0.0),
            v(5.0, 0.0, 1.0),
        ];
        let indices = vec![0, 1, 2, 3, 4, 5];
        let origin = Vec3::new(1.0, 2.0, 3.0);
        let rays = surface_rays(&vertices, &indices, origin, 2000, 9);
        assert_eq!(rays.len(), 2000);
        let mut on_floor = 0;
        for r in &rays {
            let p = Vec3::from(r.origin) + origin;
            let d = Vec3::from(r.dir);
            assert!((d.length() - 1.0).abs() < 1e-4, "{d}");
            if p.z.abs() < 1e-5 {
                on_floor += 1;
                assert!(p.x >= -1e-5 && p.y >= -1e-5 && p.x + p.y <= 4.0 + 1e-4, "{p}");
                assert!(d.z.abs() > 0.0);
            } else {
                assert!(
                    (p.x - 5.0).abs() < 1e-5 && p.y >= -1e-5 && p.z >= -1e-5 && p.y + p.z <= 1.0 + 1e-4,
                    "{p}"
                );
            }
            assert!(r.tmin > 0.0 && r.tmax == f32::MAX);
        }
        // By area: 8 of 8.5 on the floor.
        assert!((1800..1960).contains(&on_floor), "{on_floor}");
        let ups = rays
            .iter()
            .filter(|r| r.dir[2] > 0.0 && (r.origin[2] + origin.z).abs() < 1e-5)
            .count();
        assert!(ups > on_floor / 3 && ups < 2 * on_floor / 3, "{ups} of {on_floor} up");
        assert_eq!(surface_rays(&vertices, &indices, origin, 50, 9)[..], rays[..50]);
        let flat = vec![v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(2.0, 0.0, 0.0)];
        assert!(surface_rays(&flat, &[0, 1, 2], Vec3::ZERO, 10, 1).is_empty());
    }

    #[test]
    fn the_median_is_the_middle_value() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [5.0]), 5.0);
    }
}
