//! The triangles a BVH is built over: the scene's vertex and index buffers on the GPU,
//! and the texel views of them the kernels read.

use crate::error::Result;
use crate::gpu_types::GpuVertex;
use crate::vk::{Buffer, Context, TexelView};
use ash::vk;
use std::sync::Arc;

/// Triangles on the GPU: the scene's vertex and index buffers, and their texel views
/// (what the build kernels read the corners through).
#[derive(Clone, Copy)]
pub struct Geometry<'a> {
    pub vertices: &'a Buffer,
    pub indices: &'a Buffer,
    pub texels: &'a TriangleTexels,
    pub tri_count: u32,
}

/// The usage a vertex buffer needs for the BVH kernels (a storage buffer and a texel
/// buffer); its size is whole texels, as every vertex is 32 bytes.
pub const VERTEX_USAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::STORAGE_BUFFER.as_raw() | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER.as_raw(),
);

/// A mesh's vertex and index buffers as texels of uvec4 (bvh.glsl: TRIANGLE_CORNERS):
/// lavapipe fetches a texel for all lanes without a branch, where it loads a storage
/// buffer one lane and one word at a time, each behind a branch.
pub struct TriangleTexels {
    pub vertices: TexelView,
    pub indices: TexelView,
}

impl TriangleTexels {
    /// Views of `vertices` (made with `VERTEX_USAGE`) and `indices` (made by
    /// `index_buffer`).
    pub fn new(ctx: &Arc<Context>, vertices: &Buffer, indices: &Buffer) -> Result<Self> {
        Ok(Self {
            vertices: TexelView::new(ctx, vertices)?,
            indices: TexelView::new(ctx, indices)?,
        })
    }
}

/// Triangles uploaded for the BVH kernels and the traversal alone (benchmarks, tests):
/// the vertices, the padded indices and their texel views.
pub struct UploadedTriangles {
    pub vertices: Buffer,
    pub indices: Buffer,
    pub texels: TriangleTexels,
    pub tri_count: u32,
}

impl UploadedTriangles {
    pub fn new(ctx: &Arc<Context>, name: &str, vertices: &[GpuVertex], indices: &[u32]) -> Result<Self> {
        let v = Buffer::with_data(
            ctx,
            &format!("{name}.vertices"),
            VERTEX_USAGE | crate::vk::accel::input_usage(ctx),
            bytemuck::cast_slice(vertices),
        )?;
        let i = index_buffer(ctx, &format!("{name}.indices"), vk::BufferUsageFlags::empty(), indices)?;
        Ok(Self {
            texels: TriangleTexels::new(ctx, &v, &i)?,
            vertices: v,
            indices: i,
            tri_count: (indices.len() / 3) as u32,
        })
    }

    pub fn geometry(&self) -> Geometry<'_> {
        Geometry {
            vertices: &self.vertices,
            indices: &self.indices,
            texels: &self.texels,
            tri_count: self.tri_count,
        }
    }
}

/// An index buffer the BVH kernels can read: `indices` uploaded, padded to whole
/// texels of 4, with `usage` and the storage and texel usages.
pub fn index_buffer(ctx: &Arc<Context>, name: &str, usage: vk::BufferUsageFlags, indices: &[u32]) -> Result<Buffer> {
    let mut padded = indices.to_vec();
    padded.resize(indices.len().next_multiple_of(4).max(4), 0);
    let usage = usage | VERTEX_USAGE | crate::vk::accel::input_usage(ctx);
    Buffer::with_data(ctx, name, usage, bytemuck::cast_slice(&padded))
}
