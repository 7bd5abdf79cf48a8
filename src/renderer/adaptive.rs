//! What the renderer's adaptive choices have measured and chosen: the hybrid's
//! exchange rate and paths, the adaptive stages' ways, the last frame's plan.

use super::exchange::{ExchangeRate, Paths};
use super::plan::FramePlan;
use super::stages::Stages;
use super::Renderer;
use crate::settings::{Shadows, Visibility};

impl Renderer {
    /// The adaptive hybrid's measured exchange rate and the one in use.
    pub fn exchange_rate(&self) -> ExchangeRate {
        self.exchange
    }

    /// The adaptive hybrid's paths: which one the frames take, and their prices.
    pub fn hybrid_paths(&self) -> Paths {
        self.paths
    }

    /// Sets the adaptive hybrid's paths (their prices, the next frames' path), as a
    /// starting point; the frames go on measuring from it.
    pub fn set_hybrid_paths(&mut self, paths: Paths) {
        self.paths = paths;
    }

    /// The plan of the last frame recorded (`None` before the first): the path its
    /// reflections ran and showed, its G-buffer's and its shadows' ways.
    pub fn last_plan(&self) -> Option<FramePlan> {
        self.last_plan
    }

    /// The adaptive stages (`visibility`, `shadows`): each one's ways (in
    /// `Visibility::FIXED` and `Shadows::ADAPTIVE` order), which one the frames take,
    /// and their prices.
    pub fn stages(&self) -> Stages {
        self.stages
    }

    /// Whether a stage of the settings is adaptive (`visibility` or `shadows`).
    pub fn adaptive_stages(&self) -> bool {
        self.settings.visibility == Visibility::Adaptive || self.settings.shadows == Shadows::Adaptive
    }

    /// Whether every adaptive stage of the settings is priced.
    pub fn stages_priced(&self) -> bool {
        self.stages.priced(&self.settings)
    }

    /// Forgets the adaptive stages' prices: the next frames price every way again (at
    /// the clocks of now, after a warm-up).
    pub fn reprice_stages(&mut self) {
        self.stages = Stages::default();
    }
}
