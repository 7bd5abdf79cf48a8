//! The one settings struct shared by the CLI, the demo, the tuner, the benchmarks and
//! the tests, declared as one table (`settings_table!` below): each field's type,
//! default, range, what it trades, how the HUD shows it and how a change applies. The
//! struct, `Default`, `validate`, `Renderer::set_settings`, the HUD's controls,
//! `speculum settings --list` and the README's list all read that table.

pub mod field;
mod sources;

use crate::error::{Error, Result};
use crate::shader_defines::{BLUR_MAX_EXTENT, MAX_PCF_RADIUS, MAX_REFLECTION_RAYS, TILE_ONE};
pub use field::{Applies, Field, Hud, Range, Value};
use serde::{Deserialize, Serialize};
pub use sources::{Shadows, Visibility};

/// Largest render side Speculum accepts on any device: 8192 keeps every target under
/// 512 MiB, within a single allocation on lavapipe (2 GiB) and common GPUs.
pub const MAX_SIDE: u32 = 8192;

/// What the renderer computes for reflections (`about` says what each mode is).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Mode {
    Raster,
    Ssr,
    Hybrid,
    Rt,
    Provenance,
}

impl Mode {
    pub const ALL: [Mode; 5] = [Mode::Raster, Mode::Ssr, Mode::Hybrid, Mode::Rt, Mode::Provenance];

    /// Whether the frame has reflections at all (every mode but `raster`).
    pub fn reflects(self) -> bool {
        self != Mode::Raster
    }

    /// Whether SSR marches (`ssr.trace` runs): `rt` classifies only, to fail every pixel.
    pub fn marches(self) -> bool {
        matches!(self, Mode::Ssr | Mode::Hybrid | Mode::Provenance)
    }

    /// Whether failed pixels are ray traced (`ssr.compact` and `rt.reflect` run).
    pub fn traces(self) -> bool {
        matches!(self, Mode::Hybrid | Mode::Rt | Mode::Provenance)
    }

    /// Whether SSR and ray-traced reflections meet in one image (the seam blur runs).
    pub fn has_seams(self) -> bool {
        matches!(self, Mode::Hybrid | Mode::Provenance)
    }

    pub fn name(self) -> &'static str {
        match self {
            Mode::Raster => "raster",
            Mode::Ssr => "ssr",
            Mode::Hybrid => "hybrid",
            Mode::Rt => "rt",
            Mode::Provenance => "provenance",
        }
    }

    /// What the mode renders, in a line (the CLI's help, the HUD).
    pub fn about(self) -> &'static str {
        match self {
            Mode::Raster => "No reflections: direct lighting only",
            Mode::Ssr => "Screen-space reflections only; where SSR fails there is no reflection",
            Mode::Hybrid => "The method: SSR first, the failed pixels ray traced, merged, seams blurred",
            Mode::Rt => "Every reflective pixel ray traced (the quality reference), same bounces",
            Mode::Provenance => {
                "Hybrid, with each pixel painted by its reflection's source: pink = ray traced, blue = SSR, \
                 grey = no reflective surface"
            }
        }
    }
}

impl std::str::FromStr for Mode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        Mode::ALL.into_iter().find(|m| m.name() == s).ok_or_else(|| {
            Error::Settings(format!(
                "unknown mode '{s}' (modes: raster, ssr, hybrid, rt, provenance)"
            ))
        })
    }
}

/// The ray tracer every traced ray goes through (reflections and their bounces,
/// shadow rays, the `rt` reference): Speculum's own BVH or the driver's.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Tracer {
    Lbvh,
    Khr,
}

impl Tracer {
    pub const ALL: [Tracer; 2] = [Tracer::Lbvh, Tracer::Khr];

    pub fn name(self) -> &'static str {
        match self {
            Tracer::Lbvh => "lbvh",
            Tracer::Khr => "khr",
        }
    }

    /// What the tracer is, in a line (the CLI's help, the HUD).
    pub fn about(self) -> &'static str {
        match self {
            Tracer::Lbvh => "Speculum's own GPU BVH (LBVH or PLOC), walked in compute shaders",
            Tracer::Khr => {
                "The driver's acceleration structures and a ray-tracing pipeline (VK_KHR_acceleration_structure, VK_KHR_ray_tracing_pipeline)"
            }
        }
    }
}

/// The nodes the static scene's BVH is walked through (`lbvh.compact`'s layouts), or
/// whichever of them walks fastest on this device (`about` says what each is).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum WalkLayout {
    Binary,
    Wide,
    Wide8,
    Fastest,
}

impl WalkLayout {
    pub const ALL: [WalkLayout; 4] = [
        WalkLayout::Binary,
        WalkLayout::Wide,
        WalkLayout::Wide8,
        WalkLayout::Fastest,
    ];

    pub fn name(self) -> &'static str {
        match self {
            WalkLayout::Binary => "binary",
            WalkLayout::Wide => "wide",
            WalkLayout::Wide8 => "wide8",
            WalkLayout::Fastest => "fastest",
        }
    }

    /// What the layout is, in a line (the CLI's help, the HUD).
    pub fn about(self) -> &'static str {
        match self {
            WalkLayout::Binary => "Binary nodes, 32 bytes: one level a step",
            WalkLayout::Wide => "Up to four children a node, 64 bytes: two levels a step",
            WalkLayout::Wide8 => {
                "Up to eight children a node, 8-bit boxes on each node's grid, 96 bytes: three levels a step"
            }
            WalkLayout::Fastest => {
                "Each layout made at load and the same reflection and shadow rays timed through each; the fastest kept"
            }
        }
    }
}

/// How the `hybrid` mode chooses, tile by tile, between marching a pixel first and
/// tracing it straight away (`about` says what each is).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HybridPolicy {
    Adaptive,
    SsrFirst,
}

impl HybridPolicy {
    pub const ALL: [HybridPolicy; 2] = [HybridPolicy::Adaptive, HybridPolicy::SsrFirst];

    pub fn name(self) -> &'static str {
        match self {
            HybridPolicy::Adaptive => "adaptive",
            HybridPolicy::SsrFirst => "ssr_first",
        }
    }

    /// What the policy is, in a line (the CLI's help, the HUD).
    pub fn about(self) -> &'static str {
        match self {
            HybridPolicy::Adaptive => {
                "Each 8x8 tile marches first only while SSR answers more of its pixels than a march costs in rays \
                 (exchange_rate); otherwise its pixels go straight to the ray tracer"
            }
            HybridPolicy::SsrFirst => "Every reflective pixel is marched first; the ray tracer takes what SSR fails",
        }
    }
}

/// Declares `Settings`, its `Default` and `FIELDS` from one table: each field's
/// documentation (what it trades), type, default, accepted range, HUD control and how a
/// change applies.
macro_rules! settings_table {
    ($(
        $(#[doc = $doc:literal])*
        $name:ident: $ty:ty = $default:expr, $range:expr, $hud:expr, $applies:ident;
    )*) => {
        /// Every field says what it trades; `FIELDS` has the rest of the table.
        #[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
        #[serde(default, deny_unknown_fields)]
        pub struct Settings {
            $( $(#[doc = $doc])* pub $name: $ty, )*
        }

        impl Default for Settings {
            fn default() -> Self {
                Self { $( $name: $default, )* }
            }
        }

        /// The settings table, in declaration order.
        pub const FIELDS: &[Field] = &[$(
            Field {
                name: stringify!($name),
                trades: concat!($($doc),*),
                range: $range,
                hud: $hud,
                applies: Applies::$applies,
                get: |s| Value::from(s.$name),
                set: |s, v| s.$name = <$ty as field::FromValue>::from_value(v),
            },
        )*];
    };
}

const ANY_F32: Range = Range::F32 {
    min: 0.0,
    max: f32::INFINITY,
    open_min: false,
};

const fn slider(min: f64, max: f64) -> Hud {
    Hud::Slider { min, max, log: false }
}

const fn log_slider(min: f64, max: f64) -> Hud {
    Hud::Slider { min, max, log: true }
}

const fn u32s(min: u32, max: u32) -> Range {
    Range::U32 { min, max }
}

settings_table! {
    /// Render width in pixels. Every screen-space pass scales with width × height.
    width: u32 = 960, u32s(1, MAX_SIDE), Hud::Own, Resize;
    /// Render height in pixels.
    height: u32 = 540, u32s(1, MAX_SIDE), Hud::Own, Resize;
    /// Shadow-map edge in texels: sharper shadow edges vs memory and `shadow.map` time.
    shadow_map_size: u32 = 2048, u32s(1, MAX_SIDE), Hud::Choice(&[256, 512, 1024, 2048, 4096, 8192]), ShadowMap;
    /// PCF radius in shadow-map texels: softer, less aliased shadow edges vs
    /// (2r+2)^2 texel fetches per pixel in `light.direct`.
    pcf_radius: u32 = 1, u32s(0, MAX_PCF_RADIUS), slider(0.0, MAX_PCF_RADIUS as f64), NextFrame;
    /// Depth bias of the shadow compare, in light clip-space depth (fraction of the
    /// light's depth range): removes shadow acne vs detaches shadows from casters.
    shadow_bias: f32 = 0.0015, ANY_F32, slider(0.0, 0.02), NextFrame;
    /// Slope-scaled raster depth bias of `shadow.map`: less acne on surfaces at grazing
    /// light angles vs more peter-panning.
    shadow_slope_bias: f32 = 1.5, ANY_F32, slider(0.0, 8.0), ShadowMap;
    /// Exposure multiplier before tonemapping (no time cost).
    exposure: f32 = 1.0, ANY_F32, log_slider(0.05, 8.0), NextFrame;
    /// Strength of the sky's hemispherical ambient light (no time cost).
    ambient: f32 = 0.35, ANY_F32, slider(0.0, 2.0), NextFrame;
    /// What the frame's reflections come from: none, SSR, the hybrid, every pixel
    /// traced (the reference), or the hybrid painted by source (`render --help` says
    /// each).
    mode: Mode = Mode::Hybrid, Range::Any, Hud::Own, NextFrame;
    /// Reflectivity above which a pixel gets a reflection: lower reflects more surfaces
    /// at more SSR and ray-tracing work.
    reflective_min: f32 = 0.02, ANY_F32, slider(0.0, 1.0), NextFrame;
    /// Rays per reflection path in `rt.reflect` (1 = a single reflection): more shows
    /// mirrors within mirrors, each bounce costs another traversal for paths still on a
    /// reflector.
    max_bounces: u32 = 3, u32s(1, 16), slider(1.0, 16.0), NextFrame;
    /// SSR marches through the Hi-Z pyramid (`ssr.hiz`): empty screen regions cost a
    /// few steps and the march finds the first pixel the ray reaches; off, a linear DDA
    /// of `ssr_stride` px steps, kept for comparison.
    ssr_hiz: bool = true, Range::Any, Hud::Checkbox, NextFrame;
    /// SSR step budget per ray (Hi-Z cell visits, or DDA steps): more finds farther
    /// hits, at up to that many depth reads.
    ssr_max_steps: u32 = 64, u32s(1, 4096), log_slider(1.0, 512.0), NextFrame;
    /// Linear DDA step length in pixels (`ssr_hiz` off): longer reaches farther for the same budget but can
    /// step over objects thinner than a step (a hit is refined to the pixel by binary
    /// search inside its step).
    ssr_stride: f32 = 8.0, Range::F32 { min: 0.5, max: MAX_SIDE as f32, open_min: false }, log_slider(0.5, 32.0), NextFrame;
    /// Depth a surface is assumed to have, as a fraction of its distance along the view
    /// axis (so the same at any scene scale): thicker finds hits behind thin
    /// silhouettes but makes false hits behind objects.
    ssr_thickness: f32 = 0.03, ANY_F32, log_slider(0.0, 0.5), NextFrame;
    /// Longest SSR ray, in multiples of the reflecting point's distance along the view
    /// axis (scale-free): longer finds farther hits at more steps.
    ssr_max_distance: f32 = 5.0, ANY_F32, log_slider(0.1, 50.0), NextFrame;
    /// Fraction of the screen's smaller side over which SSR confidence fades at the
    /// edges: larger hides the edge seam but sends more pixels to the ray tracer.
    ssr_edge_fade: f32 = 0.05, ANY_F32, slider(0.0, 0.5), NextFrame;
    /// SSR hits below this confidence fail (go to the ray tracer): higher is cleaner
    /// and slower.
    ssr_min_confidence: f32 = 0.3, ANY_F32, slider(0.0, 1.0), NextFrame;
    /// SSR hits on surfaces whose own mirror reflection, as the pixel shows it, weighs
    /// more than this fail and go to the ray tracer (the screen holds no reflection of a
    /// reflection): the hit surface's reflectivity x Fresnel seen along the ray, times
    /// the pixel's own (toward the camera), the largest channel. Hits where less is
    /// missing (a glossy wall seen in a faint floor) are kept without it: a lower value
    /// is closer to the reference, a higher one ray traces fewer pixels.
    ssr_recursion_min: f32 = 0.02, ANY_F32, slider(0.0, 1.0), NextFrame;
    /// Reflective pixels whose own reflection weighs less than this (reflectivity x
    /// Fresnel toward the camera, the largest channel) are ray traced one in four:
    /// where SSR fails, the even corner of each 2x2 block is traced and the other three
    /// (`untraced`) take its colour, or the sky in the reflected direction where it was
    /// not traced. Higher traces fewer pixels (a dielectric seen head-on weighs 4%) at
    /// a quarter of the detail in weak reflections; 0 traces every failure.
    trace_min_weight: f32 = 0.06, ANY_F32, slider(0.0, 0.5), NextFrame;
    /// Glossy reflections: a reflective surface whose roughness lies between
    /// `glossy_mirror_max` and `glossy_rough_max` reflects rays sampled from its GGX lobe
    /// (visible normals), denoised by `reflect.denoise`, instead of a sharp mirror image.
    /// Off: every reflective surface below `glossy_rough_max` is a mirror, as before
    /// glossy tracing (cheaper, and wrong for rough surfaces).
    glossy: bool = true, Range::Any, Hud::Checkbox, NextFrame;
    /// Sampled reflection rays per glossy pixel and frame: less noise before denoising vs
    /// that many SSR marches and ray-traced paths per pixel (mirror pixels take one).
    reflection_rays: u32 = 1, u32s(1, MAX_REFLECTION_RAYS), slider(1.0, 16.0), NextFrame;
    /// Perceptual roughness below which a reflective surface is an exact mirror (one
    /// ray, no denoising): at 0.05 the GGX lobe (alpha = r^2 = 0.0025) is about two
    /// pixels wide at 960x540 and 60 degrees, so higher keeps more surfaces sharp and
    /// cheap at the cost of visibly blurred ones shown as mirrors.
    glossy_mirror_max: f32 = 0.05, Range::F32 { min: 0.0, max: 1.0, open_min: false }, slider(0.0, 0.3), NextFrame;
    /// Perceptual roughness from which a surface gets no traced reflection, only the
    /// prefiltered sky (FidelityFX SSSR's default cut-off, alpha 0.2): higher traces
    /// wider, noisier lobes at more rays and denoising.
    glossy_rough_max: f32 = 0.45, Range::F32 { min: 0.0, max: 1.0, open_min: false }, slider(0.0, 1.0), NextFrame;
    /// Edge-aware spatial filter of glossy reflections (`reflect.denoise`), radius from
    /// the lobe's width on screen, up to this many pixels (0: off, raw samples): wider
    /// is smoother at more cost and more blur of detail.
    denoise_radius: u32 = 8, u32s(0, 32), slider(0.0, 32.0), NextFrame;
    /// Temporal accumulation of glossy reflections: the running mean's longest window
    /// in frames (0 or 1: off), the history reprojected, dropped where disoccluded and
    /// clamped to the current neighbourhood: longer is smoother and converges further
    /// at more lag after changes.
    denoise_history: u32 = 16, u32s(0, 256), slider(0.0, 64.0), NextFrame;
    /// Seam blur radius in pixels (0: off): smoother SSR/RT transitions vs detail.
    blur_radius: u32 = 3, u32s(0, 16), slider(0.0, 16.0), NextFrame;
    /// Half-width in pixels of the band around SSR/RT seams that the blur touches.
    blur_band: u32 = 3, u32s(0, BLUR_MAX_EXTENT), slider(0.0, BLUR_MAX_EXTENT as f64), NextFrame;
    /// Where shadows come from, on the visible surface and at every ray-traced
    /// reflection hit: the shadow map (cheap, limited by its resolution and bias), a
    /// shadow ray per lit pixel (exact, one any-hit traversal each), or the hybrid (the
    /// map where it is sure, rays where it is not). `adaptive` prices the two of equal
    /// quality, hybrid and rays, from the frame's own timestamps (their first frames,
    /// then one frame in 64) and takes the cheaper.
    shadows: Shadows = Shadows::Map, Range::Any, Hud::Own, NextFrame;
    /// How the G-buffer is made: rasterized (vertex and fragment work, which a GPU that
    /// runs them on few units pays for), or one primary ray a pixel through the tracer
    /// (compute work; the texture's level of detail from ray cones instead of screen
    /// derivatives). Both write the same targets, so every later pass is the same.
    /// `adaptive` prices both from the frame's own timestamps (their first frames, then
    /// one frame in 64) and takes the cheaper; a fixed choice makes frames reproducible.
    visibility: Visibility = Visibility::Adaptive, Range::Any, Hud::Own, NextFrame;
    /// Hybrid shadows: a shadow-map texel within this light-depth distance of the
    /// biased compare leaves the map unsure and the pixel gets a shadow ray (acne and
    /// detached contact shadows live there): wider traces more pixels, closer to
    /// `rays`.
    shadow_band: f32 = 0.0002, ANY_F32, log_slider(0.00001, 0.01), NextFrame;
    /// The ray tracer for every traced ray (reflections with their bounces, shadow
    /// rays, the `rt` reference): Speculum's own BVH, rebuilt or refit on the GPU as
    /// the scene moves, or the driver's acceleration structures through a ray-tracing
    /// pipeline (the ray-tracing hardware where the GPU has it).
    tracer: Tracer = Tracer::Lbvh, Range::Any, Hud::Own, Tracer;
    /// How `hybrid` splits the work: `ssr_first` marches every reflective pixel and
    /// traces what SSR fails; `adaptive` sends a tile's pixels straight to the ray
    /// tracer while SSR answers less of them than a march costs (`exchange_rate`),
    /// probing a sixteenth of them a frame so the tile can win SSR back.
    hybrid_policy: HybridPolicy = HybridPolicy::Adaptive, Range::Any, Hud::Own, NextFrame;
    /// The adaptive hybrid's exchange rate: a march's cost as a fraction of a traced
    /// ray's (0: measured from the frame's own timestamps, and the frame's paths priced
    /// too, so frames follow this run's timings; a fixed value makes them reproducible).
    /// A tile marches first while SSR answers more than this share of its pixels: near
    /// 1 on a CPU driver (a march costs about a ray), about 0.1 on a GPU.
    exchange_rate: f32 = 0.0, Range::F32 { min: 0.0, max: 16.0, open_min: false }, slider(0.0, 2.0), NextFrame;
    /// Simulated seconds per rendered frame of a dynamic scene (a fixed step, so frame
    /// k is the same scene in every run): smaller is smoother motion and more frames
    /// for the same animation.
    sim_dt: f32 = 1.0 / 60.0, Range::F32 { min: 0.0, max: 1.0, open_min: true }, log_slider(0.001, 0.1), NewRenderer;
    /// Build the static scene's BVH (once, at load) with PLOC instead of the LBVH:
    /// its tree is close to a binned-SAH builder's, so every ray walks fewer nodes, at
    /// a slower build. The LBVH's tree is built too, and kept instead where it walks
    /// the reflection and shadow rays of the scene camera's view faster on this device
    /// (measured at load, reported as `static_tree`). Dynamic geometry, rebuilt or
    /// refit per frame, always gets the LBVH.
    static_ploc: bool = true, Range::Any, Hud::Checkbox, StaticBvh;
    /// The nodes the static scene's BVH is walked through: binary (32 bytes, one level
    /// a step), wide (up to four children, 64 bytes, two levels), wide8 (up to eight,
    /// 8-bit boxes, 96 bytes, three levels), or `fastest`: each made at load from the
    /// tree kept and the reflection and shadow rays of the scene camera's view timed
    /// through each, the fastest kept (reported as `static_layout`). Fewer steps walk
    /// fewer dependent loads but test more boxes: on lavapipe binary walks fastest
    /// (wide 0.9-1.1x, wide8 0.6-0.8x); a GPU may favour the wide ones. Every layout
    /// finds the same hits, so this moves time, never pixels.
    static_layout: WalkLayout = WalkLayout::Fastest, Range::Any, Hud::Own, StaticBvh;
    /// Rebuild the dynamic BVH of a scene whose only dynamic geometry is cloth every
    /// frame instead of refitting it (refit is cheaper; its tree loosens as the cloth
    /// deforms).
    cloth_rebuild: bool = false, Range::Any, Hud::Checkbox, NewRenderer;
    /// Rebuild the dynamic BVH of a scene whose only dynamic geometry is rigid bodies
    /// from the bodies' order and each body's own order of its triangles (by their
    /// Morton codes in the body, fixed since the body is rigid): no sort of the
    /// triangles, the bodies' tree above each body's subtree. Off: every triangle
    /// sorted by its Morton code in the scene, as any other rebuild.
    rigid_order: bool = true, Range::Any, Hud::Checkbox, NewRenderer;
    /// When refitting, still rebuild every this many frames (1: always rebuild).
    refit_rebuild_every: u32 = 60, u32s(1, u32::MAX), log_slider(1.0, 600.0), NewRenderer;
}

/// Rays per glossy pixel of the glossy ground truth (`Settings::glossy_reference`) that
/// `render --reference` and `bench modes` measure against unless told otherwise.
pub const GLOSSY_REFERENCE_SPP: u32 = 64;

/// Why a setting of an older Speculum is refused, naming what replaced it.
fn replaced(name: &str) -> Option<String> {
    (name == "shadow_rays").then(|| {
        "setting 'shadow_rays' was replaced by 'shadows': \"map\" (shadow_rays false), \"rays\" (shadow rays \
         on the visible surface and at every reflection hit) or \"hybrid\" (rays where the shadow map is unsure)"
            .into()
    })
}

impl Settings {
    /// Settings from a JSON object: any subset of the fields, the rest defaults. An
    /// array or any other JSON value is refused, as is an unknown field (serde names it,
    /// with its line and column).
    pub fn from_json(text: &str) -> Result<Self> {
        let value: serde_json::Value =
            serde_json::from_str(text).map_err(|e| Error::Settings(format!("not JSON: {e}")))?;
        if !value.is_object() {
            let kind = match value {
                serde_json::Value::Array(_) => "an array",
                serde_json::Value::String(_) => "a string",
                serde_json::Value::Number(_) => "a number",
                serde_json::Value::Bool(_) => "a boolean",
                _ => "null",
            };
            return Err(Error::Settings(format!(
                "settings must be a JSON object {{\"field\": value, ...}}, not {kind}"
            )));
        }
        if let Some(why) = value.as_object().and_then(|o| o.keys().find_map(|k| replaced(k))) {
            return Err(Error::Settings(why));
        }
        // Parsed from the text again (not the value) so errors keep their line and column.
        serde_json::from_str(text).map_err(|e| Error::Settings(e.to_string()))
    }

    /// The `rt` reference of these settings: with glossy reflections, `spp` rays per
    /// glossy pixel in one frame and no denoiser (the glossy ground truth); without,
    /// the same settings in `rt` mode.
    pub fn glossy_reference(&self, spp: u32) -> Settings {
        let mut rt = Settings {
            mode: Mode::Rt,
            ..self.clone()
        };
        if self.glossy {
            rt.reflection_rays = spp;
            rt.denoise_radius = 0;
            rt.denoise_history = 0;
        }
        rt
    }

    /// The names of the fields, in declaration order.
    pub fn field_names() -> Vec<String> {
        FIELDS.iter().map(|f| f.name.to_string()).collect()
    }

    /// These settings with field `name` set to `value`, checked: the value is JSON
    /// (`3`, `0.5`, `true`) or, for the mode, its name (`hybrid`). The one path by
    /// which the demo's HUD and scripts change a setting; an unknown field, a value
    /// of the wrong type or one `validate` refuses is an error naming the field.
    pub fn with_field(&self, name: &str, value: &str) -> Result<Settings> {
        let serde_json::Value::Object(mut map) = serde_json::to_value(self).expect("Settings serialize") else {
            unreachable!("Settings serialize to an object")
        };
        if let Some(why) = replaced(name) {
            return Err(Error::Settings(why));
        }
        if !map.contains_key(name) {
            return Err(Error::Settings(format!(
                "unknown setting '{name}' (settings: {})",
                Self::field_names().join(", ")
            )));
        }
        let parsed =
            serde_json::from_str(value.trim()).unwrap_or_else(|_| serde_json::Value::String(value.trim().into()));
        map.insert(name.into(), parsed);
        let s: Settings = serde_json::from_value(serde_json::Value::Object(map))
            .map_err(|e| Error::Settings(format!("{name} = {value}: {e}")))?;
        s.validate()?;
        Ok(s)
    }

    /// Checks the values that do not depend on the device: each field against its
    /// range in `FIELDS` (the resolution first, named as one).
    pub fn validate(&self) -> Result<()> {
        if self.width == 0 || self.height == 0 || self.width > MAX_SIDE || self.height > MAX_SIDE {
            return Err(Error::Settings(format!(
                "resolution {}x{} is outside 1x1..={MAX_SIDE}x{MAX_SIDE}",
                self.width, self.height
            )));
        }
        match FIELDS.iter().find_map(|f| f.range.check(f.name, (f.get)(self))) {
            Some(why) => Err(Error::Settings(why)),
            None => Ok(()),
        }
    }

    /// The fields that differ from `new` and apply as `applies`.
    pub fn changed(&self, new: &Settings, applies: Applies) -> Vec<&'static str> {
        FIELDS
            .iter()
            .filter(|f| f.applies == applies && (f.get)(self) != (f.get)(new))
            .map(|f| f.name)
            .collect()
    }
}

/// The settings table as Markdown (the README's list, `speculum settings --list`).
pub fn markdown_table() -> String {
    let defaults = Settings::default();
    let mut out =
        String::from("| setting | default | range | a change applies | what it trades |\n|---|---|---|---|---|\n");
    for f in FIELDS {
        let trades = f.trades_line();
        let range = match (f.range, (f.get)(&defaults)) {
            (Range::Any, Value::Mode(_)) => Mode::ALL.map(Mode::name).join(", "),
            (Range::Any, Value::Shadows(_)) => Shadows::ALL.map(Shadows::name).join(", "),
            (Range::Any, Value::Visibility(_)) => Visibility::ALL.map(Visibility::name).join(", "),
            (Range::Any, Value::Tracer(_)) => Tracer::ALL.map(Tracer::name).join(", "),
            (Range::Any, Value::HybridPolicy(_)) => HybridPolicy::ALL.map(HybridPolicy::name).join(", "),
            (Range::Any, Value::WalkLayout(_)) => WalkLayout::ALL.map(WalkLayout::name).join(", "),
            (Range::Any, Value::Bool(_)) => "true, false".into(),
            (r, _) => r.describe(),
        };
        out += &format!(
            "| `{}` | {} | {} | {} | {} |\n",
            f.name,
            (f.get)(&defaults),
            range,
            f.applies.describe(),
            trades.replace('|', "\\|")
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_are_valid() {
        Settings::default().validate().unwrap();
    }

    #[test]
    fn rejects_out_of_range_values() {
        let bad = [
            Settings {
                width: 0,
                ..Default::default()
            },
            Settings {
                height: MAX_SIDE + 1,
                ..Default::default()
            },
            Settings {
                shadow_map_size: 0,
                ..Default::default()
            },
            Settings {
                pcf_radius: crate::shader_defines::MAX_PCF_RADIUS + 1,
                ..Default::default()
            },
            Settings {
                exposure: f32::NAN,
                ..Default::default()
            },
            Settings {
                shadow_bias: -1.0,
                ..Default::default()
            },
        ];
        for s in bad {
            assert!(s.validate().is_err(), "{s:?}");
        }
    }

    #[test]
    fn settings_json_must_be_an_object() {
        for bad in [
            "[1, 2, 3]",
            "42",
            "\"hybrid\"",
            "null",
            "{\"widht\": 320}",
            "{\"width\": \"wide\"}",
        ] {
            assert!(Settings::from_json(bad).is_err(), "{bad}");
        }
        let e = Settings::from_json("[960, 540]").unwrap_err().to_string();
        assert!(e.contains("JSON object") && e.contains("array"), "{e}");
        let s = Settings::from_json("{\"height\": 100}").unwrap();
        assert_eq!((s.width, s.height), (Settings::default().width, 100));
    }

    #[test]
    fn with_field_sets_one_field_or_names_the_problem() {
        let d = Settings::default();
        let s = d.with_field("max_bounces", "2").unwrap();
        assert_eq!(
            s,
            Settings {
                max_bounces: 2,
                ..d.clone()
            }
        );
        assert_eq!(d.with_field("mode", "rt").unwrap().mode, Mode::Rt);
        assert_eq!(d.with_field("ssr_stride", "2.5").unwrap().ssr_stride, 2.5);
        assert!(d.with_field("ssr_stride", "1e300").is_err(), "infinite as f32");
        assert_eq!(d.with_field("shadows", "rays").unwrap().shadows, Shadows::Rays);
        assert_eq!(d.with_field("tracer", "khr").unwrap().tracer, Tracer::Khr);
        for err in [
            d.with_field("shadow_rays", "true").unwrap_err().to_string(),
            Settings::from_json(r#"{"shadow_rays": false}"#)
                .unwrap_err()
                .to_string(),
        ] {
            assert!(err.contains("'shadow_rays' was replaced by 'shadows'"), "{err}");
        }
        for (name, value, says) in [
            ("bounces", "2", "unknown setting 'bounces'"),
            ("max_bounces", "many", "max_bounces"),
            ("max_bounces", "0", "max_bounces 0"),
            ("mode", "shiny", "mode"),
            ("width", "-3", "width"),
        ] {
            let e = d.with_field(name, value).unwrap_err().to_string();
            assert!(e.contains(says), "{name} = {value}: {e}");
        }
        assert_eq!(Settings::field_names().len(), 40);
    }

    /// The README's settings list is the table's (`speculum settings --list`).
    #[test]
    fn readme_lists_the_settings_table() {
        let readme = include_str!("../../README.md");
        let start = "<!-- settings --list -->\n";
        let from = readme.find(start).expect("the README's settings list") + start.len();
        let to = from + readme[from..].find("<!-- end -->").expect("the list's end marker");
        assert_eq!(
            readme[from..to],
            markdown_table(),
            "the README's settings list differs from `speculum settings --list`"
        );
        assert_eq!(markdown_table().lines().count(), FIELDS.len() + 2);
    }

    /// Every field's default is inside its range, and each range refuses a value just
    /// outside it (so `validate` checks every field).
    #[test]
    fn every_field_is_checked_against_its_range() {
        let d = Settings::default();
        for f in FIELDS {
            assert_eq!(f.range.check(f.name, (f.get)(&d)), None, "{} default", f.name);
            let outside: Vec<Value> = match f.range {
                Range::U32 { min, max } => {
                    let below = min.checked_sub(1).map(Value::U32);
                    let above = max.checked_add(1).map(Value::U32);
                    below.into_iter().chain(above).collect()
                }
                Range::F32 { min, max, .. } => {
                    let below = if min > 0.0 { min * 0.5 } else { -1.0 };
                    [below, max * 2.0, f32::NAN].map(Value::F32).to_vec()
                }
                Range::Any => Vec::new(),
            };
            for v in outside {
                let mut s = d.clone();
                (f.set)(&mut s, v);
                let e = s.validate().expect_err(f.name).to_string();
                assert!(e.contains(f.name) || e.contains("resolution"), "{} = {v}: {e}", f.name);
            }
        }
    }

    #[test]
    fn json_round_trip_and_unknown_fields() {
        let s: Settings = serde_json::from_str(r#"{"width": 320, "pcf_radius": 2}"#).unwrap();
        assert_eq!((s.width, s.height, s.pcf_radius), (320, Settings::default().height, 2));
        assert!(serde_json::from_str::<Settings>(r#"{"widht": 320}"#).is_err());
    }
}

/// How the frame's hybrid chooses (the one place that decides it: the frame plan,
/// the reports and the benchmarks ask here).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hybrid {
    /// No hybrid choice: a mode that does not both march and trace, or the SSR-first
    /// policy (every tile marches first).
    None,
    /// Adaptive at a fixed exchange rate (`exchange_rate` in `TILE_ONE` units).
    Fixed(u32),
    /// Adaptive at the rate the frames measure, its paths chosen by their prices.
    Measured,
}

impl Hybrid {
    /// The hybrid of `st` in its own mode.
    pub fn of(st: &Settings) -> Self {
        if st.mode.marches() && st.mode.traces() {
            Self::of_policy(st)
        } else {
            Self::None
        }
    }

    /// The hybrid `st`'s policy gives a mode that marches and traces (what `bench
    /// modes` runs its hybrid modes with, whatever the base settings' mode).
    pub fn of_policy(st: &Settings) -> Self {
        match st.hybrid_policy {
            HybridPolicy::SsrFirst => Self::None,
            HybridPolicy::Adaptive if st.exchange_rate == 0.0 => Self::Measured,
            HybridPolicy::Adaptive => {
                Self::Fixed((st.exchange_rate * TILE_ONE as f32).round().clamp(1.0, 4096.0) as u32)
            }
        }
    }

    pub fn adaptive(self) -> bool {
        self != Self::None
    }

    /// Paths chosen by their measured prices (`exchange::Paths`).
    pub fn priced(self) -> bool {
        self == Self::Measured
    }
}

/// SSR settings (see `Settings` for what each trades).
#[derive(Clone, Copy, Debug)]
pub struct SsrParams {
    pub hiz: bool,
    pub max_steps: u32,
    pub stride: f32,
    pub thickness: f32,
    pub max_distance: f32,
    pub edge_fade: f32,
    pub min_confidence: f32,
    pub reflective_min: f32,
    /// Hits on surfaces more reflective than this fail (need the ray tracer's bounce).
    pub recursion_min: f32,
    /// Failed pixels whose own reflection weighs less are not traced (`FAIL_UNTRACED`).
    pub trace_min_weight: f32,
    /// The adaptive hybrid's exchange rate in 1/`TILE_ONE` (a march's cost in rays),
    /// or 0: every tile SSR-first (the SSR-first policy, and the `ssr` mode).
    pub tile_rate: u32,
    /// The march only measures the tiles: every marched pixel ends as a rays-only
    /// tile's probe does (the adaptive hybrid's probe frame while idle).
    pub measure_only: bool,
}

impl SsrParams {
    /// The SSR fields of the frame's settings.
    pub fn from_settings(st: &Settings) -> Self {
        Self {
            hiz: st.ssr_hiz,
            max_steps: st.ssr_max_steps,
            stride: st.ssr_stride,
            thickness: st.ssr_thickness,
            max_distance: st.ssr_max_distance,
            edge_fade: st.ssr_edge_fade,
            min_confidence: st.ssr_min_confidence,
            reflective_min: st.reflective_min,
            recursion_min: st.ssr_recursion_min,
            trace_min_weight: st.trace_min_weight,
            // Measured: the frame's plan puts in the rate the frames measure.
            tile_rate: match Hybrid::of(st) {
                Hybrid::Fixed(rate) => rate,
                Hybrid::None | Hybrid::Measured => 0,
            },
            measure_only: false,
        }
    }
}
