//! The GPU's BVH walks replayed on the CPU (`walk_bvh` and `walk_wide` in
//! `glsl/shared/traverse.glsl`: the same order, nearest child first, the same pushes),
//! counting what one ray's walk does: the steps (nodes visited), the boxes and the
//! triangles it tests. These are figures of a tree and a layout, the same on every
//! device: where two trees' walks differ in speed on a device but not in these counts,
//! the difference is the device's (memory order, divergence), not the tree's. The
//! replay tests the exact boxes; the GPU's static walk tests them rounded outward to a
//! 16-bit grid, and may enter a few more.

use super::lbvh::{wide8_entries, wide_entries};
use super::trace::intersect;
use crate::gpu_types::{bvh_leaf, Hit, Ray, TraversalNode, TraversalTri};
use crate::shader_defines::{BVH_INVALID, WIDE8};
use glam::Vec3;

/// What one ray's walk did.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WalkCounts {
    /// Internal nodes visited (steps of the walk's loop).
    pub steps: u32,
    /// Child boxes tested.
    pub boxes: u32,
    /// Triangles tested.
    pub triangles: u32,
}

/// `box_entry`: where the ray enters [lo, hi] within (tmin, tmax), infinity if it
/// does not.
fn box_entry(lo: [f32; 3], hi: [f32; 3], o: Vec3, inv: Vec3, tmin: f32, tmax: f32) -> f32 {
    let t0 = (Vec3::from(lo) - o) * inv;
    let t1 = (Vec3::from(hi) - o) * inv;
    let enter = t0.min(t1).max_element().max(tmin);
    let exit = t0.max(t1).min_element().min(tmax);
    if enter <= exit {
        enter
    } else {
        f32::INFINITY
    }
}

/// One ray's closest hit through the tree `nodes` (triangles `tris` in leaf order),
/// walked as the binary walk (`slots` 2), the wide one (`slots` `WIDE`) or the
/// compressed wide one (`slots` `WIDE8`; exact boxes), and what the walk did.
pub fn replay(nodes: &[TraversalNode], tris: &[TraversalTri], ray: &Ray, slots: u32) -> (Hit, WalkCounts) {
    let o = Vec3::from(ray.origin);
    let d = Vec3::from(ray.dir);
    let inv = Vec3::ONE / Vec3::select(d.cmpeq(Vec3::ZERO), Vec3::splat(1e-30), d);
    let mut best = Hit {
        t: ray.tmax,
        prim: BVH_INVALID,
        u: 0.0,
        v: 0.0,
    };
    let mut counts = WalkCounts::default();
    let leaf = |link: u32, best: &mut Hit, counts: &mut WalkCounts| {
        let (first, count) = bvh_leaf(link).expect("a leaf link");
        for t in &tris[first as usize..(first + count) as usize] {
            counts.triangles += 1;
            let corners = [Vec3::from(t.a), Vec3::from(t.b), Vec3::from(t.c)];
            if let Some((th, u, v)) = intersect(ray, &corners) {
                let closer = th < best.t || (th == best.t && t.id < best.prim);
                if th > ray.tmin && closer {
                    *best = Hit {
                        t: th,
                        prim: t.id,
                        u,
                        v,
                    };
                }
            }
        }
    };
    let mut stack: Vec<u32> = Vec::new();
    let mut node = 0u32;
    loop {
        counts.steps += 1;
        // The node's children: (box entry, link), as the walk tests them.
        let children: Vec<([f32; 3], [f32; 3], u32)> = match slots {
            2 => {
                let n = &nodes[node as usize];
                vec![(n.lo0, n.hi0, n.child0), (n.lo1, n.hi1, n.child1)]
            }
            WIDE8 => wide8_entries(nodes, node as usize),
            _ => wide_entries(nodes, node as usize),
        };
        let mut t: Vec<(f32, u32)> = children
            .iter()
            .map(|&(lo, hi, link)| {
                counts.boxes += 1;
                (box_entry(lo, hi, o, inv, ray.tmin, best.t), link)
            })
            .collect();
        for e in t.iter_mut() {
            if e.0 != f32::INFINITY && bvh_leaf(e.1).is_some() {
                leaf(e.1, &mut best, &mut counts);
                e.0 = f32::INFINITY;
            }
        }
        let next = match slots {
            2 => binary_next(&t, &mut stack),
            WIDE8 => wide8_next(t, best.t, &mut stack),
            _ => wide_next(t, best.t, &mut stack),
        };
        if let Some(next) = next {
            node = next;
            continue;
        }
        match stack.pop() {
            Some(next) => node = next,
            None => break,
        }
    }
    (best, counts)
}

/// `walk_bvh`'s choice after a node's leaves: the nearer of the entered internal
/// children (the other pushed), or `None` to pop.
fn binary_next(t: &[(f32, u32)], stack: &mut Vec<u32>) -> Option<u32> {
    let ((t0, c0), (t1, c1)) = (t[0], t[1]);
    match (t0 != f32::INFINITY, t1 != f32::INFINITY) {
        (true, true) => {
            let (near, far) = if t0 <= t1 { (c0, c1) } else { (c1, c0) };
            stack.push(far);
            Some(near)
        }
        (true, false) => Some(c0),
        (false, true) => Some(c1),
        (false, false) => None,
    }
}

/// `walk_wide`'s choice after a node's leaves: children entered beyond `best_t`
/// dropped, the rest ordered by its sorting network, all but the nearest pushed far
/// first; the nearest, or `None` to pop.
fn wide_next(mut t: Vec<(f32, u32)>, best_t: f32, stack: &mut Vec<u32>) -> Option<u32> {
    t.resize(crate::shader_defines::WIDE as usize, (f32::INFINITY, BVH_INVALID));
    for e in t.iter_mut() {
        if e.0 > best_t {
            e.0 = f32::INFINITY;
        }
    }
    order4(&mut t);
    if t[0].0 == f32::INFINITY {
        return None;
    }
    for k in (1..t.len()).rev() {
        if t[k].0 != f32::INFINITY {
            stack.push(t[k].1);
        }
    }
    Some(t[0].1)
}

/// Four children (entry distance, link) ordered by the walks' sorting network
/// (`WIDE_ORDER4`: a swap only where the later is strictly nearer).
fn order4(four: &mut [(f32, u32)]) {
    for (a, b) in [(0, 1), (2, 3), (0, 2), (1, 3), (1, 2)] {
        if four[b].0 < four[a].0 {
            four.swap(a, b);
        }
    }
}

/// `walk_wide8`'s choice after a node's leaves: children entered beyond `best_t`
/// dropped, each four ordered by `walk_wide`'s network, all but the nearest pushed far
/// first, the two fours merged from their far ends (ties: the second four's pushed
/// first); the nearest (ties: the first four's), or `None` to pop.
fn wide8_next(mut t: Vec<(f32, u32)>, best_t: f32, stack: &mut Vec<u32>) -> Option<u32> {
    t.resize(WIDE8 as usize, (f32::INFINITY, BVH_INVALID));
    for e in t.iter_mut() {
        if e.0 > best_t {
            e.0 = f32::INFINITY;
        }
    }
    for four in t.chunks_mut(4) {
        order4(four);
    }
    let (a, b) = t.split_at(4);
    let entered = |f: &[(f32, u32)]| f.iter().filter(|e| e.0 != f32::INFINITY).count();
    let (na, nb) = (entered(a), entered(b));
    if na + nb == 0 {
        return None;
    }
    let near_a = na > 0 && (nb == 0 || a[0].0 <= b[0].0);
    let (stop_a, stop_b) = if near_a { (1, 0) } else { (0, 1) };
    let (mut ia, mut ib) = (na, nb);
    while ia > stop_a || ib > stop_b {
        let take_a = ia > stop_a && (ib <= stop_b || a[ia - 1].0 > b[ib - 1].0);
        if take_a {
            ia -= 1;
            stack.push(a[ia].1);
        } else {
            ib -= 1;
            stack.push(b[ib].1);
        }
    }
    Some(if near_a { a[0].1 } else { b[0].1 })
}

/// The share of lanes busy when consecutive rays walk `width` at a time in lockstep, as
/// a SIMD group (lavapipe's 8 lanes, a GPU's warp of 32) runs a dispatch's consecutive
/// invocations: a group takes as many passes as its longest walk, so the share is the
/// steps walked over each group's size times its longest walk, summed over the groups
/// of `steps` (walk lengths in ray order). 1 when every group's walks are alike or
/// there are none.
pub fn lockstep_busy(steps: &[u32], width: usize) -> f64 {
    let (walked, passes) = steps.chunks(width.max(1)).fold((0u64, 0u64), |(w, p), group| {
        let longest = group.iter().copied().max().unwrap_or(0) as u64;
        (
            w + group.iter().map(|&s| s as u64).sum::<u64>(),
            p + longest * group.len() as u64,
        )
    });
    if passes == 0 {
        1.0
    } else {
        walked as f64 / passes as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cpu_ref::lbvh::{build, morton_keys, sort_pairs};
    use crate::cpu_ref::trace::brute_force;
    use crate::scene::soup::{default_size, random_soup};
    use rand::{Rng, SeedableRng};

    /// Both walks of an LBVH over a random soup find brute force's hits (ties aside),
    /// visit at most the tree's nodes, and the wide walk takes about half the steps for
    /// four box tests a step; a miss far from the scene takes one step and no triangle.
    #[test]
    fn every_replay_finds_brute_force_hits_and_counts_its_work() {
        let n = 2000;
        let (v, i) = random_soup(n, 1.0, default_size(n), 5);
        let keys = morton_keys(&v, &i, 1);
        let (keys, values) = sort_pairs(&keys, &(0..n as u32).collect::<Vec<_>>());
        let bvh = build(&keys, &values, &v, &i);
        let mut rng = rand::rngs::StdRng::seed_from_u64(6);
        let mut r = || {
            Vec3::new(
                rng.random_range(-1.5..1.5),
                rng.random_range(-1.5..1.5),
                rng.random_range(-1.5..1.5),
            )
        };
        let rays: Vec<Ray> = (0..500).map(|_| Ray::through(r() * 2.0, r() * 0.5)).collect();
        let mut totals = [WalkCounts::default(); 3];
        let mut ties = 0;
        for ray in &rays {
            let want = brute_force(ray, &v, &i);
            for (k, slots) in [2, crate::shader_defines::WIDE, WIDE8].into_iter().enumerate() {
                let (hit, c) = replay(&bvh.nodes, &bvh.tris, ray, slots);
                assert_eq!(hit.t, want.t, "slots {slots}");
                ties += (hit.prim != want.prim) as u32;
                assert!((c.steps as usize) < n && c.boxes >= 2 * c.steps);
                totals[k].steps += c.steps;
                totals[k].boxes += c.boxes;
                totals[k].triangles += c.triangles;
            }
        }
        assert!(ties <= 2, "{ties} ties");
        let [binary, wide, wide8] = totals;
        // Two levels a step: about half the steps, as many boxes (four a step); three
        // levels: about a third.
        assert!(
            2 * wide.steps < 3 * binary.steps && wide.boxes < 2 * binary.boxes,
            "{binary:?} {wide:?}"
        );
        assert!(
            2 * wide8.steps < binary.steps && wide8.boxes < 3 * binary.boxes,
            "{binary:?} {wide8:?}"
        );
        assert!(binary.triangles > 0 && wide.triangles > 0 && wide8.triangles > 0);
        let away = Ray {
            origin: [10.0, 10.0, 10.0],
            tmin: 0.0,
            dir: [1.0, 0.0, 0.0],
            tmax: f32::MAX,
        };
        for slots in [2, crate::shader_defines::WIDE, WIDE8] {
            let (hit, c) = replay(&bvh.nodes, &bvh.tris, &away, slots);
            assert_eq!((hit.prim, c.steps, c.triangles), (BVH_INVALID, 1, 0));
        }
    }

    /// The lockstep share on walks of known lengths: alike walks keep every lane busy,
    /// one long walk in a group idles the rest, and a wider group never does better.
    #[test]
    fn lockstep_busy_counts_the_idle_lanes() {
        assert_eq!(lockstep_busy(&[5; 64], 8), 1.0);
        assert_eq!(lockstep_busy(&[], 32), 1.0);
        // A group of 8: one walk of 9 steps, seven of 1: 16 of 72 lane passes busy.
        let mut steps = vec![1; 16];
        steps[3] = 9;
        assert_eq!(lockstep_busy(&steps, 8), (16.0 + 8.0) / (72.0 + 8.0));
        assert_eq!(lockstep_busy(&steps, 16), 24.0 / 144.0);
        // A partial last group counts only its lanes.
        assert_eq!(lockstep_busy(&[2, 2, 2, 1, 3], 4), 10.0 / (8.0 + 3.0));
        let mut rng = rand::rngs::StdRng::seed_from_u64(9);
        let random: Vec<u32> = (0..320).map(|_| rng.random_range(1..100)).collect();
        let (b8, b32) = (lockstep_busy(&random, 8), lockstep_busy(&random, 32));
        assert!(0.0 < b32 && b32 <= b8 && b8 < 1.0, "{b8} {b32}");
    }
}
