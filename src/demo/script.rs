//! Demo scripts (`speculum demo --script FILE`): the demo driven without a person, for
//! tests and CI under Xvfb. One step per line, `#` starts a comment:
//!
//! ```text
//! wait 10                 # run 10 frames (skipped ones, while minimized, count too)
//! key 3                   # press a key as a person would (see `Action::from_key`)
//! set max_bounces 2       # set a setting through the HUD's path (Settings::with_field)
//! resize 640 360          # ask the window system for this window size
//! minimize                # minimize the window (rendering stops until restore)
//! restore
//! camera 1,2,3 0,0,0      # put the camera at a position, looking at a target
//! screenshot out.png      # the last frame without the HUD, plus out.json beside it
//! window-shot win.png     # the next frame as the window shows it, HUD included
//! compare                 # render the view in rt mode and print SSIM/RMSE against it
//! save-settings s.json    # what the HUD's "save settings" button writes
//! quit                    # exit 0 (the end of the script quits too)
//! ```

use crate::error::{Error, Result};
use crate::settings::Mode;
use glam::Vec3;
use std::path::PathBuf;

/// What a key press does (the same for a person and a script).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Action {
    /// 1–5: raster, ssr, hybrid, rt, provenance.
    Mode(Mode),
    /// F: paint the fail mask instead of the frame.
    FailMask,
    /// H: hide or show the HUD.
    Hud,
    /// P: save a screenshot without the HUD (and its JSON).
    Screenshot,
    /// Space: pause or play the animation.
    Pause,
    /// Period: one animation step while paused.
    Step,
    /// Backspace: restart the animation.
    Restart,
    /// R: back to the scene's camera.
    ResetCamera,
    /// C: compare the view with `rt`.
    Compare,
    /// M: next present mode the surface offers (FIFO, MAILBOX, IMMEDIATE).
    PresentMode,
    /// Escape: quit.
    Quit,
}

/// The keys of `Action`s and what they do, for `--help` and `docs/demo.md`.
pub const KEYS: &[(&str, &str)] = &[
    ("1-5", "mode: raster, ssr, hybrid, rt, provenance"),
    ("F", "fail-mask view (colours by fail reason; legend in the HUD)"),
    ("H", "hide / show the HUD"),
    (
        "P",
        "screenshot without the HUD: speculum_NNNN.png + .json (settings, camera, timings)",
    ),
    ("Space", "pause / play the animation"),
    (".", "one animation step while paused"),
    ("Backspace", "restart the animation"),
    ("R", "reset the camera to the scene's"),
    ("C", "compare the view with rt (SSIM, RMSE)"),
    ("M", "next present mode (fifo, mailbox, immediate where supported)"),
    ("Esc", "quit"),
    ("W A S D, Q E", "fly forward, left, back, right, down, up (Shift: 4x)"),
    ("right mouse + move", "look around"),
    ("scroll", "fly speed"),
];

impl Action {
    /// The action of a key by its name: `1`..`5`, `f`, `h`, `p`, `space`, `.`,
    /// `backspace`, `r`, `c`, `m`, `escape` (case-insensitive).
    pub fn from_key(name: &str) -> Option<Action> {
        Some(match name.to_ascii_lowercase().as_str() {
            "1" => Action::Mode(Mode::Raster),
            "2" => Action::Mode(Mode::Ssr),
            "3" => Action::Mode(Mode::Hybrid),
            "4" => Action::Mode(Mode::Rt),
            "5" => Action::Mode(Mode::Provenance),
            "f" => Action::FailMask,
            "h" => Action::Hud,
            "p" => Action::Screenshot,
            "space" => Action::Pause,
            "." | "period" => Action::Step,
            "backspace" => Action::Restart,
            "r" => Action::ResetCamera,
            "c" => Action::Compare,
            "m" => Action::PresentMode,
            "escape" | "esc" => Action::Quit,
            _ => return None,
        })
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum Step {
    Wait(u32),
    Key(Action),
    Set(String, String),
    Resize(u32, u32),
    Minimize,
    Restore,
    Camera(Vec3, Vec3),
    Screenshot(PathBuf),
    WindowShot(PathBuf),
    Compare,
    SaveSettings(PathBuf),
    Quit,
}

fn vec3(s: &str) -> Option<Vec3> {
    let v: Vec<f32> = s.split(',').map(|c| c.trim().parse().ok()).collect::<Option<_>>()?;
    (v.len() == 3 && v.iter().all(|c| c.is_finite())).then(|| Vec3::new(v[0], v[1], v[2]))
}

/// Parses a script; an error names the line and what is wrong with it. Settings are
/// checked when the step runs (they depend on the settings before it).
pub fn parse(text: &str) -> Result<Vec<Step>> {
    let mut steps = Vec::new();
    for (i, raw) in text.lines().enumerate() {
        let line = raw.split('#').next().unwrap_or("").trim();
        if line.is_empty() {
            continue;
        }
        steps.push(parse_step(line, i + 1)?);
    }
    Ok(steps)
}

/// One step of a script: `line` (comment and blanks stripped, not empty) at line
/// `number`.
fn parse_step(line: &str, number: usize) -> Result<Step> {
    let words: Vec<&str> = line.split_whitespace().collect();
    let bad = |why: &str| Error::Input(format!("script line {number}: '{line}': {why}"));
    let args = |n: usize| -> Result<()> {
        if words.len() != n + 1 {
            return Err(bad(&format!("'{}' takes {n} argument(s)", words[0])));
        }
        Ok(())
    };
    Ok(match words[0] {
        "wait" => {
            args(1)?;
            let n: u32 = words[1].parse().map_err(|_| bad("frames must be a whole number"))?;
            if n > 1_000_000 {
                return Err(bad("at most 1000000 frames"));
            }
            Step::Wait(n)
        }
        "key" => {
            args(1)?;
            Step::Key(
                Action::from_key(words[1])
                    .ok_or_else(|| bad("unknown key (keys: 1-5 f h p space . backspace r c m escape)"))?,
            )
        }
        "set" => {
            if words.len() < 3 {
                return Err(bad("'set' takes a setting and a value"));
            }
            Step::Set(words[1].into(), words[2..].join(" "))
        }
        "resize" => {
            args(2)?;
            let side = |s: &str| -> Result<u32> {
                match s.parse::<u32>() {
                    Ok(v) if (1..=crate::settings::MAX_SIDE).contains(&v) => Ok(v),
                    _ => Err(bad(&format!("sizes are 1..={}", crate::settings::MAX_SIDE))),
                }
            };
            Step::Resize(side(words[1])?, side(words[2])?)
        }
        "minimize" => {
            args(0)?;
            Step::Minimize
        }
        "restore" => {
            args(0)?;
            Step::Restore
        }
        "camera" => {
            args(2)?;
            let p = vec3(words[1]).ok_or_else(|| bad("position must be x,y,z"))?;
            let t = vec3(words[2]).ok_or_else(|| bad("target must be x,y,z"))?;
            if p == t {
                return Err(bad("the camera must not look at its own position"));
            }
            Step::Camera(p, t)
        }
        "screenshot" => {
            args(1)?;
            let path = PathBuf::from(words[1]);
            crate::output::check(&path, crate::output::Kind::Png)?;
            Step::Screenshot(path)
        }
        "window-shot" => {
            args(1)?;
            let path = PathBuf::from(words[1]);
            crate::output::check(&path, crate::output::Kind::Png)?;
            Step::WindowShot(path)
        }
        "compare" => {
            args(0)?;
            Step::Compare
        }
        "save-settings" => {
            args(1)?;
            let path = PathBuf::from(words[1]);
            crate::output::check(&path, crate::output::Kind::Json)?;
            Step::SaveSettings(path)
        }
        "quit" => {
            args(0)?;
            Step::Quit
        }
        other => {
            return Err(bad(&format!(
                "unknown step '{other}' (steps: wait, key, set, resize, minimize, restore, camera, screenshot, \
                 window-shot, compare, save-settings, quit)"
            )))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_step() {
        let dir = std::env::temp_dir();
        let shot = dir.join("speculum_script_test.png");
        let text = format!(
            "# a comment\nwait 3\nkey 4   # rt\nkey F\nset mode hybrid\nset ssr_stride 2.5\nresize 320 200\n\
             minimize\nrestore\ncamera 1,2,3 0,0.5,0\nscreenshot {}\ncompare\nquit\n",
            shot.display()
        );
        let steps = parse(&text).unwrap();
        assert_eq!(
            steps,
            vec![
                Step::Wait(3),
                Step::Key(Action::Mode(Mode::Rt)),
                Step::Key(Action::FailMask),
                Step::Set("mode".into(), "hybrid".into()),
                Step::Set("ssr_stride".into(), "2.5".into()),
                Step::Resize(320, 200),
                Step::Minimize,
                Step::Restore,
                Step::Camera(Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.0, 0.5, 0.0)),
                Step::Screenshot(shot),
                Step::Compare,
                Step::Quit,
            ]
        );
    }

    #[test]
    fn bad_lines_are_named() {
        for (text, says) in [
            ("wait\n", "line 1"),
            ("wait 3\nwait x\n", "line 2"),
            ("key Z\n", "unknown key"),
            ("resize 0 10\n", "sizes"),
            ("resize 10\n", "2 argument"),
            ("camera 1,2 0,0,0\n", "position"),
            ("camera 1,2,3 1,2,3\n", "own position"),
            ("screenshot out.jpg\n", "PNG"),
            ("jump\n", "unknown step 'jump'"),
            ("set max_bounces\n", "a setting and a value"),
        ] {
            let e = parse(text).unwrap_err().to_string();
            assert!(e.contains(says), "{text:?}: {e}");
        }
    }
}
