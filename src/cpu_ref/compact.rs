//! Reference of `ssr.compact` (`glsl/compact_*.comp`).

/// The pixels whose mask value is nonzero, row-major, packed `x | y << 16`.
pub fn compact(mask: &[u32], width: u32) -> Vec<u32> {
    mask.iter()
        .enumerate()
        .filter(|(_, &m)| m != 0)
        .map(|(i, _)| (i as u32 % width) | ((i as u32 / width) << 16))
        .collect()
}
