// Exclusive prefix sum across one workgroup of WG_SCAN_SIZE invocations, in shared
// memory, in two levels of short serial scans: WG_SCAN_GROUP invocations each scan a
// group of WG_SCAN_GROUP consecutive values, then one invocation scans the group
// totals. Four barriers whatever the size: a barrier is the expensive step on a CPU
// driver (lavapipe switches every SIMD batch of the workgroup at each one), and the
// serial work is WG_SCAN_GROUP + WG_SCAN_SIZE / WG_SCAN_GROUP additions per
// scanning invocation. Every invocation must call it (it contains barriers).
#ifndef WG_SCAN_GLSL
#define WG_SCAN_GLSL

#define WG_SCAN_GROUP 16u
// WG_SCAN_SIZE is a multiple of WG_SCAN_GROUP (asserted in shader_defines.rs).
#define WG_SCAN_GROUPS (WG_SCAN_SIZE / WG_SCAN_GROUP)

shared uint s_wg_scan[WG_SCAN_SIZE];
shared uint s_wg_scan_groups[WG_SCAN_GROUPS + 1u];

// Returns the sum of `value` over the invocations before this one; `total` receives
// the sum over the whole workgroup.
uint wg_exclusive_scan(uint value, out uint total) {
    uint l = gl_LocalInvocationID.x;
    s_wg_scan[l] = value;
    barrier();
    if (l < WG_SCAN_GROUPS) {
        uint sum = 0u;
        for (uint k = 0u; k < WG_SCAN_GROUP; ++k) {
            uint v = s_wg_scan[l * WG_SCAN_GROUP + k];
            s_wg_scan[l * WG_SCAN_GROUP + k] = sum;
            sum += v;
        }
        s_wg_scan_groups[l] = sum;
    }
    barrier();
    if (l == 0u) {
        uint sum = 0u;
        for (uint g = 0u; g < WG_SCAN_GROUPS; ++g) {
            uint v = s_wg_scan_groups[g];
            s_wg_scan_groups[g] = sum;
            sum += v;
        }
        s_wg_scan_groups[WG_SCAN_GROUPS] = sum;
    }
    barrier();
    total = s_wg_scan_groups[WG_SCAN_GROUPS];
    uint exclusive = s_wg_scan_groups[l / WG_SCAN_GROUP] + s_wg_scan[l];
    barrier(); // the arrays may be reused right after
    return exclusive;
}
#endif
