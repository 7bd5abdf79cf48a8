//! Bad input gives a one-line error naming the problem and a non-zero exit: never a
//! panic, a hang or a validation message. Runs the real `speculum` binary.

use std::path::Path;
use std::process::Command;

/// Runs `speculum render ARGS` with validation on; returns (success, stderr).
fn run(args: &[&str], dir: &Path) -> (bool, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_speculum"))
        .arg("render")
        .args(args)
        .args(["--frames", "1", "--warmup", "0", "--width", "64", "--height", "48"])
        .arg("--out")
        .arg(dir.join("out.png"))
        .env("SPECULUM_VALIDATION", "1")
        .current_dir(dir)
        .output()
        .expect("run speculum");
    (out.status.success(), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Asserts a clean failure whose error line contains every one of `needles`.
fn assert_fails(args: &[&str], dir: &Path, needles: &[&str]) {
    let (ok, stderr) = run(args, dir);
    assert!(!ok, "{args:?} should fail; stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    assert!(
        !stderr.contains("[vulkan"),
        "{args:?} caused validation messages: {stderr}"
    );
    let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
    assert_eq!(lines.len(), 1, "{args:?}: expected one error line, got: {stderr}");
    assert!(lines[0].starts_with("error: "), "{stderr}");
    for n in needles {
        assert!(lines[0].contains(n), "{args:?}: '{n}' not in: {}", lines[0]);
    }
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    std::fs::write(dir.join(name), text).unwrap();
    dir.join(name).display().to_string()
}

const CUBE_FACES: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n";

/// A valid OBJ with an MTL and a texture renders: the error cases below fail for
/// their own reason, not because OBJ loading is broken.
#[test]
fn valid_obj_with_mtl_and_texture_renders() {
    let dir = tempfile::tempdir().unwrap();
    let img = image::RgbaImage::from_pixel(4, 4, image::Rgba([200, 100, 50, 255]));
    img.save(dir.path().join("tex.png")).unwrap();
    write(
        dir.path(),
        "m.mtl",
        "newmtl red\nKd 1 0.2 0.2\nKs 0.9 0.9 0.9\nNs 200\nillum 3\nmap_Kd tex.png\n",
    );
    let obj = write(dir.path(), "q.obj", &format!("mtllib m.mtl\nusemtl red\n{CUBE_FACES}"));
    let (ok, stderr) = run(&["--scene", &obj], dir.path());
    assert!(ok, "{stderr}");
    assert!(dir.path().join("out.png").exists());
    let scene = speculum::scene::load(&obj).unwrap();
    assert_eq!(scene.triangle_count(), 2);
    let m = &scene.materials[0];
    assert!(
        (m.reflectivity - 0.9).abs() < 1e-6,
        "illum 3 takes reflectivity from Ks"
    );
    assert!(
        (m.roughness - (2.0f32 / 202.0).sqrt()).abs() < 1e-6,
        "roughness from Ns"
    );
    assert!(
        m.albedo.x > m.albedo.y && m.albedo.y > m.albedo.z,
        "texture tint applied: {:?}",
        m.albedo
    );
}

#[test]
fn unknown_scene_name() {
    let dir = tempfile::tempdir().unwrap();
    assert_fails(
        &["--scene", "no_such_scene"],
        dir.path(),
        &["unknown scene 'no_such_scene'", "room"],
    );
}

#[test]
fn missing_obj_file() {
    let dir = tempfile::tempdir().unwrap();
    assert_fails(
        &["--scene", "missing.obj"],
        dir.path(),
        &["cannot read OBJ file", "missing.obj"],
    );
}

#[test]
fn malformed_obj_file() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(dir.path(), "bad.obj", "v 1 2 x\nf 1 2 3\n");
    assert_fails(&["--scene", &obj], dir.path(), &["invalid OBJ file", "bad.obj"]);
}

#[test]
fn missing_mtl_file() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(
        dir.path(),
        "a.obj",
        &format!("mtllib nowhere.mtl\nusemtl x\n{CUBE_FACES}"),
    );
    assert_fails(&["--scene", &obj], dir.path(), &["cannot read MTL file", "nowhere.mtl"]);
}

#[test]
fn malformed_mtl_file() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "bad.mtl", "newmtl x\nKd 1 0.5\n");
    let obj = write(dir.path(), "a.obj", &format!("mtllib bad.mtl\nusemtl x\n{CUBE_FACES}"));
    assert_fails(&["--scene", &obj], dir.path(), &["invalid MTL file", "bad.mtl"]);
}

#[test]
fn missing_texture() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "t.mtl", "newmtl x\nKd 1 1 1\nmap_Kd gone.png\n");
    let obj = write(dir.path(), "a.obj", &format!("mtllib t.mtl\nusemtl x\n{CUBE_FACES}"));
    assert_fails(&["--scene", &obj], dir.path(), &["cannot read texture", "gone.png"]);
}

#[test]
fn corrupt_texture() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "junk.png", "this is not a png");
    write(dir.path(), "t.mtl", "newmtl x\nKd 1 1 1\nmap_Kd junk.png\n");
    let obj = write(dir.path(), "a.obj", &format!("mtllib t.mtl\nusemtl x\n{CUBE_FACES}"));
    assert_fails(&["--scene", &obj], dir.path(), &["invalid texture", "junk.png"]);
}

#[test]
fn nan_coordinates() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(dir.path(), "nan.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n");
    assert_fails(&["--scene", &obj], dir.path(), &["non-finite", "nan.obj"]);
}

#[test]
fn obj_without_triangles() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(dir.path(), "empty.obj", "# only vertices\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    assert_fails(&["--scene", &obj], dir.path(), &["no triangles", "empty.obj"]);
}

#[test]
fn zero_and_absurd_resolutions() {
    let dir = tempfile::tempdir().unwrap();
    for (w, h) in [("0", "0"), ("100000", "100000"), ("640", "0")] {
        // Later flags win in clap: these override the helper's 64x48.
        let out = Command::new(env!("CARGO_BIN_EXE_speculum"))
            .args(["render", "--frames", "1", "--width", w, "--height", h])
            .current_dir(dir.path())
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success());
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(stderr.contains(&format!("resolution {w}x{h}")), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
}

#[test]
fn zero_frames() {
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_speculum"))
        .args(["render", "--frames", "0", "--width", "32", "--height", "32"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && stderr.contains("--frames must be at least 1"),
        "{stderr}"
    );
}

/// `compare`: a missing image, a corrupt one, and images of different sizes.
#[test]
fn compare_rejects_bad_images() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.png");
    image::RgbaImage::from_pixel(32, 32, image::Rgba([10, 20, 30, 255]))
        .save(&a)
        .unwrap();
    let small = dir.path().join("small.png");
    image::RgbaImage::from_pixel(16, 32, image::Rgba([10, 20, 30, 255]))
        .save(&small)
        .unwrap();
    write(dir.path(), "junk.png", "not an image");
    let run = |b: &str| {
        let out = Command::new(env!("CARGO_BIN_EXE_speculum"))
            .arg("compare")
            .arg(&a)
            .arg(dir.path().join(b))
            .output()
            .unwrap();
        (
            out.status.success(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
        )
    };
    let (ok, _, stdout) = run("a.png");
    assert!(
        ok && stdout.contains("SSIM 1.000000") && stdout.contains("RMSE 0.000000"),
        "{stdout}"
    );
    for (b, needle) in [
        ("missing.png", "cannot read image"),
        ("junk.png", "invalid image"),
        ("small.png", "sizes differ"),
    ] {
        let (ok, stderr, _) = run(b);
        assert!(
            !ok && stderr.contains(needle) && !stderr.contains("panicked"),
            "{b}: {stderr}"
        );
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
}
