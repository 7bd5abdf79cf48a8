//! The frame table (docs/architecture.md) as data: its rows in frame order (`Row`),
//! each row's timer scopes, and from them every scope a frame can report (`SCOPES`).
//! The plan (`plan`) says which rows a frame runs; `frame` records them.

use crate::passes::compose;
use crate::passes::reflect_denoise;
use crate::passes::reflect_merge;
use crate::passes::rt_reflect;
use crate::passes::ssr_hiz;
use crate::passes::ssr_trace;
use crate::passes::{
    gbuffer, gbuffer_trace, light_direct, shadow_map, shadow_trace, sim_cloth, sim_skin, sim_transform, ssr_compact,
};
use crate::tracers::khr;
use crate::tracers::lbvh::dynamic::DynamicBvh;

/// Timer scope of the whole frame.
pub const FRAME: &str = "frame";
/// Timer scope of the per-frame uniform upload.
pub const UNIFORMS: &str = "uniforms";
/// The rigid bodies' time step on the CPU (wall clock, while the frame is recorded).
pub const SIM_RIGID: &str = "sim.rigid";
/// Timer scope of the adaptive hybrid's recheck: an idle path's classification, rays
/// and merge, run before the frame's own path to price it without showing it.
pub const RECHECK: &str = "reflect.recheck";

/// The rows the adaptive hybrid's paths are priced by (`exchange::Paths`): those that
/// differ between them, `ssr.hiz` to `reflect.denoise`.
pub fn reflection_rows() -> &'static [Row] {
    let at = |row| Row::ALL.iter().position(|&r| r == row).expect("a row of the table");
    &Row::ALL[at(Row::SsrHiz)..=at(Row::ReflectDenoise)]
}

/// One row of the frame table (docs/architecture.md), declared in frame order.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub enum Row {
    Uniforms,
    SimRigid,
    SimTransform,
    SimCloth,
    SimSkin,
    /// The dynamic BVH's rebuild or refit (`lbvh.*`; the static BVH is built once).
    DynamicBvh,
    /// The vendor tracer's structures of a moving scene (`as.*`; the static ones are
    /// built once).
    DynamicAccel,
    ShadowMap,
    /// The G-buffer rasterized (`visibility` raster).
    GBuffer,
    /// The G-buffer by primary rays (`visibility` rays).
    GBufferTrace,
    ShadowClassify,
    ShadowCompact,
    ShadowTrace,
    LightDirect,
    /// The adaptive hybrid's recheck of an idle path (one frame in `RECHECK_EVERY`),
    /// before the frame's own path writes every output again.
    ReflectRecheck,
    SsrHiz,
    SsrClassify,
    SsrTrace,
    SsrCompact,
    RtReflect,
    ReflectMerge,
    /// The glossy reflections' spatial and temporal filters (`glossy` on, with a
    /// `denoise_radius` or a `denoise_history` to apply).
    ReflectDenoise,
    Compose,
}

impl Row {
    /// Every row, in frame order.
    pub const ALL: [Row; 23] = [
        Row::Uniforms,
        Row::SimRigid,
        Row::SimTransform,
        Row::SimCloth,
        Row::SimSkin,
        Row::DynamicBvh,
        Row::DynamicAccel,
        Row::ShadowMap,
        Row::GBuffer,
        Row::GBufferTrace,
        Row::ShadowClassify,
        Row::ShadowCompact,
        Row::ShadowTrace,
        Row::LightDirect,
        Row::ReflectRecheck,
        Row::SsrHiz,
        Row::SsrClassify,
        Row::SsrTrace,
        Row::SsrCompact,
        Row::RtReflect,
        Row::ReflectMerge,
        Row::ReflectDenoise,
        Row::Compose,
    ];

    /// The timer scopes the row reports under (the dynamic BVH's stages each open
    /// their own).
    pub const fn scopes(self) -> &'static [&'static str] {
        match self {
            Row::Uniforms => &[UNIFORMS],
            Row::SimRigid => &[SIM_RIGID],
            Row::SimTransform => &[sim_transform::NAME],
            Row::SimCloth => &[sim_cloth::NAME],
            Row::SimSkin => &[sim_skin::NAME],
            Row::DynamicBvh => &DynamicBvh::SCOPES,
            Row::DynamicAccel => &khr::SCOPES,
            Row::ShadowMap => &[shadow_map::NAME],
            Row::GBuffer => &[gbuffer::NAME],
            Row::GBufferTrace => &[gbuffer_trace::NAME],
            Row::ShadowClassify => &[shadow_trace::CLASSIFY_NAME],
            Row::ShadowCompact => &[shadow_trace::COMPACT_NAME],
            Row::ShadowTrace => &[shadow_trace::NAME],
            Row::LightDirect => &[light_direct::NAME],
            Row::ReflectRecheck => &[RECHECK],
            Row::SsrHiz => &[ssr_hiz::NAME],
            Row::SsrClassify => &[ssr_trace::CLASSIFY_NAME],
            Row::SsrTrace => &[ssr_trace::NAME],
            Row::SsrCompact => &[ssr_compact::NAME],
            Row::RtReflect => &[rt_reflect::NAME],
            Row::ReflectMerge => &[reflect_merge::NAME],
            Row::ReflectDenoise => &[reflect_denoise::NAME],
            Row::Compose => &[compose::NAME],
        }
    }

    /// The row's one scope; rows with stages have none of their own.
    pub(super) fn scope(self) -> &'static str {
        match self.scopes() {
            [name] => name,
            _ => panic!("frame row {self:?} has stages, not one scope"),
        }
    }
}

const SCOPE_COUNT: usize = {
    let (mut n, mut i) = (1, 0);
    while i < Row::ALL.len() {
        assert!(Row::ALL[i] as usize == i, "Row::ALL is the declaration order");
        n += Row::ALL[i].scopes().len();
        i += 1;
    }
    n
};

/// Every timer scope a frame can have, in frame order (`FRAME` last), from the rows'
/// scopes: the keys of every report's `passes_ms`, a pass a mode (or a static scene)
/// does not run reported as `null`. All are GPU time but `sim.rigid`, the CPU's; the
/// dynamic BVH's stages are `lbvh.*` (the static BVH's, built once, are reported apart).
pub const SCOPES: [&str; SCOPE_COUNT] = {
    let mut out = [FRAME; SCOPE_COUNT];
    let (mut k, mut i) = (0, 0);
    while i < Row::ALL.len() {
        let scopes = Row::ALL[i].scopes();
        let mut j = 0;
        while j < scopes.len() {
            out[k] = scopes[j];
            k += 1;
            j += 1;
        }
        i += 1;
    }
    out
};

#[cfg(test)]
mod tests {
    use super::*;

    /// The scopes are the rows' scopes in frame order, each once, `frame` last.
    #[test]
    fn scopes_are_the_rows_in_order() {
        let rows: Vec<&str> = Row::ALL.iter().flat_map(|r| r.scopes().iter().copied()).collect();
        assert_eq!(SCOPES[..SCOPES.len() - 1], rows[..]);
        assert_eq!(SCOPES.last(), Some(&FRAME));
        let mut unique = SCOPES.to_vec();
        unique.sort();
        unique.dedup();
        assert_eq!(unique.len(), SCOPES.len(), "a scope named twice");
        assert_eq!(SCOPES[..2], [UNIFORMS, SIM_RIGID]);
    }
}
