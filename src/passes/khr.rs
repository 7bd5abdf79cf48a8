//! `as.*`: the vendor tracer's acceleration structures for a scene (`tracer = khr`).
//! Static geometry: one bottom level built once for fast tracing and compacted, the
//! triangles in the scene's order (primitive i is the scene's triangle i, which is
//! what a hit reports). The top level holds its one instance (mask 1, custom index 0).
//! CPU reference: `cpu_ref::trace::brute_force` (tests/suite/khr.rs), as for the LBVH.

use super::{Geometry, KhrTrace};
use crate::error::Result;
use crate::gpu_types::GpuVertex;
use crate::vk::accel::{self, Accel, Build, Scratch, Triangles};
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context};
use ash::vk;
use std::sync::Arc;

pub const BLAS_STATIC: &str = "as.static";
pub const TLAS: &str = "as.tlas";

/// Instance mask bits (glsl/shared/trace_khr.glsl): a trace given 0 triangles of a
/// kind skips the instances of that kind.
pub const MASK_STATIC: u8 = 1;
pub const MASK_DYNAMIC: u8 = 2;

/// A scene's acceleration structures.
pub struct KhrScene {
    static_blas: Option<Accel>,
    tlas: Accel,
    /// The top level's instances (kept: a build reads them).
    _instances: Buffer,
}

/// `g` as a build's triangles: positions are the first 12 bytes of each `GpuVertex`.
pub fn triangles<'a>(g: &Geometry<'a>) -> Triangles<'a> {
    let stride = std::mem::size_of::<GpuVertex>() as u64;
    Triangles {
        vertices: g.vertices,
        stride,
        vertex_count: (g.vertices.size / stride) as u32,
        indices: g.indices,
        tri_count: g.tri_count,
    }
}

const IDENTITY: [[f32; 4]; 3] = [[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]];

impl KhrScene {
    /// The structures of a static scene: its bottom level (built and compacted) and a
    /// top level over it, both built now.
    pub fn new_static(ctx: &Arc<Context>, geometry: &Geometry<'_>) -> Result<Self> {
        let blas = accel::static_blas(ctx, BLAS_STATIC, &triangles(geometry))?;
        let instances = [accel::instance(IDENTITY, 0, MASK_STATIC, blas.address)];
        let instance_buffer = Buffer::with_data(
            ctx,
            "as.instances",
            accel::INSTANCE_USAGE,
            &accel::instance_bytes(&instances),
        )?;
        let build = Build::instances(
            ctx,
            &instance_buffer,
            instances.len() as u32,
            vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE,
        )?;
        let tlas = build.create(ctx, TLAS)?;
        let scratch = Scratch::new(ctx, "as.tlas.scratch", build.sizes(ctx).build_scratch_size)?;
        ctx.one_shot(|cmd| {
            // RAW: the top level's build reads the bottom level built before (its own
            // submission) and the uploaded instances.
            barrier::global(&ctx.device, cmd, access::TRANSFER_WRITE, access::AS_BUILD_INPUT);
            build.record(ctx, cmd, &tlas, None, &scratch);
        })?;
        Ok(Self {
            static_blas: Some(blas),
            tlas,
            _instances: instance_buffer,
        })
    }

    /// What a trace through these structures binds.
    pub fn trace<'a>(
        &'a self,
        static_geometry: Option<Geometry<'a>>,
        dynamic_geometry: Option<Geometry<'a>>,
    ) -> KhrTrace<'a> {
        debug_assert_eq!(static_geometry.is_some(), self.static_blas.is_some());
        KhrTrace {
            tlas: &self.tlas,
            static_geometry,
            dynamic_geometry,
        }
    }
}
