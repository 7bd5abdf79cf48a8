//! `as.*`: the vendor tracer's acceleration structures for a scene (`tracer = khr`),
//! the vendor's way (the method's OptiX counterpart):
//! - static geometry: one bottom level built once for fast tracing and compacted, its
//!   triangles handed to the driver in `StaticOrder` (Morton by default: a driver that
//!   splits the primitive range at its middle, as lavapipe's does, builds a tree only
//!   as good as that order) with a permutation back to the scene's triangle ids;
//! - rigid bodies: one bottom level per body shape, built once in the shape's own
//!   space and compacted; every body is an instance of its shape's, placed by its pose;
//! - cloth: one bottom level over the cloths' world-space triangles, built with
//!   `ALLOW_UPDATE`, updated every frame (`as.cloth`) and rebuilt on `DynamicBvh`'s
//!   refit schedule (every `refit_rebuild_every` frames; every frame with
//!   `cloth_rebuild`): an update keeps the tree's topology as a refit does, so it
//!   loosens the same way;
//! - the top level (`as.tlas`): the static instance, the cloth's and one per body,
//!   rebuilt every frame a dynamic scene moves, from the poses the host stepped (no
//!   triangle is rebuilt); a static scene's is built once.
//!
//! Instances carry the geometry's kind in their mask (`MASK_*`) and the first triangle
//! of their bottom level in the geometry's numbering in their custom index
//! (`glsl/shared/hit.glsl`), so a hit reports the triangle ids the LBVH reports.
//! CPU reference: `cpu_ref::trace::brute_force` (tests/suite/khr.rs), as for the LBVH.

use super::{Geometry, KhrTrace};
use crate::error::Result;
use crate::gpu_types::GpuVertex;
use crate::vk::accel::{self, Accel, Build, Scratch, Triangles};
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, GpuTimer};
use ash::vk;
use glam::Mat4;
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

pub const BLAS_STATIC: &str = "as.static";
/// Timer scope of the cloth's bottom-level update or rebuild.
pub const CLOTH: &str = "as.cloth";
/// Timer scope of the top level's rebuild.
pub const TLAS: &str = "as.tlas";
/// The per-frame scopes, in order.
pub const SCOPES: [&str; 2] = [CLOTH, TLAS];

/// Instance mask bits (glsl/shared/trace_khr.glsl): a trace given 0 triangles of a
/// kind skips the instances of that kind.
pub const MASK_STATIC: u8 = 1;
pub const MASK_DYNAMIC: u8 = 2;
/// `KHR_DYNAMIC_INSTANCE` and the largest first triangle a custom index holds.
const DYNAMIC_INSTANCE: u32 = 0x80_0000;
const MAX_FIRST_TRIANGLE: u32 = 0x7f_ffff;

/// The order the static triangles are handed to the driver in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StaticOrder {
    /// The scene's own (its files').
    File,
    /// By the 63-bit Morton code of each triangle's centroid in the centroids' box:
    /// spatially coherent whatever the file's order.
    Morton,
}

impl StaticOrder {
    pub fn name(self) -> &'static str {
        match self {
            StaticOrder::File => "file",
            StaticOrder::Morton => "morton",
        }
    }

    /// The bottom level's triangles as scene triangle ids, in this order.
    pub fn permutation(self, vertices: &[GpuVertex], indices: &[u32]) -> Vec<u32> {
        let n = (indices.len() / 3) as u32;
        match self {
            StaticOrder::File => (0..n).collect(),
            StaticOrder::Morton => {
                let centroid = |t: usize| {
                    let p = |k: usize| glam::Vec3::from(vertices[indices[3 * t + k] as usize].position);
                    (p(0) + p(1) + p(2)) / 3.0
                };
                let centroids: Vec<glam::Vec3> = (0..n as usize).map(centroid).collect();
                let lo = centroids.iter().fold(glam::Vec3::INFINITY, |a, &c| a.min(c));
                let hi = centroids.iter().fold(glam::Vec3::NEG_INFINITY, |a, &c| a.max(c));
                let scale = ((1u32 << 21) - 1) as f32 / (hi - lo).max(glam::Vec3::splat(f32::MIN_POSITIVE));
                let keys: Vec<u64> = centroids
                    .iter()
                    .map(|&c| {
                        let q = ((c - lo) * scale).as_uvec3();
                        spread21(q.x) << 2 | spread21(q.y) << 1 | spread21(q.z)
                    })
                    .collect();
                let mut perm: Vec<u32> = (0..n).collect();
                perm.sort_by_key(|&t| keys[t as usize]); // stable: equal keys keep file order
                perm
            }
        }
    }
}

/// The low 21 bits of `v`, each moved to every third bit (a Morton code's one axis).
fn spread21(v: u32) -> u64 {
    let mut x = (v & 0x1f_ffff) as u64;
    x = (x | x << 32) & 0x001f_0000_0000_ffff;
    x = (x | x << 16) & 0x001f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

/// The static triangles as the vendor tracer builds them: their geometry on the GPU,
/// and (made on the host) the order to hand them over in.
pub struct StaticInput<'a> {
    pub geometry: Geometry<'a>,
    /// Each bottom-level primitive's scene triangle id (`StaticOrder::permutation`).
    pub perm: Vec<u32>,
    /// The scene's indices, three per primitive, in that order.
    pub ordered: Vec<u32>,
}

impl<'a> StaticInput<'a> {
    /// `geometry`, whose triangles are `vertices` and `indices` on the host, in `order`.
    pub fn new(geometry: Geometry<'a>, vertices: &[GpuVertex], indices: &[u32], order: StaticOrder) -> Self {
        let perm = order.permutation(vertices, indices);
        let ordered = perm
            .iter()
            .flat_map(|&t| indices[3 * t as usize..3 * t as usize + 3].iter().copied())
            .collect();
        Self {
            geometry,
            perm,
            ordered,
        }
    }
}

/// One rigid body: its triangles in the dynamic numbering and the body whose shape
/// (the same object-space triangles) it shares; a body is its own shape's first.
#[derive(Clone, Copy, Debug)]
pub struct BodyRange {
    pub first_tri: u32,
    pub tris: u32,
    pub shape_of: u32,
}

/// The moving geometry as the vendor tracer builds it.
pub struct DynamicLayout<'a> {
    /// The bodies' vertices in their own spaces (`GpuVertex`) and their count.
    pub objects: &'a Buffer,
    pub object_vertices: u32,
    /// The world-space vertices `sim.*` write, and the dynamic indices.
    pub world: Geometry<'a>,
    pub bodies: Vec<BodyRange>,
    /// The cloths' triangles (after the bodies'): first and count.
    pub cloth: Option<(u32, u32)>,
    /// Rebuild the cloth's bottom level every this many frames (1: every frame).
    pub rebuild_every: u32,
}

/// The cloth's bottom level and its schedule.
struct ClothAccel {
    blas: Accel,
    scratch: Scratch,
    range: (u32, u32),
    rebuild_every: u32,
    /// Updates since the last build; `None`: never built (the next frame builds).
    updates: Option<u32>,
}

/// A scene's acceleration structures.
pub struct KhrScene {
    ctx: Arc<Context>,
    static_blas: Option<Accel>,
    /// The static triangles' indices in the bottom level's order, and each primitive's
    /// scene triangle id (what `trace_khr.glsl` maps a static hit back through).
    _static_indices: Buffer,
    static_perm: Buffer,
    /// One per distinct body shape, and each body's (first triangle, shape's index).
    shapes: Vec<Accel>,
    bodies: Vec<(u32, usize)>,
    cloth: Option<ClothAccel>,
    tlas: Accel,
    tlas_scratch: Scratch,
    /// The top level's instances, one buffer per frame slot (the host writes a slot's
    /// while another frame in flight reads its own).
    instances: Vec<Buffer>,
    instance_count: u32,
    static_tris: u32,
}

/// Triangles `first..first + count` over `vertices` (`vertex_count` `GpuVertex`es, whose
/// positions are their first 12 bytes) and `indices`, as a build's input.
pub fn triangles<'a>(
    vertices: &'a Buffer,
    vertex_count: u32,
    indices: &'a Buffer,
    (first, count): (u32, u32),
) -> Triangles<'a> {
    Triangles {
        vertices,
        stride: std::mem::size_of::<GpuVertex>() as u64,
        vertex_count,
        indices,
        index_offset: 12 * first as u64,
        tri_count: count,
    }
}

fn vertex_count(g: &Geometry<'_>) -> u32 {
    (g.vertices.size / std::mem::size_of::<GpuVertex>() as u64) as u32
}

/// A pose as an instance's 3x4 row-major transform.
fn rows(m: &Mat4) -> [[f32; 4]; 3] {
    let r = |i: usize| m.row(i).to_array();
    [r(0), r(1), r(2)]
}

impl KhrScene {
    /// The structures of a scene: the static triangles' and the bodies' shapes' bottom
    /// levels built and compacted now, the cloth's built on the first frame, and the
    /// top level built now with the bodies at `poses`.
    pub fn new(
        ctx: &Arc<Context>,
        input: &StaticInput<'_>,
        dynamic: Option<&DynamicLayout<'_>>,
        poses: &[Mat4],
    ) -> Result<Self> {
        let g = &input.geometry;
        let static_tris = g.tri_count;
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER | accel::input_usage(ctx);
        let ordered = bytemuck::cast_slice(&input.ordered);
        let static_indices = Buffer::with_data(ctx, "as.static.indices", usage, ordered)?;
        let static_perm = Buffer::with_data(ctx, "as.static.perm", usage, bytemuck::cast_slice(&input.perm))?;
        let static_blas = (static_tris > 0)
            .then(|| {
                let t = triangles(g.vertices, vertex_count(g), &static_indices, (0, static_tris));
                accel::static_blas(ctx, BLAS_STATIC, &t)
            })
            .transpose()?;
        let (mut shapes, mut bodies, mut cloth) = (Vec::new(), Vec::new(), None);
        if let Some(d) = dynamic {
            let firsts = d.bodies.iter().map(|b| b.first_tri).chain(d.cloth.map(|c| c.0));
            let what = || "a moving bottom level's first triangle, in an instance's custom index".to_string();
            let last = firsts.max().unwrap_or(0) as u64;
            ctx.check_limit(what, last, "as its id", "23 bits", MAX_FIRST_TRIANGLE as u64)?;
            let mut shape_index = vec![usize::MAX; d.bodies.len()];
            for (i, b) in d.bodies.iter().enumerate() {
                if b.shape_of as usize == i {
                    let t = triangles(d.objects, d.object_vertices, d.world.indices, (b.first_tri, b.tris));
                    shapes.push(accel::static_blas(ctx, &format!("as.shape{}", shapes.len()), &t)?);
                    shape_index[i] = shapes.len() - 1;
                }
                bodies.push((b.first_tri, shape_index[b.shape_of as usize]));
            }
            if let Some(range) = d.cloth {
                cloth = Some(ClothAccel::new(ctx, d, range)?);
            }
        }
        let instance_count = static_blas.is_some() as u32 + cloth.is_some() as u32 + bodies.len() as u32;
        let instances = vec![Self::instance_buffer(ctx, instance_count)?];
        let build = Build::instances(ctx, &instances[0], instance_count, tlas_flags())?;
        let tlas = build.create(ctx, TLAS)?;
        let tlas_scratch = Scratch::new(ctx, "as.tlas.scratch", build.sizes(ctx).build_scratch_size)?;
        let mut scene = Self {
            ctx: ctx.clone(),
            static_blas,
            _static_indices: static_indices,
            static_perm,
            shapes,
            bodies,
            cloth,
            tlas,
            tlas_scratch,
            instances,
            instance_count,
            static_tris,
        };
        // The first top level (the cloth's instance, if any, stays inactive until its
        // first build, in a frame that rebuilds the top level too).
        scene.write_instances(0, poses);
        ctx.one_shot(|cmd| {
            // RAW: the build reads the bottom levels built and the instances written before.
            barrier::global(&ctx.device, cmd, access::ALL_READ_WRITE, access::AS_BUILD);
            scene.record_tlas(cmd, 0);
        })?;
        Ok(scene)
    }

    /// The structures of a static scene (no bodies, no cloth).
    pub fn new_static(ctx: &Arc<Context>, input: &StaticInput<'_>) -> Result<Self> {
        Self::new(ctx, input, None, &[])
    }

    fn instance_buffer(ctx: &Arc<Context>, count: u32) -> Result<Buffer> {
        let size = count.max(1) as u64 * std::mem::size_of::<vk::AccelerationStructureInstanceKHR>() as u64;
        Buffer::unbound(
            ctx,
            "as.instances",
            size,
            accel::INSTANCE_USAGE,
            MemoryLocation::CpuToGpu,
        )
    }

    /// Frame slots (one instance buffer each); the GPU must be idle.
    pub fn set_slots(&mut self, n: usize) -> Result<()> {
        self.instances.truncate(n.max(1));
        while self.instances.len() < n {
            self.instances
                .push(Self::instance_buffer(&self.ctx, self.instance_count)?);
        }
        Ok(())
    }

    /// Writes the instances of the frame recorded with `slot` (whose previous frame has
    /// finished): the static geometry's, the cloth's, the bodies' at `poses`.
    fn write_instances(&mut self, slot: usize, poses: &[Mat4]) {
        const IDENTITY: [[f32; 4]; 3] = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];
        let mut list = Vec::with_capacity(self.instance_count as usize);
        if let Some(s) = &self.static_blas {
            list.push(accel::instance(IDENTITY, 0, MASK_STATIC, s.address));
        }
        if let Some(c) = &self.cloth {
            // Not built yet: an instance of address 0 is inactive.
            let blas = if c.updates.is_some() { c.blas.address } else { 0 };
            list.push(accel::instance(
                IDENTITY,
                DYNAMIC_INSTANCE | c.range.0,
                MASK_DYNAMIC,
                blas,
            ));
        }
        for (&(first, shape), pose) in self.bodies.iter().zip(poses) {
            let blas = self.shapes[shape].address;
            list.push(accel::instance(
                rows(pose),
                DYNAMIC_INSTANCE | first,
                MASK_DYNAMIC,
                blas,
            ));
        }
        let bytes = accel::instance_bytes(&list);
        self.instances[slot].mapped_mut().expect("CpuToGpu is mapped")[..bytes.len()].copy_from_slice(&bytes);
    }

    fn record_tlas(&self, cmd: vk::CommandBuffer, slot: usize) {
        let build = Build::instances(&self.ctx, &self.instances[slot], self.instance_count, tlas_flags())
            .expect("checked when the scene was made");
        build.record(&self.ctx, cmd, &self.tlas, None, &self.tlas_scratch);
    }

    /// Records a moving scene's frame of structures with `slot` (whose previous frame
    /// has finished): the cloth's bottom level updated or rebuilt from `world` (the
    /// vertices `sim.cloth` just wrote), then the top level rebuilt with the bodies at
    /// `poses`. The top level ends visible to ray tracing.
    pub fn record_frame(
        &mut self,
        cmd: vk::CommandBuffer,
        timer: &mut GpuTimer,
        slot: usize,
        poses: &[Mat4],
        world: &Geometry<'_>,
    ) {
        let ctx = self.ctx.clone();
        let d = &ctx.device;
        // WAR: the previous frame's rays are done with the structures rebuilt here; RAW:
        // the simulation's vertices before the build reads them.
        barrier::global(d, cmd, access::ALL_READ_WRITE, access::AS_BUILD);
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::AS_BUILD_INPUT);
        if let Some(c) = &mut self.cloth {
            c.record(&ctx, cmd, timer, world);
            // RAW: the top level's build reads the cloth's bottom level.
            barrier::global(d, cmd, access::AS_BUILD, access::AS_BUILD);
        }
        self.write_instances(slot, poses);
        timer.scope(cmd, TLAS, || self.record_tlas(cmd, slot));
        // RAW: the rays read the top level.
        barrier::global(d, cmd, access::AS_BUILD, access::RT_ANY);
    }

    /// Back to the initial state: the cloth's bottom level is rebuilt next frame.
    pub fn reset(&mut self) {
        if let Some(c) = &mut self.cloth {
            c.updates = None;
        }
    }

    /// What a trace through these structures binds.
    pub fn trace<'a>(&'a self, static_geometry: Geometry<'a>, dynamic_geometry: Option<Geometry<'a>>) -> KhrTrace<'a> {
        debug_assert_eq!(static_geometry.tri_count, self.static_tris);
        KhrTrace {
            tlas: &self.tlas,
            static_perm: &self.static_perm,
            static_geometry: (self.static_tris > 0).then_some(static_geometry),
            dynamic_geometry,
        }
    }
}

impl ClothAccel {
    fn new(ctx: &Arc<Context>, d: &DynamicLayout<'_>, range: (u32, u32)) -> Result<Self> {
        let t = triangles(d.world.vertices, vertex_count(&d.world), d.world.indices, range);
        let build = Build::triangles(ctx, &t, cloth_flags())?;
        let sizes = build.sizes(ctx);
        let scratch = sizes.build_scratch_size.max(sizes.update_scratch_size);
        Ok(Self {
            blas: build.create(ctx, CLOTH)?,
            scratch: Scratch::new(ctx, "as.cloth.scratch", scratch)?,
            range,
            rebuild_every: d.rebuild_every.max(1),
            updates: None,
        })
    }

    /// Records this frame's update of the bottom level, or its rebuild when it was
    /// never built or has been updated `rebuild_every - 1` times.
    fn record(&mut self, ctx: &Context, cmd: vk::CommandBuffer, timer: &mut GpuTimer, world: &Geometry<'_>) {
        let t = triangles(world.vertices, vertex_count(world), world.indices, self.range);
        let build = Build::triangles(ctx, &t, cloth_flags()).expect("checked when the scene was made");
        let update = self.updates.is_some_and(|u| u + 1 < self.rebuild_every);
        timer.scope(cmd, CLOTH, || {
            build.record(ctx, cmd, &self.blas, update.then_some(&self.blas), &self.scratch)
        });
        self.updates = Some(if update { self.updates.unwrap_or(0) + 1 } else { 0 });
    }
}

fn cloth_flags() -> vk::BuildAccelerationStructureFlagsKHR {
    vk::BuildAccelerationStructureFlagsKHR::ALLOW_UPDATE | vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE
}

/// A top level rebuilt every frame: built fast.
fn tlas_flags() -> vk::BuildAccelerationStructureFlagsKHR {
    vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_BUILD
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Morton codes interleave x, y, z from the top; the order follows space.
    #[test]
    fn morton_order_interleaves_and_sorts_by_space() {
        assert_eq!(spread21(0b111), 0b1001001);
        assert_eq!(spread21(0x1f_ffff), 0x1249_2492_4924_9249);
        // Four unit triangles along x, given in scrambled order.
        let xs = [3.0f32, 0.0, 2.0, 1.0];
        let vertices: Vec<GpuVertex> = xs
            .iter()
            .flat_map(|&x| {
                [[x, 0.0, 0.0], [x + 0.1, 0.0, 0.0], [x, 0.1, 0.0]].map(|p| GpuVertex {
                    position: p,
                    material: 0,
                    normal: [0.0, 0.0, 1.0],
                    object: 0,
                })
            })
            .collect();
        let indices: Vec<u32> = (0..12).collect();
        assert_eq!(StaticOrder::Morton.permutation(&vertices, &indices), [1, 3, 2, 0]);
        assert_eq!(StaticOrder::File.permutation(&vertices, &indices), [0, 1, 2, 3]);
    }
}
