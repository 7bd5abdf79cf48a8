//! The GPU LBVH against its CPU references: Morton codes and the radix sort exactly,
//! the fit's tree (topology, slots, links) exactly, boxes exactly (min/max are exact in
//! f32), the BVH invariants on random and degenerate inputs, and both refits.

use crate::common;

use glam::Vec3;
use rand::Rng;
use speculum::cpu_ref::lbvh as cref;
use speculum::gpu_types::{GpuVertex, PackedBvh};
use speculum::scene::soup::{default_size, random_soup};
use speculum::shader_defines::{BVH_INVALID, ORDER_H_MAX, SORT_ITEMS_MAX, SORT_WG_CPU, SORT_WG_GPU};
use speculum::tracers::lbvh::sort::{RadixSort, SortBuffers, SortTile};
use speculum::tracers::lbvh::{Bvh, LbvhBuilder, MortonBits, StaticLayout, UploadedTriangles};
use speculum::vk::{Context, GpuTimer};
use std::sync::Arc;

/// The test's triangles on the GPU, as the build kernels read them.
fn upload(ctx: &Arc<Context>, vertices: &[GpuVertex], indices: &[u32]) -> UploadedTriangles {
    UploadedTriangles::new(ctx, "test", vertices, indices).unwrap()
}

fn build(ctx: &Arc<Context>, b: &LbvhBuilder, g: &UploadedTriangles, bits: MortonBits) -> Bvh {
    build_in(ctx, b, g, bits, StaticLayout::Binary)
}

/// `build`, the static walk's nodes in `layout`.
fn build_in(ctx: &Arc<Context>, b: &LbvhBuilder, g: &UploadedTriangles, bits: MortonBits, layout: StaticLayout) -> Bvh {
    let bvh = Bvh::new_static_in(ctx, g.tri_count, bits, layout).unwrap();
    // Poison the nodes and triangles: what the kernels fail to write cannot pass the
    // checks.
    poison_packed(&bvh);
    let mut timer = GpuTimer::new(ctx, 8).unwrap();
    ctx.one_shot(|cmd| {
        timer.reset(cmd);
        b.record_build(cmd, &mut timer, g.geometry(), &bvh);
    })
    .unwrap();
    bvh
}

fn poison_packed(bvh: &Bvh) {
    bvh.tnodes.write(&vec![0xa5u8; bvh.tnodes.size as usize]).unwrap();
    bvh.ttris.write(&vec![0x5au8; bvh.ttris.size as usize]).unwrap();
}

/// The BVH the fit or a refit wrote equals the CPU's `want` bit for bit (boxes and edges
/// are copies and exact subtractions), but for the nodes' `unused` words, which no
/// kernel writes. Returns what the GPU wrote.
fn assert_packed(bvh: &Bvh, want: &PackedBvh, what: &str) -> PackedBvh {
    let mut got = bvh.read_packed().unwrap();
    for nd in &mut got.nodes {
        nd.unused = 0;
    }
    assert_eq!(got.nodes.len(), want.nodes.len(), "{what}: nodes");
    for (k, (g, w)) in got.nodes.iter().zip(&want.nodes).enumerate() {
        assert_eq!(
            (g.child0, g.child1, g.parent),
            (w.child0, w.child1, w.parent),
            "{what}: links of node {k}"
        );
        assert_eq!(g, w, "{what}: node {k}");
    }
    assert_eq!(got.tris, want.tris, "{what}: triangles in leaf order");
    got
}

/// The CPU's BVH over `v`, `i` from the keys of `keys_from` (the same vertices, or the
/// ones the tree was built on before they moved).
fn cpu_bvh(keys_from: &[GpuVertex], v: &[GpuVertex], i: &[u32], bits: MortonBits) -> PackedBvh {
    let n = i.len() / 3;
    let keys = cref::morton_keys(keys_from, i, bits.key_words());
    let (sk, sv) = cref::sort_pairs(&keys, &(0..n as u32).collect::<Vec<_>>());
    cref::build(&sk, &sv, v, i)
}

/// The GPU's own sorted (key, triangle) pairs, as its Morton and sort stages left them
/// in `bvh`: the fit's input. Each stage's expected output is built from the GPU's
/// previous stage, so a key that a device's rounding moved cannot pose as a broken fit
/// (the keys have their own test, `bounds_morton_and_sort_match_cpu_exactly`).
fn gpu_sorted(bvh: &Bvh) -> (Vec<u64>, Vec<u32>) {
    let (n, kw) = (bvh.tri_count as usize, bvh.bits.key_words());
    let keys: Vec<u32> = bytemuck::pod_collect_to_vec(&bvh.sort.keys[0].read().unwrap());
    let values: Vec<u32> = bytemuck::pod_collect_to_vec(&bvh.sort.values[0].read().unwrap());
    (keys_u64(&keys[..n * kw as usize], kw), values[..n].to_vec())
}

/// The CPU's tree over `v`, `i` from the GPU's sorted keys in `bvh` (`gpu_sorted`).
fn tree_from_gpu_keys(bvh: &Bvh, v: &[GpuVertex], i: &[u32]) -> PackedBvh {
    let (keys, values) = gpu_sorted(bvh);
    cref::build(&keys, &values, v, i)
}

fn keys_u64(raw: &[u32], key_words: u32) -> Vec<u64> {
    if key_words == 1 {
        raw.iter().map(|&k| k as u64).collect()
    } else {
        raw.chunks_exact(2).map(|w| w[0] as u64 | (w[1] as u64) << 32).collect()
    }
}

/// Random soups of every size the issue names, both key widths: bounds, Morton codes,
/// and the sorted (key, id) pairs equal the CPU's exactly.
#[test]
fn bounds_morton_and_sort_match_cpu_exactly() {
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    for (seed, &n) in [1usize, 2, 3, 1000, 65537, 300000].iter().enumerate() {
        let (v, i) = random_soup(n, 10.0, default_size(n) * 10.0, seed as u64);
        let g = upload(&ctx, &v, &i);
        for bits in [MortonBits::Bits30, MortonBits::Bits63] {
            let kw = bits.key_words();
            let bvh = Bvh::new(&ctx, g.tri_count, bits).unwrap();
            bvh.sort.keys[0]
                .write(&vec![0xeeu8; bvh.sort.keys[0].size as usize])
                .unwrap();
            ctx.one_shot(|cmd| {
                b.record_bounds(cmd, g.geometry(), &bvh);
                b.record_morton(cmd, g.geometry(), &bvh);
            })
            .unwrap();
            let (cb, sb) = bvh.read_bounds().unwrap();
            assert_eq!((cb, sb), cref::bounds(&v, &i), "n={n}: bounds");
            let gpu_keys = keys_u64(
                &bytemuck::pod_collect_to_vec(&bvh.sort.keys[0].read().unwrap())[..n * kw as usize],
                kw,
            );
            // The codes' one division is the GPU's: the reference multiplies by the
            // quotient the kernel stored, which Vulkan lets differ from IEEE by 2.5 ULP.
            let scale = bvh.read_unit_scale().unwrap();
            let ieee = cref::unit_scale(cb.lo, cb.hi);
            for a in 0..3 {
                let ulps = (scale[a].to_bits() as i64 - ieee[a].to_bits() as i64).abs();
                assert!(ulps <= 3, "n={n}: the scale's axis {a} is {ulps} ULP from IEEE");
            }
            let cpu_keys = cref::morton_keys_scaled(&v, &i, kw, scale);
            assert_eq!(gpu_keys, cpu_keys, "n={n} {bits:?}: Morton codes");
            if n == 300000 {
                // What that buys: a device whose quotient is 1 ULP off IEEE (as NVIDIA's
                // reciprocal can be) codes some triangles into other cells, so a
                // reference that divided for itself would fail on it.
                let off = Vec3::from_array(scale.to_array().map(|x| f32::from_bits(x.to_bits() + 1)));
                let moved = cref::morton_keys_scaled(&v, &i, kw, off);
                let differ = moved.iter().zip(&cpu_keys).filter(|(a, b)| a != b).count();
                assert!(differ > 0, "{bits:?}: a 1-ULP quotient moved no key");
                eprintln!("{bits:?}: a 1-ULP larger quotient moves {differ} of {n} keys");
            }
            ctx.one_shot(|cmd| b.sort.record(cmd, &bvh.sort, n as u32)).unwrap();
            let sorted_keys = keys_u64(
                &bytemuck::pod_collect_to_vec(&bvh.sort.keys[0].read().unwrap())[..n * kw as usize],
                kw,
            );
            let sorted_values: Vec<u32> = bytemuck::pod_collect_to_vec(&bvh.sort.values[0].read().unwrap());
            let (want_k, want_v) = cref::sort_pairs(&cpu_keys, &(0..n as u32).collect::<Vec<_>>());
            assert_eq!(sorted_keys, want_k, "n={n} {bits:?}: sorted keys");
            assert_eq!(
                &sorted_values[..n],
                &want_v[..],
                "n={n} {bits:?}: sorted ids (stability)"
            );
        }
    }
}

/// `sort_scan` (`bench lbvh --sort-scan`) scans every sort of more than one tile, on
/// a GPU's tiles and a CPU device's alike; without it each keeps its fused sizes.
#[test]
fn sort_scan_turns_the_fused_offsets_off() {
    use ash::vk::PhysicalDeviceType as Kind;
    for (kind, tile) in [(Kind::DISCRETE_GPU, SortTile::GPU), (Kind::CPU, SortTile::CPU)] {
        assert!(tile.fused > 1, "{kind:?}: {tile:?}");
        for scan in [false, true] {
            let ctx = common::context_with(speculum::vk::ContextDesc {
                kernels_for: Some(kind),
                sort_scan: scan,
                ..Default::default()
            });
            let fused = if scan { 0 } else { tile.fused };
            assert_eq!(
                RadixSort::new(&ctx).unwrap().tile(),
                SortTile { fused, ..tile },
                "{kind:?}"
            );
            assert_eq!(ctx.validation_messages(), 0);
        }
    }
}

/// `local_sort_scatter` (`bench lbvh --local-sort-scatter`) gives the sort written out
/// in order where the tiles are a GPU's, and leaves a CPU device's tiles direct.
#[test]
fn the_local_sort_scatter_takes_gpu_tiles_only() {
    use ash::vk::PhysicalDeviceType as Kind;
    for (kind, expected) in [(Kind::DISCRETE_GPU, SortTile::GPU_LOCAL), (Kind::CPU, SortTile::CPU)] {
        let ctx = common::context_with(speculum::vk::ContextDesc {
            kernels_for: Some(kind),
            local_sort_scatter: true,
            ..Default::default()
        });
        assert_eq!(RadixSort::new(&ctx).unwrap().tile(), expected, "{kind:?}");
        assert_eq!(ctx.validation_messages(), 0);
    }
}

/// The radix sort alone on random keys with many duplicates (few distinct values and
/// full-range values), random payloads, 1- and 2-word keys, with each tile size a
/// device can get and the largest allowed: equal to a stable sort.
#[test]
fn radix_sort_is_a_stable_sort() {
    let ctx = common::context();
    let mut rng = common::rng(7);
    let shapes = [
        SortTile::GPU,
        SortTile::GPU_LOCAL,
        SortTile::CPU,
        SortTile {
            wg: SORT_WG_GPU,
            items: SORT_ITEMS_MAX,
            local: false,
            fused: 16,
        },
        SortTile {
            wg: SORT_WG_CPU,
            items: SORT_ITEMS_MAX,
            local: false,
            fused: 16,
        },
        SortTile {
            wg: SORT_WG_CPU,
            items: 64,
            local: false,
            fused: 0,
        },
        // Every sort of more than one tile scanned, and fused past the defaults.
        SortTile {
            fused: 0,
            ..SortTile::GPU
        },
        SortTile {
            fused: 0,
            ..SortTile::CPU
        },
        SortTile {
            fused: 1000,
            ..SortTile::CPU
        },
    ];
    for tile in shapes {
        let sort = RadixSort::with_tile(&ctx, tile).unwrap();
        for &n in &[1u32, 2, 3, 1000, 4096, 4097, 65537, 300000] {
            for kw in [1u32, 2] {
                for distinct in [Some(5u64), None] {
                    let keys: Vec<u64> = (0..n)
                        .map(|_| {
                            let k: u64 = rng.random();
                            let k = distinct.map_or(k, |d| (k % d).wrapping_mul(0x9e37_79b9_7f4a_7c15));
                            if kw == 1 {
                                k & 0xffff_ffff
                            } else {
                                k
                            }
                        })
                        .collect();
                    let values: Vec<u32> = (0..n).map(|_| rng.random()).collect();
                    let bufs = SortBuffers::new(&ctx, n, kw).unwrap();
                    let raw: Vec<u32> = if kw == 1 {
                        keys.iter().map(|&k| k as u32).collect()
                    } else {
                        keys.iter().flat_map(|&k| [k as u32, (k >> 32) as u32]).collect()
                    };
                    bufs.keys[0].write(bytemuck::cast_slice(&raw)).unwrap();
                    bufs.values[0].write(bytemuck::cast_slice(&values)).unwrap();
                    bufs.keys[1].write(&vec![0x5au8; bufs.keys[1].size as usize]).unwrap();
                    ctx.one_shot(|cmd| sort.record(cmd, &bufs, n)).unwrap();
                    let got_k = keys_u64(
                        &bytemuck::pod_collect_to_vec(&bufs.keys[0].read().unwrap())[..(n * kw) as usize],
                        kw,
                    );
                    let got_v: Vec<u32> = bytemuck::pod_collect_to_vec(&bufs.values[0].read().unwrap());
                    let (want_k, want_v) = cref::sort_pairs(&keys, &values);
                    assert_eq!(got_k, want_k, "{tile:?} n={n} kw={kw} distinct={distinct:?}");
                    assert_eq!(
                        &got_v[..n as usize],
                        &want_v[..],
                        "{tile:?} n={n} kw={kw} distinct={distinct:?}: payload order"
                    );
                }
            }
        }
    }
}

/// Full builds: the tree (child links, slots, parent links) equals the CPU's top-down
/// radix tree exactly, boxes and triangles equal the CPU's exactly, and the invariants
/// hold; with the fit climbing freely and in lockstep (the variant lavapipe before
/// Mesa 25 gets) alike.
#[test]
fn fit_matches_cpu_exactly() {
    let ctx = common::context();
    for lockstep in [false, true] {
        fit_matches_cpu(&ctx, &LbvhBuilder::with_fit(&ctx, lockstep).unwrap());
    }
}

fn fit_matches_cpu(ctx: &Arc<Context>, b: &LbvhBuilder) {
    for (seed, &n) in [1usize, 2, 3, 1000, 65537].iter().enumerate() {
        let (v, i) = random_soup(n, 3.0, default_size(n) * 3.0, 100 + seed as u64);
        let g = upload(ctx, &v, &i);
        for bits in [MortonBits::Bits30, MortonBits::Bits63] {
            let bvh = build(ctx, b, &g, bits);
            let want = tree_from_gpu_keys(&bvh, &v, &i);
            let got = assert_packed(&bvh, &want, &format!("n={n} {bits:?}"));
            cref::check_bvh(&got, &v, &i).unwrap_or_else(|e| panic!("n={n} {bits:?}: {e}"));
        }
    }
}

fn soup_from(tris: &[[Vec3; 3]]) -> (Vec<GpuVertex>, Vec<u32>) {
    let v = tris
        .iter()
        .flatten()
        .map(|p| GpuVertex {
            position: p.to_array(),
            material: 0,
            normal: [0.0, 1.0, 0.0],
            object: 0,
        })
        .collect();
    (v, (0..3 * tris.len() as u32).collect())
}

/// Degenerate inputs still give valid BVHs: all triangles coplanar, all centroids
/// equal, zero-area triangles, huge and tiny coordinates.
#[test]
fn degenerate_inputs_give_valid_bvhs() {
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let mut rng = common::rng(11);
    let mut r = |s: f32| {
        Vec3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    };
    let n = 5000;
    let cases: Vec<(&str, Vec<[Vec3; 3]>)> = vec![
        (
            "coplanar",
            (0..n)
                .map(|_| [r(1.0), r(1.0), r(1.0)].map(|p| Vec3::new(p.x, 0.5, p.z)))
                .collect(),
        ),
        (
            "equal centroids",
            (0..n)
                .map(|_| {
                    let d = r(1.0);
                    let e = r(1.0);
                    [Vec3::ONE + d, Vec3::ONE + e, Vec3::ONE - d - e]
                })
                .collect(),
        ),
        (
            "zero area",
            (0..n)
                .map(|_| {
                    let p = r(1.0);
                    let d = r(0.1);
                    [p, p + d, p + 2.0 * d]
                })
                .collect(),
        ),
        ("single point", (0..n).map(|_| [Vec3::splat(2.0); 3]).collect()),
        (
            "huge",
            (0..n)
                .map(|_| {
                    let c = r(1e6);
                    [c, c + r(1e3), c + r(1e3)]
                })
                .collect(),
        ),
        (
            "tiny",
            (0..n)
                .map(|_| {
                    let c = r(1e-6);
                    [c, c + r(1e-9), c + r(1e-9)]
                })
                .collect(),
        ),
    ];
    for (name, tris) in cases {
        let (v, i) = soup_from(&tris);
        let g = upload(&ctx, &v, &i);
        for bits in [MortonBits::Bits30, MortonBits::Bits63] {
            let bvh = build(&ctx, &b, &g, bits);
            let got = assert_packed(&bvh, &tree_from_gpu_keys(&bvh, &v, &i), &format!("{name} {bits:?}"));
            cref::check_bvh(&got, &v, &i).unwrap_or_else(|e| panic!("{name} {bits:?}: {e}"));
        }
    }
}

/// The invariant checker rejects broken trees (so the tests above can fail).
#[test]
fn invariant_checker_rejects_broken_trees() {
    let (v, i) = random_soup(100, 1.0, 0.1, 3);
    let good = cpu_bvh(&v, &v, &i, MortonBits::Bits30);
    cref::check_bvh(&good, &v, &i).unwrap();
    type Spoil = fn(&mut PackedBvh);
    let broken: [(&str, Spoil); 6] = [
        ("a shrunk box", |b| b.nodes[5].hi0[0] -= 1e-3),
        ("a triangle in two leaves", |b| {
            let last = b.tris.len() - 1;
            b.tris[last].id = b.tris[last - 1].id;
        }),
        ("a wrong parent link", |b| b.nodes[3].parent ^= 1),
        ("a leaf's wrong parent link", |b| b.tris[7].parent ^= 2),
        ("a node reached twice", |b| b.nodes[0].child1 = b.nodes[0].child0),
        ("a moved corner", |b| b.tris[2].b[1] += 1e-3),
    ];
    for (what, spoil) in broken {
        let mut b = good.clone();
        spoil(&mut b);
        assert!(cref::check_bvh(&b, &v, &i).is_err(), "{what} passed");
    }
}

fn wave(v: &[GpuVertex]) -> Vec<GpuVertex> {
    v.iter()
        .map(|p| {
            let mut q = *p;
            q.position[1] += 0.3 * (q.position[0] * 2.0).sin();
            q
        })
        .collect()
}

/// The fit re-run after every vertex moved (`record_refit`, the tree from the keys
/// still sorted) equals the CPU's tree of the old keys over the moved triangles, and
/// passes the invariants.
#[test]
fn refit_matches_cpu_after_moving_vertices() {
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let n = 20000;
    let (v, i) = random_soup(n, 2.0, default_size(n) * 2.0, 5);
    let g = upload(&ctx, &v, &i);
    let bvh = build(&ctx, &b, &g, MortonBits::Bits30);
    let before = bvh.read_packed().unwrap();
    let moved = wave(&v);
    g.vertices.write(bytemuck::cast_slice(&moved)).unwrap();
    poison_packed(&bvh);
    let mut timer = GpuTimer::new(&ctx, 2).unwrap();
    ctx.one_shot(|cmd| {
        timer.reset(cmd);
        b.record_refit(cmd, &mut timer, g.geometry(), &bvh);
    })
    .unwrap();
    let after = assert_packed(&bvh, &tree_from_gpu_keys(&bvh, &moved, &i), "refit");
    assert_ne!(after.nodes, before.nodes, "the boxes moved");
    cref::check_bvh(&after, &moved, &i).unwrap();
}

/// The scheduled refit (leaves, then height levels, the top in one workgroup) gives
/// exactly the CPU refit's boxes after the vertices move (leaves kept as built), for trees whose levels all fit the
/// top pass (300 triangles) and ones with big levels of their own (20,000); the
/// schedule orders every node after both its children.
#[test]
fn scheduled_refit_matches_cpu() {
    use speculum::tracers::lbvh::{refit_order, RefitSchedule};
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    for n in [1usize, 2, 300, 20000] {
        let (v, i) = random_soup(n, 2.0, default_size(n) * 2.0, 7);
        let g = upload(&ctx, &v, &i);
        let bvh = build(&ctx, &b, &g, MortonBits::Bits30);
        let before = bvh.read_packed().unwrap();
        let (order, levels) = refit_order(&before, n as u32);
        assert_eq!(order.len(), n - 1, "every internal node once");
        let mut rank = vec![usize::MAX; before.nodes.len()];
        for (k, &s) in order.iter().enumerate() {
            rank[s as usize] = k;
        }
        // Every node after its children in the binary tree (the parent links), also
        // those inside leaves of several triangles.
        for (s, nd) in before.nodes.iter().enumerate().skip(1) {
            let p = (nd.parent >> 1) as usize;
            assert!(rank[s] < rank[p], "node {p} before its child {s}");
        }
        assert!(levels.windows(2).all(|w| w[1][1] <= w[0][1]), "levels never grow");
        let schedule = RefitSchedule::of(&ctx, &bvh).unwrap();
        let moved = wave(&v);
        g.vertices.write(bytemuck::cast_slice(&moved)).unwrap();
        // Poison every box and corner, keeping the tree: each must be written.
        let mut poisoned = before.clone();
        for nd in &mut poisoned.nodes {
            (nd.lo0, nd.hi0, nd.lo1, nd.hi1) = ([f32::NAN; 3], [f32::NAN; 3], [f32::NAN; 3], [f32::NAN; 3]);
        }
        for t in &mut poisoned.tris {
            (t.a, t.b, t.c) = ([f32::NAN; 3], [f32::NAN; 3], [f32::NAN; 3]);
        }
        bvh.tnodes.write(bytemuck::cast_slice(&poisoned.nodes)).unwrap();
        bvh.ttris.write(bytemuck::cast_slice(&poisoned.tris)).unwrap();
        let mut timer = GpuTimer::new(&ctx, 2).unwrap();
        ctx.one_shot(|cmd| {
            timer.reset(cmd);
            b.record_refit_scheduled(cmd, &mut timer, g.geometry(), &bvh, &schedule);
        })
        .unwrap();
        // The same tree and leaves (the fit would choose other leaves over the moved
        // triangles; the refit keeps them), every box and triangle recomputed.
        let after = assert_packed(
            &bvh,
            &cref::refit(&tree_from_gpu_keys(&bvh, &v, &i), &moved, &i),
            &format!("scheduled refit, {n} triangles"),
        );
        cref::check_bvh(&after, &moved, &i).unwrap();
        assert!(levels.iter().any(|l| l[1] > 1024) == (n > 5000), "{n}: {levels:?}");
    }
}

/// The size class in the keys' top bits keeps walls from stretching the small
/// triangles' subtrees: on `room` and `mirrors` (walls and floors around small objects)
/// the LBVH's SAH cost stays within 1.4x the CPU binned-SAH builder's (1.68 and 1.48
/// with plain Morton codes), and a tree over small triangles alone is the plain one.
#[test]
fn size_classes_keep_walls_apart() {
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    for scene in [
        speculum::scene::builtin::room().unwrap(),
        speculum::scene::builtin::mirrors().unwrap(),
    ] {
        let (v, i) = (&scene.vertices, &scene.indices);
        let g = upload(&ctx, v, i);
        let bvh = build(&ctx, &b, &g, MortonBits::Bits30);
        let ratio = cref::sah_cost(&bvh.read_packed().unwrap().nodes, i.len() / 3)
            / speculum::cpu_ref::trace::CpuBvh::build(v, i).sah_cost();
        println!("{}: SAH {ratio:.3} of binned SAH", scene.name);
        assert!(ratio < 1.4, "{}: SAH ratio {ratio:.3}", scene.name);
        let keys = cref::morton_keys(v, i, 1);
        assert!(
            keys.iter().any(|k| k >> 30 == 0) && keys.iter().any(|k| k >> 30 == 3),
            "{}: large and small triangles",
            scene.name
        );
    }
    let (v, i) = random_soup(1000, 1.0, default_size(1000), 3);
    assert!(
        cref::morton_keys(&v, &i, 1).iter().all(|k| k >> 30 == 3),
        "a soup of small triangles is one class"
    );
}

/// PLOC builds (the static scene's tree): the nodes, slots, links and boxes equal
/// `cpu_ref::lbvh::ploc` bit for bit after the LBVH's sort, the invariants hold, on
/// counts the one-workgroup tail builds alone (up to `PLOC_TAIL_CAP`, the cap itself
/// included) and ones the rounds hand over to it (one above the cap too), and a build
/// whose first submission runs too few rounds for the tail (none) is finished by
/// `finish` to the same tree; its SAH on `room` stays within 1.05x of binned SAH (1.28x for the LBVH).
#[test]
fn ploc_matches_cpu_exactly() {
    use speculum::shader_defines::{PLOC_RADIUS, PLOC_TAIL_CAP};
    use speculum::tracers::lbvh::ploc::{first_rounds, PlocBuilder, PlocScratch};
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let p = PlocBuilder::new(&ctx).unwrap();
    let room = speculum::scene::builtin::room().unwrap();
    let cap = PLOC_TAIL_CAP as usize;
    let mut cases: Vec<(String, Vec<GpuVertex>, Vec<u32>)> = [1usize, 2, 3, 1000, cap, cap + 1, 65537]
        .iter()
        .enumerate()
        .map(|(seed, &n)| {
            let (v, i) = random_soup(n, 3.0, default_size(n) * 3.0, 200 + seed as u64);
            (format!("soup {n}"), v, i)
        })
        .collect();
    cases.push(("room".into(), room.vertices.clone(), room.indices.clone()));
    for (name, v, i) in &cases {
        let n = (i.len() / 3) as u32;
        let g = upload(&ctx, v, i);
        let scratch = PlocScratch::new(&ctx, n).unwrap();
        for first in [first_rounds(n), 0] {
            let bvh = Bvh::new(&ctx, n, MortonBits::Bits30).unwrap();
            poison_packed(&bvh);
            ctx.one_shot(|cmd| {
                b.record_bounds(cmd, g.geometry(), &bvh);
                b.record_morton(cmd, g.geometry(), &bvh);
                b.sort.record(cmd, &bvh.sort, n);
            })
            .unwrap();
            // PLOC's expected tree from the GPU's own sorted order (`gpu_sorted`).
            let want = cref::ploc(&gpu_sorted(&bvh).1, v, i, PLOC_RADIUS as usize);
            ctx.one_shot(|cmd| p.record(cmd, g.geometry(), &bvh, &scratch, first))
                .unwrap();
            let rounds = p.finish(n, &bvh, &scratch, first).unwrap();
            let what = format!("{name}, {first} rounds first ({rounds} in all)");
            let got = assert_packed(&bvh, &want, &what);
            cref::check_bvh(&got, v, i).unwrap_or_else(|e| panic!("{what}: {e}"));
            if name == "room" {
                let ratio =
                    cref::sah_cost(&got.nodes, n as usize) / speculum::cpu_ref::trace::CpuBvh::build(v, i).sah_cost();
                println!("room: PLOC SAH {ratio:.3} of binned SAH");
                assert!(ratio < 1.05, "room: PLOC SAH ratio {ratio:.3}");
            }
        }
    }
    assert_eq!(ctx.validation_messages(), 0);
}

/// `lbvh.compact` writes the CPU's compact nodes exactly (output poisoned), for LBVH and
/// PLOC trees of random soups, of degenerate inputs (flat, a point, huge and tiny
/// coordinates, a small scene far from the origin), of a single triangle, and after a
/// refit moved the root's box, in both layouts; and every node holds its binary node's
/// children (wide: each internal one opened into its two), each rounded box holding its
/// exact box within two grid steps of it, with the same link, unused slots empty.
#[test]
fn compact_nodes_match_cpu_and_hold_the_boxes() {
    use speculum::tracers::lbvh::ploc::{first_rounds, PlocScratch};
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let mut rng = common::rng(31);
    let mut r = |s: f32| {
        Vec3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    };
    let n = 3000;
    let mut cases: Vec<(String, Vec<GpuVertex>, Vec<u32>)> = [1usize, 2, 1000, 40000]
        .iter()
        .map(|&k| {
            let (v, i) = random_soup(k, 2.0, default_size(k) * 2.0, k as u64);
            (format!("soup {k}"), v, i)
        })
        .collect();
    let shaped: Vec<(&str, Vec<[Vec3; 3]>)> = vec![
        (
            "flat",
            (0..n)
                .map(|_| [r(1.0), r(1.0), r(1.0)].map(|p| Vec3::new(p.x, -0.25, p.z)))
                .collect(),
        ),
        ("a point", (0..n).map(|_| [Vec3::splat(-3.0); 3]).collect()),
        ("huge", (0..n).map(|_| [r(1e6), r(1e6), r(1e6)]).collect()),
        ("tiny", (0..n).map(|_| [r(1e-6), r(1e-6), r(1e-6)]).collect()),
        (
            "far from the origin",
            (0..n)
                .map(|_| {
                    let c = Vec3::new(3.0e5, -7.0e4, 1.0e5) + r(0.5);
                    [c, c + r(0.01), c + r(0.01)]
                })
                .collect(),
        ),
    ];
    for (name, tris) in shaped {
        let (v, i) = soup_from(&tris);
        cases.push((name.into(), v, i));
    }
    let check = |bvh: &Bvh, what: &str| {
        let got = compact_poisoned(&ctx, &b, bvh);
        assert!(bvh.compact_current(), "{what}: compact nodes current");
        let nodes = bvh.read_packed().unwrap().nodes;
        let layout = bvh.compact.as_ref().unwrap().layout;
        let slots = layout.slots() as usize;
        assert_eq!(
            read_counts(bvh),
            cref::order_counts(&nodes).expect("a built tree is a tree"),
            "{what}: the builder's order counts"
        );
        let want = cref::compact_nodes(&nodes, slots as u32);
        assert_written(&got, &want, &format!("{what}, {layout:?}: compact nodes"));
        // In preorder, or in the slots where the tree is too deep (PLOC's of a point).
        let place = cref::written_places(&nodes, slots as u32);
        let placed = place.iter().filter(|&&p| p != BVH_INVALID).count();
        let texels = layout.texels() as usize;
        assert_eq!(2 + texels * placed, want.len(), "{what}: the nodes placed are written");
        let (g, st) = (Vec3::from_array(f32_3(got[0])), Vec3::from_array(f32_3(got[1])));
        // Every node placed holds its binary node's children (wide: each internal one
        // opened): each rounded box holds its exact box within two grid steps, with its
        // link (an internal node's: its place).
        let link = |c: u32| match speculum::gpu_types::bvh_leaf(c) {
            Some(_) => c,
            None => place[c as usize],
        };
        for (k, nd) in nodes.iter().enumerate() {
            if place[k] == BVH_INVALID {
                continue;
            }
            if layout == StaticLayout::Wide8 {
                // The compressed node holds binary node k's subtree opened three levels
                // (in order), each box within two steps of the node's own grid.
                let at = 2 + texels * place[k] as usize;
                let node = &got[at..at + texels];
                let h = node[0];
                let st = Vec3::from_array([0, 8, 16].map(|s| f32::from_bits((h[3] >> s & 0xff) << 23)));
                let entries = cref::wide8_entries(&nodes, k);
                assert!(
                    (2..=8).contains(&entries.len()),
                    "{what}: node {k}: {} children",
                    entries.len()
                );
                for (slot, (rounded, l)) in cref::wide8_boxes(node).into_iter().enumerate() {
                    let Some(&(lo, hi, c)) = entries.get(slot) else {
                        assert_eq!(l, BVH_INVALID, "{what}: node {k} slot {slot}: unused");
                        continue;
                    };
                    let (lo, hi) = (Vec3::from(lo), Vec3::from(hi));
                    let within = (lo - rounded.lo).cmpge(Vec3::ZERO).all()
                        && (rounded.hi - hi).cmpge(Vec3::ZERO).all()
                        && (lo - rounded.lo).cmple(2.0 * st).all()
                        && (rounded.hi - hi).cmple(2.0 * st).all();
                    assert!(
                        within,
                        "{what}: node {k} slot {slot}: {lo}..{hi} rounded to {rounded:?}"
                    );
                    assert_eq!(l, link(c), "{what}: node {k} slot {slot}: link");
                }
                continue;
            }
            let mut want = Vec::new();
            for side in 0..2u32 {
                let c = [nd.child0, nd.child1][side as usize];
                match speculum::gpu_types::bvh_leaf(c) {
                    _ if slots == 2 => want.push((speculum::aabb::Aabb::of_half(nd, side), link(c))),
                    Some(_) => want.push((speculum::aabb::Aabb::of_half(nd, side), c)),
                    None => {
                        let m = &nodes[c as usize];
                        want.push((speculum::aabb::Aabb::of_half(m, 0), link(m.child0)));
                        want.push((speculum::aabb::Aabb::of_half(m, 1), link(m.child1)));
                    }
                }
            }
            assert!(want.len() <= slots);
            for slot in 0..slots {
                let half = got[2 + slots * place[k] as usize + slot];
                let Some((exact, link)) = want.get(slot) else {
                    assert_eq!(half, cref::WIDE_EMPTY, "{what}: node {k} slot {slot}: unused");
                    continue;
                };
                let rounded = cref::compact_box(half, g, st);
                let within = (exact.lo - rounded.lo).cmpge(Vec3::ZERO).all()
                    && (rounded.hi - exact.hi).cmpge(Vec3::ZERO).all()
                    && (exact.lo - rounded.lo).cmple(2.0 * st).all()
                    && (rounded.hi - exact.hi).cmple(2.0 * st).all();
                assert!(within, "{what}: node {k} slot {slot}: {exact:?} rounded to {rounded:?}");
                assert_eq!(half[3], *link, "{what}: node {k} slot {slot}: link");
            }
        }
    };
    for ((name, v, i), layout) in cases.iter().zip(StaticLayout::ALL.iter().cycle()) {
        // Both layouts of every case: the cases alternate which comes first.
        let other = StaticLayout::ALL.into_iter().find(|l| l != layout).unwrap();
        let g = upload(&ctx, v, i);
        let n = (i.len() / 3) as u32;
        let bvh = build_in(&ctx, &b, &g, MortonBits::Bits30, *layout);
        assert!(!bvh.compact_current(), "{name}: stale after the build");
        check(&bvh, &format!("{name}, LBVH"));
        check(
            &build_in(&ctx, &b, &g, MortonBits::Bits30, other),
            &format!("{name}, LBVH"),
        );
        let ploc = Bvh::new_static_in(&ctx, n, MortonBits::Bits30, *layout).unwrap();
        let scratch = PlocScratch::new(&ctx, n).unwrap();
        let mut timer = GpuTimer::new(&ctx, 8).unwrap();
        ctx.one_shot(|cmd| {
            timer.reset(cmd);
            b.record_build_ploc(cmd, &mut timer, g.geometry(), &ploc, &scratch);
        })
        .unwrap();
        b.ploc.finish(n, &ploc, &scratch, first_rounds(n)).unwrap();
        check(&ploc, &format!("{name}, PLOC"));
        if name == "soup 40000" {
            g.vertices.write(bytemuck::cast_slice(&wave(v))).unwrap();
            ctx.one_shot(|cmd| {
                timer.reset(cmd);
                b.record_refit(cmd, &mut timer, g.geometry(), &bvh);
            })
            .unwrap();
            assert!(!bvh.compact_current(), "{name}: stale after the refit");
            check(&bvh, &format!("{name}, refit"));
        }
    }
    assert_eq!(ctx.validation_messages(), 0);
}

/// `lbvh.compact` recorded into `bvh`'s compact nodes poisoned with 0xc3 bytes; what
/// it left there.
fn compact_poisoned(ctx: &Arc<Context>, b: &LbvhBuilder, bvh: &Bvh) -> Vec<[u32; 4]> {
    let compact = &bvh.compact.as_ref().expect("made by new_static").buffer;
    compact.write(&vec![0xc3u8; compact.size as usize]).unwrap();
    let mut timer = GpuTimer::new(ctx, 2).unwrap();
    ctx.one_shot(|cmd| {
        timer.reset(cmd);
        b.record_compact(cmd, &mut timer, bvh);
    })
    .unwrap();
    bytemuck::pod_collect_to_vec(&compact.read().unwrap())
}

/// The compact nodes `got` (`compact_poisoned`) start with `want` exactly, and the
/// poison is untouched past them.
fn assert_written(got: &[[u32; 4]], want: &[[u32; 4]], what: &str) {
    let first = (0..want.len()).find(|&t| got[t] != want[t]);
    assert!(
        first.is_none(),
        "{what}: differ first at texel {first:?} of {}: {:?} against {:?}",
        want.len(),
        first.map(|t| got[t]),
        first.map(|t| want[t])
    );
    assert!(
        got[want.len()..].iter().all(|t| *t == [0xc3c3_c3c3; 4]),
        "{what}: nothing written past the nodes placed"
    );
}

fn f32_3(t: [u32; 4]) -> [f32; 3] {
    [f32::from_bits(t[0]), f32::from_bits(t[1]), f32::from_bits(t[2])]
}

/// A rigid rebuild (`tracers::lbvh::rigid`): random bodies (one without triangles, two
/// alike in one pose, so their codes tie) under random poses, 1, 2, 9 and 300 of them.
/// The layout orders each body's triangles by their object-space keys; the kernels'
/// keys and values equal `cpu_ref::lbvh::rigid_keys` exactly (outputs poisoned), come
/// out sorted with every triangle once; and the fit over them builds the CPU's tree
/// from the same pairs, which passes the invariants.
#[test]
fn rigid_keys_match_cpu_and_build_the_cpu_tree() {
    use glam::{Mat4, Quat};
    use speculum::tracers::lbvh::rigid::{RigidKeys, RigidLayout};
    let ctx = common::context();
    let b = LbvhBuilder::new(&ctx).unwrap();
    let mut rng = common::rng(23);
    for bodies in [1u32, 2, 9, 300] {
        // Object-space bodies: a soup each, around its own origin.
        let (mut objects, mut i) = (Vec::new(), Vec::new());
        for body in 0..bodies {
            let n = if bodies > 2 && body == 3 {
                0
            } else {
                rng.random_range(1..40usize)
            };
            if n == 0 {
                continue;
            }
            // Bodies 1 and 2 alike (and posed alike below): their codes tie.
            let twin = bodies > 2 && (body == 1 || body == 2);
            let (n, seed) = if twin { (17, 1) } else { (n, rng.random()) };
            let (sv, si) = random_soup(n, 1.0, default_size(n), seed);
            let base = objects.len() as u32;
            objects.extend(sv.iter().map(|v| GpuVertex {
                position: (Vec3::from(v.position) - Vec3::splat(0.5)).to_array(),
                object: body,
                ..*v
            }));
            i.extend(si.iter().map(|k| base + k));
        }
        let mut poses: Vec<Mat4> = (0..bodies)
            .map(|_| {
                let axis = Vec3::new(rng.random(), rng.random(), rng.random::<f32>() + 0.1).normalize();
                let t = Vec3::new(rng.random(), rng.random(), rng.random()) * 8.0 - 4.0;
                Mat4::from_rotation_translation(Quat::from_axis_angle(axis, rng.random::<f32>() * 6.0), t)
            })
            .collect();
        if bodies > 2 {
            poses[2] = poses[1]; // two bodies on one spot: equal codes, told apart by index
        }
        let world: Vec<GpuVertex> = objects
            .iter()
            .map(|o| speculum::cpu_ref::sim::transform(o, &poses))
            .collect();
        let layout = RigidLayout::new(&objects, &i, bodies).unwrap();
        let n = i.len() / 3;
        for body in 0..bodies as usize {
            let mut places: Vec<(u32, u32)> = layout
                .tri_info
                .iter()
                .filter(|t| t[0] as usize == body)
                .map(|t| (t[1], t[2]))
                .collect();
            places.sort();
            assert_eq!(
                places.len() as u32,
                layout.bodies[body].tri_count,
                "{bodies} bodies: body {body}'s count"
            );
            assert!(
                places.iter().enumerate().all(|(k, p)| p.0 == k as u32) && places.windows(2).all(|w| w[0].1 <= w[1].1),
                "{bodies} bodies: body {body}'s order is not by its keys"
            );
        }
        let g = upload(&ctx, &world, &i);
        let bvh = Bvh::new(&ctx, n as u32, MortonBits::Bits30).unwrap();
        poison_packed(&bvh);
        bvh.sort.keys[0]
            .write(&vec![0x5au8; bvh.sort.keys[0].size as usize])
            .unwrap();
        bvh.sort.values[0]
            .write(&vec![0xa5u8; bvh.sort.values[0].size as usize])
            .unwrap();
        let rigid = RigidKeys::new(&ctx, &layout).unwrap();
        let pose_buf = speculum::vk::Buffer::with_data(
            &ctx,
            "test.poses",
            ash::vk::BufferUsageFlags::STORAGE_BUFFER,
            bytemuck::cast_slice(&poses),
        )
        .unwrap();
        let mut timer = GpuTimer::new(&ctx, 8).unwrap();
        ctx.one_shot(|cmd| {
            timer.reset(cmd);
            b.record_build_rigid(cmd, &mut timer, g.geometry(), &bvh, &rigid, &pose_buf);
        })
        .unwrap();
        let keys: Vec<u32> = bytemuck::pod_collect_to_vec(&bvh.sort.keys[0].read().unwrap());
        let values: Vec<u32> = bytemuck::pod_collect_to_vec(&bvh.sort.values[0].read().unwrap());
        let (want_k, want_v) = cref::rigid_keys(
            &layout.bodies,
            &poses,
            &layout.tri_info,
            layout.rank_bits(),
            layout.cell_bits(),
            Some(rigid.read_scale().unwrap()),
        );
        assert_eq!(&keys[..n], &want_k[..], "{bodies} bodies: keys");
        assert_eq!(&values[..n], &want_v[..], "{bodies} bodies: values");
        assert!(
            want_k.windows(2).all(|w| w[0] <= w[1]),
            "{bodies} bodies: keys not sorted"
        );
        let mut seen = want_v.clone();
        seen.sort();
        assert_eq!(
            seen,
            (0..n as u32).collect::<Vec<_>>(),
            "{bodies} bodies: every triangle once"
        );
        // The tree from the GPU's own keys (`gpu_sorted`'s rule).
        let want = tree_from_gpu_keys(&bvh, &world, &i);
        let got = assert_packed(&bvh, &want, &format!("{bodies} bodies"));
        cref::check_bvh(&got, &world, &i).unwrap_or_else(|e| panic!("{bodies} bodies: {e}"));
    }
}

/// `lbvh.compact` after a planted tree (output poisoned): the compact nodes equal the
/// CPU's exactly, nothing written past them. Chains of 33, 65, 100 and 254 nodes
/// planted with their counts (5, 6, 7 and 8 jump rounds, the most a build records:
/// both halves of the turn-taking states; the deepest node of the first two exactly as
/// many steps below the root as the rounds span), each also cut by a leaf near its end
/// (nodes 61 to 98 of 100 inside that leaf, deeper than the rounds reach: not placed),
/// in preorder; a chain of 255 (`ORDER_H_MAX` deep: past what the rounds reach) keeps
/// every node in its slot, as does a chain planted without counts (a plant of too few
/// nodes or counts is refused).
/// A builder whose fit climbs in lockstep leaves the same counts as the free climb
/// (both equal to the CPU's).
#[test]
fn compact_order_is_preorder_or_the_slots() {
    use speculum::gpu_types::{bvh_leaf_link, TraversalNode};
    let ctx = common::context();
    let free = LbvhBuilder::new(&ctx).unwrap();
    let lockstep = LbvhBuilder::with_fit(&ctx, true).unwrap();
    for m in [33u32, 65, 100, 254, 255] {
        let (v, i) = random_soup(m as usize + 1, 1.0, default_size(1000), u64::from(m));
        let g = upload(&ctx, &v, &i);
        for layout in StaticLayout::ALL {
            let bvh = build_in(&ctx, &free, &g, MortonBits::Bits30, layout);
            let built = bvh.read_packed().unwrap().nodes;
            let slots = layout.slots();
            let root = built[0];
            let node = |c0, c1, parent| TraversalNode {
                child0: c0,
                child1: c1,
                parent,
                ..root
            };
            let link = |s: u32| if s == 0 { BVH_INVALID } else { (s - 1) << 1 | 1 };
            let chain: Vec<TraversalNode> = (0..m)
                .map(|s| match s + 1 == m {
                    true => node(bvh_leaf_link(s, 1), bvh_leaf_link(s + 1, 1), link(s)),
                    false => node(bvh_leaf_link(s, 1), s + 1, link(s)),
                })
                .collect();
            let mut cut = chain.clone();
            cut[60.min(m as usize - 2)].child1 = bvh_leaf_link(61, 2);
            for (name, nodes) in [("chain", &chain), ("cut chain", &cut)] {
                let what = format!("{name} of {m}, {layout:?}");
                let counts = cref::order_counts(nodes).expect("a chain is a tree");
                bvh.plant(nodes, Some(&counts)).unwrap();
                assert!(cref::compact_places(nodes, slots).is_some(), "{what}: ordered");
                let want = cref::compact_nodes(nodes, slots);
                // Only the whole chain of 255 keeps its slots (a binary chain's preorder
                // is its slots: the wide layouts tell them apart).
                let in_slots = (0..m).collect::<Vec<u32>>();
                let kept = want == cref::compact_nodes_placed(nodes, slots, &in_slots);
                let deep = m == ORDER_H_MAX && name == "chain";
                assert!(kept == deep || slots == 2, "{what}: in its slots {kept}");
                assert_written(&compact_poisoned(&ctx, &free, &bvh), &want, &what);
            }
            let in_slots: Vec<u32> = (0..m).collect();
            let counts = cref::order_counts(&chain).unwrap();
            assert!(bvh.plant(&chain[1..], None).is_err(), "a node short");
            assert!(bvh.plant(&chain, Some(&counts[1..])).is_err(), "a count short");
            bvh.plant(&chain, None).unwrap();
            assert_written(
                &compact_poisoned(&ctx, &free, &bvh),
                &cref::compact_nodes_placed(&chain, slots, &in_slots),
                &format!("chain of {m} without counts, {layout:?}"),
            );
            let stepped = build_in(&ctx, &lockstep, &g, MortonBits::Bits30, layout);
            let nodes = stepped.read_packed().unwrap().nodes;
            assert_eq!(nodes, built, "lockstep, {m}: the tree");
            assert_eq!(
                read_counts(&stepped),
                cref::order_counts(&nodes).unwrap(),
                "lockstep, {m}: counts"
            );
            assert_written(
                &compact_poisoned(&ctx, &lockstep, &stepped),
                &cref::compact_nodes(&nodes, slots),
                &format!("lockstep, {m}, {layout:?}"),
            );
        }
    }
    assert_eq!(ctx.validation_messages(), 0);
}

/// The order counts a build left (`Bvh::counts`), a node's each.
fn read_counts(bvh: &Bvh) -> Vec<[u32; 4]> {
    let nodes = (bvh.tri_count as usize - 1).max(1);
    bytemuck::pod_collect_to_vec::<u8, [u32; 4]>(&bvh.counts.read().unwrap())[..nodes].to_vec()
}
