//! Bounded reads (issue 20, class 4): every input is a regular file read with a size
//! bound that fits its kind (`speculum::error::bounds`), so an endless input
//! (`/dev/zero`, here behind a name with the right extension) or a huge one is refused
//! at once with one line naming it, never read until memory runs out. Runs the real
//! `speculum` binary, each run killed (and the test failed) after 30 s.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Runs `speculum ARGS` in `dir`; returns (exit code, stderr), failing after 30 s.
fn speculum(args: &[&str], dir: &Path) -> (i32, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_speculum"))
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run speculum");
    let start = Instant::now();
    loop {
        if let Some(status) = child.try_wait().unwrap() {
            let mut err = String::new();
            std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
            return (status.code().unwrap_or(-1), err);
        }
        if start.elapsed() > Duration::from_secs(30) {
            let _ = child.kill();
            panic!("{args:?} still running after 30 s: an unbounded read?");
        }
        std::thread::sleep(Duration::from_millis(20));
    }
}

fn assert_refused(args: &[&str], dir: &Path, needles: &[&str]) {
    let (code, stderr) = speculum(args, dir);
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(code, 1, "{args:?}: {stderr}");
    assert_eq!(lines.len(), 1, "{args:?}: one line expected: {stderr}");
    for n in needles {
        assert!(lines[0].contains(n), "{args:?}: '{n}' not in {}", lines[0]);
    }
}

#[test]
fn endless_inputs_are_refused_as_not_regular_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for name in [
        "zero.toml",
        "zero.obj",
        "zero.ply",
        "zero.json",
        "zero.png",
        "zero.bin",
        "zero.mtl",
    ] {
        std::os::unix::fs::symlink("/dev/zero", d.join(name)).unwrap();
    }
    std::fs::write(d.join("m.obj"), "mtllib zero.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let device = "not a regular file";
    assert_refused(
        &["render", "--scene", "zero.toml"],
        d,
        &["scene file", "zero.toml", device],
    );
    assert_refused(&["render", "--scene", "zero.obj"], d, &["OBJ file", device]);
    assert_refused(&["render", "--scene", "zero.ply"], d, &["PLY file", device]);
    assert_refused(&["render", "--scene", "m.obj"], d, &["MTL file", "zero.mtl", device]);
    assert_refused(&["render", "--settings", "zero.json"], d, &["settings file", device]);
    assert_refused(&["compare", "zero.png", "zero.png"], d, &["image", device]);
    assert_refused(
        &["bench", "lbvh", "--tris", "100", "--rays-file", "zero.bin"],
        d,
        &["rays file", device],
    );
    assert_refused(&["tune", "zero.toml"], d, &["sweep file", device]);
    assert_refused(
        &["bench", "suite", "--quick", "--baseline", "zero.json"],
        d,
        &["baseline", device],
    );
}

#[test]
fn inputs_beyond_their_bound_are_refused_before_they_are_read() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Sparse files: their size is what counts, no disk is used.
    let sparse = |name: &str, len: u64| {
        std::fs::File::create(d.join(name)).unwrap().set_len(len).unwrap();
    };
    sparse("big.toml", speculum::error::bounds::TEXT + 1);
    sparse("big.obj", speculum::error::bounds::MODEL + 1);
    sparse("big.json", speculum::error::bounds::TEXT + 1);
    sparse("big.png", speculum::error::bounds::IMAGE + 1);
    sparse("big.bin", speculum::error::bounds::RAYS + 32);
    assert_refused(
        &["render", "--scene", "big.toml"],
        d,
        &["scene file", "more than the 16 MiB"],
    );
    assert_refused(
        &["render", "--scene", "big.obj"],
        d,
        &["OBJ file", "more than the 1024 MiB"],
    );
    assert_refused(
        &["render", "--settings", "big.json"],
        d,
        &["settings file", "more than the 16 MiB"],
    );
    assert_refused(
        &["compare", "big.png", "big.png"],
        d,
        &["image", "more than the 256 MiB"],
    );
    assert_refused(
        &["bench", "lbvh", "--tris", "100", "--rays-file", "big.bin"],
        d,
        &["rays file", "more than"],
    );
    // At the bound itself a file is read (and then judged on its contents).
    sparse("edge.json", speculum::error::bounds::TEXT);
    let (code, err) = speculum(&["render", "--settings", "edge.json"], d);
    assert_eq!(code, 1);
    assert!(!err.contains("more than"), "{err}");
}
