//! Outputs respect what they would replace (issue 20, classes 1-3): a target that is
//! not a regular file is refused, a symlink is written through, two outputs of one run
//! never name the same file nor an input, and an unwritable folder is found before any
//! GPU work. Every refusal is one `error:` line and exit 1, and leaves every output
//! and input as it was. Runs the real `speculum` binary.

use std::os::unix::fs::FileTypeExt;
use std::path::Path;
use std::process::Command;

use crate::common::speculum_in as speculum;

/// Asserts a refusal before any GPU work: exit 1, one `error:` line holding `needles`.
fn assert_refused(args: &[&str], dir: &Path, needles: &[&str]) {
    let (code, stderr) = speculum(args, dir);
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(code, 1, "{args:?}: {stderr}");
    assert_eq!(lines.len(), 1, "{args:?}: one line expected: {stderr}");
    assert!(lines[0].starts_with("error: "), "{stderr}");
    for n in needles {
        assert!(lines[0].contains(n), "{args:?}: '{n}' not in {}", lines[0]);
    }
}

const SMALL: [&str; 8] = ["--width", "64", "--height", "48", "--frames", "1", "--warmup", "0"];

fn render_args<'a>(extra: &[&'a str]) -> Vec<&'a str> {
    let mut v = vec!["render"];
    v.extend(SMALL);
    v.extend(extra);
    v
}

/// Files in `dir` (names), sorted: nothing appears or disappears on a refusal.
fn listing(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

#[test]
fn device_nodes_fifos_and_folders_are_never_replaced() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for (args, needle) in [
        (render_args(&["--timings", "/dev/full"]), "a device"),
        (render_args(&["--timings", "/dev/null"]), "a device"),
        (vec!["compare", "a.png", "b.png", "--json", "/dev/null"], "a device"),
        (
            vec!["bench", "lbvh", "--tris", "100", "--dump-hits", "/dev/null"],
            "a device",
        ),
        (vec!["bench", "modes", "--json", "/dev/null"], "a device"),
    ] {
        assert_refused(&args, d, &[needle, "regular file"]);
    }
    for dev in ["/dev/full", "/dev/null"] {
        assert!(
            std::fs::metadata(dev).unwrap().file_type().is_char_device(),
            "{dev} replaced"
        );
    }
    let fifo = d.join("fifo.json");
    if Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()) {
        assert_refused(&render_args(&["--timings", "fifo.json"]), d, &["a FIFO"]);
        assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
    } else {
        eprintln!("SKIPPED: no mkfifo here; the FIFO case did not run");
    }
    std::fs::create_dir(d.join("folder.png")).unwrap();
    assert_refused(&render_args(&["--out", "folder.png"]), d, &["is a folder"]);
    assert!(d.join("folder.png").is_dir());
}

#[test]
fn outputs_of_one_run_never_collide_nor_overwrite_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = "[[object]]\nshape = \"sphere\"\nmaterial = \"chrome\"\n";
    std::fs::write(d.join("s.toml"), scene).unwrap();
    let before = listing(d);
    for (args, needles) in [
        (
            render_args(&["--out", "a.png", "--fail-mask", "./a.png"]),
            vec!["--out and --fail-mask"],
        ),
        (
            render_args(&["--out", "a.png", "--reference", "--fail-mask", "a_rt.png"]),
            vec!["--reference (its <out>_rt.png) and --fail-mask"],
        ),
        (
            vec!["render", "--frames", "6", "--out", "a.png", "--contact-sheet", "a.png"],
            vec!["--out and --contact-sheet"],
        ),
        (
            render_args(&["--timings", "a.png", "--out", "a.png"]),
            vec!["name the same file"],
        ),
        (
            render_args(&["--scene", "s.toml", "--timings", "s.toml"]),
            vec!["--timings would overwrite the input --scene"],
        ),
        (
            vec![
                "bench",
                "lbvh",
                "--tris",
                "100",
                "--dump-rays",
                "d.bin",
                "--dump-hits",
                "d.bin",
            ],
            vec!["--dump-rays and --dump-hits"],
        ),
        (
            vec!["bench", "suite", "--quick", "--json", "-", "--markdown", "-"],
            vec!["--json and --markdown"],
        ),
    ] {
        assert_refused(&args, d, &needles);
    }
    assert_eq!(listing(d), before, "a refused run leaves no file behind");
    assert_eq!(std::fs::read_to_string(d.join("s.toml")).unwrap(), scene);

    // compare: an output onto one of the images it reads.
    let png = |name: &str, v: u8| {
        image::RgbaImage::from_pixel(32, 32, image::Rgba([v, v, v, 255]))
            .save(d.join(name))
            .unwrap();
        std::fs::read(d.join(name)).unwrap()
    };
    let (a, b) = (png("a.png", 10), png("b.png", 200));
    assert_refused(
        &["compare", "a.png", "b.png", "--json", "a.png"],
        d,
        &["--json would overwrite the input image A"],
    );
    assert_refused(
        &["compare", "a.png", "b.png", "--diff", "./b.png"],
        d,
        &["--diff would overwrite the input image B"],
    );
    assert_refused(
        &["compare", "a.png", "b.png", "--diff", "d.png", "--json", "d.png"],
        d,
        &["--diff and --json"],
    );
    assert_eq!(
        (
            std::fs::read(d.join("a.png")).unwrap(),
            std::fs::read(d.join("b.png")).unwrap()
        ),
        (a, b)
    );
}

#[test]
fn a_symlinked_output_is_written_through() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("real.json"), b"old").unwrap();
    std::os::unix::fs::symlink(d.join("real.json"), d.join("link.json")).unwrap();
    let (code, stderr) = speculum(&render_args(&["--timings", "link.json", "--quiet"]), d);
    assert_eq!(code, 0, "{stderr}");
    assert!(std::fs::symlink_metadata(d.join("link.json"))
        .unwrap()
        .file_type()
        .is_symlink());
    let report = std::fs::read_to_string(d.join("real.json")).unwrap();
    assert!(report.contains("\"kind\": \"render\""), "{report}");
    std::os::unix::fs::symlink(d.join("missing/x.json"), d.join("dangling.json")).unwrap();
    assert_refused(&render_args(&["--timings", "dangling.json"]), d, &["symlink"]);
}

#[test]
fn an_unwritable_folder_is_found_before_any_gpu_work() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::create_dir(d.join("ro")).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(d.join("ro"), std::fs::Permissions::from_mode(0o555)).unwrap();
    let probe = d.join("ro/probe");
    let writable = std::fs::write(&probe, b"").is_ok();
    let _ = std::fs::remove_file(&probe);
    let immutable = writable
        && Command::new("chattr")
            .arg("+i")
            .arg(d.join("ro"))
            .status()
            .is_ok_and(|s| s.success());
    if writable && !immutable {
        eprintln!("SKIPPED: as root without chattr +i, no folder here is unwritable");
        return;
    }
    for args in [
        render_args(&["--out", "ro/a.png"]),
        render_args(&["--fail-mask", "ro/m.png"]),
        render_args(&["--timings", "ro/t.json"]),
        vec!["bench", "suite", "--quick", "--json", "ro/s.json"],
        vec!["bench", "lbvh", "--tris", "100", "--json", "ro/l.json"],
    ] {
        assert_refused(&args, d, &["cannot write in folder"]);
    }
    let _ = Command::new("chattr").arg("-i").arg(d.join("ro")).status();
    assert_eq!(listing(&d.join("ro")), Vec::<String>::new());
}
