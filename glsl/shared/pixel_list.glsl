// Pixel lists (the ray list, the SSR march list): one uint per pixel, x in the low
// 16 bits, y in the high 16.
#ifndef PIXEL_LIST_GLSL
#define PIXEL_LIST_GLSL
uint pack_pixel(uvec2 p) {
    return p.x | (p.y << 16);
}

ivec2 unpack_pixel(uint packed) {
    return ivec2(packed & 0xffffu, packed >> 16);
}

// The indirect dispatch size (x, y) of `groups` workgroups: at most LIST_GROUPS_X along
// x (the limit every device has), the rest over y. Each component is non-decreasing in
// `groups`, so kernels that append to a list may atomicMax them as the list grows.
uvec2 list_groups(uint groups) {
    return uvec2(min(groups, LIST_GROUPS_X), max((groups + LIST_GROUPS_X - 1u) / LIST_GROUPS_X, 1u));
}

#ifndef PIXEL_LIST_NO_DISPATCH
// (Ray-generation shaders define PIXEL_LIST_NO_DISPATCH: they have no workgroups.)
// This workgroup's index in a dispatch sized by `list_groups` (row-major over x, y).
uint list_workgroup() {
    return gl_WorkGroupID.y * gl_NumWorkGroups.x + gl_WorkGroupID.x;
}

// The list entry of this invocation, for kernels dispatched with one invocation per
// entry (1D workgroups of `wg_size`; `gl_WorkGroupSize` is not yet known where this is
// included), covering the list's `length` entries. lavapipe hands each of its threads
// one contiguous range of a dispatch's workgroups (llvmpipe's lp_cs_tpool), and a list
// in screen order costs very differently from one end to the other (on `room` the back
// wall's rays come first and are cheap, the floor's come last and are dear), so one
// thread would be left with most of the work. Workgroups therefore take the list's
// workgroup-sized chunks in a striped order: of LIST_STRIPES equal stripes, workgroup
// w takes chunk w / LIST_STRIPES of stripe w % LIST_STRIPES, so any contiguous range of
// workgroups holds an even share of every stripe. Chunks past the last whole stripe
// keep their place, as do workgroups past the list's end (a 2D dispatch's last row);
// entries within a chunk stay consecutive (coherent SIMD groups).
// GPUs schedule workgroups dynamically and lose nothing by it.
uint list_entry(uint length, uint wg_size) {
    uint n = (length + wg_size - 1u) / wg_size, w = list_workgroup();
    uint per_stripe = n / LIST_STRIPES;
    uint chunk = w < per_stripe * LIST_STRIPES ? (w % LIST_STRIPES) * per_stripe + w / LIST_STRIPES : w;
    return chunk * wg_size + gl_LocalInvocationID.x;
}
#endif // PIXEL_LIST_NO_DISPATCH
#endif
