//! The order of the static walk's nodes (`lbvh.compact`'s first steps,
//! `glsl/shared/bvh_order.glsl`): each node's place in preorder from the root, so a
//! walk going down reads the node after the one it left, and only the nodes a walk can
//! reach take room (binary: the internal nodes outside leaves; wide: those at an even
//! depth; compressed wide: at a depth divisible by three). Made on the GPU: the builders leave each node's subtree counts
//! (`Bvh::counts`, written bottom-up as they make the tree), then each node's place by
//! pointer jumping (`lbvh_order_init`, `lbvh_order_jump`), as many rounds as the tree's
//! height asks (indirect dispatches). CPU reference: `cpu_ref::lbvh::compact_places`.

use crate::error::Result;
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Groups, Pipeline, Resource, TexelView};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// Jump rounds recorded for `nodes` internal nodes: enough for the deepest tree they
/// can make that is put in preorder (`order_ordered` in `bvh_order.glsl`: a chain of
/// them, or a tree `ORDER_H_MAX - 1` deep), `order_rounds` of that height; a tree runs
/// the rounds its height needs, the rest dispatch nothing.
pub fn recorded_rounds(nodes: u32) -> u32 {
    order_rounds(nodes.min(crate::shader_defines::ORDER_H_MAX - 1))
}

/// `order_rounds` of `bvh_order.glsl`: the jump rounds a tree of height `h` needs.
fn order_rounds(h: u32) -> u32 {
    if h <= 2 {
        0
    } else {
        (h - 2).ilog2() + 1
    }
}

/// The order's scratch, beside the compact nodes: 32 bytes a node and the rounds'
/// indirect arguments.
pub struct OrderScratch {
    /// The jump states, read and written in turns.
    pub(super) jump: [Buffer; 2],
    /// The same, as the rounds and lbvh.compact read them (texels of uvec4).
    pub(super) jump_texels: [TexelView; 2],
    /// One `VkDispatchIndirectCommand` a recorded round, 16 bytes apart.
    args: Buffer,
}

impl OrderScratch {
    pub fn new(ctx: &Arc<Context>, nodes: u32) -> Result<Self> {
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let buf = |name: &str, bytes: u64, extra| {
            Buffer::new(ctx, name, bytes.max(16), usage | extra, MemoryLocation::GpuOnly)
        };
        let n = u64::from(nodes.max(1));
        let texels = vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
        let jump = [
            buf("lbvh.order.jump0", n * 16, texels)?,
            buf("lbvh.order.jump1", n * 16, texels)?,
        ];
        Ok(Self {
            jump_texels: [TexelView::new(ctx, &jump[0])?, TexelView::new(ctx, &jump[1])?],
            jump,
            args: buf(
                "lbvh.order.args",
                u64::from(recorded_rounds(nodes)) * 16,
                vk::BufferUsageFlags::INDIRECT_BUFFER,
            )?,
        })
    }
}

/// Push constants of `lbvh_order_jump.comp`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct JumpPush {
    node_count: u32,
    /// The layout's children a node (its depth phases).
    slots: u32,
}

/// Push constants of `lbvh_order_init.comp`.
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct InitPush {
    node_count: u32,
    slots: u32,
    rounds: u32,
}

/// The order's kernels.
pub struct OrderKernels {
    ctx: Arc<Context>,
    init: Pipeline,
    jump: Pipeline,
}

impl OrderKernels {
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        Ok(Self {
            ctx: ctx.clone(),
            init: Pipeline::compute::<InitPush>(ctx, "lbvh.order.init", shaders::LBVH_ORDER_INIT_COMP)?,
            jump: Pipeline::compute::<JumpPush>(ctx, "lbvh.order.jump", shaders::LBVH_ORDER_JUMP_COMP)?,
        })
    }

    /// Records the order of `node_count` binary nodes (`nodes`, their texels, and
    /// `counts`, the builder's, visible to compute reads) for a layout of `slots`
    /// children a node, into `s`; it ends visible to compute reads. Earlier reads of the
    /// scratch must be complete (caller's barrier, the indirect ones included).
    pub fn record(
        &self,
        cmd: vk::CommandBuffer,
        nodes: Resource<'_>,
        counts: &Buffer,
        node_count: u32,
        slots: u32,
        s: &OrderScratch,
    ) {
        let d = &self.ctx.device;
        let rounds = recorded_rounds(node_count);
        self.init.dispatch(
            cmd,
            &[
                ("nodes", nodes),
                ("counts", Resource::Buffer(counts)),
                ("jump", Resource::Buffer(&s.jump[0])),
                ("args", Resource::Buffer(&s.args)),
            ],
            &InitPush {
                node_count,
                slots,
                rounds,
            },
            Groups::Cover([node_count, 1, 1]),
        );
        for r in 0..rounds as usize {
            // RAW on the states just written (and the rounds' arguments), WAR on those
            // the round before read.
            barrier::global(d, cmd, access::COMPUTE_READ_WRITE, access::COMPUTE_ANY);
            self.jump.dispatch(
                cmd,
                &[
                    ("from_state", Resource::Texels(&s.jump_texels[r % 2])),
                    ("to", Resource::Buffer(&s.jump[(r + 1) % 2])),
                ],
                &JumpPush { node_count, slots },
                Groups::IndirectAt(&s.args, 16 * r as u64),
            );
        }
        // RAW: lbvh.compact reads the last states.
        barrier::global(d, cmd, access::COMPUTE_WRITE, access::COMPUTE_READ);
    }
}
