//! The frame's screen passes, grouped by the stage of the frame they record
//! (`frame.rs`: `record_lighting`, `record_reflections`). Each group is made, and
//! resized with the screen, in one place: a new pass or screen-sized image touches its
//! group (field, `new`, `resize`) and its row in the frame, not the `Renderer`.

use crate::error::Result;
use crate::passes::gbuffer::GBufferPass;
use crate::passes::gbuffer_trace::GBufferTracePass;
use crate::passes::light_direct::LightDirectPass;
use crate::passes::reflect_denoise::DenoisePass;
use crate::passes::reflect_merge::MergePass;
use crate::passes::rt_reflect::RtReflectPass;
use crate::passes::shadow_map::ShadowMapPass;
use crate::passes::shadow_trace::{self, ShadowTracePass};
use crate::passes::ssr_compact::{self, CompactPass};
use crate::passes::ssr_hiz::HiZPass;
use crate::passes::ssr_trace::SsrPass;
use crate::settings::Settings;
use crate::vk::Context;
use ash::vk;
use std::sync::Arc;

/// `shadow.map` to `light.direct`: the shadow map, the G-buffer (rasterized or traced), the
/// shadow rays and the direct light.
pub struct Lighting {
    pub shadow: ShadowMapPass,
    pub gbuffer: GBufferPass,
    /// `gbuffer.trace`: the same G-buffer (`gbuffer`'s targets) by primary rays.
    pub gbuffer_trace: GBufferTracePass,
    pub shadow_trace: ShadowTracePass,
    /// `shadow.compact`: the shadow mask's compaction into the shadow-ray list.
    pub shadow_compact: CompactPass,
    pub light: LightDirectPass,
}

impl Lighting {
    pub(super) fn new(ctx: &Arc<Context>, settings: &Settings, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            shadow: Self::shadow_map(ctx, settings)?,
            gbuffer: GBufferPass::new(ctx, extent)?,
            gbuffer_trace: GBufferTracePass::new(ctx, extent)?,
            shadow_trace: ShadowTracePass::new(ctx, extent)?,
            shadow_compact: CompactPass::new(ctx, shadow_trace::COMPACT_PIPELINES, extent)?,
            light: LightDirectPass::new(ctx, extent)?,
        })
    }

    /// The shadow map of `settings` (its size and slope bias).
    pub(super) fn shadow_map(ctx: &Arc<Context>, settings: &Settings) -> Result<ShadowMapPass> {
        ShadowMapPass::new(ctx, settings.shadow_map_size, settings.shadow_slope_bias)
    }

    /// Every screen-sized image at `extent` (the shadow map is not screen-sized).
    pub(super) fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.gbuffer.resize(extent)?;
        self.gbuffer_trace.resize(extent)?;
        self.shadow_trace.resize(extent)?;
        self.shadow_compact.resize(extent)?;
        self.light.resize(extent)
    }
}

/// `ssr.hiz` to `reflect.denoise`: screen-space reflections, the failed pixels'
/// compaction and rays, the merge and the glossy filter.
pub struct Reflections {
    pub hiz: HiZPass,
    pub ssr: SsrPass,
    pub compact: CompactPass,
    pub rt: RtReflectPass,
    pub merge: MergePass,
    pub denoise: DenoisePass,
}

impl Reflections {
    pub(super) fn new(ctx: &Arc<Context>, extent: vk::Extent2D) -> Result<Self> {
        Ok(Self {
            hiz: HiZPass::new(ctx, extent)?,
            ssr: SsrPass::new(ctx, extent)?,
            compact: CompactPass::new(ctx, ssr_compact::PIPELINES, extent)?,
            rt: RtReflectPass::new(ctx, extent)?,
            merge: MergePass::new(ctx, extent)?,
            denoise: DenoisePass::new(ctx, extent)?,
        })
    }

    /// Every screen-sized image and list at `extent`.
    pub(super) fn resize(&mut self, extent: vk::Extent2D) -> Result<()> {
        self.hiz.resize(extent)?;
        self.ssr.resize(extent)?;
        self.compact.resize(extent)?;
        self.rt.resize(extent)?;
        self.merge.resize(extent)?;
        self.denoise.resize(extent)
    }
}
