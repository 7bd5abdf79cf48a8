//! `Bvh`: a tree's buffers on the GPU (nodes, triangles in leaf order, the static
//! walk's compact nodes, the sort's scratch), and the refit's schedule by height.

use super::sort::SortBuffers;
use super::{MortonBits, StaticLayout, MAX_TRIANGLES};
use crate::aabb::{ordered_to_float, Aabb};
use crate::error::{Error, Result};
use crate::gpu_types::{PackedBvh, TraversalNode, TraversalTri};
use crate::vk::{Buffer, Context, TexelView};
use ash::vk;
use glam::Vec3;
use gpu_allocator::MemoryLocation;
use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;

/// The static walk's nodes (`lbvh.compact`; `glsl/shared/bvh.glsl`): 2 + texels x
/// max(N-1, 1) texels of 16 bytes in `layout` (`StaticLayout::texels`), and the same as the walk reads them.
pub struct CompactNodes {
    pub buffer: Buffer,
    pub texels: TexelView,
    pub layout: StaticLayout,
    /// Where `lbvh.compact` puts each node (its scratch).
    pub order: super::order::OrderScratch,
}

impl CompactNodes {
    /// Memory for the static walk's nodes of a tree of `tri_count` triangles in
    /// `layout` (one node a binary node), and its order's scratch.
    pub fn new(ctx: &Arc<Context>, tri_count: u32, layout: StaticLayout) -> Result<Self> {
        let buffer = Buffer::new(
            ctx,
            "lbvh.compact",
            (2 + layout.texels() as u64 * (tri_count as u64 - 1).max(1)) * 16,
            vk::BufferUsageFlags::STORAGE_BUFFER
                | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER
                | vk::BufferUsageFlags::TRANSFER_DST
                | vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::GpuOnly,
        )?;
        Ok(Self {
            texels: TexelView::new(ctx, &buffer)?,
            buffer,
            layout,
            order: super::order::OrderScratch::new(ctx, (tri_count - 1).max(1))?,
        })
    }
}

/// A BVH on the GPU and the scratch memory to rebuild it.
pub struct Bvh {
    /// max(N-1, 1) `TraversalNode`s (written by the fit and the refit).
    pub tnodes: Buffer,
    /// N `TraversalTri`s, in leaf order.
    pub ttris: Buffer,
    /// `tnodes` and `ttris` as the traversal reads them (texel buffers).
    pub node_texels: TexelView,
    pub tri_texels: TexelView,
    /// The compact nodes the walk of the static BVH reads (`Bvh::new_static`; none for
    /// a BVH only ever walked as the dynamic one).
    pub compact: Option<CompactNodes>,
    /// Builds and refits recorded, and the count when `compact` was last recorded.
    pub(super) shaped: AtomicU32,
    pub(super) compacted: AtomicU32,
    /// The fit's swap word per internal node (the first child's outer end).
    pub(super) ends: Buffer,
    /// The fit's SAH cost of the subtree in each half of each node.
    pub(super) costs: Buffer,
    /// Each node's order counts (`glsl/shared/bvh_order.glsl`: a `uvec4` a node), which
    /// the builders write for a BVH with compact nodes and `lbvh.compact` reads; 16
    /// bytes, never written, for one without.
    pub counts: Buffer,
    pub(super) bounds: Buffer,
    pub sort: SortBuffers,
    pub tri_count: u32,
    pub bits: MortonBits,
}

impl Bvh {
    /// Memory for a BVH over `tri_count` triangles.
    pub fn new(ctx: &Arc<Context>, tri_count: u32, bits: MortonBits) -> Result<Self> {
        Self::alloc(ctx, tri_count, bits, false)
    }

    /// `new`'s memory, with room for every node's order counts where `ordered` (a BVH
    /// that will have compact nodes).
    fn alloc(ctx: &Arc<Context>, tri_count: u32, bits: MortonBits, ordered: bool) -> Result<Self> {
        if tri_count == 0 {
            return Err(Error::Bvh("a BVH needs at least one triangle".into()));
        }
        if tri_count > MAX_TRIANGLES {
            return Err(Error::Bvh(format!(
                "{tri_count} triangles exceed the LBVH limit of {MAX_TRIANGLES}"
            )));
        }
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let buf = |name: &str, bytes: u64| Buffer::new(ctx, name, bytes, usage, MemoryLocation::GpuOnly);
        // What the traversal reads, also as texel buffers (TexelView).
        let texels = |name: &str, bytes: u64| {
            Buffer::new(
                ctx,
                name,
                bytes,
                usage | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER,
                MemoryLocation::GpuOnly,
            )
        };
        let tnodes = texels(
            "lbvh.tnodes",
            (tri_count as u64 - 1).max(1) * std::mem::size_of::<TraversalNode>() as u64,
        )?;
        let ttris = texels(
            "lbvh.ttris",
            tri_count as u64 * std::mem::size_of::<TraversalTri>() as u64,
        )?;
        Ok(Self {
            node_texels: TexelView::new(ctx, &tnodes)?,
            tri_texels: TexelView::new(ctx, &ttris)?,
            compact: None,
            shaped: AtomicU32::new(1),
            compacted: AtomicU32::new(0),
            tnodes,
            ttris,
            ends: buf("lbvh.ends", (tri_count as u64 - 1).max(1) * 4)?,
            costs: buf("lbvh.costs", (tri_count as u64 - 1).max(1) * 2 * 4)?,
            counts: buf(
                "lbvh.order.counts",
                if ordered {
                    (tri_count as u64 - 1).max(1) * 16
                } else {
                    16
                },
            )?,
            bounds: buf("lbvh.bounds", 15 * 4)?,
            sort: SortBuffers::new(ctx, tri_count, bits.key_words())?,
            tri_count,
            bits,
        })
    }

    /// Memory for a BVH walked as the static one: `new` and its compact nodes, binary.
    pub fn new_static(ctx: &Arc<Context>, tri_count: u32, bits: MortonBits) -> Result<Self> {
        Self::new_static_in(ctx, tri_count, bits, StaticLayout::Binary)
    }

    /// `new_static` with the walk's nodes in `layout`.
    pub fn new_static_in(ctx: &Arc<Context>, tri_count: u32, bits: MortonBits, layout: StaticLayout) -> Result<Self> {
        let mut bvh = Self::alloc(ctx, tri_count, bits, true)?;
        bvh.compact = Some(CompactNodes::new(ctx, tri_count, layout)?);
        Ok(bvh)
    }

    /// Puts `nodes` in place of the static walk's nodes and returns those it had (a
    /// static BVH's: `new_static`). Nodes made for this tree since its last build or
    /// refit (`LbvhBuilder::compact_now`) stay current: the walk can be timed in several
    /// layouts without making any twice. The GPU must be done with the nodes taken out
    /// before they are dropped.
    pub fn swap_compact(&mut self, nodes: CompactNodes) -> CompactNodes {
        self.compact
            .replace(nodes)
            .expect("compact nodes of a BVH made by Bvh::new_static")
    }

    /// Bytes of the BVH itself (nodes, compact nodes if any, and triangles), without
    /// the rebuild scratch.
    pub fn bytes(&self) -> u64 {
        self.tnodes.size + self.compact.as_ref().map_or(0, |c| c.buffer.size) + self.ttris.size
    }

    /// Whether the BVH has compact nodes, recorded after the last build or refit
    /// recorded (what the walk of the static BVH needs).
    pub fn compact_current(&self) -> bool {
        self.compact.is_some() && self.compacted.load(Ordering::Relaxed) == self.shaped.load(Ordering::Relaxed)
    }

    /// A build or refit of the nodes was recorded: the compact nodes are stale.
    pub(super) fn reshaped(&self) {
        self.shaped.fetch_add(1, Ordering::Relaxed);
    }

    /// Whether the builders write the order counts (`counts`): a BVH with compact nodes.
    pub(super) fn ordered(&self) -> u32 {
        u32::from(self.compact.is_some())
    }

    /// Writes `nodes` from the host: a tree no builder made (tests, tools), its compact
    /// nodes stale. With `counts` (each node's, `cpu_ref::lbvh::order_counts`) the compact
    /// nodes are ordered by them; without, the counts are cleared and every node keeps
    /// its slot. Both must hold every node of the BVH.
    pub fn plant(&self, nodes: &[TraversalNode], counts: Option<&[[u32; 4]]>) -> Result<()> {
        let want = self.tnodes.size as usize / std::mem::size_of::<TraversalNode>();
        if nodes.len() != want || counts.is_some_and(|c| c.len() != want) {
            return Err(Error::Bvh(format!(
                "{} nodes and {:?} counts planted into a BVH of {want} nodes",
                nodes.len(),
                counts.map(<[_]>::len)
            )));
        }
        self.tnodes.write(bytemuck::cast_slice(nodes))?;
        if self.compact.is_some() {
            match counts {
                Some(c) => self.counts.write(bytemuck::cast_slice(c))?,
                None => self.counts.write(&vec![0u8; self.counts.size as usize])?,
            }
        }
        self.reshaped();
        Ok(())
    }

    /// (centroid bounds, scene bounds) from the last `lbvh.bounds`, read back.
    pub fn read_bounds(&self) -> Result<(Aabb, Aabb)> {
        let w: Vec<u32> = bytemuck::pod_collect_to_vec(&self.bounds.read()?);
        let v = |i: usize| {
            Vec3::new(
                ordered_to_float(w[i]),
                ordered_to_float(w[i + 1]),
                ordered_to_float(w[i + 2]),
            )
        };
        Ok((Aabb { lo: v(0), hi: v(3) }, Aabb { lo: v(6), hi: v(9) }))
    }

    /// The per-axis scale `lbvh.morton` quantized the centroids with (its one
    /// division, `unit_scale` in `bvh.glsl`), read back: the CPU reference of the codes
    /// multiplies by the GPU's own quotient (`cpu_ref::lbvh::morton_keys_scaled`).
    pub fn read_unit_scale(&self) -> Result<Vec3> {
        let w: Vec<u32> = bytemuck::pod_collect_to_vec(&self.bounds.read()?);
        Ok(Vec3::new(
            f32::from_bits(w[12]),
            f32::from_bits(w[13]),
            f32::from_bits(w[14]),
        ))
    }

    /// The nodes and triangles, read back (for tests and benchmarks).
    pub fn read_packed(&self) -> Result<PackedBvh> {
        Ok(PackedBvh {
            nodes: bytemuck::pod_collect_to_vec(&self.tnodes.read()?),
            tris: bytemuck::pod_collect_to_vec(&self.ttris.read()?),
        })
    }
}

/// The order in which a refit of a fixed topology can visit the internal nodes: by
/// height (1: both children leaves), so a level's children are all done when it runs.
/// Made on the CPU from the nodes of a built BVH (`of`), valid until it is rebuilt.
pub struct RefitSchedule {
    /// Internal nodes by height, lowest first.
    pub(super) order: Buffer,
    /// (first, count) into `order` of each height level.
    pub(super) levels: Buffer,
    pub(super) level_list: Vec<[u32; 2]>,
}

impl RefitSchedule {
    /// The schedule of `bvh` as built now (reads its nodes back; waits for the GPU).
    pub fn of(ctx: &Arc<Context>, bvh: &Bvh) -> Result<Self> {
        let (order, level_list) = refit_order(&bvh.read_packed()?, bvh.tri_count);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER;
        Ok(Self {
            order: Buffer::with_data(ctx, "lbvh.refit_order", usage, bytemuck::cast_slice(&order))?,
            levels: Buffer::with_data(ctx, "lbvh.refit_levels", usage, bytemuck::cast_slice(&level_list))?,
            level_list,
        })
    }
}

/// Internal node slots ordered by height (triangles are 0) in the binary tree of parent
/// links (also the nodes inside leaves of several triangles, whose boxes the refit
/// keeps), and each level's (first, count).
pub fn refit_order(bvh: &PackedBvh, tri_count: u32) -> (Vec<u32>, Vec<[u32; 2]>) {
    let internal = tri_count.saturating_sub(1) as usize;
    // Each node's height, from its children's as they become known: a node is done when
    // both its halves have reported, then reports to its own parent.
    let mut height = vec![0u32; internal];
    let mut reported = vec![0u8; internal];
    let mut ready: Vec<(u32, u32)> = if internal == 0 {
        Vec::new()
    } else {
        bvh.tris.iter().map(|t| (t.parent, 0)).collect()
    };
    while let Some((link, h)) = ready.pop() {
        let s = (link >> 1) as usize;
        height[s] = height[s].max(h + 1);
        reported[s] += 1;
        if reported[s] == 2 && s != 0 {
            ready.push((bvh.nodes[s].parent, height[s]));
        }
    }
    let top = height.iter().copied().max().unwrap_or(0);
    let mut levels = vec![[0u32; 2]; top as usize];
    for h in &height {
        levels[*h as usize - 1][1] += 1;
    }
    let mut first = 0;
    for l in &mut levels {
        l[0] = first;
        first += l[1];
    }
    let mut fill: Vec<u32> = levels.iter().map(|l| l[0]).collect();
    let mut order = vec![0u32; internal];
    for (s, h) in height.iter().enumerate() {
        let h = *h as usize - 1;
        order[fill[h] as usize] = s as u32;
        fill[h] += 1;
    }
    (order, levels)
}

/// Stack entries the static walk through this tree's wide nodes (`lbvh.compact`) can
/// need at most: along its worst path from the root, each wide node's internal
/// children but one (a step pushes all but the nearest).
pub fn wide_stack_need(nodes: &[TraversalNode]) -> u32 {
    opened_stack_need(nodes, 2)
}

/// `wide_stack_need` for the compressed wide nodes (`StaticLayout::Wide8`).
pub fn wide8_stack_need(nodes: &[TraversalNode]) -> u32 {
    opened_stack_need(nodes, 3)
}

/// `wide_stack_need` for nodes made by opening a binary node `levels` levels down: a
/// wide node's internal children are the internal nodes that many levels below it.
fn opened_stack_need(nodes: &[TraversalNode], levels: u32) -> u32 {
    let internal = |c: u32| crate::gpu_types::bvh_leaf(c).is_none();
    let mut most = 0;
    let mut stack = vec![(0u32, 0u32)];
    while let Some((s, held)) = stack.pop() {
        most = most.max(held);
        let mut children = vec![s];
        for _ in 0..levels {
            children = children
                .into_iter()
                .flat_map(|c| [nodes[c as usize].child0, nodes[c as usize].child1])
                .filter(|&c| internal(c))
                .collect();
        }
        let pushed = (children.len() as u32).saturating_sub(1);
        most = most.max(held + pushed);
        stack.extend(children.into_iter().map(|c| (c, held + pushed)));
    }
    most
}

/// Stack entries a walk of this tree can need at most: the internal nodes on its
/// longest path from the root (a walk holds at most one pending child per node it
/// descends through).
pub fn stack_need(nodes: &[TraversalNode]) -> u32 {
    let mut deepest = 0;
    let mut stack = vec![(0u32, 1u32)];
    while let Some((s, depth)) = stack.pop() {
        deepest = deepest.max(depth);
        let nd = &nodes[s as usize];
        for c in [nd.child0, nd.child1] {
            if crate::gpu_types::bvh_leaf(c).is_none() {
                stack.push((c, depth + 1));
            }
        }
    }
    deepest
}
