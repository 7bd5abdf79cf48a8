//! The windowed demo, driven by scripts under an X server (Xvfb), with validation on.
//! Its own test binary (`harness = false`): winit allows one event loop per process on
//! the main thread, so each case runs the `speculum` binary as a child.
//!
//! Uses `$DISPLAY` when it names a working server, else starts `Xvfb`; when neither is
//! possible every case is skipped with a message saying so (exit 0).

mod common;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// An X server for the cases: the caller's, or an Xvfb this test started.
struct Display {
    name: String,
    xvfb: Option<Child>,
}

impl Drop for Display {
    fn drop(&mut self) {
        if let Some(x) = &mut self.xvfb {
            // SIGTERM lets Xvfb remove its lock and socket (SIGKILL, `Child::kill`,
            // left them behind, and 20 stale numbers later no display was free);
            // SIGKILL only if it does not exit within 5 s.
            let terminated = Command::new("kill")
                .args(["-TERM", &x.id().to_string()])
                .status()
                .is_ok_and(|s| s.success());
            let start = Instant::now();
            while terminated && start.elapsed() < Duration::from_secs(5) {
                if let Ok(Some(_)) = x.try_wait() {
                    return;
                }
                std::thread::sleep(Duration::from_millis(20));
            }
            let _ = x.kill();
            let _ = x.wait();
        }
    }
}

fn display_works(name: &str) -> bool {
    // An X server listens on /tmp/.X11-unix/X<n> for display :<n>.
    let n = name.trim_start_matches(':').split('.').next().unwrap_or("");
    Path::new(&format!("/tmp/.X11-unix/X{n}")).exists()
}

fn find_display() -> Result<Display, String> {
    if let Ok(name) = std::env::var("DISPLAY") {
        if display_works(&name) {
            return Ok(Display { name, xvfb: None });
        }
    }
    // Xvfb chooses a free number itself and writes it to its stdout once it accepts
    // connections (`-displayfd`): two test binaries at once each get their own server
    // (a number chosen here by its lock file was raced: both took one, and the first
    // to finish killed the other's server).
    let mut child = Command::new("Xvfb")
        .args(["-displayfd", "1", "-screen", "0", "1280x720x24", "-nolisten", "tcp"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| format!("cannot start Xvfb ({e}); install xvfb"))?;
    let stdout = child.stdout.take().expect("piped");
    let (send, receive) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut line = String::new();
        let _ = std::io::BufRead::read_line(&mut std::io::BufReader::new(stdout), &mut line);
        let _ = send.send(line);
    });
    let mut display = Display {
        name: String::new(),
        xvfb: Some(child),
    };
    match receive.recv_timeout(Duration::from_secs(10)) {
        Ok(line) if line.trim().parse::<u32>().is_ok() => {
            display.name = format!(":{}", line.trim());
            Ok(display)
        }
        Ok(line) => Err(format!("Xvfb did not start (it said {line:?})")),
        Err(_) => Err("Xvfb did not start within 10 s".into()),
    }
}

struct Run {
    ok: bool,
    stderr: String,
    stdout: String,
}

/// Runs `speculum demo --validation` with `args` on `display`.
fn demo(display: &Display, args: &[&str]) -> Run {
    let out = common::speculum(["demo", "--validation"])
        .args(args)
        .env("DISPLAY", &display.name)
        .env_remove("WAYLAND_DISPLAY")
        .run();
    Run {
        ok: out.ok(),
        stderr: out.stderr,
        stdout: out.stdout,
    }
}

/// The run succeeded and the validation layer said nothing (leaked objects at exit
/// included: they are reported when the device is destroyed).
fn assert_clean(run: &Run, what: &str) {
    assert!(run.ok, "{what} failed:\n{}", run.stderr);
    let messages: Vec<&str> = run.stderr.lines().filter(|l| l.contains("[vulkan")).collect();
    assert!(
        messages.is_empty(),
        "{what}: validation messages:\n{}",
        messages.join("\n")
    );
}

fn script(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Writes `text` as a script, runs the demo on it with `args`, and checks the run is
/// clean; its output.
fn scripted(display: &Display, dir: &Path, what: &str, text: &str, args: &[&str]) -> Run {
    let s = script(dir, &format!("{what}.txt"), text);
    let mut all = args.to_vec();
    all.extend(["--script", s.to_str().unwrap()]);
    let run = demo(display, &all);
    assert_clean(&run, what);
    run
}

fn png(path: &Path) -> image::RgbaImage {
    speculum::metrics::load_rgba(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A window shot (the swapchain image copied out after the blit) with the HUD hidden
/// is the frame itself, pixel for pixel: the blit at the same size copies, and the
/// copy's channel order is undone; with the HUD shown it differs. The window shot is
/// the frame after, so what changes from frame to frame is fixed: glossy reflections
/// are off (their samples change every frame), the G-buffer rasterized and the hybrid
/// SSR-first (the adaptive stages' pricing frames and the adaptive hybrid's probe
/// frames and tile flips follow this run's timings).
fn window_shot_is_the_frame(display: &Display, dir: &Path) {
    let d = dir.display();
    let text = format!(
        "set glossy false\nset visibility raster\nset hybrid_policy ssr_first\nwait 2\n\
         window-shot {d}/with_hud.png\nwait 1\nkey h\nwait 2\nscreenshot {d}/frame.png\n\
         window-shot {d}/window.png\nwait 2\n"
    );
    scripted(
        display,
        dir,
        "window_shot",
        &text,
        &["--scene", "room", "--width", "320", "--height", "180"],
    );
    let (frame, window) = (png(&dir.join("frame.png")), png(&dir.join("window.png")));
    assert_eq!(window.dimensions(), (320, 180));
    assert!(frame == window, "the window shot without the HUD is not the frame");
    assert!(
        png(&dir.join("with_hud.png")) != frame,
        "the HUD is not in the window shot"
    );
}

/// Every mode in turn, a screenshot in each; the hybrid one is what `speculum render`
/// makes of the same view and settings (the SSR-first hybrid: the adaptive one's path
/// follows each run's timings, and the demo's frame is not render's first).
fn modes_match_render(display: &Display, dir: &Path) {
    let mut text = String::from("set hybrid_policy ssr_first\nwait 2\n");
    for k in 1..=5 {
        text += &format!("key {k}\nwait 2\nscreenshot {}/mode{k}.png\n", dir.display());
    }
    text += &format!("key 3\nkey f\nwait 2\nscreenshot {}/failmask.png\n", dir.display());
    scripted(
        display,
        dir,
        "modes",
        &text,
        &["--scene", "mirrors", "--width", "320", "--height", "180"],
    );
    let shots: Vec<image::RgbaImage> = (1..=5).map(|k| png(&dir.join(format!("mode{k}.png")))).collect();
    for (k, shot) in shots.iter().enumerate() {
        assert_eq!(shot.dimensions(), (320, 180), "mode {}", k + 1);
        let meta = json(&dir.join(format!("mode{}.json", k + 1)));
        let want = speculum::settings::Mode::ALL[k].name();
        assert_eq!(meta["mode"], want);
    }
    for a in 0..5 {
        for b in a + 1..5 {
            // ssr and hybrid agree where SSR answers; every other pair differs widely.
            assert!(shots[a] != shots[b], "modes {} and {} look the same", a + 1, b + 1);
        }
    }
    assert!(
        png(&dir.join("failmask.png")) != shots[2],
        "the fail-mask view differs from the frame"
    );

    let meta = json(&dir.join("mode3.json"));
    let v = |key: &str| {
        let a = meta["camera"][key].as_array().unwrap();
        format!("{},{},{}", a[0], a[1], a[2])
    };
    let out = dir.join("render_hybrid.png");
    let settings = dir.join("ssr_first.json");
    std::fs::write(&settings, r#"{"hybrid_policy": "ssr_first"}"#).unwrap();
    let r = common::speculum([
        "render", "--scene", "mirrors", "--mode", "hybrid", "--width", "320", "--height", "180",
    ])
    .args(["--frames", "1", "--warmup", "0", "--quiet"])
    .arg("--settings")
    .arg(&settings)
    .arg(format!("--camera-pos={}", v("position")))
    .arg(format!("--camera-target={}", v("target")))
    .arg("--out")
    .arg(&out)
    .run();
    assert!(r.ok(), "{}", r.stderr);
    let c = speculum::metrics::compare_files(&dir.join("mode3.png"), &out).unwrap();
    println!(
        "demo hybrid screenshot vs render: SSIM {:.5}, RMSE {:.5}",
        c.ssim, c.rmse
    );
    assert!(c.ssim >= 0.99, "SSIM {} against render", c.ssim);
}

/// 50 resizes to random sizes (1x1 among them) and 10 minimize/restore cycles, then
/// a screenshot that is not blank; no validation message throughout.
fn resize_storm(display: &Display, dir: &Path) {
    let mut rng = 0x2545F491u32;
    let mut next = |n: u32| {
        rng ^= rng << 13;
        rng ^= rng >> 17;
        rng ^= rng << 5;
        rng % n
    };
    let mut text = String::from("wait 2\n");
    for i in 0..50 {
        let (w, h) = if i % 10 == 3 {
            (1, 1)
        } else {
            (1 + next(700), 1 + next(500))
        };
        text += &format!("resize {w} {h}\nwait {}\n", 1 + next(2));
        if i % 5 == 0 {
            text += "minimize\nwait 2\nrestore\nwait 1\n";
        }
    }
    text += &format!("resize 400 240\nwait 3\nscreenshot {}/storm.png\n", dir.display());
    let run = scripted(
        display,
        dir,
        "storm",
        &text,
        &["--width", "320", "--height", "180", "--verbose"],
    );
    let recreations = run.stderr.lines().filter(|l| l.contains("demo: swapchain ")).count();
    assert!(
        recreations >= 30,
        "only {recreations} swapchain recreations:\n{}",
        run.stderr
    );
    let shot = png(&dir.join("storm.png"));
    assert_eq!(shot.dimensions(), (400, 240));
    let luma: Vec<f64> = speculum::metrics::luma(shot.as_raw());
    let mean = luma.iter().sum::<f64>() / luma.len() as f64;
    let var = luma.iter().map(|l| (l - mean).powi(2)).sum::<f64>() / luma.len() as f64;
    assert!(
        mean > 0.05 && var > 1e-3,
        "blank screenshot: mean {mean}, variance {var}"
    );
}

/// The HUD's setting path (`set`): bounces, SSR budget and resolution change the image
/// (the SSR-first hybrid, which marches every frame).
fn settings_change_the_image(display: &Display, dir: &Path) {
    let d = dir.display();
    let text = format!(
        "set hybrid_policy ssr_first\nwait 2\nscreenshot {d}/base.png\nset max_bounces 1\nwait 2\nscreenshot {d}/bounces.png\n\
         set max_bounces 3\nset ssr_max_steps 4\nwait 2\nscreenshot {d}/steps.png\n\
         set ssr_max_steps 64\nset width 240\nwait 2\nscreenshot {d}/width.png\n\
         save-settings {d}/saved.json\n"
    );
    scripted(
        display,
        dir,
        "settings",
        &text,
        &["--scene", "mirrors", "--width", "320", "--height", "180"],
    );
    let base = png(&dir.join("base.png"));
    assert!(png(&dir.join("bounces.png")) != base, "max_bounces changes the image");
    assert!(png(&dir.join("steps.png")) != base, "ssr_max_steps changes the image");
    assert_eq!(
        png(&dir.join("width.png")).dimensions(),
        (240, 180),
        "the width changes the size"
    );
    let saved = std::fs::read_to_string(dir.join("saved.json")).unwrap();
    let s = speculum::Settings::from_json(&saved).unwrap();
    assert_eq!(
        (s.width, s.max_bounces, s.ssr_max_steps),
        (240, 3, 64),
        "save-settings writes what render reads"
    );
}

/// A dynamic scene: paused it holds still, `.` steps it once, Backspace restarts it
/// (glossy reflections off: their samples change every frame, paused or not; the
/// SSR-first hybrid: the adaptive one's probe frames march where its other frames may
/// not, a change of a few pixels; the G-buffer rasterized: the adaptive visibility's
/// pricing frames, which trace it, last as long as their timings fail their
/// self-check, longer on a loaded machine, and move a few edge pixels).
fn animation_controls(display: &Display, dir: &Path) {
    let d = dir.display();
    let text = format!(
        "set glossy false\nset hybrid_policy ssr_first\nset visibility raster\nwait 4\nkey space\nwait 2\nscreenshot {d}/a.png\nwait 2\nscreenshot {d}/b.png\nkey .\nwait 2\n\
         screenshot {d}/c.png\nkey backspace\nwait 2\nscreenshot {d}/d.png\n"
    );
    scripted(
        display,
        dir,
        "animation",
        &text,
        &["--scene", "drop", "--width", "240", "--height", "135"],
    );
    let steps = |n: &str| json(&dir.join(format!("{n}.json")))["sim_steps"].as_u64().unwrap();
    assert!(
        steps("a") >= 4 && steps("b") == steps("a"),
        "paused: {} then {}",
        steps("a"),
        steps("b")
    );
    assert!(
        png(&dir.join("a.png")) == png(&dir.join("b.png")),
        "a paused scene holds still"
    );
    assert_eq!(steps("c"), steps("b") + 1, "one step");
    assert!(
        png(&dir.join("c.png")) != png(&dir.join("b.png")),
        "a step moves the bodies"
    );
    assert_eq!(steps("d"), 0, "restarted (and still paused)");
}

/// A bad script is refused with its line before a window opens; a bad setting in it
/// fails the run when its step comes, naming the setting; a missing script is named.
fn bad_scripts_are_refused(display: &Display, dir: &Path) {
    for (text, says) in [
        ("wait 2\njump 3\n", "script line 2"),
        ("wait 2\nset max_bounces 0\n", "max_bounces 0"),
        ("wait 2\nset no_such_setting 1\n", "unknown setting"),
    ] {
        let s = script(dir, "bad.txt", text);
        let run = demo(
            display,
            &["--width", "160", "--height", "90", "--script", s.to_str().unwrap()],
        );
        assert!(!run.ok, "{text:?} ran");
        assert!(run.stderr.contains(says), "{text:?}: {}", run.stderr);
    }
    let run = demo(display, &["--script", "/no/such/script.txt"]);
    assert!(!run.ok && run.stderr.contains("demo script"), "{}", run.stderr);
    let _ = run.stdout;
}

/// One case: a display and a folder of its own.
type Case = fn(&Display, &Path);

fn main() {
    // `cargo test -- --list` and filters: this binary has one test.
    let args: Vec<String> = std::env::args().collect();
    if args.iter().any(|a| a == "--list") {
        println!("demo: test");
        return;
    }
    let display = match find_display() {
        Ok(d) => d,
        Err(why) => {
            println!("demo tests skipped: no X server ({why})");
            return;
        }
    };
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, Case); 6] = [
        ("modes_match_render", modes_match_render),
        ("window_shot_is_the_frame", window_shot_is_the_frame),
        ("resize_storm", resize_storm),
        ("settings_change_the_image", settings_change_the_image),
        ("animation_controls", animation_controls),
        ("bad_scripts_are_refused", bad_scripts_are_refused),
    ];
    // Names to run (libtest's filters); options and their values are ignored.
    let mut filter: Vec<&String> = Vec::new();
    let mut skip_value = false;
    for a in args.iter().skip(1) {
        if std::mem::take(&mut skip_value) {
            continue;
        }
        if a.starts_with('-') {
            skip_value = matches!(a.as_str(), "--test-threads" | "--skip" | "--format" | "--color");
            continue;
        }
        filter.push(a);
    }
    for (name, case) in cases {
        if !filter.is_empty() && !filter.iter().any(|f| name.contains(f.as_str())) {
            continue;
        }
        let start = Instant::now();
        let sub = dir.path().join(name);
        std::fs::create_dir_all(&sub).unwrap();
        case(&display, &sub);
        println!("test demo::{name} ... ok ({:.1} s)", start.elapsed().as_secs_f64());
    }
}
