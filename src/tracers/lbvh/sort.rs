//! `lbvh.sort`: stable LSD radix sort of (key, value) pairs, 4 bits per pass, each pass
//! count → scan → scatter (reduce-then-scan: no workgroup waits on another; a sort of
//! few tiles, count → scatter, `SortTile::fused`). A tile is
//! one workgroup's keys, `SortTile::wg` threads x `SortTile::items` keys, its shape
//! chosen for the device (`SortTile::for_device`).
//! CPU reference: `cpu_ref::lbvh::sort_pairs` (tests/suite/lbvh.rs).

use crate::error::{Error, Result};
use crate::shader_defines::{
    SORT_BINS, SORT_ITEMS_CPU, SORT_ITEMS_GPU, SORT_ITEMS_MAX, SORT_RADIX_BITS, SORT_WG_CPU, SORT_WG_GPU,
};
use crate::shaders;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, GpuTimer, Groups, Pipeline, Resource, TexelView};
use ash::vk;
use bytemuck::{Pod, Zeroable};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// `SortTile::fused` of a GPU's tiles: up to 1M keys, each scatter workgroup reads
/// 16 x 256 counts (16 a thread) where the scan costs a dispatch and a barrier, which a
/// GPU's small sorts are made of (the H200 sorted the Sponza-class model's 66K keys in
/// 0.17 ms, 24 dispatches: their barriers, not its keys).
const SORT_FUSED_TILES_GPU: u32 = 256;
/// ... and of a CPU device's: up to 256K keys, a quarter as many counts a workgroup,
/// each read one lane at a time on lavapipe, 8 a thread at most.
const SORT_FUSED_TILES_CPU: u32 = 32;

/// The sort's steps, each under its scope in every pass where the sort is timed step
/// by step (`RadixSort::record_timed`: `bench lbvh`), summed over the passes.
pub const COUNT: &str = "lbvh.sort.count";
pub const SCAN: &str = "lbvh.sort.scan";
pub const SCATTER: &str = "lbvh.sort.scatter";
pub const STEPS: [&str; 3] = [COUNT, SCAN, SCATTER];

/// The fewest keys per tile (one workgroup of the count and scatter kernels) a sort
/// takes (`RadixSort::with_tile`): the counts buffer is sized for that many tiles.
const MIN_TILE: u32 = SORT_WG_GPU * SORT_ITEMS_GPU;
/// Most keys one sort handles: the 65535-workgroup limit at the smallest tile.
pub const MAX_KEYS: u32 = 65535 * MIN_TILE;

#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
struct SortPush {
    n: u32,
    shift: u32,
    key_words: u32,
    num_tiles: u32,
}

/// Ping-pong buffers for sorting up to `capacity` keys of `key_words` words.
pub struct SortBuffers {
    /// Keys; the sorted result is in `keys[0]` (every sort has an even pass count).
    pub keys: [Buffer; 2],
    /// Values; the sorted result is in `values[0]`.
    pub values: [Buffer; 2],
    /// `keys` and `values` as the kernels read them: texel buffers of uvec4.
    pub key_texels: [TexelView; 2],
    pub value_texels: [TexelView; 2],
    counts: Buffer,
    pub capacity: u32,
    pub key_words: u32,
}

impl SortBuffers {
    pub fn new(ctx: &Arc<Context>, capacity: u32, key_words: u32) -> Result<Self> {
        if capacity > MAX_KEYS {
            return Err(Error::Bvh(format!(
                "{capacity} keys exceed the radix sort's limit of {MAX_KEYS}"
            )));
        }
        assert!(key_words == 1 || key_words == 2);
        let usage = vk::BufferUsageFlags::STORAGE_BUFFER
            | vk::BufferUsageFlags::TRANSFER_DST
            | vk::BufferUsageFlags::TRANSFER_SRC;
        let buf = |name: &str, bytes: u64| Buffer::new(ctx, name, bytes, usage, MemoryLocation::GpuOnly);
        let texels = |name: &str, bytes: u64| {
            let usage = usage | vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER;
            Buffer::new(ctx, name, bytes, usage, MemoryLocation::GpuOnly)
        };
        // Whole quads of keys: the kernels read keys and values 4 at a time.
        let n = capacity.max(1).next_multiple_of(4) as u64;
        let tiles = capacity.div_ceil(MIN_TILE).max(1) as u64;
        let keys = [
            texels("sort.keys0", n * 4 * key_words as u64)?,
            texels("sort.keys1", n * 4 * key_words as u64)?,
        ];
        let values = [texels("sort.values0", n * 4)?, texels("sort.values1", n * 4)?];
        Ok(Self {
            key_texels: [TexelView::new(ctx, &keys[0])?, TexelView::new(ctx, &keys[1])?],
            value_texels: [TexelView::new(ctx, &values[0])?, TexelView::new(ctx, &values[1])?],
            keys,
            values,
            counts: buf("sort.counts", tiles * SORT_BINS as u64 * 4)?,
            capacity,
            key_words,
        })
    }
}

/// The shape of a sort's tiles: the kernels' specialization constants.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SortTile {
    /// Threads per workgroup (SORT_WG, the local size).
    pub wg: u32,
    /// Keys per thread (SORT_ITEMS).
    pub items: u32,
    /// The scatter puts a tile's pairs in order in shared memory first and writes them
    /// out by consecutive invocations to consecutive slots (`radix_scatter.comp`'s
    /// LOCAL_ORDER; tiles of `SORT_BINS` keys a thread), where it writes each key to
    /// its slot from the invocation that read it.
    pub local: bool,
    /// A sort of 2 to this many tiles runs no scan: each scatter workgroup finds its
    /// tile's offsets from the count's histograms itself (`radix_scatter.comp`'s
    /// FUSED_TILES), reading all `SORT_BINS` x tiles of them, where a scan is a
    /// dispatch and a barrier a pass. 0: always the scan.
    pub fused: u32,
}

impl SortTile {
    /// A GPU's: enough workgroups to fill it.
    pub const GPU: Self = Self {
        wg: SORT_WG_GPU,
        items: SORT_ITEMS_GPU,
        local: false,
        fused: SORT_FUSED_TILES_GPU,
    };
    /// A GPU's, written out in order (`SortTile::local`): a candidate for large sorts,
    /// for a GPU run to measure (`bench lbvh --local-sort-scatter`).
    pub const GPU_LOCAL: Self = Self {
        local: true,
        ..Self::GPU
    };
    /// A CPU device's: fewer and longer tiles, each of fewer SIMD batches, whose cost is
    /// per tile (ranking, barriers).
    pub const CPU: Self = Self {
        wg: SORT_WG_CPU,
        items: SORT_ITEMS_CPU,
        local: false,
        fused: SORT_FUSED_TILES_CPU,
    };

    pub fn for_device(kind: vk::PhysicalDeviceType) -> Self {
        if kind == vk::PhysicalDeviceType::CPU {
            Self::CPU
        } else {
            Self::GPU
        }
    }

    /// The tile `RadixSort::new` makes on `ctx`: the device's (`Context::kernels_for`),
    /// written out in order where `Context::local_sort_scatter` asks and the tile allows
    /// (a GPU's), every sort scanned where `Context::sort_scan` asks.
    pub fn of_context(ctx: &Context) -> Self {
        let tile = Self::for_device(ctx.kernels_for);
        let local = ctx.local_sort_scatter && tile.items == SORT_BINS;
        let fused = if ctx.sort_scan { 0 } else { tile.fused };
        Self { local, fused, ..tile }
    }

    /// Keys per tile.
    pub fn keys(self) -> u32 {
        self.wg * self.items
    }
}

pub struct RadixSort {
    ctx: Arc<Context>,
    tile: SortTile,
    count: Pipeline,
    scan: Pipeline,
    scatter: Pipeline,
}

impl RadixSort {
    /// The kernels with the tile shape for this context (`SortTile::of_context`).
    pub fn new(ctx: &Arc<Context>) -> Result<Self> {
        Self::with_tile(ctx, SortTile::of_context(ctx))
    }

    /// The tile shape the kernels were made for.
    pub fn tile(&self) -> SortTile {
        self.tile
    }

    /// The kernels with this tile shape, whatever the device (tests run every shape on
    /// one device): SORT_WG_GPU or SORT_WG_CPU threads, `SORT_ITEMS_GPU..=SORT_ITEMS_MAX`
    /// keys each (a multiple of 4), at least MIN_TILE keys a tile; written out in order
    /// (`local`) only with SORT_BINS keys a thread (the staging reuses the scatter's
    /// SORT_BINS x SORT_WG counts).
    pub fn with_tile(ctx: &Arc<Context>, tile: SortTile) -> Result<Self> {
        assert!(
            (tile.wg == SORT_WG_GPU || tile.wg == SORT_WG_CPU)
                && (SORT_ITEMS_GPU..=SORT_ITEMS_MAX).contains(&tile.items)
                && tile.items.is_multiple_of(4)
                && tile.keys() >= MIN_TILE
                && (!tile.local || tile.items == SORT_BINS),
            "sort tile {tile:?}"
        );
        let c = [tile.items, tile.wg];
        let kernel = |name, shader| Pipeline::compute_specialized::<SortPush>(ctx, name, shader, &c);
        let scatter = [tile.items, tile.wg, tile.local as u32, tile.fused];
        Ok(Self {
            ctx: ctx.clone(),
            tile,
            count: kernel("lbvh.sort.count", shaders::RADIX_COUNT_COMP)?,
            scan: kernel("lbvh.sort.scan", shaders::RADIX_SCAN_COMP)?,
            scatter: Pipeline::compute_specialized::<SortPush>(
                ctx,
                "lbvh.sort.scatter",
                shaders::RADIX_SCATTER_COMP,
                &scatter,
            )?,
        })
    }

    /// Records the sort of the first `n` pairs in `keys[0]`/`values[0]`, which must be
    /// visible to compute reads; the result is left in `keys[0]`/`values[0]`, visible
    /// to compute reads.
    pub fn record(&self, cmd: vk::CommandBuffer, b: &SortBuffers, n: u32) {
        self.record_steps(cmd, b, n, None);
    }

    /// `record`, each step of each pass under its scope in `timer` (`STEPS`; a sort of
    /// one tile runs its scatter alone).
    pub fn record_timed(&self, cmd: vk::CommandBuffer, b: &SortBuffers, n: u32, timer: &mut GpuTimer) {
        self.record_steps(cmd, b, n, Some(timer));
    }

    fn record_steps(&self, cmd: vk::CommandBuffer, b: &SortBuffers, n: u32, mut timer: Option<&mut GpuTimer>) {
        let mut step = |name, record: &mut dyn FnMut()| match timer.as_deref_mut() {
            Some(t) => t.scope(cmd, name, record),
            None => record(),
        };
        assert!(n <= b.capacity, "sorting {n} keys in buffers for {}", b.capacity);
        if n <= 1 {
            return;
        }
        let d = &self.ctx.device;
        let num_tiles = n.div_ceil(self.tile.keys());
        let passes = 32 * b.key_words / SORT_RADIX_BITS;
        let rw = access::COMPUTE_READ_WRITE;
        let tiles = Groups::Exact([num_tiles, 1, 1]);
        for pass in 0..passes {
            let (i, o) = ((pass % 2) as usize, ((pass + 1) % 2) as usize);
            let push = SortPush {
                n,
                shift: pass * SORT_RADIX_BITS,
                key_words: b.key_words,
                num_tiles,
            };
            // One tile ranks its keys without global offsets (radix_scatter.comp): a
            // small sort (a few bodies, `room`) is one dispatch per pass, not three.
            if num_tiles > 1 {
                let fused = num_tiles <= self.tile.fused;
                let count = [
                    ("keys", Resource::Texels(&b.key_texels[i])),
                    ("counts", Resource::Buffer(&b.counts)),
                ];
                step(COUNT, &mut || {
                    self.count.dispatch(cmd, &count, &push, tiles);
                    // RAW: the scan reads the histograms just written.
                    barrier::global(d, cmd, access::COMPUTE_WRITE, rw);
                });
                if !fused {
                    let scan = [("counts", Resource::Buffer(&b.counts))];
                    step(SCAN, &mut || {
                        self.scan.dispatch(cmd, &scan, &push, Groups::Exact([1, 1, 1]));
                        // RAW: the scatter reads the scanned offsets.
                        barrier::global(d, cmd, access::COMPUTE_WRITE, rw);
                    });
                }
            }
            let scatter = [
                ("keys_in", Resource::Texels(&b.key_texels[i])),
                ("values_in", Resource::Texels(&b.value_texels[i])),
                ("keys_out", Resource::Buffer(&b.keys[o])),
                ("values_out", Resource::Buffer(&b.values[o])),
                ("offsets", Resource::Buffer(&b.counts)),
            ];
            step(SCATTER, &mut || {
                self.scatter.dispatch(cmd, &scatter, &push, tiles);
                // RAW: the next pass (or the caller) reads the scattered pairs; WAR:
                // the next pass's count overwrites the offsets the scatter read.
                barrier::global(d, cmd, access::COMPUTE_WRITE, rw);
            });
        }
    }
}
