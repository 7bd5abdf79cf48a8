//! What the settings table says of each field (`super::FIELDS`): its range, how the
//! HUD shows it, how a change applies, and its value as one type for generic code
//! (validation, the HUD, the README's list).

use super::{HybridPolicy, Mode, Settings, Shadows, Tracer, Visibility, WalkLayout};

/// One setting: everything the struct, validation, the renderer, the HUD, the CLI and
/// the README need to know of it.
pub struct Field {
    pub name: &'static str,
    /// What it trades (quality against time), from the field's documentation.
    pub trades: &'static str,
    pub range: Range,
    pub hud: Hud,
    pub applies: Applies,
    pub get: fn(&Settings) -> Value,
    /// Sets the field; `value` is of the field's type (as `get` returns it).
    pub set: fn(&mut Settings, Value),
}

/// The values a field accepts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Range {
    /// Integers in `min..=max`.
    U32 { min: u32, max: u32 },
    /// Finite numbers in `min..=max` (`max` infinite: no upper bound), or in
    /// `(min, max]` when `open_min`.
    F32 { min: f32, max: f32, open_min: bool },
    /// Every value of the type (a flag, a mode).
    Any,
}

/// How the demo's HUD shows a field.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Hud {
    /// A slider over `min..=max` (typing may go beyond, within `Range`), logarithmic
    /// when `log`.
    Slider {
        min: f64,
        max: f64,
        log: bool,
    },
    /// A list of values to pick from.
    Choice(&'static [u32]),
    Checkbox,
    /// Shown elsewhere (the resolution list, the mode buttons).
    Own,
}

/// How a change of the field reaches the frame (`Renderer::set_settings`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Applies {
    /// Read as the next frame is recorded.
    NextFrame,
    /// Recreates the screen-sized images and lists (waits for the GPU).
    Resize,
    /// Recreates the shadow map (waits for the GPU).
    ShadowMap,
    /// Rebuilds the static scene's BVH (waits for the GPU).
    StaticBvh,
    /// A dynamic scene's simulation is made with it: a new renderer (the animation
    /// restarts); a static scene's applies it next frame.
    NewRenderer,
    /// Remakes the tracing passes and the tracer's structures (waits for the GPU).
    Tracer,
}

impl Field {
    /// What the field trades, on one line (its documentation's lines joined).
    pub fn trades_line(&self) -> String {
        self.trades.split_whitespace().collect::<Vec<_>>().join(" ")
    }
}

impl Applies {
    pub fn describe(self) -> &'static str {
        match self {
            Applies::NextFrame => "next frame",
            Applies::Resize => "resize",
            Applies::ShadowMap => "new shadow map",
            Applies::StaticBvh => "static BVH rebuilt",
            Applies::NewRenderer => "new renderer (dynamic scenes)",
            Applies::Tracer => "new tracer",
        }
    }
}

/// A field's value.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    U32(u32),
    F32(f32),
    Bool(bool),
    Mode(Mode),
    Shadows(Shadows),
    Visibility(Visibility),
    Tracer(Tracer),
    HybridPolicy(HybridPolicy),
    WalkLayout(WalkLayout),
}

/// The field's type back from a `Value` (`Field::set`); a value of another type is a
/// bug in the caller.
pub trait FromValue: Sized {
    fn from_value(v: Value) -> Self;
}

/// `Value` from a field's type and back.
macro_rules! value_of {
    ($t:ty, $variant:ident) => {
        impl From<$t> for Value {
            fn from(v: $t) -> Self {
                Value::$variant(v)
            }
        }

        impl FromValue for $t {
            fn from_value(v: Value) -> Self {
                match v {
                    Value::$variant(x) => x,
                    other => panic!("a {} setting given {other:?}", stringify!($t)),
                }
            }
        }
    };
}
value_of!(u32, U32);
value_of!(f32, F32);
value_of!(bool, Bool);
value_of!(Mode, Mode);
value_of!(Shadows, Shadows);
value_of!(Visibility, Visibility);
value_of!(Tracer, Tracer);
value_of!(HybridPolicy, HybridPolicy);
value_of!(WalkLayout, WalkLayout);

impl std::fmt::Display for Value {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Value::U32(v) => write!(f, "{v}"),
            Value::F32(v) => write!(f, "{v}"),
            Value::Bool(v) => write!(f, "{v}"),
            Value::Mode(m) => write!(f, "{}", m.name()),
            Value::Shadows(m) => write!(f, "{}", m.name()),
            Value::Visibility(v) => write!(f, "{}", v.name()),
            Value::Tracer(t) => write!(f, "{}", t.name()),
            Value::HybridPolicy(p) => write!(f, "{}", p.name()),
            Value::WalkLayout(l) => write!(f, "{}", l.name()),
        }
    }
}

impl Range {
    /// Why `v` (of the field `name`) is outside the range; `None` when it is inside.
    pub fn check(&self, name: &str, v: Value) -> Option<String> {
        match (*self, v) {
            (Range::U32 { min, max }, Value::U32(v)) if v < min || v > max => {
                Some(format!("{name} {v} is outside {min}..={max}"))
            }
            (Range::F32 { min, max, open_min }, Value::F32(v)) => {
                let inside = v.is_finite() && v <= max && if open_min { v > min } else { v >= min };
                match () {
                    _ if inside => None,
                    _ if open_min => Some(format!("{name} {v} must be a finite number in ({min}, {max}]")),
                    _ if max.is_infinite() => Some(format!("{name} {v} must be a finite number >= {min}")),
                    _ => Some(format!("{name} {v} must be a finite number in {min}..={max}")),
                }
            }
            _ => None,
        }
    }

    /// The range as the README's list writes it.
    pub fn describe(&self) -> String {
        match *self {
            Range::U32 { min, max: u32::MAX } => format!(">= {min}"),
            Range::U32 { min, max } => format!("{min}..={max}"),
            Range::F32 {
                min,
                max,
                open_min: true,
            } => format!("({min}, {max}]"),
            Range::F32 { min, max, .. } if max.is_infinite() => format!(">= {min}"),
            Range::F32 { min, max, .. } => format!("{min}..={max}"),
            Range::Any => "any".into(),
        }
    }
}
