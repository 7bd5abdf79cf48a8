//! The static scene's tree, built once at load. With `static_ploc`, PLOC's, unless the
//! LBVH's tree of the same triangles walks this device's rays faster: both are built,
//! the same rays traced through each in alternation, and the faster kept. The rays are
//! what a frame traces: the scene camera's view, where it hits, starts a reflection
//! ray (on a reflective material) and a shadow ray towards the sun (any hit); rays
//! from the scene's surfaces in random directions make up the reflections where the
//! view sees few reflectors. A PLOC tree has walked faster on lavapipe on every
//! built-in scene, and 4x slower than the LBVH's on an NVIDIA H200 on a scanned statue
//! (docs/lbvh.md); measuring on the device at hand is what keeps it from ever walking
//! slower. Both trees find the same hits (the closest, equal distances to the smaller
//! id), so the choice moves time, never pixels.

use crate::error::Result;
use crate::gpu_types::{GpuVertex, Hit, Ray};
use crate::passes::rt_trace::{TracePass, NAME};
use crate::scene::{Camera, Scene};
use crate::settings::{Settings, WalkLayout};
use crate::shader_defines::{BVH_INVALID, HIT_DYNAMIC};
use crate::tracers::lbvh::{Bvh, BvhKind, CompactNodes, Geometry, LbvhBuilder, MortonBits, StaticLayout, COMPACT};
use crate::tracers::{Lbvh, TraceScene};
use crate::vk::{remeasure, Context};
use ash::vk;
use glam::Vec3;
use rand::{Rng, SeedableRng};
use serde::Serialize;
use std::sync::Arc;

/// Rays each tree walks per timed round: on a GPU the frame's pixels, as a frame traces
/// them, within `RAYS_GPU` (an H200 holds 270,336 invocations at once: fewer rays time
/// one wave's slowest walks, not the walk's throughput) and `RAYS_GPU_MAX` (eight such
/// waves); on a CPU device (lavapipe walks 0.3-30 Mrays/s) few, so a load stays short.
const RAYS_GPU: u32 = 262_144;
const RAYS_GPU_MAX: u32 = 2_097_152;
const RAYS_CPU: u32 = 16_384;
/// Timed rounds of each tree, the two alternating, after one untimed round each (a
/// round whose timestamps fail their self-check is measured again: `vk::remeasure`).
const ROUNDS: usize = 3;

/// How the static walk reads the static scene's BVH as it is built (`fastest`: binary
/// first, then `choose_layout`).
pub fn layout(settings: &Settings) -> StaticLayout {
    match settings.static_layout {
        WalkLayout::Binary | WalkLayout::Fastest => StaticLayout::Binary,
        WalkLayout::Wide => StaticLayout::Wide,
        WalkLayout::Wide8 => StaticLayout::Wide8,
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
    /// GPU milliseconds of the rays through each tree (`rt.trace`: the reflection
    /// rays' and the shadow rays' times, added), medians of the timed rounds.
    pub ploc_ms: f64,
    pub lbvh_ms: f64,
    /// Rays a round, reflection and shadow rays together (`ChoiceRays`).
    pub rays: u32,
}

impl StaticTreeChoice {
    /// One line of text: the tree kept and both prices.
    pub fn summary(&self) -> String {
        format!(
            "{} kept (PLOC {:.3} ms, LBVH {:.3} ms for {} reflection and shadow rays)",
            self.kept, self.ploc_ms, self.lbvh_ms, self.rays
        )
    }
}

/// What the measured choice of the static walk's nodes found (`static_layout =
/// fastest`): the layout kept and the same rays' GPU milliseconds through each
/// (`rt.trace`, reflection and shadow rays added, medians of the timed rounds; `None`
/// for a layout whose walk of the tree would not fit its stack, never made).
#[derive(Clone, Debug, Serialize)]
pub struct StaticLayoutChoice {
    pub kept: &'static str,
    pub binary_ms: Option<f64>,
    pub wide_ms: Option<f64>,
    pub wide8_ms: Option<f64>,
    /// Rays a round, reflection and shadow rays together (`ChoiceRays`).
    pub rays: u32,
}

impl StaticLayoutChoice {
    /// One line of text: the layout kept and each one's price.
    pub fn summary(&self) -> String {
        let ms = |m: Option<f64>| m.map_or("too deep".into(), |m| format!("{m:.3} ms"));
        format!(
            "{} nodes kept (binary {}, wide {}, wide8 {} for {} reflection and shadow rays)",
            self.kept,
            ms(self.binary_ms),
            ms(self.wide_ms),
            ms(self.wide8_ms),
            self.rays
        )
    }
}

/// Rays for the choice on a device of `device_type`, for frames of `pixels`.
pub fn ray_count(device_type: vk::PhysicalDeviceType, pixels: u64) -> u32 {
    if device_type == vk::PhysicalDeviceType::CPU {
        RAYS_CPU
    } else {
        pixels.clamp(RAYS_GPU as u64, RAYS_GPU_MAX as u64) as u32
    }
}

/// The corners of triangle `t` of `vertices` and `indices` (the renderer does not
/// call the CPU references, whose `cpu_ref::lbvh::triangle` is the same).
fn corners(vertices: &[GpuVertex], indices: &[u32], t: usize) -> [Vec3; 3] {
    [0, 1, 2].map(|k| Vec3::from(vertices[indices[3 * t + k] as usize].position))
}

/// `count` rays from points on the triangles of `vertices` and `indices` (each
/// triangle drawn by its area, a point uniform on it), less `origin` (the render
/// origin: the GPU's copy of the scene is relative to it), each in a direction uniform
/// over the hemisphere on a random side of its triangle; tmin a 1e-4 of the scene's
/// diagonal, so a ray does not stop at its own triangle. Reproducible by `seed`. None
/// for a scene without area.
pub fn surface_rays(vertices: &[GpuVertex], indices: &[u32], origin: Vec3, count: u32, seed: u64) -> Vec<Ray> {
    let tris = indices.len() / 3;
    let mut areas = Vec::with_capacity(tris);
    let (mut lo, mut hi, mut total) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN), 0.0f64);
    for t in 0..tris {
        let [a, b, c] = corners(vertices, indices, t);
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
            let [a, b, c] = corners(vertices, indices, t);
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

/// Rays from the camera through the pixel centres of an image of about `count` pixels
/// and `aspect` (width over height), less `origin`, their directions of unit length,
/// in 8x8 tiles row by row as a frame's kernels take neighbouring pixels together (a
/// subgroup of random pixels diverges, and then every tree walks alike slowly).
pub fn view_rays(camera: &Camera, aspect: f32, origin: Vec3, count: u32) -> Vec<Ray> {
    let forward = (camera.target - camera.position).normalize_or_zero();
    let right = forward.cross(camera.up).normalize_or_zero();
    let up = right.cross(forward);
    let tan = (0.5 * camera.fov_y_deg.to_radians()).tan();
    let h = ((count as f32 / aspect).sqrt() as u32).max(1);
    let w = (count / h).max(1);
    let (tiles_x, tiles_y) = (w.div_ceil(8), h.div_ceil(8));
    let mut rays = Vec::with_capacity((w * h) as usize);
    for tile in 0..tiles_x * tiles_y {
        let (tx, ty) = (tile % tiles_x, tile / tiles_x);
        for k in 0..64 {
            let (px, py) = (8 * tx + k % 8, 8 * ty + k / 8);
            if px >= w || py >= h {
                continue;
            }
            let x = 2.0 * (px as f32 + 0.5) / w as f32 - 1.0;
            let y = 1.0 - 2.0 * (py as f32 + 0.5) / h as f32;
            let d = (forward + right * (x * tan * aspect) + up * (y * tan)).normalize_or_zero();
            rays.push(Ray {
                origin: (camera.position - origin).to_array(),
                tmin: camera.near,
                dir: d.to_array(),
                tmax: camera.far,
            });
        }
    }
    rays
}

/// The rays the choice of the static tree times, as a frame traces them: reflection
/// rays (closest hit) and shadow rays (any hit).
#[derive(Clone, Debug, Default)]
pub struct ChoiceRays {
    pub reflect: Vec<Ray>,
    pub shadow: Vec<Ray>,
}

impl ChoiceRays {
    /// Rays of both kinds.
    pub fn len(&self) -> usize {
        self.reflect.len() + self.shadow.len()
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// What the view `rays` (unit directions) seen against their `hits` on the static
/// triangles of the scene (ids in index order) start, from each hit point with tmin
/// `tmin`: the mirror reflection where the triangle's material reflects more than
/// `reflective_min`, and a shadow ray towards the sun `to_sun` where the side facing
/// the viewer faces it: the rays a frame traces. Misses start none.
pub fn frame_rays_from(
    (rays, hits): (&[Ray], &[Hit]),
    scene: &Scene,
    reflective_min: f32,
    to_sun: Vec3,
    tmin: f32,
) -> ChoiceRays {
    let mut out = ChoiceRays::default();
    for (r, h) in rays.iter().zip(hits) {
        if h.prim == BVH_INVALID || h.prim & HIT_DYNAMIC != 0 || h.t.is_nan() || h.t <= 0.0 {
            continue;
        }
        let t = h.prim as usize;
        let [a, b, c] = corners(&scene.vertices, &scene.indices, t);
        let n = (b - a).cross(c - a).normalize_or_zero();
        if n == Vec3::ZERO {
            continue;
        }
        let d = Vec3::from(r.dir);
        let p = (Vec3::from(r.origin) + d * h.t).to_array();
        let ray = |dir: Vec3| Ray {
            origin: p,
            tmin,
            dir: dir.to_array(),
            tmax: f32::MAX,
        };
        let material = scene.vertices[scene.indices[3 * t] as usize].material as usize;
        if scene
            .materials
            .get(material)
            .is_some_and(|m| m.reflectivity > reflective_min)
        {
            out.reflect.push(ray(d.reflect(n)));
        }
        let facing = if n.dot(d) < 0.0 { n } else { -n };
        if facing.dot(to_sun) > 0.0 {
            out.shadow.push(ray(to_sun));
        }
    }
    out
}

/// The rays the choice of the static tree times (`choose`): `ray_count` rays of the
/// scene camera's view traced through `tree` over `geom` (any tree: both find the same
/// hits), and the reflection and shadow rays they start (`frame_rays_from`); where the
/// view starts fewer than half the count of reflection rays, rays from the surfaces
/// (`surface_rays`) make them up. Computed once, at load: the static scene does not
/// change.
pub fn frame_rays(
    ctx: &Arc<Context>,
    tracer: &TracePass<Lbvh>,
    geom: Geometry<'_>,
    tree: &Bvh,
    scene: &Scene,
    settings: &Settings,
    origin: Vec3,
) -> Result<ChoiceRays> {
    let count = ray_count(ctx.device_type, settings.width as u64 * settings.height as u64);
    let aspect = settings.width as f32 / settings.height as f32;
    let view = view_rays(&scene.camera, aspect, origin, count);
    let scene_tree = TraceScene::of_static(tree, geom);
    let (hits, _) = tracer.trace(&view, scene_tree, false)?;
    let (lo, hi) = scene.bounds();
    let tmin = 1e-4 * (hi - lo).length();
    let mut rays = frame_rays_from(
        (&view, &hits),
        scene,
        settings.reflective_min,
        scene.light.direction,
        tmin,
    );
    let short = (count / 2).saturating_sub(rays.reflect.len() as u32);
    rays.reflect
        .extend(surface_rays(&scene.vertices, &scene.indices, origin, short, 2));
    Ok(rays)
}

/// GPU milliseconds per stage of a build, by timer scope.
pub type Scopes = Vec<(&'static str, f64)>;

/// A build's GPU milliseconds per stage and the kind built (`LbvhBuilder::build_now`).
pub type Stages = (Scopes, BvhKind);

/// The static tree kept, its build's GPU milliseconds per stage, and the choices of
/// its tree and its walk's nodes.
pub type Kept = (Bvh, Scopes, Option<StaticTreeChoice>, Option<StaticLayoutChoice>);

/// Builds the static scene's BVH over `geom` into `bvh` (`layout(settings)`) with the
/// settings' builder, then `choose`. Returns the tree kept, its build's GPU
/// milliseconds per stage, and the choice.
pub fn build(
    ctx: &Arc<Context>,
    builder: &LbvhBuilder,
    geom: Geometry<'_>,
    bvh: Bvh,
    settings: &Settings,
    rays: &ChoiceRays,
) -> Result<Kept> {
    let built = builder.build_now(geom, &bvh, kind(settings))?;
    let tracer = TracePass::<Lbvh>::new(ctx)?;
    choose(ctx, (builder, &tracer), geom, (bvh, built), settings, rays)
}

/// After `bvh` was built over `geom` (`built`: its stages' GPU milliseconds and the
/// kind built): the tree (`choose_tree`), then its walk's nodes (`choose_layout`).
pub fn choose(
    ctx: &Arc<Context>,
    kernels: (&LbvhBuilder, &TracePass<Lbvh>),
    geom: Geometry<'_>,
    built: (Bvh, Stages),
    settings: &Settings,
    rays: &ChoiceRays,
) -> Result<Kept> {
    let (bvh, scopes, tree) = choose_tree(ctx, kernels, geom, built, settings, rays)?;
    let (bvh, scopes, layout) = choose_layout(ctx, kernels, geom, (bvh, scopes), settings, rays)?;
    Ok((bvh, scopes, tree, layout))
}

/// With PLOC built, also builds the LBVH's tree and keeps the one that walks `rays`
/// faster through `tracer` (see the module). Returns the tree kept, its build's GPU
/// milliseconds per stage, and the choice (`None` when the LBVH was asked for, when the
/// PLOC tree was too deep for the walk and the LBVH was built instead, or without
/// rays).
fn choose_tree(
    ctx: &Arc<Context>,
    (builder, tracer): (&LbvhBuilder, &TracePass<Lbvh>),
    geom: Geometry<'_>,
    (bvh, (scopes, built)): (Bvh, Stages),
    settings: &Settings,
    rays: &ChoiceRays,
) -> Result<(Bvh, Scopes, Option<StaticTreeChoice>)> {
    if built != BvhKind::Ploc || rays.is_empty() {
        return Ok((bvh, scopes, None));
    }
    let lbvh = Bvh::new_static_in(ctx, geom.tri_count, MortonBits::Bits30, layout(settings))?;
    let (lbvh_scopes, _) = builder.build_now(geom, &lbvh, BvhKind::Lbvh)?;
    let time = |tree: &Bvh| ray_ms(tracer, geom, tree, rays);
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

/// GPU milliseconds of `rays` through `tree` over `geom` (`rt.trace`: the reflection
/// rays' closest hits and the shadow rays' any hits, added; each remeasured until its
/// timestamps check).
fn ray_ms(tracer: &TracePass<Lbvh>, geom: Geometry<'_>, tree: &Bvh, rays: &ChoiceRays) -> Result<f64> {
    let scene = TraceScene::of_static(tree, geom);
    let mut total = 0.0;
    for (set, any_hit) in [(&rays.reflect, false), (&rays.shadow, true)] {
        let (_, readout, _) = remeasure(|| tracer.trace(set, scene, any_hit))?;
        total += readout.get(NAME).unwrap_or(0.0);
    }
    Ok(total)
}

/// With `static_layout = fastest`, after the static tree was kept (`choose`, binary):
/// its walk's nodes made in every other layout whose walk of the tree fits the stack
/// (`StaticLayout::fits`: a deep PLOC tree may fit the binary walk's and not a wide
/// one's), the same `rays` timed through each in turn (`ROUNDS` after an untimed one),
/// and the fastest kept, its `lbvh.compact` time in the build's stages. Returns the tree with the nodes kept and the choice
/// (`None` for a fixed layout, or without rays).
pub fn choose_layout(
    ctx: &Arc<Context>,
    (builder, tracer): (&LbvhBuilder, &TracePass<Lbvh>),
    geom: Geometry<'_>,
    (mut bvh, mut scopes): (Bvh, Scopes),
    settings: &Settings,
    rays: &ChoiceRays,
) -> Result<(Bvh, Scopes, Option<StaticLayoutChoice>)> {
    if settings.static_layout != WalkLayout::Fastest || rays.is_empty() {
        return Ok((bvh, scopes, None));
    }
    let first = bvh.compact.as_ref().map(|c| c.layout);
    let compact_ms = |s: &[(&'static str, f64)]| s.iter().find(|(n, _)| *n == COMPACT).map_or(0.0, |(_, ms)| *ms);
    let nodes: Vec<crate::gpu_types::TraversalNode> = bytemuck::pod_collect_to_vec(&bvh.tnodes.read()?);
    // Each layout's nodes (the first's are in the tree) and its compaction's time.
    let mut made: Vec<(StaticLayout, Option<CompactNodes>, f64)> = Vec::new();
    for layout in StaticLayout::ALL {
        if Some(layout) == first {
            made.push((layout, None, compact_ms(&scopes)));
            continue;
        }
        if !layout.fits(&nodes) {
            continue;
        }
        let held = bvh.swap_compact(CompactNodes::new(ctx, geom.tri_count, layout)?);
        let ms = compact_ms(&builder.compact_now(&bvh)?);
        made.push((layout, Some(bvh.swap_compact(held)), ms));
    }
    let mut ms = vec![Vec::new(); made.len()];
    for round in 0..=ROUNDS {
        for (k, (_, nodes, _)) in made.iter_mut().enumerate() {
            // Each layout's nodes in the tree in turn, then back in their place.
            let held = nodes.take().map(|n| bvh.swap_compact(n));
            let t = ray_ms(tracer, geom, &bvh, rays)?;
            *nodes = held.map(|h| bvh.swap_compact(h));
            if round > 0 {
                ms[k].push(t);
            }
        }
    }
    let medians: Vec<f64> = ms.iter_mut().map(|m| median(m)).collect();
    let at = |l: StaticLayout| made.iter().position(|m| m.0 == l).map(|k| medians[k]);
    let (binary_ms, wide_ms, wide8_ms) = (
        at(StaticLayout::Binary),
        at(StaticLayout::Wide),
        at(StaticLayout::Wide8),
    );
    let best = (0..made.len())
        .min_by(|&a, &b| medians[a].total_cmp(&medians[b]))
        .expect("layouts to choose from");
    let (layout, nodes, compact) = made.swap_remove(best);
    if let Some(nodes) = nodes {
        bvh.swap_compact(nodes);
    }
    for (name, t) in scopes.iter_mut() {
        if *name == COMPACT {
            *t = compact;
        }
    }
    let choice = StaticLayoutChoice {
        kept: layout.name(),
        binary_ms,
        wide_ms,
        wide8_ms,
        rays: rays.len() as u32,
    };
    Ok((bvh, scopes, Some(choice)))
}

/// The median of `v` (not empty; NaN sorts last).
fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A GPU times the frame's pixels (at least a wave's worth, at most eight); a CPU
    /// device few, whatever the frame.
    #[test]
    fn the_choice_traces_a_frame_of_rays_on_a_gpu() {
        let gpu = vk::PhysicalDeviceType::DISCRETE_GPU;
        assert_eq!(ray_count(gpu, 1920 * 1080), 2_073_600);
        assert_eq!(ray_count(gpu, 320 * 180), RAYS_GPU);
        assert_eq!(ray_count(gpu, 3840 * 2160), RAYS_GPU_MAX);
        assert_eq!(ray_count(vk::PhysicalDeviceType::CPU, 1920 * 1080), RAYS_CPU);
    }

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

    /// The view's rays leave the camera through the whole image in 8x8 tiles; where
    /// they hit, a reflective floor starts a mirror reflection and, lit, a shadow ray
    /// towards the sun; a matte floor only the shadow ray; a floor seen from its unlit
    /// side, none; a miss, none.
    #[test]
    fn frame_rays_follow_the_view() {
        let camera = Camera {
            position: Vec3::new(0.0, 2.0, 0.0),
            target: Vec3::new(0.0, 0.0, -2.0),
            up: Vec3::Y,
            fov_y_deg: 60.0,
            near: 0.01,
            far: 100.0,
        };
        let view = view_rays(&camera, 2.0, Vec3::ZERO, 1000);
        assert!((900..=1000).contains(&view.len()), "{}", view.len());
        for r in &view {
            assert_eq!(r.origin, [0.0, 2.0, 0.0]);
            assert!((Vec3::from(r.dir).length() - 1.0).abs() < 1e-5);
        }
        // Neighbours in a tile: the first 8 rays are one row of pixels, left to right,
        // the next 8 the row below.
        assert!(view[..8].windows(2).all(|w| w[0].dir[0] < w[1].dir[0]));
        assert!((view[8].dir[0] - view[0].dir[0]).abs() < 0.01 && view[8].dir[1] < view[0].dir[1]);
        let mut scene = crate::scene::builtin::room().unwrap();
        let p = Vec3::new(0.3, 0.0, -2.0);
        let down = Ray {
            origin: [0.3, 2.0, -2.0],
            tmin: 0.0,
            dir: [0.0, -1.0, 0.0],
            tmax: f32::MAX,
        };
        // A floor triangle of the scene, its material made a mirror, then matte.
        let t = (0..scene.indices.len() / 3)
            .find(|&t| {
                let c = |k| Vec3::from(scene.vertices[scene.indices[3 * t + k] as usize].position);
                let n = (c(1) - c(0)).cross(c(2) - c(0));
                n.x == 0.0 && n.z == 0.0 && c(0).y.abs() < 1e-3
            })
            .expect("room has a floor at y = 0");
        let hit = Hit {
            t: 2.0,
            prim: t as u32,
            u: 0.2,
            v: 0.2,
        };
        let material = scene.vertices[scene.indices[3 * t] as usize].material as usize;
        let sun = Vec3::new(0.0, 1.0, 1.0).normalize();
        scene.materials[material].reflectivity = 0.5;
        let rays = frame_rays_from((&[down], &[hit]), &scene, 0.02, sun, 1e-3);
        assert_eq!((rays.reflect.len(), rays.shadow.len()), (1, 1));
        assert_eq!(rays.reflect[0].origin, p.to_array());
        assert!(Vec3::from(rays.reflect[0].dir).abs_diff_eq(Vec3::Y, 1e-6));
        assert_eq!((rays.shadow[0].dir, rays.shadow[0].tmin), (sun.to_array(), 1e-3));
        scene.materials[material].reflectivity = 0.0;
        let rays = frame_rays_from((&[down], &[hit]), &scene, 0.02, sun, 1e-3);
        assert_eq!((rays.reflect.len(), rays.shadow.len()), (0, 1));
        let rays = frame_rays_from((&[down], &[hit]), &scene, 0.02, -sun, 1e-3);
        assert!(rays.is_empty(), "the sun below the floor: no shadow ray");
        let miss = Hit {
            prim: BVH_INVALID,
            ..hit
        };
        assert!(frame_rays_from((&[down], &[miss]), &scene, 0.02, sun, 1e-3).is_empty());
    }

    #[test]
    fn the_median_is_the_middle_value() {
        assert_eq!(median(&mut [3.0, 1.0, 2.0]), 2.0);
        assert_eq!(median(&mut [5.0]), 5.0);
    }
}
