#version 460
// lbvh.hierarchy: the binary radix tree of Karras 2012 ("Maximizing Parallelism in
// the Construction of BVHs, Octrees, and k-d Trees", HPG 2012), one invocation per
// internal node, plus the leaves. Equal keys are told apart by their index (the
// paper's section 4: delta falls back to 32*words + clz(i ^ j)).
// Mirrored exactly by cpu_ref::lbvh::hierarchy.
#include "bvh.glsl"

layout(local_size_x = LBVH_WG) in;

layout(binding = 0, std430) readonly buffer Keys { uint keys[]; };
layout(binding = 1, std430) readonly buffer Values { uint values[]; };
layout(binding = 2, std430) writeonly buffer Nodes { BvhNode nodes[]; };
layout(binding = 3, std430) writeonly buffer Parents { uint parents[]; };

layout(push_constant) uniform Push {
    uint n;         // triangles (leaves)
    uint key_words; // 1 or 2
} pc;

uint clz32(uint x) {
    return uint(31 - findMSB(x)); // findMSB(0) = -1: clz32(0) = 32
}

// Length of the common prefix of keys i and j; -1 when j is out of range.
int delta(int i, int j) {
    if (j < 0 || j >= int(pc.n)) {
        return -1;
    }
    uint prefix = 0u;
    for (int w = int(pc.key_words) - 1; w >= 0; --w) {
        uint x = keys[uint(i) * pc.key_words + uint(w)] ^ keys[uint(j) * pc.key_words + uint(w)];
        if (x != 0u) {
            return int(prefix + clz32(x));
        }
        prefix += 32u;
    }
    return int(prefix + clz32(uint(i) ^ uint(j)));
}

void main() {
    int i = int(gl_GlobalInvocationID.x);
    int n = int(pc.n);
    if (i >= n) {
        return;
    }
    // Leaf i holds the i-th triangle in Morton order.
    nodes[n - 1 + i].left = BVH_LEAF_BIT | values[i];
    nodes[n - 1 + i].right = BVH_INVALID;
    if (i == 0) {
        parents[0] = BVH_INVALID; // the root (a leaf when n == 1)
    }
    if (i >= n - 1) {
        return;
    }
    // Direction of the node's range, and its other end j.
    int d = delta(i, i + 1) - delta(i, i - 1) >= 0 ? 1 : -1;
    int delta_min = delta(i, i - d);
    int l_max = 2;
    while (delta(i, i + l_max * d) > delta_min) {
        l_max *= 2;
    }
    int l = 0;
    for (int t = l_max / 2; t >= 1; t /= 2) {
        if (delta(i, i + (l + t) * d) > delta_min) {
            l += t;
        }
    }
    int j = i + l * d;
    // The split: the last key of the range that shares more than delta_node bits with i.
    int delta_node = delta(i, j);
    int s = 0;
    for (int div = 2;; div *= 2) {
        int t = (l + div - 1) / div;
        if (delta(i, i + (s + t) * d) > delta_node) {
            s += t;
        }
        if (t == 1) {
            break;
        }
    }
    int gamma = i + s * d + min(d, 0);
    uint left = min(i, j) == gamma ? uint(n - 1 + gamma) : uint(gamma);
    uint right = max(i, j) == gamma + 1 ? uint(n - 1 + gamma + 1) : uint(gamma + 1);
    nodes[i].left = left;
    nodes[i].right = right;
    parents[left] = uint(i);
    parents[right] = uint(i);
}
