// Exclusive prefix sum across one workgroup of WG_SCAN_SIZE invocations, in shared
// memory (Hillis-Steele). Every invocation must call it (it contains barriers).
#ifndef WG_SCAN_GLSL
#define WG_SCAN_GLSL

shared uint s_wg_scan[WG_SCAN_SIZE];

// Returns the sum of `value` over the invocations before this one; `total` receives
// the sum over the whole workgroup.
uint wg_exclusive_scan(uint value, out uint total) {
    uint l = gl_LocalInvocationID.x;
    s_wg_scan[l] = value;
    barrier();
    for (uint offset = 1u; offset < WG_SCAN_SIZE; offset <<= 1) {
        uint add = l >= offset ? s_wg_scan[l - offset] : 0u;
        barrier();
        s_wg_scan[l] += add;
        barrier();
    }
    total = s_wg_scan[WG_SCAN_SIZE - 1u];
    uint inclusive = s_wg_scan[l];
    barrier(); // the array may be reused right after
    return inclusive - value;
}
#endif
