//! How the static walk reads a tree: the layouts `lbvh.compact` writes.

use crate::gpu_types::TraversalNode;

/// How the static walk reads a tree (`lbvh.compact` writes it): binary nodes of two
/// children (32 bytes), wide nodes of up to `WIDE` (64 bytes: a binary node's children,
/// each internal one opened into its two), which take half the steps, both with boxes
/// rounded outward to a 16-bit grid over the root's box; or compressed wide nodes of up
/// to `WIDE8` (96 bytes: a binary node's subtree opened three levels, each box rounded
/// outward to 8 bits on the node's own grid), a third of the steps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StaticLayout {
    #[default]
    Binary,
    Wide,
    Wide8,
}

impl StaticLayout {
    pub const ALL: [StaticLayout; 3] = [StaticLayout::Binary, StaticLayout::Wide, StaticLayout::Wide8];

    pub fn name(self) -> &'static str {
        match self {
            StaticLayout::Binary => "binary",
            StaticLayout::Wide => "wide",
            StaticLayout::Wide8 => "wide8",
        }
    }

    pub fn about(self) -> &'static str {
        match self {
            StaticLayout::Binary => "two children a node, 32 bytes: one level a step",
            StaticLayout::Wide => {
                "up to four children a node (a binary node's, internal ones opened), 64 bytes: two levels a step"
            }
            StaticLayout::Wide8 => {
                "up to eight children a node (three levels opened), 8-bit boxes on each node's grid, 96 bytes: three levels a step"
            }
        }
    }

    /// Children a node holds (the compact nodes' header says it to the walk).
    pub fn slots(self) -> u32 {
        match self {
            StaticLayout::Binary => 2,
            StaticLayout::Wide => crate::shader_defines::WIDE,
            StaticLayout::Wide8 => crate::shader_defines::WIDE8,
        }
    }

    /// Stack entries a walk of the tree `nodes` in this layout can need at most
    /// (`stack_need`, `wide_stack_need`, `wide8_stack_need`).
    pub fn stack_need(self, nodes: &[TraversalNode]) -> u32 {
        match self {
            StaticLayout::Binary => super::stack_need(nodes),
            StaticLayout::Wide => super::wide_stack_need(nodes),
            StaticLayout::Wide8 => super::wide8_stack_need(nodes),
        }
    }

    /// Whether the walk of the tree `nodes` in this layout fits its stack
    /// (`TRACE_STACK`): a tree of one-word keys always does (`tracers::lbvh` asserts
    /// it); a PLOC tree is measured.
    pub fn fits(self, nodes: &[TraversalNode]) -> bool {
        self.stack_need(nodes) <= crate::shader_defines::TRACE_STACK
    }

    /// 16-byte texels a node takes.
    pub fn texels(self) -> u32 {
        match self {
            StaticLayout::Wide8 => crate::shader_defines::WIDE8_TEXELS,
            _ => self.slots(),
        }
    }
}
