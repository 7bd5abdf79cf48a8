//! The rebuild of a BVH over rigid bodies: the keys `lbvh.fit` builds from, without
//! sorting the triangles. A rigid body's triangles keep their relative positions, so
//! their order by object-space Morton code (`RigidLayout`, computed once) stays a good
//! order for its subtree; only the bodies' order changes. Per frame:
//! `lbvh.bounds` (`lbvh_body_keys.comp`, one workgroup): each body's center in the
//! world, their bounds, each body's Morton code; `lbvh.sort` (`lbvh_body_ranks.comp`):
//! each body's rank by (code, index) and the first slot of its triangles;
//! `lbvh.morton` (`lbvh_rigid_keys.comp`): each triangle's key — the cell of its body's
//! center (the first `cell_bits` of the body's code), the body's rank, then the
//! triangle's object-space key — written at its slot, so the keys come out
//! sorted. Then `lbvh.fit` as for any build: the bodies' tree above, each body's
//! subtree below, the boxes from this frame's world-space vertices. The same tree
//! layout as a full build, refittable the same way.
//! CPU reference: `cpu_ref::lbvh::rigid_keys` (tests/suite/lbvh.rs).

use super::{Bvh, BOUNDS, MORTON, SORT};
use crate::aabb::{cells10, morton30, size_class, unit_in, Aabb};
use crate::error::{Error, Result};
use crate::gpu_types::{GpuVertex, RigidBody};
use crate::scene::Scene;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, GpuTimer, Groups, Pipeline, Resource, TexelView};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use std::sync::Arc;

/// Most bodies a rigid rebuild orders: their ranks and cells take at most 24 bits of
/// a key (`cell_bits`), leaving 8 for a triangle's object-space key.
pub const MAX_BODIES: u32 = 1 << 12;

/// Whether the dynamic BVH of `scene` gets the rigid rebuild (with `rigid_order` on):
/// its dynamic geometry is rigid bodies alone, 1 to `MAX_BODIES` of them.
pub fn applies(scene: &Scene, rigid_order: bool) -> bool {
    rigid_order
        && scene.cloths.is_empty()
        && scene.animated.is_none()
        && (1..=MAX_BODIES).contains(&(scene.bodies.len() as u32))
}

/// The bodies' object-space data a rigid rebuild needs, computed once.
#[derive(Clone, Debug, PartialEq)]
pub struct RigidLayout {
    /// Per body: its object-space box's center and its triangle count.
    pub bodies: Vec<RigidBody>,
    /// Per triangle (input order): [body, place in the body's order, object-space key, 0].
    /// A body's order is by (key, triangle index); the key is the triangle's size class
    /// against the body's box (2 bits) above the 30-bit Morton code of its centroid in
    /// the bounds of the body's centroids, as `lbvh.morton` codes a scene.
    pub tri_info: Vec<[u32; 4]>,
}

impl RigidLayout {
    /// The layout of `body_count` bodies whose object-space vertices carry their body in
    /// `object`; every triangle belongs to the body of its first vertex.
    pub fn new(vertices: &[GpuVertex], indices: &[u32], body_count: u32) -> Result<Self> {
        if body_count == 0 || body_count > MAX_BODIES {
            return Err(Error::Bvh(format!(
                "a rigid rebuild orders 1 to {MAX_BODIES} bodies, not {body_count}"
            )));
        }
        let tri_count = indices.len() / 3;
        let corners = |t: usize| [0, 1, 2].map(|k| Vec3::from(vertices[indices[3 * t + k] as usize].position));
        let mut members: Vec<Vec<u32>> = vec![Vec::new(); body_count as usize];
        for t in 0..tri_count {
            let body = vertices[indices[3 * t] as usize].object;
            if body >= body_count {
                return Err(Error::Bvh(format!("triangle {t} names body {body} of {body_count}")));
            }
            members[body as usize].push(t as u32);
        }
        let mut bodies = Vec::with_capacity(body_count as usize);
        let mut tri_info = vec![[0u32; 4]; tri_count];
        for (b, tris) in members.iter().enumerate() {
            let (centroids, boxes) = tris.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(c, s), &t| {
                let tri = corners(t as usize);
                (c.grow(centroid(&tri)), s.union(Aabb::of_triangle(&tri)))
            });
            let center = if tris.is_empty() {
                Vec3::ZERO
            } else {
                (boxes.lo + boxes.hi) * 0.5
            };
            bodies.push(RigidBody {
                center: center.to_array(),
                tri_count: tris.len() as u32,
            });
            let s2 = (boxes.hi - boxes.lo).length_squared();
            let mut keyed: Vec<(u32, u32)> = tris
                .iter()
                .map(|&t| {
                    let tri = corners(t as usize);
                    let b = Aabb::of_triangle(&tri);
                    let class = size_class((b.hi - b.lo).length_squared(), s2, 2);
                    let code = morton30(cells10(unit_in(centroid(&tri), centroids.lo, centroids.hi)));
                    ((class << 30) | code, t)
                })
                .collect();
            keyed.sort_unstable();
            for (place, &(key, t)) in keyed.iter().enumerate() {
                tri_info[t as usize] = [b as u32, place as u32, key, 0];
            }
        }
        Ok(Self { bodies, tri_info })
    }

    /// Bits that hold every body's rank (0 for one body).
    pub fn rank_bits(&self) -> u32 {
        rank_bits(self.bodies.len() as u32)
    }

    /// Bits of a body's Morton code above its rank in a key (`cell_bits`).
    pub fn cell_bits(&self) -> u32 {
        cell_bits(self.bodies.len() as u32)
    }
}

/// Bits that hold the ranks 0..bodies.
pub fn rank_bits(bodies: u32) -> u32 {
    if bodies <= 1 {
        0
    } else {
        32 - (bodies - 1).leading_zeros()
    }
}

/// Bits of a body's Morton code at the top of a key: whole axes' worth (a multiple of 3)
/// for at least as many cells as bodies, so the tree's top levels split space between
/// bodies, as a scene's LBVH does (ranks alone split the bodies' Morton order at its
/// median, whose halves' boxes overlap).
pub fn cell_bits(bodies: u32) -> u32 {
    3 * rank_bits(bodies).div_ceil(3)
}

fn centroid(tri: &[Vec3; 3]) -> Vec3 {
    (tri[0] + tri[1] + tri[2]) * (1.0 / 3.0)
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct BodyPush {
    body_count: u32,
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct KeysPush {
    tri_count: u32,
    rank_bits: u32,
    cell_bits: u32,
}

/// A rigid rebuild's buffers and kernels for one set of bodies.
pub struct RigidKeys {
    ctx: Arc<Context>,
    bodies: Buffer,
    /// The memory behind `tri_info_texels`.
    _tri_info: Buffer,
    tri_info_texels: TexelView,
    body_keys: Buffer,
    key_texels: TexelView,
    /// Every body's triangle count, as texels of 4 (the memory behind `count_texels`).
    _counts: Buffer,
    count_texels: TexelView,
    places: Buffer,
    place_texels: TexelView,
    /// The unit scale `lbvh.bounds` coded the bodies' centers with (3 floats).
    scale: Buffer,
    body_keys_kernel: Pipeline,
    ranks_kernel: Pipeline,
    keys_kernel: Pipeline,
    body_count: u32,
    tri_count: u32,
    rank_bits: u32,
    cell_bits: u32,
}

impl RigidKeys {
    pub fn new(ctx: &Arc<Context>, layout: &RigidLayout) -> Result<Self> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let texels = storage | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
        let body_count = layout.bodies.len() as u32;
        let tri_info = Buffer::with_data(ctx, "rigid.tri_info", texels, bytemuck::cast_slice(&layout.tri_info))?;
        // Codes and counts in whole texels of 4 (lbvh_body_ranks.comp reads 4 at a time).
        let padded = body_count.next_multiple_of(4) as usize;
        let mut counts: Vec<u32> = layout.bodies.iter().map(|b| b.tri_count).collect();
        counts.resize(padded, 0);
        let counts = Buffer::with_data(ctx, "rigid.counts", texels, bytemuck::cast_slice(&counts))?;
        let body_keys = Buffer::new(
            ctx,
            "rigid.body_keys",
            padded as u64 * 4,
            texels,
            gpu_allocator::MemoryLocation::GpuOnly,
        )?;
        let places = Buffer::new(
            ctx,
            "rigid.places",
            body_count as u64 * 16,
            texels,
            gpu_allocator::MemoryLocation::GpuOnly,
        )?;
        Ok(Self {
            ctx: ctx.clone(),
            bodies: Buffer::with_data(ctx, "rigid.bodies", storage, bytemuck::cast_slice(&layout.bodies))?,
            tri_info_texels: TexelView::new(ctx, &tri_info)?,
            _tri_info: tri_info,
            key_texels: TexelView::new(ctx, &body_keys)?,
            body_keys,
            count_texels: TexelView::new(ctx, &counts)?,
            _counts: counts,
            place_texels: TexelView::new(ctx, &places)?,
            places,
            scale: Buffer::new(
                ctx,
                "rigid.scale",
                12,
                storage | vk::BufferUsageFlags::TRANSFER_SRC,
                gpu_allocator::MemoryLocation::GpuOnly,
            )?,
            body_keys_kernel: Pipeline::compute::<BodyPush>(ctx, "lbvh.body_keys", shaders::LBVH_BODY_KEYS_COMP)?,
            ranks_kernel: Pipeline::compute::<BodyPush>(ctx, "lbvh.body_ranks", shaders::LBVH_BODY_RANKS_COMP)?,
            keys_kernel: Pipeline::compute::<KeysPush>(ctx, "lbvh.rigid_keys", shaders::LBVH_RIGID_KEYS_COMP)?,
            body_count,
            tri_count: layout.tri_info.len() as u32,
            rank_bits: layout.rank_bits(),
            cell_bits: layout.cell_bits(),
        })
    }

    /// The unit scale the last rebuild coded the bodies' centers with (the codes' one
    /// division, the GPU's own quotient), read back for the CPU reference.
    pub fn read_scale(&self) -> Result<Vec3> {
        Ok(Vec3::from_array(bytemuck::pod_read_unaligned(
            &self.scale.read()?[..12],
        )))
    }

    /// Records the keys and values of a rebuild under `poses` (one `Mat4` per body,
    /// visible to compute reads) into `bvh`'s sorted pairs (`sort.keys[0]`,
    /// `sort.values[0]`, one-word keys), each kernel under its scope; they end visible
    /// to compute reads (`lbvh.fit`).
    pub fn record(&self, cmd: vk::CommandBuffer, timer: &mut GpuTimer, poses: &Buffer, bvh: &Bvh) {
        assert_eq!(bvh.tri_count, self.tri_count, "BVH sized for another triangle count");
        assert_eq!(bvh.sort.key_words, 1, "a rigid rebuild writes one-word keys");
        let d = &self.ctx.device;
        let bodies = BodyPush {
            body_count: self.body_count,
        };
        // WAR: the previous rebuild's reads of the body keys, places and pairs are done.
        barrier::global(d, cmd, access::COMPUTE_READ, access::COMPUTE_WRITE);
        timer.begin(cmd, BOUNDS);
        self.body_keys_kernel.dispatch(
            cmd,
            &[
                ("bodies", Resource::Buffer(&self.bodies)),
                ("poses", Resource::Buffer(poses)),
                ("body_keys", Resource::Buffer(&self.body_keys)),
                ("scale", Resource::Buffer(&self.scale)),
            ],
            &bodies,
            Groups::Exact([1, 1, 1]),
        );
        timer.end(cmd, BOUNDS);
        // RAW: the ranks read every body's code.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ_WRITE);
        timer.begin(cmd, SORT);
        self.ranks_kernel.dispatch(
            cmd,
            &[
                ("counts", Resource::Texels(&self.count_texels)),
                ("body_keys", Resource::Texels(&self.key_texels)),
                ("places", Resource::Buffer(&self.places)),
            ],
            &bodies,
            Groups::Cover([self.body_count, 1, 1]),
        );
        timer.end(cmd, SORT);
        // RAW: the keys read the places.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ_WRITE);
        timer.begin(cmd, MORTON);
        self.keys_kernel.dispatch(
            cmd,
            &[
                ("tri_info", Resource::Texels(&self.tri_info_texels)),
                ("places", Resource::Texels(&self.place_texels)),
                ("keys", Resource::Buffer(&bvh.sort.keys[0])),
                ("values", Resource::Buffer(&bvh.sort.values[0])),
            ],
            &KeysPush {
                tri_count: self.tri_count,
                rank_bits: self.rank_bits,
                cell_bits: self.cell_bits,
            },
            Groups::Cover([self.tri_count, 1, 1]),
        );
        timer.end(cmd, MORTON);
        // RAW: the fit reads the pairs.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ_WRITE);
    }
}
