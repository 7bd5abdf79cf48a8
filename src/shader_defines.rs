// Constants shared by Rust and GLSL, defined here once.
//
// build.rs `include!`s this file and passes every entry of `SHADER_DEFINES` to shaderc
// as a `#define`, so a GLSL kernel and the Rust code that dispatches it can never
// disagree. (Plain `//` comments only: this file is also compiled inside build.rs.)

/// Edge of the square workgroup of every 2D image kernel. 8x8 = 64 invocations is a
/// whole number of subgroups on lavapipe (8 wide) and NVIDIA (32 wide); larger groups
/// help little for these bandwidth-bound passes and hurt occupancy on small images.
pub const WG_2D: u32 = 8;

/// Material id written to the G-buffer where no geometry covers the pixel (the sky).
/// Real materials are numbered from 0, so later passes test `id == MATERIAL_NONE`.
pub const MATERIAL_NONE: u32 = 0xffff_ffff;

/// `Material::texture_layer` of an untextured material.
pub const TEXTURE_NONE: u32 = 0xffff_ffff;

/// Largest PCF kernel radius in shadow-map texels that `light.direct` accepts: the
/// (2r+1)^2 taps bound the cost of the shadow lookup per pixel.
pub const MAX_PCF_RADIUS: u32 = 4;

/// Workgroup size of the 1D LBVH kernels (bounds, morton, fit, refit) and of
/// `rt.trace` over a ray buffer:
/// 256 = 32 subgroups on lavapipe, 8 on NVIDIA; enough to hide latency on GPUs.
pub const LBVH_WG: u32 = 256;
/// Threads of the one workgroup that finds the rigid bodies' centers, their bounds and
/// codes (`lbvh_body_keys.comp`): bodies are few, and a CPU device switches through
/// every SIMD batch of a workgroup at each barrier.
pub const RIGID_WG: u32 = 64;

/// Workgroup of the scheduled refit's last pass (`lbvh_refit_top.comp`): one workgroup
/// refits every level of at most this many nodes, the tree's top, in one dispatch.
/// Vulkan's minimum `maxComputeWorkGroupInvocations` is 128; every desktop GPU and
/// lavapipe allow 1024, and a device below it is refused with a line naming it
/// (`vk::device::limits_shortfall`).
pub const REFIT_TOP_WG: u32 = 1024;

/// Triangles each `lbvh.bounds` invocation folds before the workgroup reduction: fewer
/// workgroups, so fewer reduction rounds and global atomics (1M triangles on
/// lavapipe: 7 ms with 64 against 9-10 with 16).
pub const LBVH_BOUNDS_ITEMS: u32 = 64;

/// Radix-sort digit width in bits. 4 bits (16 bins) keeps every thread's per-digit
/// counts in shared memory (16 x 256 x 4 B = 16 KiB, within lavapipe's 32 KiB), so the
/// scatter ranks keys stably without any workgroup waiting on another.
pub const SORT_RADIX_BITS: u32 = 4;
/// Bins per radix pass.
pub const SORT_BINS: u32 = 1 << SORT_RADIX_BITS;
/// Threads per radix-sort workgroup (the kernels' specialization constant SORT_WG, their
/// local size): on a GPU, a full workgroup ...
pub const SORT_WG_GPU: u32 = 256;
/// ... on a CPU device, a quarter of one: lavapipe runs a workgroup on one thread as
/// SIMD batches of 8 invocations and switches through every batch at each barrier, so
/// a sort pass of one tile (up to 8K keys: a few bodies, `room`) costs what its batches
/// cost, not its keys (`bench lbvh`, 64 keys: 0.57 ms with 256, 0.28-0.35 with 64;
/// 4,860: 0.79 ms, 0.55-0.57; the bunny's 69K: 3.98, 3.56).
pub const SORT_WG_CPU: u32 = 64;
/// Keys each sort thread owns, consecutively (the kernels' specialization constant
/// SORT_ITEMS; a tile is SORT_WG x SORT_ITEMS keys): on a GPU, enough workgroups to
/// fill it ...
pub const SORT_ITEMS_GPU: u32 = 16;
/// ... on a CPU device (lavapipe), fewer and longer tiles: the per-tile ranking and
/// barriers are the cost there (`bench lbvh`, 200K keys: 19.5 ms with 16, 14.6 with 64;
/// with the count's register histograms, 1M keys: 46-49 ms with 64, 40.5-42 with 128,
/// 39.5-40.5 with 160 and 252, but the 69K-key bunny 3.8 ms with 128, 4.5-6.1 with 192
/// and 252: one full tile and one nearly empty leave a worker thread idle; with 64-thread
/// workgroups, 192 and 252 within noise of 128).
pub const SORT_ITEMS_CPU: u32 = 128;
/// The scatter counts a thread's digits in registers, 16 bins of 8 bits (radix.glsl);
/// the kernels read keys in quads, so every tile size is a multiple of 4.
pub const SORT_ITEMS_MAX: u32 = 252;
const _: () = assert!(SORT_BINS == 16 && SORT_ITEMS_GPU <= SORT_ITEMS_MAX && SORT_ITEMS_CPU <= SORT_ITEMS_MAX);
const _: () = assert!(SORT_ITEMS_GPU <= SORT_ITEMS_CPU);
const _: () = assert!(SORT_ITEMS_GPU.is_multiple_of(4) && SORT_ITEMS_CPU.is_multiple_of(4) && SORT_ITEMS_MAX.is_multiple_of(4));

/// Threads per workgroup of the `ssr.compact` count, scan and scatter kernels (each
/// thread owns COMPACT_ITEMS consecutive slots of the 8x8-block order): the scan of the
/// per-tile counts runs in one workgroup of COMPACT_WG threads.
pub const COMPACT_WG: u32 = 256;
/// Slots each compaction thread owns: a tile is COMPACT_WG x COMPACT_ITEMS slots.
pub const COMPACT_ITEMS: u32 = 16;
// wg_scan.glsl scans in groups of 16 invocations.
const _: () = assert!(SORT_WG_GPU.is_multiple_of(16) && SORT_WG_CPU.is_multiple_of(16) && COMPACT_WG.is_multiple_of(16));

/// Invocations per workgroup of `rt.reflect`, which runs over the compacted ray list
/// (`ssr.compact` writes its indirect arguments in these units): 32 of lavapipe's
/// 8-lane SIMD groups, 8 NVIDIA warps.
pub const RT_LIST_WG: u32 = 256;

/// PLOC's search radius (`lbvh.ploc`): each cluster looks for its nearest among this
/// many clusters on either side. Meister & Bittner 2018 use 16; 8 makes trees that
/// walk in as few steps or fewer on the models measured but two (`spheres` 1.06x, a
/// 200K-triangle surface 1.01x), for half the search and its scratch
/// (docs/experiments.md).
pub const PLOC_RADIUS: u32 = 8;
/// Workgroup of PLOC's per-round scan of tile counts (one workgroup).
pub const PLOC_SCAN_WG: u32 = 256;
/// Clusters at most which PLOC's last rounds run in one workgroup (`ploc_tail.comp`),
/// their boxes in shared memory, rather than as four dispatches each: the last 20-30
/// of a build's 35-60 rounds. On lavapipe a workgroup runs on one core at about twice
/// the rounds' time per cluster, and a round's dispatches cost about 0.1 ms: 256 and
/// 512 measured alike, 4096 slower (docs/experiments.md).
pub const PLOC_TAIL_CAP: u32 = 512;
/// Workgroup of PLOC's last rounds.
pub const PLOC_TAIL_WG: u32 = 256;
const _: () = assert!(PLOC_SCAN_WG.is_multiple_of(16) && LBVH_WG.is_multiple_of(16));
// ploc_tail_round.glsl packs its counts in 16 bits.
const _: () = assert!(PLOC_TAIL_WG.is_multiple_of(16) && PLOC_TAIL_CAP < 1 << 16);
// Its shared memory (boxes, the scan) within the 16 KiB every Vulkan device has.
const _: () = assert!(PLOC_TAIL_CAP * 24 + (PLOC_TAIL_WG + PLOC_TAIL_WG / 16 + 1) * 4 <= 16384);

/// Marks a BVH child link as a leaf: (count - 1) << `BVH_LEAF_COUNT_SHIFT` | the
/// position of its first triangle in leaf order.
pub const BVH_LEAF_BIT: u32 = 0x8000_0000;
/// Where a leaf's triangle count (minus one) starts in its child link.
pub const BVH_LEAF_COUNT_SHIFT: u32 = 24;
/// Most triangles in one BVH leaf (the fit chooses leaves up to this size by SAH).
pub const BVH_LEAF_MAX: u32 = 4;
const _: () = assert!(BVH_LEAF_MAX - 1 < 1 << (31 - BVH_LEAF_COUNT_SHIFT));
/// "No node / no primitive" (parent of the root, the primitive of a miss).
pub const BVH_INVALID: u32 = 0xffff_ffff;
/// Set in a hit's triangle id when the triangle is the dynamic geometry's (numbered in
/// the dynamic BVH's own buffers). A miss's `BVH_INVALID` has it set too: a hit is told
/// from a miss first.
pub const HIT_DYNAMIC: u32 = 0x8000_0000;
/// Children of a wide node of the static walk (`lbvh.compact`): a binary node's two,
/// each internal one opened into its own two.
pub const WIDE: u32 = 4;
// The static walk orders a wide node's children by a sorting network of four.
const _: () = assert!(WIDE == 4);
/// Children of a compressed wide node of the static walk (`lbvh.compact`, the `wide8`
/// layout): a binary node's subtree opened three levels, each child's box in 8 bits an
/// axis on the node's own grid (Ylitie, Karras & Laine 2017's quantization).
pub const WIDE8: u32 = 8;
/// 16-byte texels of a compressed wide node: its grid, its children's quantized boxes
/// (three texels), their links (two).
pub const WIDE8_TEXELS: u32 = 6;
/// Traversal stack entries per ray. An LBVH over one-word keys (a 30-bit
/// Morton code and 2 size-class bits) is at most 32 + ceil(log2 N) levels deep (equal
/// keys split by index); the binary walk holds at most one pending child per level, the
/// wide walk at most `WIDE - 1` per two levels, the compressed wide walk `WIDE8 - 1`
/// per three: enough for every tree the frame builds (`tracers::lbvh` asserts it
/// against `MAX_TRIANGLES`). Two-word keys (`bench lbvh --bits 63`) can build deeper
/// trees: the deepest chain the tests build from them (tests/suite/trace.rs) needs 147
/// entries in the compressed wide walk. A walk that runs out of stack returns t = -1,
/// which the benchmark counts as a mismatch.
pub const TRACE_STACK: u32 = 152;

/// The height a node's order counts hold (`glsl/shared/bvh_order.glsl`): that or more.
/// A tree this deep keeps its nodes in their slots in the static walk's layout, where
/// a shallower one is put in preorder by at most `order_rounds(ORDER_H_MAX - 1)` jump
/// rounds (`tracers::lbvh::order::recorded_rounds`).
pub const ORDER_H_MAX: u32 = 255;

/// Binary-search steps that refine an SSR hit inside its last stride: log2 of the
/// largest stride worth refining to one pixel (16 px).
pub const SSR_REFINE_STEPS: u32 = 4;

/// Invocations per workgroup of ssr.trace, which runs over the march list: eight of
/// lavapipe's 8-lane SIMD groups.
pub const SSR_LIST_WG: u32 = 64;

/// Stripes of a pixel list that its workgroups interleave (`list_entry` in
/// `glsl/shared/pixel_list.glsl`), so that each lavapipe thread's contiguous range of
/// workgroups gets an even share of the list.
pub const LIST_STRIPES: u32 = 16;

/// Most workgroups a list kernel's indirect dispatch puts along x: Vulkan's guaranteed
/// minimum of `maxComputeWorkGroupCount[0]` (lavapipe's limit). Longer lists spread over
/// y as well (`list_groups` in `glsl/shared/pixel_list.glsl`), so a list of any length a
/// frame can hold is dispatched on any device.
pub const LIST_GROUPS_X: u32 = 65535;

/// Pixels of one row (or column) segment that a `reflect.merge` blur workgroup owns.
pub const BLUR_LINE: u32 = 64;
/// Largest seam-blur radius and band (pixels): the shared-memory apron of a blur
/// workgroup, so `BLUR_LINE + 2 * BLUR_MAX_EXTENT` texels (3 KiB) of shared memory.
pub const BLUR_MAX_EXTENT: u32 = 64;

/// Most sampled reflection rays per glossy pixel in one frame (`reflection_rays`; `render
/// --spp N` references take N in one frame): the path loop's bound.
pub const MAX_REFLECTION_RAYS: u32 = 1024;
/// The R2 low-discrepancy sequence (Roberts 2018) in 32-bit fixed point: sample k of a
/// pixel is fract(k * (1/g, 1/g^2) + the pixel's rotation), g the plastic number, so that
/// integer wrap-around is the fraction and GPU and CPU draw the same bits.
pub const R2_A1: u32 = 0xC13F_A9A9;
pub const R2_A2: u32 = 0x91E1_0DA5;
/// The hit distance (`ssr.hit_distance`) of a reflection that met nothing the screen or
/// the tracer holds (the sky, a failed march left to the tracer): as far as can be.
pub const HIT_FAR: u32 = 0x7149_f2ca; // 1e30 as f32 bits

/// Taps of `reflect.denoise`'s spatial filter besides the centre (a golden-angle spiral,
/// rotated per pixel and frame).
pub const DENOISE_TAPS: u32 = 16;

/// Fail-mask reason bits written by `ssr.classify` and `ssr.trace` (any nonzero value
/// sends the pixel to the ray tracer): the march left the screen or crossed the near plane,
pub const SHADOWS_MAP: u32 = 0;
pub const SHADOWS_RAYS: u32 = 1;
pub const SHADOWS_HYBRID: u32 = 2;

/// Why a pixel gets a shadow ray (`shadow.classify`'s mask; nonzero means "needs a
/// ray"): outside the shadow map.
pub const SHADOW_OUTSIDE: u32 = 1;
/// The shadow map's texels under the PCF footprint disagree (a shadow edge).
pub const SHADOW_EDGE: u32 = 2;
/// A texel's depth is within `shadow_band` of the biased compare (acne, contact).
pub const SHADOW_NEAR: u32 = 4;
/// The sun grazes the surface (n.l below `SHADOW_GRAZING_NDL` in shading.glsl): the
/// map's depth slope outruns any bias there.
pub const SHADOW_GRAZING: u32 = 8;
/// Every lit pixel is traced (`rays`).
pub const SHADOW_ALL: u32 = 16;

pub const FAIL_LEFT_SCREEN: u32 = 1;
/// ... it passed behind geometry thicker than the threshold (what lies beyond is a guess),
pub const FAIL_BEHIND: u32 = 2;
/// ... it ran out of steps,
pub const FAIL_OUT_OF_STEPS: u32 = 4;
/// ... it hit a surface facing away from it,
pub const FAIL_BACK_FACE: u32 = 8;
/// ... its confidence (screen-edge and toward-camera fades) was below the threshold,
pub const FAIL_LOW_CONFIDENCE: u32 = 16;
/// ... it hit a reflective surface (the screen holds no recursive reflection),
pub const FAIL_HIT_REFLECTIVE: u32 = 32;
/// ... or SSR was off (`rt` mode: every reflective pixel is traced).
pub const FAIL_FORCED: u32 = 64;
/// Not a failure: SSR hit with a confidence in [min_confidence, 1). The pixel is ray
/// traced too and `reflect.merge` blends confidence x SSR + (1 - confidence) x RT, so
/// the screen-edge and toward-camera fades are smooth; alone in the mask.
pub const FAIL_BLEND: u32 = 128;
/// With a reason bit: the pixel's own reflection weighs less than `trace_min_weight`
/// and it is not the traced corner of its 2x2 block, so it is not ray traced: it takes
/// that corner's ray-traced colour, or where that was not traced SSR's answer, the sky
/// in the reflected direction (what a miss of the ray tracer returns).
pub const FAIL_UNTRACED: u32 = 256;
/// Not marched: its tile is rays-only (the adaptive hybrid, `hybrid_policy`), so the
/// pixel goes straight to the ray tracer; alone in the mask.
pub const FAIL_SKIPPED: u32 = 512;

/// The adaptive hybrid's tiles: `WG_2D` x `WG_2D` pixels, `ssr.classify`'s workgroups.
/// A tile's state word holds its smoothed SSR success (`TILE_SUCCESS`: 0 to
/// `TILE_ONE`, the share of its marched pixels SSR answered, in 1/256), whether that
/// is known yet (`TILE_KNOWN`), its class (`TILE_RAYS_ONLY`; clear: SSR-first), and
/// from bit `TILE_FLIPS_SHIFT` up how often its class has changed since the tiles were
/// reset (saturating at `TILE_FLIPS_MAX`): the measure of the tiles' stability.
pub const TILE_SUCCESS: u32 = 0x3ff;
pub const TILE_ONE: u32 = 256;
pub const TILE_KNOWN: u32 = 1 << 10;
pub const TILE_RAYS_ONLY: u32 = 1 << 11;
pub const TILE_FLIPS_SHIFT: u32 = 16;
pub const TILE_FLIPS_MAX: u32 = 0xffff;
/// A tile changes class only when its success passes the exchange rate by a quarter of
/// the rate, at least 1 and at most this (in 1/256): noise in a few marched pixels does
/// not flip it every frame, and a device whose march costs a few hundredths of a ray (a
/// GPU's 1/18) still has a band below its rate for tiles to turn rays-only in.
pub const TILE_HYSTERESIS: u32 = 16;
/// Words per tile in the tile buffers: the state, then the frame's marched pixels and
/// those SSR answered (atomics of `ssr.trace`).
pub const TILE_WORDS: u32 = 3;

/// Provenance of a pixel's reflection, as `reflect.merge` labels it.
pub const SOURCE_NONE: u32 = 0;
pub const SOURCE_SSR: u32 = 1;
pub const SOURCE_RT: u32 = 2;

/// `compose` modes: tonemap the lit colour only, add the merged reflection weighted by
/// reflectivity, or paint each pixel by the source of its reflection.
pub const COMPOSE_PLAIN: u32 = 0;
pub const COMPOSE_REFLECT: u32 = 1;
pub const COMPOSE_PROVENANCE: u32 = 2;
/// ... or paint each reflective pixel by its fail-mask reason (the demo's fail-mask
/// view; the same colours as `--fail-mask` images).
pub const COMPOSE_FAIL_MASK: u32 = 3;

/// An sRGB colour packed as r | g << 8 | b << 16 (GLSL: `unpackUnorm4x8(c).rgb`).
pub const fn rgb8(r: u8, g: u8, b: u8) -> u32 {
    r as u32 | (g as u32) << 8 | (b as u32) << 16
}
/// Fail-mask colours (`--fail-mask` images and the demo's view): a reflective pixel
/// SSR answered is dark blue; a failed one is coloured by its lowest reason bit:
/// yellow, orange, red, magenta, cyan, green, white, light blue (an SSR hit blended
/// with the ray tracer's); an untraced one (`FAIL_UNTRACED`) grey, whatever its reason;
/// one of a rays-only tile (`FAIL_SKIPPED`) brown.
pub const MASK_COLOUR_SSR_OK: u32 = rgb8(30, 50, 140);
pub const MASK_COLOUR_0: u32 = rgb8(240, 220, 40);
pub const MASK_COLOUR_1: u32 = rgb8(250, 130, 20);
pub const MASK_COLOUR_2: u32 = rgb8(220, 30, 30);
pub const MASK_COLOUR_3: u32 = rgb8(230, 40, 230);
pub const MASK_COLOUR_4: u32 = rgb8(40, 220, 230);
pub const MASK_COLOUR_5: u32 = rgb8(40, 200, 60);
pub const MASK_COLOUR_6: u32 = rgb8(255, 255, 255);
pub const MASK_COLOUR_7: u32 = rgb8(120, 170, 255);
pub const MASK_COLOUR_8: u32 = rgb8(110, 110, 120);
pub const MASK_COLOUR_9: u32 = rgb8(150, 90, 40);

/// Every constant above, as `(name, value)`, in the form build.rs hands to shaderc.
pub const SHADER_DEFINES: &[(&str, u32)] = &[
    ("WG_2D", WG_2D),
    ("MATERIAL_NONE", MATERIAL_NONE),
    ("TEXTURE_NONE", TEXTURE_NONE),
    ("MAX_PCF_RADIUS", MAX_PCF_RADIUS),
    ("LBVH_WG", LBVH_WG),
    ("RIGID_WG", RIGID_WG),
    ("REFIT_TOP_WG", REFIT_TOP_WG),
    ("LBVH_BOUNDS_ITEMS", LBVH_BOUNDS_ITEMS),
    ("SORT_RADIX_BITS", SORT_RADIX_BITS),
    ("SORT_BINS", SORT_BINS),
    ("COMPACT_WG", COMPACT_WG),
    ("COMPACT_ITEMS", COMPACT_ITEMS),
    ("RT_LIST_WG", RT_LIST_WG),
    ("PLOC_RADIUS", PLOC_RADIUS),
    ("PLOC_SCAN_WG", PLOC_SCAN_WG),
    ("PLOC_TAIL_CAP", PLOC_TAIL_CAP),
    ("PLOC_TAIL_WG", PLOC_TAIL_WG),
    ("BVH_LEAF_BIT", BVH_LEAF_BIT),
    ("BVH_LEAF_COUNT_SHIFT", BVH_LEAF_COUNT_SHIFT),
    ("BVH_LEAF_MAX", BVH_LEAF_MAX),
    ("BVH_INVALID", BVH_INVALID),
    ("HIT_DYNAMIC", HIT_DYNAMIC),
    ("TRACE_STACK", TRACE_STACK),
    ("ORDER_H_MAX", ORDER_H_MAX),
    ("WIDE", WIDE),
    ("WIDE8", WIDE8),
    ("WIDE8_TEXELS", WIDE8_TEXELS),
    ("SSR_REFINE_STEPS", SSR_REFINE_STEPS),
    ("SSR_LIST_WG", SSR_LIST_WG),
    ("LIST_STRIPES", LIST_STRIPES),
    ("LIST_GROUPS_X", LIST_GROUPS_X),
    ("BLUR_LINE", BLUR_LINE),
    ("BLUR_MAX_EXTENT", BLUR_MAX_EXTENT),
    ("MAX_REFLECTION_RAYS", MAX_REFLECTION_RAYS),
    ("R2_A1", R2_A1),
    ("R2_A2", R2_A2),
    ("DENOISE_TAPS", DENOISE_TAPS),
    ("HIT_FAR_BITS", HIT_FAR),
    ("SHADOWS_MAP", SHADOWS_MAP),
    ("SHADOWS_RAYS", SHADOWS_RAYS),
    ("SHADOWS_HYBRID", SHADOWS_HYBRID),
    ("SHADOW_OUTSIDE", SHADOW_OUTSIDE),
    ("SHADOW_EDGE", SHADOW_EDGE),
    ("SHADOW_NEAR", SHADOW_NEAR),
    ("SHADOW_GRAZING", SHADOW_GRAZING),
    ("SHADOW_ALL", SHADOW_ALL),
    ("FAIL_LEFT_SCREEN", FAIL_LEFT_SCREEN),
    ("FAIL_BEHIND", FAIL_BEHIND),
    ("FAIL_OUT_OF_STEPS", FAIL_OUT_OF_STEPS),
    ("FAIL_BACK_FACE", FAIL_BACK_FACE),
    ("FAIL_LOW_CONFIDENCE", FAIL_LOW_CONFIDENCE),
    ("FAIL_HIT_REFLECTIVE", FAIL_HIT_REFLECTIVE),
    ("FAIL_FORCED", FAIL_FORCED),
    ("FAIL_BLEND", FAIL_BLEND),
    ("FAIL_UNTRACED", FAIL_UNTRACED),
    ("FAIL_SKIPPED", FAIL_SKIPPED),
    ("TILE_SUCCESS", TILE_SUCCESS),
    ("TILE_ONE", TILE_ONE),
    ("TILE_KNOWN", TILE_KNOWN),
    ("TILE_RAYS_ONLY", TILE_RAYS_ONLY),
    ("TILE_HYSTERESIS", TILE_HYSTERESIS),
    ("TILE_FLIPS_SHIFT", TILE_FLIPS_SHIFT),
    ("TILE_FLIPS_MAX", TILE_FLIPS_MAX),
    ("TILE_WORDS", TILE_WORDS),
    ("SOURCE_NONE", SOURCE_NONE),
    ("SOURCE_SSR", SOURCE_SSR),
    ("SOURCE_RT", SOURCE_RT),
    ("COMPOSE_PLAIN", COMPOSE_PLAIN),
    ("COMPOSE_REFLECT", COMPOSE_REFLECT),
    ("COMPOSE_PROVENANCE", COMPOSE_PROVENANCE),
    ("COMPOSE_FAIL_MASK", COMPOSE_FAIL_MASK),
    ("MASK_COLOUR_SSR_OK", MASK_COLOUR_SSR_OK),
    ("MASK_COLOUR_0", MASK_COLOUR_0),
    ("MASK_COLOUR_1", MASK_COLOUR_1),
    ("MASK_COLOUR_2", MASK_COLOUR_2),
    ("MASK_COLOUR_3", MASK_COLOUR_3),
    ("MASK_COLOUR_4", MASK_COLOUR_4),
    ("MASK_COLOUR_5", MASK_COLOUR_5),
    ("MASK_COLOUR_6", MASK_COLOUR_6),
    ("MASK_COLOUR_7", MASK_COLOUR_7),
    ("MASK_COLOUR_8", MASK_COLOUR_8),
    ("MASK_COLOUR_9", MASK_COLOUR_9),
];
