//! `rt.trace` against the CPU: closest hits equal brute force (ids exactly, t within
//! 1e-5 relative), over one BVH and over static + dynamic together; any-hit agrees on
//! occlusion; a refit BVH traces like a fresh build.

use crate::common;

use glam::Vec3;
use rand::Rng;
use speculum::cpu_ref::lbvh::triangle;
use speculum::cpu_ref::trace::{brute_force, intersect, CpuBvh};
use speculum::gpu_types::{GpuVertex, Hit, Ray};
use speculum::passes::rt_trace::{Refill, TracePass};
use speculum::scene::soup::{default_size, random_soup};
use speculum::shader_defines::{BVH_INVALID, BVH_LEAF_MAX, HIT_DYNAMIC};
use speculum::tracers::lbvh::{Bvh, Geometry, LbvhBuilder, MortonBits, StaticLayout, UploadedTriangles};
use speculum::tracers::{Lbvh, TraceScene, Traceable};
use speculum::vk::{Context, GpuTimer};
use std::sync::Arc;

struct Built {
    triangles: UploadedTriangles,
    bvh: Bvh,
}

impl Built {
    fn new(ctx: &Arc<Context>, b: &LbvhBuilder, v: &[GpuVertex], i: &[u32], bits: MortonBits) -> Self {
        Self::new_in(ctx, b, (v, i), bits, StaticLayout::Binary)
    }
    /// `new`, the static walk's nodes in `layout`.
    fn new_in(
        ctx: &Arc<Context>,
        b: &LbvhBuilder,
        (v, i): (&[GpuVertex], &[u32]),
        bits: MortonBits,
        layout: StaticLayout,
    ) -> Self {
        let triangles = UploadedTriangles::new(ctx, "t", v, i).unwrap();
        let bvh = Bvh::new_static_in(ctx, (i.len() / 3) as u32, bits, layout).unwrap();
        let built = Self { triangles, bvh };
        built.rebuild(ctx, b);
        built
    }
    fn geometry(&self) -> Geometry<'_> {
        self.triangles.geometry()
    }
    fn traceable(&self) -> Traceable<'_> {
        Traceable {
            bvh: &self.bvh,
            geometry: self.geometry(),
        }
    }
    /// The tree walked as the static BVH (its compact nodes, boxes rounded outward) and
    /// as the dynamic one (its exact 64-byte nodes), named.
    fn both_walks(&self) -> [(&'static str, TraceScene<'_>); 2] {
        [
            (
                "static (compact nodes)",
                TraceScene {
                    static_bvh: Some(self.traceable()),
                    dynamic_bvh: None,
                },
            ),
            (
                "dynamic (exact nodes)",
                TraceScene {
                    static_bvh: None,
                    dynamic_bvh: Some(self.traceable()),
                },
            ),
        ]
    }
    fn rebuild(&self, ctx: &Arc<Context>, b: &LbvhBuilder) {
        let mut timer = GpuTimer::new(ctx, 8).unwrap();
        ctx.one_shot(|cmd| {
            timer.reset(cmd);
            b.record_build(cmd, &mut timer, self.geometry(), &self.bvh);
            b.record_compact(cmd, &mut timer, &self.bvh);
        })
        .unwrap();
    }
}

/// Rays from random points around the soup: half aimed at random triangles (hits),
/// half in random directions (many misses).
pub(crate) fn random_rays(n: usize, v: &[GpuVertex], i: &[u32], scale: f32, seed: u64) -> Vec<Ray> {
    let mut rng = common::rng(seed);
    let tris = i.len() / 3;
    (0..n)
        .map(|k| {
            let o = Vec3::new(
                rng.random_range(-1.5..1.5),
                rng.random_range(-1.5..1.5),
                rng.random_range(-1.5..1.5),
            ) * scale;
            let d = if k % 2 == 0 {
                let t = triangle(v, i, rng.random_range(0..tris));
                let (a, b): (f32, f32) = (rng.random(), rng.random());
                let (a, b) = if a + b > 1.0 { (1.0 - a, 1.0 - b) } else { (a, b) };
                (t[0] + (t[1] - t[0]) * a + (t[2] - t[0]) * b) - o
            } else {
                Vec3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                )
            };
            Ray {
                origin: o.to_array(),
                tmin: 0.0,
                dir: d.to_array(),
                tmax: 1e30,
            }
        })
        .collect()
}

/// Compares GPU and CPU hits. Equal t between two triangles is a tie the two sides may
/// break differently only if their float results differ: such a pair passes when the
/// GPU's triangle really is hit at the CPU's t; ties are counted and must be rare.
fn compare(gpu: &[Hit], cpu: &[Hit], rays: &[Ray], tri_of: impl Fn(u32) -> [Vec3; 3]) -> usize {
    compare_within(gpu, cpu, rays, tri_of, (1e-5, 1e-4))
}

/// `compare` with t within `t_rel` relative and barycentrics within `bary` absolute.
pub(crate) fn compare_within(
    gpu: &[Hit],
    cpu: &[Hit],
    rays: &[Ray],
    tri_of: impl Fn(u32) -> [Vec3; 3],
    (t_rel, bary): (f32, f32),
) -> usize {
    let mut ties = 0;
    for (k, ((g, c), r)) in gpu.iter().zip(cpu).zip(rays).enumerate() {
        assert!(g.t >= 0.0, "ray {k}: traversal stack overflow");
        let close = |a: f32, b: f32| (a - b).abs() <= t_rel * a.abs().max(b.abs()).max(1.0);
        if g.prim == c.prim {
            assert!(close(g.t, c.t), "ray {k}: t {} vs {}", g.t, c.t);
            if g.prim != BVH_INVALID {
                assert!(
                    (g.u - c.u).abs() < bary && (g.v - c.v).abs() < bary,
                    "ray {k}: barycentrics"
                );
            }
        } else {
            assert!(
                g.prim != BVH_INVALID && c.prim != BVH_INVALID,
                "ray {k}: gpu {g:?} cpu {c:?}"
            );
            let t = intersect(r, &tri_of(g.prim)).map(|h| h.0);
            assert!(
                t.is_some_and(|t| close(t, c.t)) && close(g.t, c.t),
                "ray {k}: gpu {g:?} cpu {c:?}"
            );
            ties += 1;
        }
    }
    ties
}

/// 10,000+ random rays against a 3,000-triangle soup: every hit equals brute force, with
/// both key widths and both static layouts; the CPU SAH BVH (the benchmark's reference)
/// agrees with brute force.
#[test]
fn closest_hits_equal_brute_force() {
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let tracer = TracePass::<Lbvh>::new(&ctx).unwrap();
    let n = 3000;
    let (v, i) = random_soup(n, 1.0, default_size(n), 21);
    let rays = random_rays(12000, &v, &i, 1.0, 22);
    let cpu: Vec<Hit> = rays.iter().map(|r| brute_force(r, &v, &i)).collect();
    let hits = cpu.iter().filter(|h| h.prim != BVH_INVALID).count();
    assert!(hits > 6000 && hits < 11500, "a mix of hits and misses: {hits}");
    let sah = CpuBvh::build(&v, &i);
    let via_sah: Vec<Hit> = rays.iter().map(|r| sah.trace(r, &v, &i)).collect();
    assert_eq!(via_sah, cpu, "CPU SAH BVH traversal equals brute force");
    let cases = MortonBits::ALL
        .into_iter()
        .flat_map(|b| StaticLayout::ALL.map(|l| (b, l)));
    for (bits, layout) in cases {
        let built = Built::new_in(&ctx, &b, (&v, &i), bits, layout);
        let [(_, as_static), (_, as_dynamic)] = built.both_walks();
        let (gpu, _) = tracer.trace(&rays, as_static, false).unwrap();
        let ties = compare(&gpu, &cpu, &rays, |p| triangle(&v, &i, p as usize));
        assert!(ties <= rays.len() / 1000, "{ties} ties");
        // The same BVH walked as the dynamic one (its exact 64-byte nodes, not the
        // static walk's compact ones, whose boxes are rounded outward): the same hits.
        let (exact, _) = tracer.trace(&rays, as_dynamic, false).unwrap();
        let exact: Vec<Hit> = exact.into_iter().map(Hit::without_bvh_bit).collect();
        assert_eq!(
            gpu, exact,
            "{bits:?}, {layout:?}: compact and exact nodes give the same hits"
        );
    }
}

/// The walk with its lanes refilled (`TracePass::refilled`: each invocation takes a new
/// ray from a queue when its walk ends) gives rt.trace's hits bit for bit, closest and
/// any hit (each a real one), on trees of both builders in every layout (rays of a count that no subgroup
/// or workgroup divides, so the queue's last take is partial), in its default shape and
/// the extremes (refills once every lane idles, one ray a lane; once one lane of 64
/// idles, 37 rays a lane), and the rays' hits are brute force's; a tree it does not walk
/// (another layout, a dynamic BVH) fails every ray (t = -1) rather than answering
/// wrongly.
#[test]
fn the_refilled_walk_gives_rt_traces_hits() {
    use speculum::tracers::lbvh::BvhKind;
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let tracer = TracePass::<Lbvh>::new(&ctx).unwrap();
    let n = 3000;
    let (v, i) = random_soup(n, 1.0, default_size(n), 61);
    let rays = random_rays(12_345, &v, &i, 1.0, 62);
    let shadow: Vec<Ray> = rays.iter().map(|r| Ray { tmax: 0.9, ..*r }).collect();
    let cpu: Vec<Hit> = rays.iter().map(|r| brute_force(r, &v, &i)).collect();
    let shapes = [
        Refill::DEFAULT,
        Refill::new(1, 1).unwrap(),
        Refill::new(64, 37).unwrap(),
    ];
    // A shape out of range (a share of 0 would never refill) cannot be made.
    for (share, rays_per_lane) in [(0, 4), (4, 0)] {
        assert!(Refill::new(share, rays_per_lane).is_err(), "{share}:{rays_per_lane}");
    }
    for layout in StaticLayout::ALL {
        let refilled = shapes.map(|shape| TracePass::<Lbvh>::refilled(&ctx, layout, shape).unwrap());
        let built = Built::new_in(&ctx, &b, (&v, &i), MortonBits::Bits30, layout);
        for kind in BvhKind::ALL {
            let (_, made) = b.build_now(built.geometry(), &built.bvh, kind).unwrap();
            assert_eq!(made, kind);
            let [(_, scene), _] = built.both_walks();
            let sets = [(&rays, false), (&shadow, true)];
            for ((set, any_hit), (refilled, shape)) in sets
                .into_iter()
                .flat_map(|s| refilled.iter().zip(shapes).map(move |r| (s, r)))
            {
                let (want, _) = tracer.trace(set, scene, any_hit).unwrap();
                let (got, _) = refilled.trace(set, scene, any_hit).unwrap();
                let differ = want.iter().zip(&got).filter(|(a, b)| a != b).count();
                let case = format!("{layout:?}, {kind:?}, any hit {any_hit}, refill {shape}");
                assert_eq!(differ, 0, "{case}: {differ} of {} hits differ", set.len());
                let hits = got.iter().filter(|h| h.prim != BVH_INVALID).count();
                assert!(
                    hits > set.len() / 5 && hits < set.len(),
                    "{case}: a mix of hits and misses ({hits})"
                );
                if !any_hit {
                    let ties = compare(&got, &cpu, set, |p| triangle(&v, &i, p as usize));
                    assert!(ties <= set.len() / 1000, "{ties} ties");
                }
                for (h, r) in got.iter().zip(set.iter()).filter(|(h, _)| h.prim != BVH_INVALID) {
                    let t = intersect(r, &triangle(&v, &i, h.prim as usize)).expect("a real hit").0;
                    assert!(
                        (t - h.t).abs() <= 1e-5 * t.abs().max(1.0) && h.t > r.tmin && h.t < r.tmax,
                        "{case}"
                    );
                }
            }
        }
        // Another layout's nodes, and the dynamic BVH: every ray a failed walk.
        let other = StaticLayout::ALL[(layout as usize + 1) % 3];
        let elsewhere = Built::new_in(&ctx, &b, (&v, &i), MortonBits::Bits30, other);
        for (walk, scene) in [elsewhere.both_walks()[0], built.both_walks()[1]] {
            let (got, _) = refilled[0].trace(&rays[..100], scene, false).unwrap();
            assert!(
                got.iter().all(|h| h.t == -1.0),
                "{layout:?} through {other:?}, {walk}: {:?}",
                got[0]
            );
        }
    }
    assert_eq!(ctx.validation_messages(), 0);
}

/// Rays aimed at points a hair inside each triangle's corners (where the triangle meets
/// its leaf's box, within a grid step of it: the compact nodes round boxes outward by
/// less than two) hit as brute force says, through the static walk's compact nodes and
/// the dynamic walk's exact ones: a box rounded or decoded a step short loses them.
#[test]
fn rays_at_triangle_corners_hit_through_rounded_boxes() {
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let tracer = TracePass::<Lbvh>::new(&ctx).unwrap();
    let n = 2000;
    let (v, i) = random_soup(n, 1.0, default_size(n), 61);
    let mut rng = common::rng(62);
    let rays: Vec<Ray> = (0..n)
        .flat_map(|t| {
            let tri = triangle(&v, &i, t);
            let center = (tri[0] + tri[1] + tri[2]) / 3.0;
            tri.map(|corner| corner + (center - corner) * 1e-4)
        })
        .map(|target| {
            let o = Vec3::new(
                rng.random_range(-1.5..1.5),
                rng.random_range(-1.5..1.5),
                rng.random_range(-1.5..1.5),
            );
            Ray::through(o, target)
        })
        .collect();
    let cpu: Vec<Hit> = rays.iter().map(|r| brute_force(r, &v, &i)).collect();
    for layout in StaticLayout::ALL {
        let built = Built::new_in(&ctx, &b, (&v, &i), MortonBits::Bits30, layout);
        for (walk, scene) in built.both_walks() {
            let (gpu, _) = tracer.trace(&rays, scene, false).unwrap();
            let gpu: Vec<Hit> = gpu.into_iter().map(Hit::without_bvh_bit).collect();
            let ties = compare(&gpu, &cpu, &rays, |p| triangle(&v, &i, p as usize));
            assert!(ties <= 10, "{walk}, {layout:?}: {ties} ties");
        }
    }
    assert_eq!(ctx.validation_messages(), 0);
}

/// Static and dynamic BVHs traced together equal brute force over both triangle sets
/// (dynamic ids carry `HIT_DYNAMIC`).
#[test]
fn static_and_dynamic_bvhs_together() {
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let tracer = TracePass::<Lbvh>::new(&ctx).unwrap();
    let (sv, si) = random_soup(2000, 1.0, default_size(4000), 31);
    let (dv, di) = random_soup(2000, 1.0, default_size(4000), 32);
    // The static BVH through its wide nodes (the binary ones are covered above).
    let st = Built::new_in(&ctx, &b, (&sv, &si), MortonBits::Bits30, StaticLayout::Wide);
    let dy = Built::new(&ctx, &b, &dv, &di, MortonBits::Bits30);
    let mut all_v = sv.clone();
    all_v.extend(&dv);
    let all_i: Vec<u32> = (0..all_v.len() as u32).collect();
    let rays = random_rays(10000, &all_v, &all_i, 1.0, 33);
    let cpu: Vec<Hit> = rays
        .iter()
        .map(|r| {
            let mut h = brute_force(r, &all_v, &all_i);
            if h.prim != BVH_INVALID && h.prim >= 2000 {
                h.prim = (h.prim - 2000) | HIT_DYNAMIC;
            }
            h
        })
        .collect();
    let scene = TraceScene {
        static_bvh: Some(st.traceable()),
        dynamic_bvh: Some(dy.traceable()),
    };
    let (gpu, _) = tracer.trace(&rays, scene, false).unwrap();
    let tri_of = |p: u32| {
        if p & HIT_DYNAMIC != 0 {
            triangle(&dv, &di, (p & !HIT_DYNAMIC) as usize)
        } else {
            triangle(&sv, &si, p as usize)
        }
    };
    let ties = compare(&gpu, &cpu, &rays, tri_of);
    assert!(ties <= 10, "{ties} ties");
    assert!(
        gpu.iter().any(|h| h.prim != BVH_INVALID && h.prim & HIT_DYNAMIC != 0),
        "some hits are dynamic"
    );
    assert!(
        gpu.iter().any(|h| h.prim != BVH_INVALID && h.prim & HIT_DYNAMIC == 0),
        "some hits are static"
    );
}

/// Any-hit (shadow rays) reports a hit exactly when closest-hit finds one, and the hit
/// it reports is a real intersection inside the interval.
#[test]
fn any_hit_agrees_on_occlusion() {
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let tracer = TracePass::<Lbvh>::new(&ctx).unwrap();
    let (v, i) = random_soup(3000, 1.0, default_size(3000), 41);
    let built = Built::new(&ctx, &b, &v, &i, MortonBits::Bits30);
    // Finite segments, as shadow rays are.
    let rays: Vec<Ray> = random_rays(10000, &v, &i, 1.0, 42)
        .into_iter()
        .map(|r| Ray { tmax: 0.9, ..r })
        .collect();
    let scene = TraceScene {
        static_bvh: Some(built.traceable()),
        dynamic_bvh: None,
    };
    let (closest, _) = tracer.trace(&rays, scene, false).unwrap();
    let (any, _) = tracer.trace(&rays, scene, true).unwrap();
    let mut occluded = 0;
    for (k, ((c, a), r)) in closest.iter().zip(&any).zip(&rays).enumerate() {
        assert_eq!(c.prim == BVH_INVALID, a.prim == BVH_INVALID, "ray {k}");
        if a.prim != BVH_INVALID {
            occluded += 1;
            let t = intersect(r, &triangle(&v, &i, a.prim as usize))
                .expect("any-hit names a real hit")
                .0;
            assert!((t - a.t).abs() <= 1e-5 * t.abs().max(1.0) && a.t > r.tmin && a.t < r.tmax && a.t >= c.t);
        }
    }
    assert!(occluded > 1000 && occluded < 9000, "{occluded}");
}

/// After moving the vertices, a refit BVH gives exactly the hits of a fresh build.
#[test]
fn refit_traces_like_a_fresh_build() {
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let tracer = TracePass::<Lbvh>::new(&ctx).unwrap();
    let (v, i) = random_soup(4000, 1.0, default_size(4000), 51);
    let refit = Built::new(&ctx, &b, &v, &i, MortonBits::Bits30);
    let moved: Vec<GpuVertex> = v
        .iter()
        .map(|p| {
            let mut q = *p;
            q.position[0] += 0.2 * (3.0 * q.position[1]).sin();
            q.position[2] += 0.1 * q.position[0];
            q
        })
        .collect();
    refit.triangles.vertices.write(bytemuck::cast_slice(&moved)).unwrap();
    let mut timer = GpuTimer::new(&ctx, 2).unwrap();
    ctx.one_shot(|cmd| {
        timer.reset(cmd);
        b.record_refit(cmd, &mut timer, refit.geometry(), &refit.bvh);
        b.record_compact(cmd, &mut timer, &refit.bvh);
    })
    .unwrap();
    let fresh = Built::new(&ctx, &b, &moved, &i, MortonBits::Bits30);
    let rays = random_rays(10000, &moved, &i, 1.0, 52);
    let (a, _) = tracer
        .trace(
            &rays,
            TraceScene {
                static_bvh: Some(refit.traceable()),
                dynamic_bvh: None,
            },
            false,
        )
        .unwrap();
    let (f, _) = tracer
        .trace(
            &rays,
            TraceScene {
                static_bvh: Some(fresh.traceable()),
                dynamic_bvh: None,
            },
            false,
        )
        .unwrap();
    assert_eq!(a, f);
    assert!(a.iter().filter(|h| h.prim != BVH_INVALID).count() > 4000);
}

/// After `drop`'s bodies have moved for 30 frames, the renderer's dynamic BVH (rebuilt
/// in the frame over the vertices `sim.transform` moved) traces like brute force over
/// those vertices: rays aimed at random dynamic triangles from around the room, and
/// random ones; dynamic hits carry `HIT_DYNAMIC`.
#[test]
fn the_moved_dynamic_bvh_equals_brute_force() {
    let ctx = common::context();
    let scene = speculum::scene::builtin::drop().unwrap();
    let settings = speculum::Settings {
        width: 64,
        height: 48,
        mode: speculum::settings::Mode::Raster,
        ..Default::default()
    };
    let mut r = speculum::Renderer::new(&ctx, &scene, &settings).unwrap();
    for _ in 0..30 {
        r.render_frame().unwrap();
    }
    let v = r.read_dynamic_vertices().unwrap().unwrap();
    let i = scene.dynamic_meshes().indices;
    // The bodies did move: most vertices are far from where they started.
    let start = speculum::sim::rigid::RigidWorld::new(&scene, settings.sim_dt)
        .unwrap()
        .poses();
    let moved = scene
        .dynamic_meshes()
        .vertices
        .iter()
        .zip(&v)
        .filter(|(o, w)| {
            let p0 = Vec3::from(speculum::cpu_ref::sim::transform(o, &start).position);
            (p0 - Vec3::from(w.position)).length() > 0.2
        })
        .count();
    assert!(moved * 2 > v.len(), "{moved} of {} vertices moved", v.len());
    dynamic_bvh_matches_brute_force(&ctx, &r, (&v, &i), 4.0, 31);
}

/// The renderer's dynamic BVH over world-space vertices `v` (read back) and triangles
/// `i` traces like brute force over them: 8,000 rays from a box of half-size 1.5
/// `scale` around the origin, half aimed at random triangles (`random_rays`); dynamic
/// hits carry `HIT_DYNAMIC`; over 3,000 hits, ties under one in a thousand.
pub(crate) fn dynamic_bvh_matches_brute_force(
    ctx: &Arc<Context>,
    r: &speculum::Renderer,
    (v, i): (&[GpuVertex], &[u32]),
    scale: f32,
    seed: u64,
) {
    let rays = random_rays(8000, v, i, scale, seed);
    let cpu: Vec<Hit> = rays
        .iter()
        .map(|ray| {
            let h = brute_force(ray, v, i);
            if h.prim == BVH_INVALID {
                h
            } else {
                Hit {
                    prim: h.prim | HIT_DYNAMIC,
                    ..h
                }
            }
        })
        .collect();
    let tracer = TracePass::<Lbvh>::new(ctx).unwrap();
    let scene_bvhs = TraceScene {
        static_bvh: None,
        dynamic_bvh: r.dynamic_traceable(),
    };
    let (gpu, _) = tracer.trace(&rays, scene_bvhs, false).unwrap();
    let ties = compare(&gpu, &cpu, &rays, |p| triangle(v, i, (p & !HIT_DYNAMIC) as usize));
    let hits = gpu.iter().filter(|h| h.prim != BVH_INVALID).count();
    assert!(hits > 3000 && ties <= rays.len() / 1000, "{hits} hits, {ties} ties");
}

/// The deepest trees the builders make fit the traversal stack: 65 triangles whose
/// 63-bit keys each set one bit (centroids at (2^b + 1/2) / 2^21 along one axis, plus
/// 0 and 1), thirty-two copies each (three levels of nodes above eight leaves of four),
/// build a chain 67 levels deep. Every box starts at x = -1, where a ray along x
/// starts, so all entries tie at t = 0 and a walk holds a sibling at every level: 65
/// pending subtrees for the binary walk, 96 for the wide one and 147 for the compressed
/// wide one, within `TRACE_STACK`; with 63-bit and 30-bit keys the ray gets brute
/// force's answer.
#[test]
fn the_deepest_built_tree_fits_the_stack() {
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let mut centroids = vec![Vec3::ZERO, Vec3::ONE];
    for axis in 0..3 {
        for bit in 0..21 {
            let mut p = Vec3::ZERO;
            p[axis] = ((1u32 << bit) as f32 + 0.5) / 2_097_152.0;
            centroids.push(p);
        }
    }
    let (mut v, mut i) = (Vec::new(), Vec::new());
    for p in &centroids {
        // Two corners fixed at x = -1, the third placing the centroid at p (to within
        // a rounding far below a key bit's width, hence the half).
        let (v1, v2) = (Vec3::new(-1.0, -1.0, -1.0), Vec3::new(-1.0, 2.0, 2.0));
        let v3 = 3.0 * *p - v1 - v2;
        for _copy in 0..8 * BVH_LEAF_MAX {
            for c in [v1, v2, v3] {
                i.push(v.len() as u32);
                v.push(GpuVertex {
                    position: c.to_array(),
                    material: 0,
                    normal: [1.0, 0.0, 0.0],
                    object: 0,
                });
            }
        }
    }
    let ray = Ray {
        origin: [-1.0, 0.5, 0.5],
        tmin: 0.0,
        dir: [1.0, 0.0, 0.0],
        tmax: 100.0,
    };
    let want = brute_force(&ray, &v, &i);
    let tracer = TracePass::<Lbvh>::new(&ctx).unwrap();
    let cases = [MortonBits::Bits63, MortonBits::Bits30]
        .into_iter()
        .flat_map(|b| StaticLayout::ALL.map(|l| (b, l)));
    for (bits, layout) in cases {
        let built = Built::new_in(&ctx, &b, (&v, &i), bits, layout);
        let depth = speculum::tracers::lbvh::stack_need(&built.bvh.read_packed().unwrap().nodes);
        assert!(
            bits == MortonBits::Bits30 || depth > 64,
            "{bits:?}: a chain {depth} deep"
        );
        for (walk, scene) in built.both_walks() {
            let (hits, _) = tracer.trace(&[ray], scene, false).unwrap();
            let h = hits[0].without_bvh_bit();
            assert_eq!((h.t, h.prim), (want.t, want.prim), "{bits:?}, {layout:?}, {walk}");
        }
    }
    assert_eq!(ctx.validation_messages(), 0);
}

/// A tree deeper than the traversal stack is reported, never silently wrong. A tree is
/// planted whose every box is the scene's (so a ray through the scene enters every
/// node, all at one t) in units of six nodes: X with children Y and Z, Y with the next
/// unit's X and P, Z with Q and R, and P, Q, R each with two one-triangle leaves. The
/// binary walks (static and dynamic) hold two pending nodes a unit (Z, P), the wide walk
/// three (P, Q, R: the grandchildren of X but the next X). `units` of them overflow
/// every walk's stack (t = -1), its lanes refilled or not; a third as many do not. The compressed wide walk gets
/// units of fourteen: X opened three levels to the next X and seven nodes of two
/// leaves each, all seven held a unit.
#[test]
fn a_tree_deeper_than_the_stack_is_reported() {
    use speculum::gpu_types::{bvh_leaf_link, TraversalNode};
    use speculum::shader_defines::TRACE_STACK;
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let units = (TRACE_STACK / 2 + 8) as usize;
    let (v, i) = random_soup(6 * units + 2, 1.0, default_size(1000), 17);
    let binary = Built::new(&ctx, &b, &v, &i, MortonBits::Bits30);
    let wide = Built::new_in(&ctx, &b, (&v, &i), MortonBits::Bits30, StaticLayout::Wide);
    let wide8 = Built::new_in(&ctx, &b, (&v, &i), MortonBits::Bits30, StaticLayout::Wide8);
    let units8 = (TRACE_STACK / 7 + 2) as usize;
    let nodes: Vec<TraversalNode> = bytemuck::pod_collect_to_vec(&binary.bvh.tnodes.read().unwrap());
    let (lo, hi) = nodes.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), n| {
        (
            lo.min(Vec3::from(n.lo0)).min(Vec3::from(n.lo1)),
            hi.max(Vec3::from(n.hi0)).max(Vec3::from(n.hi1)),
        )
    });
    let node = |c0: u32, c1: u32| TraversalNode {
        lo0: lo.to_array(),
        child0: c0,
        hi0: hi.to_array(),
        lo1: lo.to_array(),
        child1: c1,
        hi1: hi.to_array(),
        ..nodes[0]
    };
    // `units` units planted from the root, each of its nodes `Some((c0, c1))` (links as
    // offsets from the unit's first node; the unit's length is the next unit's) or
    // `None` (two one-triangle leaves), then a node of two leaves.
    let plant = |unit: &[Option<(u32, u32)>], units: usize| -> Vec<TraversalNode> {
        let mut planted = nodes.clone();
        let mut leaf = 0u32;
        let mut leaves = || {
            leaf += 2;
            node(bvh_leaf_link(leaf - 2, 1), bvh_leaf_link(leaf - 1, 1))
        };
        for u in 0..units {
            let x = (unit.len() * u) as u32;
            for (k, links) in unit.iter().enumerate() {
                planted[x as usize + k] = match links {
                    Some((c0, c1)) => node(x + c0, x + c1),
                    None => leaves(),
                };
            }
        }
        planted[unit.len() * units] = leaves();
        planted
    };
    // X -> (Y, Z), Y -> (next X, P), Z -> (Q, R); P, Q, R of two leaves.
    let six = [Some((1, 2)), Some((6, 3)), Some((4, 5)), None, None, None];
    // X -> (A, B), A -> (C, D), B -> (E, F), C -> (next X, G1), D -> (G2, G3),
    // E -> (G4, G5), F -> (G6, G7); G1..G7 of two leaves.
    let mut fourteen = vec![None; 14];
    fourteen[..7].copy_from_slice(&[
        Some((1, 2)),
        Some((3, 4)),
        Some((5, 6)),
        Some((14, 7)),
        Some((8, 9)),
        Some((10, 11)),
        Some((12, 13)),
    ]);
    let center = 0.5 * (lo + hi);
    let ray = Ray {
        origin: (center - 2.0 * (hi - lo)).to_array(),
        tmin: 0.0,
        dir: (hi - lo).normalize().to_array(),
        tmax: f32::MAX,
    };
    let tracer = TracePass::<Lbvh>::new(&ctx).unwrap();
    let refilled = StaticLayout::ALL.map(|l| TracePass::<Lbvh>::refilled(&ctx, l, Refill::DEFAULT).unwrap());
    for (count, overflows) in [(units, true), (units / 3, false)] {
        let count8 = if overflows { units8 } else { units8 / 3 };
        for (built, planted) in [
            (&binary, plant(&six, count)),
            (&wide, plant(&six, count)),
            (&wide8, plant(&fourteen, count8)),
        ] {
            built.bvh.plant(&planted, None).unwrap();
            let mut timer = GpuTimer::new(&ctx, 8).unwrap();
            ctx.one_shot(|cmd| {
                timer.reset(cmd);
                b.record_compact(cmd, &mut timer, &built.bvh);
            })
            .unwrap();
        }
        // Each static layout's walk, and refilled; the dynamic walk.
        let mut walks = vec![("dynamic".to_string(), &tracer, binary.both_walks()[1].1)];
        for ((built, layout), refilled) in [&binary, &wide, &wide8]
            .into_iter()
            .zip(StaticLayout::ALL)
            .zip(&refilled)
        {
            let scene = built.both_walks()[0].1;
            walks.push((format!("static {layout:?}"), &tracer, scene));
            walks.push((format!("static {layout:?}, lanes refilled"), refilled, scene));
        }
        for (walk, tracer, scene) in walks {
            let (hits, _) = tracer.trace(&[ray], scene, false).unwrap();
            assert_eq!(
                hits[0].t == -1.0,
                overflows,
                "{count} units, the {walk} walk: {:?}",
                hits[0]
            );
        }
    }
    assert_eq!(ctx.validation_messages(), 0);
}

/// A walk that cannot end is stopped: with the root's first child planted as the root
/// itself (its half box the scene's, so every ray entering the scene takes it; its
/// second half a speck in a corner), a walk would circle the root forever without a
/// push. Bounded by the triangle count, it stops and reports t = -1, in the static walk
/// (compact nodes made from the planted tree), the dynamic one and the static walk
/// with its lanes refilled alike; a ray that misses the scene's box still misses.
#[test]
fn a_planted_cycle_ends_in_a_reported_overrun() {
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let (v, i) = random_soup(300, 1.0, default_size(300), 11);
    let built = Built::new(&ctx, &b, &v, &i, MortonBits::Bits30);
    let mut nodes: Vec<speculum::gpu_types::TraversalNode> =
        bytemuck::pod_collect_to_vec(&built.bvh.tnodes.read().unwrap());
    let root = nodes[0];
    let (lo, hi) = (
        Vec3::from(root.lo0).min(Vec3::from(root.lo1)),
        Vec3::from(root.hi0).max(Vec3::from(root.hi1)),
    );
    let speck = lo + 1e-3 * (hi - lo);
    nodes[0] = speculum::gpu_types::TraversalNode {
        lo0: lo.to_array(),
        child0: 0,
        hi0: hi.to_array(),
        lo1: lo.to_array(),
        hi1: speck.to_array(),
        ..root
    };
    built.bvh.plant(&nodes, None).unwrap();
    let mut timer = GpuTimer::new(&ctx, 8).unwrap();
    ctx.one_shot(|cmd| {
        timer.reset(cmd);
        b.record_compact(cmd, &mut timer, &built.bvh);
    })
    .unwrap();
    let center = 0.5 * (lo + hi);
    let through = Ray {
        origin: (center - 2.0 * (hi - lo)).to_array(),
        tmin: 0.0,
        dir: (hi - lo).normalize().to_array(),
        tmax: f32::MAX,
    };
    let past = Ray {
        origin: (hi + Vec3::ONE).to_array(),
        dir: [1.0, 0.0, 0.0],
        ..through
    };
    let tracer = TracePass::<Lbvh>::new(&ctx).unwrap();
    let refilled = TracePass::<Lbvh>::refilled(&ctx, StaticLayout::Binary, Refill::DEFAULT).unwrap();
    let [as_static, as_dynamic] = built.both_walks();
    // The walk with its lanes refilled walks the static BVH alone.
    let walks = [(&tracer, as_static), (&tracer, as_dynamic), (&refilled, as_static)];
    for (tracer, (_, scene)) in walks {
        let (hits, _) = tracer.trace(&[through, past], scene, false).unwrap();
        assert_eq!(
            (hits[0].t, hits[0].prim),
            (-1.0, BVH_INVALID),
            "the overrun is reported"
        );
        assert_eq!(
            (hits[1].t, hits[1].prim),
            (f32::MAX, BVH_INVALID),
            "a miss stays a miss"
        );
    }
    assert_eq!(ctx.validation_messages(), 0);
}

/// With `static_ploc` the static tree kept (`renderer::static_tree::build`) is the one
/// the choice names, bit for bit a fresh build by its builder and not the other's, and
/// the one whose rays' walk measured cheaper; with `static_layout = fastest` its nodes
/// are the layout whose walk measured cheapest; its hits equal brute force. With the
/// LBVH asked for, a layout asked for, or without rays, nothing is measured and the
/// tree and nodes are as asked.
#[test]
fn the_static_tree_kept_is_the_one_that_walked_faster() {
    use speculum::renderer::static_tree;
    use speculum::settings::Settings;
    use speculum::tracers::lbvh::BvhKind;
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let n = 4000;
    let (v, i) = random_soup(n, 1.0, default_size(n), 31);
    let triangles = UploadedTriangles::new(&ctx, "t", &v, &i).unwrap();
    let geom = triangles.geometry();
    let fresh = || Bvh::new_static_in(&ctx, n as u32, MortonBits::Bits30, StaticLayout::Binary).unwrap();
    let tree = |bvh: &Bvh| {
        let mut t = bvh.read_packed().unwrap();
        t.nodes.iter_mut().for_each(|n| n.unused = 0);
        t
    };
    let built_by = |kind| {
        let bvh = fresh();
        b.build_now(geom, &bvh, kind).unwrap();
        tree(&bvh)
    };
    let (ploc, lbvh) = (built_by(BvhKind::Ploc), built_by(BvhKind::Lbvh));
    assert!(ploc != lbvh, "the two builders' trees differ");
    let rays = static_tree::ChoiceRays {
        reflect: static_tree::surface_rays(&v, &i, Vec3::ZERO, 3072, 3),
        shadow: static_tree::surface_rays(&v, &i, Vec3::ZERO, 1024, 4),
    };
    let settings = Settings::default();
    assert!(settings.static_ploc);
    let (kept, scopes, choice, layout) = static_tree::build(&ctx, &b, geom, fresh(), &settings, &rays).unwrap();
    let choice = choice.expect("static_ploc measures");
    // The default `fastest` layout: the nodes kept are the layout whose walk measured
    // cheapest, made for the tree kept, their compaction's time the build's.
    let layout = layout.expect("static_layout = fastest measures");
    // The soup's trees fit every walk's stack: every layout is priced.
    let price = |ms: Option<f64>| ms.expect("every layout fits this tree");
    let priced = [
        ("binary", price(layout.binary_ms)),
        ("wide", price(layout.wide_ms)),
        ("wide8", price(layout.wide8_ms)),
    ];
    assert!(
        priced.iter().all(|(_, ms)| *ms > 0.0) && layout.rays == 4096,
        "{layout:?}"
    );
    let cheapest = priced.iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap().0;
    assert_eq!(layout.kept, cheapest, "{layout:?}");
    let nodes = kept.compact.as_ref().expect("compact nodes");
    assert_eq!(nodes.layout.name(), layout.kept);
    assert!(kept.compact_current());
    assert!(scopes
        .iter()
        .any(|(n, ms)| *n == speculum::tracers::lbvh::COMPACT && *ms > 0.0));
    assert_eq!(choice.rays, 4096);
    assert!(choice.ploc_ms > 0.0 && choice.lbvh_ms > 0.0, "{choice:?}");
    let want = if choice.lbvh_ms < choice.ploc_ms {
        "lbvh"
    } else {
        "ploc"
    };
    assert_eq!(choice.kept, want, "{choice:?}");
    assert!(tree(&kept) == if want == "lbvh" { lbvh.clone() } else { ploc.clone() });
    let tracer = TracePass::<Lbvh>::new(&ctx).unwrap();
    let scene = TraceScene {
        static_bvh: Some(Traceable {
            bvh: &kept,
            geometry: geom,
        }),
        dynamic_bvh: None,
    };
    let some = &rays.reflect[..1000];
    let (gpu, _) = tracer.trace(some, scene, false).unwrap();
    let cpu: Vec<Hit> = some.iter().map(|r| brute_force(r, &v, &i)).collect();
    let ties = compare(&gpu, &cpu, some, |p| triangle(&v, &i, p as usize));
    assert!(ties <= 2, "{ties} ties");
    let lbvh_only = Settings {
        static_ploc: false,
        ..settings.clone()
    };
    let (kept, _, choice, _) = static_tree::build(&ctx, &b, geom, fresh(), &lbvh_only, &rays).unwrap();
    assert!(choice.is_none() && tree(&kept) == lbvh);
    let none = static_tree::ChoiceRays::default();
    let (kept, _, choice, layout) = static_tree::build(&ctx, &b, geom, fresh(), &settings, &none).unwrap();
    assert!(choice.is_none() && layout.is_none() && tree(&kept) == ploc);
    // A layout asked for is kept, unmeasured.
    let wide8 = Settings {
        static_layout: speculum::settings::WalkLayout::Wide8,
        ..settings.clone()
    };
    let in_wide8 = Bvh::new_static_in(&ctx, n as u32, MortonBits::Bits30, StaticLayout::Wide8).unwrap();
    let (kept, _, _, layout) = static_tree::build(&ctx, &b, geom, in_wide8, &wide8, &rays).unwrap();
    assert!(layout.is_none() && kept.compact.as_ref().unwrap().layout == StaticLayout::Wide8);
}
