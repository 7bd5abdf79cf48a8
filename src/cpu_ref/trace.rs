//! Reference ray tracing: the watertight ray/triangle test of the GPU walk, brute force
//! over all triangles, and a binned-SAH BVH built on the CPU (Wald 2007, "On fast
//! Construction of SAH-based Bounding Volume Hierarchies") that serves both as the
//! quality yardstick for the LBVH and as a fast reference tracer.

use super::lbvh::{centroid, triangle, Aabb};
use crate::gpu_types::{GpuVertex, Hit, Ray};
use crate::shader_defines::BVH_INVALID;
use glam::Vec3;

/// The ray as the watertight test sees it (`TriRay` in `glsl/shared/traverse.glsl`):
/// origin and direction with the axes turned so the direction's largest component is z.
struct TriRay {
    o: [f32; 3],
    d: [f32; 3],
    kz: usize,
}

/// `turn_axes`: v.yzx for kz 0, v.zxy for kz 1, v for kz 2.
fn turn_axes(v: [f32; 3], kz: usize) -> [f32; 3] {
    [v[(kz + 1) % 3], v[(kz + 2) % 3], v[kz]]
}

impl TriRay {
    fn new(ray: &Ray) -> Self {
        let m = ray.dir.map(f32::abs);
        let kz = if m[0] >= m[1] {
            if m[0] >= m[2] {
                0
            } else {
                2
            }
        } else if m[1] >= m[2] {
            1
        } else {
            2
        };
        Self {
            o: turn_axes(ray.origin, kz),
            d: turn_axes(ray.dir, kz),
            kz,
        }
    }

    /// `tri_corner`: corner `v` relative to the origin, projected across the ray (x, y)
    /// and along its axis (z). Plain f32 mul and sub, each rounded once (Rust never
    /// fuses them), as the shader's `precise` ones.
    fn corner(&self, v: Vec3) -> [f32; 3] {
        let v = turn_axes(v.to_array(), self.kz);
        let p = [v[0] - self.o[0], v[1] - self.o[1], v[2] - self.o[2]];
        let d = self.d;
        [p[1] * d[2] - p[2] * d[1], p[2] * d[0] - p[0] * d[2], p[2]]
    }
}

/// The watertight ray/triangle test of `glsl/shared/traverse.glsl` (`tri_hit`: Woop,
/// Benthin & Wald 2013 without divisions), double-sided: Some((t, u, v)) when the ray
/// crosses the triangle or one of its edges or corners (t unbounded here; the caller
/// applies its interval). The edge functions are the GPU's bit for bit, so hit or miss
/// is exact on every device; t, u and v are one division each (within a few ULP of the
/// GPU's).
pub fn intersect(ray: &Ray, tri: &[Vec3; 3]) -> Option<(f32, f32, f32)> {
    let r = TriRay::new(ray);
    let (pa, pb, pc) = (r.corner(tri[0]), r.corner(tri[1]), r.corner(tri[2]));
    let eu = pc[0] * pb[1] - pc[1] * pb[0];
    let ev = pa[0] * pc[1] - pa[1] * pc[0];
    let ew = pb[0] * pa[1] - pb[1] * pa[0];
    if (eu < 0.0 || ev < 0.0 || ew < 0.0) && (eu > 0.0 || ev > 0.0 || ew > 0.0) {
        return None;
    }
    let det = eu + ev + ew;
    if det == 0.0 {
        return None;
    }
    let depth = eu * pa[2] + ev * pb[2] + ew * pc[2];
    let t = depth / (det * r.d[2]);
    Some((t, ev / det, ew / det))
}

/// Applies a candidate to the best hit with the kernel's rule: tmin < t, closer, equal t
/// going to the smaller id.
fn consider(best: &mut Hit, ray: &Ray, id: u32, cand: Option<(f32, f32, f32)>) {
    if let Some((t, u, v)) = cand {
        let closer = t < best.t || (t == best.t && id < best.prim);
        if t > ray.tmin && closer {
            *best = Hit { t, prim: id, u, v };
        }
    }
}

/// Closest hit by testing every triangle.
pub fn brute_force(ray: &Ray, vertices: &[GpuVertex], indices: &[u32]) -> Hit {
    let mut best = Hit {
        t: ray.tmax,
        prim: BVH_INVALID,
        u: 0.0,
        v: 0.0,
    };
    for t in 0..indices.len() / 3 {
        consider(
            &mut best,
            ray,
            t as u32,
            intersect(ray, &triangle(vertices, indices, t)),
        );
    }
    best
}

/// A node of the CPU BVH: leaves hold a range of `CpuBvh::prims`.
#[derive(Clone, Copy, Debug)]
pub struct CpuNode {
    pub bounds: Aabb,
    /// Internal: index of the left child (the right child follows it). Leaf: first prim.
    pub first: u32,
    /// 0 for internal nodes, else the number of triangles.
    pub count: u32,
}

/// A binned-SAH BVH over triangles.
pub struct CpuBvh {
    pub nodes: Vec<CpuNode>,
    pub prims: Vec<u32>,
}

const BINS: usize = 16;
/// Leaf size limit of the SAH builder (it may stop earlier when splitting costs more).
pub const MAX_LEAF: usize = 4;

impl CpuBvh {
    /// Builds with 16 bins per axis over centroid bounds; unit costs for a traversal
    /// step and a triangle test, as `sah_cost` evaluates.
    pub fn build(vertices: &[GpuVertex], indices: &[u32]) -> Self {
        let n = indices.len() / 3;
        let boxes: Vec<Aabb> = (0..n)
            .map(|t| Aabb::of_triangle(&triangle(vertices, indices, t)))
            .collect();
        let centers: Vec<Vec3> = (0..n).map(|t| centroid(&triangle(vertices, indices, t))).collect();
        let mut bvh = CpuBvh {
            nodes: Vec::with_capacity(2 * n),
            prims: (0..n as u32).collect(),
        };
        bvh.nodes.push(CpuNode {
            bounds: Aabb::EMPTY,
            first: 0,
            count: n as u32,
        });
        let mut work = vec![0usize];
        while let Some(ni) = work.pop() {
            let (first, count) = (bvh.nodes[ni].first as usize, bvh.nodes[ni].count as usize);
            let range = &mut bvh.prims[first..first + count];
            let bounds = range.iter().fold(Aabb::EMPTY, |b, &p| b.union(boxes[p as usize]));
            bvh.nodes[ni].bounds = bounds;
            if count <= 1 {
                continue;
            }
            let cb = range.iter().fold(Aabb::EMPTY, |b, &p| b.grow(centers[p as usize]));
            let best = best_split(range, &boxes, &centers, cb);
            let leaf_cost = bounds.area() * count as f32;
            let split_cost = best.map(|b| bounds.area() + b.0);
            let mid = match best {
                Some((_, axis, split)) if count > MAX_LEAF || split_cost.is_some_and(|c| c < leaf_cost) => {
                    let (lo, hi) = (cb.lo[axis], cb.hi[axis]);
                    let scale = BINS as f32 / (hi - lo);
                    let mut i = 0;
                    for j in 0..count {
                        let p = range[j];
                        if ((((centers[p as usize][axis] - lo) * scale) as usize).min(BINS - 1)) < split {
                            range.swap(i, j);
                            i += 1;
                        }
                    }
                    i
                }
                // All centroids equal: split the range in half if it is too big for a leaf.
                None if count > MAX_LEAF => count / 2,
                _ => continue,
            };
            let left = bvh.nodes.len();
            bvh.nodes[ni].first = left as u32;
            bvh.nodes[ni].count = 0;
            bvh.nodes.push(CpuNode {
                bounds: Aabb::EMPTY,
                first: first as u32,
                count: mid as u32,
            });
            bvh.nodes.push(CpuNode {
                bounds: Aabb::EMPTY,
                first: (first + mid) as u32,
                count: (count - mid) as u32,
            });
            work.push(left);
            work.push(left + 1);
        }
        bvh
    }

    /// SAH cost with unit traversal and triangle-test costs, relative to the root area:
    /// the same measure as `lbvh::sah_cost_nodes`.
    pub fn sah_cost(&self) -> f64 {
        let root = self.nodes[0].bounds.area() as f64;
        self.nodes
            .iter()
            .map(|n| n.bounds.area() as f64 / root * if n.count == 0 { 1.0 } else { n.count as f64 })
            .sum()
    }

    /// Closest hit, with the kernel's rules (same result as `brute_force`).
    pub fn trace(&self, ray: &Ray, vertices: &[GpuVertex], indices: &[u32]) -> Hit {
        let mut best = Hit {
            t: ray.tmax,
            prim: BVH_INVALID,
            u: 0.0,
            v: 0.0,
        };
        let (o, d) = (Vec3::from(ray.origin), Vec3::from(ray.dir));
        let inv = Vec3::ONE / Vec3::select(d.cmpeq(Vec3::ZERO), Vec3::splat(1e-30), d);
        let enters = |b: &Aabb, tmax: f32| {
            let t0 = (b.lo - o) * inv;
            let t1 = (b.hi - o) * inv;
            let enter = t0.min(t1).max_element().max(ray.tmin);
            let exit = t0.max(t1).min_element().min(tmax);
            enter <= exit
        };
        let mut stack = vec![0usize];
        while let Some(i) = stack.pop() {
            let n = &self.nodes[i];
            // `<=` on t: a triangle at exactly best.t may still win on a smaller id.
            if !enters(&n.bounds, best.t) {
                continue;
            }
            if n.count == 0 {
                stack.push(n.first as usize);
                stack.push(n.first as usize + 1);
            } else {
                for &p in &self.prims[n.first as usize..(n.first + n.count) as usize] {
                    consider(
                        &mut best,
                        ray,
                        p,
                        intersect(ray, &triangle(vertices, indices, p as usize)),
                    );
                }
            }
        }
        best
    }
}

/// The binned-SAH split of the triangles `range` whose centroids span `cb`: the best
/// (cost, axis, split bin) over all axes, `None` where every axis is flat.
fn best_split(range: &[u32], boxes: &[Aabb], centers: &[Vec3], cb: Aabb) -> Option<(f32, usize, usize)> {
    let mut best: Option<(f32, usize, usize)> = None;
    #[allow(clippy::needless_range_loop)] // `axis` indexes Vec3s, not one slice
    for axis in 0..3 {
        let (lo, hi) = (cb.lo[axis], cb.hi[axis]);
        if hi <= lo {
            continue;
        }
        let scale = BINS as f32 / (hi - lo);
        let bin_of = |p: u32| (((centers[p as usize][axis] - lo) * scale) as usize).min(BINS - 1);
        let mut bin_box = [Aabb::EMPTY; BINS];
        let mut bin_n = [0usize; BINS];
        for &p in range.iter() {
            let b = bin_of(p);
            bin_box[b] = bin_box[b].union(boxes[p as usize]);
            bin_n[b] += 1;
        }
        let mut right_area = [0f32; BINS];
        let mut right_n = [0usize; BINS];
        let (mut acc, mut acc_n) = (Aabb::EMPTY, 0);
        for b in (1..BINS).rev() {
            acc = acc.union(bin_box[b]);
            acc_n += bin_n[b];
            right_area[b] = acc.area();
            right_n[b] = acc_n;
        }
        let (mut acc, mut acc_n) = (Aabb::EMPTY, 0);
        for split in 1..BINS {
            acc = acc.union(bin_box[split - 1]);
            acc_n += bin_n[split - 1];
            if acc_n == 0 || right_n[split] == 0 {
                continue;
            }
            let cost = acc.area() * acc_n as f32 + right_area[split] * right_n[split] as f32;
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, split));
            }
        }
    }
    best
}
