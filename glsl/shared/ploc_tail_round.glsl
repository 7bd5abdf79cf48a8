// One PLOC round of ploc_tail.comp from SRC to DST, included once per direction (with
// SRC, DST and ROUND defined). As the round kernels: every cluster's nearest (the boxes
// copied to shared memory first), then each kept cluster's position and each merge's
// slot from an exclusive scan of (kept | merges << 16), here over runs of consecutive
// clusters per invocation (the counts fit 16 bits: PLOC_TAIL_CAP < 65536). `merges`
// counts the build's merges so far; returns the clusters left.

uint ROUND(uint c, inout uint merges) {
    uint l = gl_LocalInvocationID.x;
    for (uint i = l; i < c; i += PLOC_TAIL_WG) {
        vec3 lo = SRC[i].lo, hi = SRC[i].hi;
        s_box[6u * i] = lo.x;
        s_box[6u * i + 1u] = lo.y;
        s_box[6u * i + 2u] = lo.z;
        s_box[6u * i + 3u] = hi.x;
        s_box[6u * i + 4u] = hi.y;
        s_box[6u * i + 5u] = hi.z;
    }
    // The search reads other invocations' boxes.
    barrier();
    for (uint i = l; i < c; i += PLOC_TAIL_WG) {
        uint best;
        PLOC_NEAREST(tail_box, i, c, best)
        nearest[i] = best;
    }
    // The flags read other invocations' nearest.
    memoryBarrierBuffer();
    barrier();
    uint per = (c + PLOC_TAIL_WG - 1u) / PLOC_TAIL_WG;
    uint first = min(c, l * per), last = min(c, first + per);
    uint packed = 0u;
    for (uint i = first; i < last; ++i) {
        PLOC_FLAGS(nearest, i, keep, merge)
        packed += (keep ? 1u : 0u) | (merge ? 1u << 16 : 0u);
    }
    uint total;
    uint run = wg_exclusive_scan(packed, total);
    for (uint i = first; i < last; ++i) {
        PLOC_FLAGS(nearest, i, keep, merge)
        if (merge) {
            Cluster a = SRC[i], b = SRC[nn_];
            uint slot = pc.n - 2u - (merges + (run >> 16));
            PLOC_WRITE_NODE(tnodes, ttris, slot, a, b)
            PLOC_WRITE_COUNTS(counts, slot, a, b)
            DST[run & 0xffffu] = ploc_merged(a, b, slot);
        } else if (keep) {
            DST[run & 0xffffu] = SRC[i];
        }
        run += (keep ? 1u : 0u) | (merge ? 1u << 16 : 0u);
    }
    merges += total >> 16;
    // The next round reads DST and writes `nearest` and SRC.
    memoryBarrierBuffer();
    barrier();
    return total & 0xffffu;
}
