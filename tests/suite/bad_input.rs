//! Bad input gives a one-line error naming the problem and a non-zero exit: never a
//! panic, a hang or a validation message. Runs the real `speculum` binary.

use crate::common;

use std::path::Path;

/// Runs `speculum render ARGS` with validation on; returns (success, stderr).
fn run(args: &[&str], dir: &Path) -> (bool, String) {
    let out = common::speculum(["render"])
        .args(args)
        .args(["--frames", "1", "--warmup", "0", "--width", "64", "--height", "48"])
        .arg("--out")
        .arg(dir.join("out.png"))
        .dir(dir)
        .run();
    (out.ok(), out.stderr)
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
    let scene = speculum::scene::load_with(&obj, speculum::scene::Floor::None).unwrap();
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
    assert_eq!(m.albedo, glam::Vec3::new(1.0, 0.2, 0.2), "Kd is the factor");
    let t = &scene.textures[m.texture.expect("map_Kd gives a texture") as usize];
    assert_eq!(
        (t.image.dimensions(), t.image.get_pixel(1, 2).0),
        ((4, 4), [200, 100, 50, 255])
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
    // A missing MTL is a warning naming it; the model renders in the default material.
    let dir = tempfile::tempdir().unwrap();
    let obj = write(
        dir.path(),
        "a.obj",
        &format!("mtllib nowhere.mtl\nusemtl x\n{CUBE_FACES}"),
    );
    let (ok, stderr) = run(&["--scene", &obj], dir.path());
    assert!(ok, "{stderr}");
    let warnings: Vec<&str> = stderr.lines().filter(|l| l.starts_with("warning: ")).collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    assert!(
        warnings[0].contains("nowhere.mtl") && warnings[0].contains("default"),
        "{stderr}"
    );
    let scene = speculum::scene::load_with(&obj, speculum::scene::Floor::None).unwrap();
    assert_eq!(scene.materials.len(), 1);
    assert_eq!(scene.materials[0].name, "default");
}

/// `map_Kd` options are skipped: the texture named after them is the one read.
#[test]
fn texture_options_before_the_file_name() {
    let dir = tempfile::tempdir().unwrap();
    let img = image::RgbaImage::from_pixel(4, 4, image::Rgba([255, 0, 0, 255]));
    img.save(dir.path().join("red.png")).unwrap();
    write(
        dir.path(),
        "o.mtl",
        "newmtl t\nKd 1 1 1\nmap_Kd -s 2 2 1 -bm 0.5 red.png\n",
    );
    let obj = write(dir.path(), "o.obj", &format!("mtllib o.mtl\nusemtl t\n{CUBE_FACES}"));
    let (ok, stderr) = run(&["--scene", &obj], dir.path());
    assert!(ok, "{stderr}");
    let scene = speculum::scene::load_with(&obj, speculum::scene::Floor::None).unwrap();
    let t = scene.materials[0].texture.expect("the file after the options");
    assert_eq!(scene.textures[t as usize].image.get_pixel(0, 0).0, [255, 0, 0, 255]);
}

#[test]
fn malformed_mtl_file() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "bad.mtl", "newmtl x\nKd 1 0.5\n");
    let obj = write(dir.path(), "a.obj", &format!("mtllib bad.mtl\nusemtl x\n{CUBE_FACES}"));
    assert_fails(&["--scene", &obj], dir.path(), &["invalid MTL file", "bad.mtl"]);
}

/// A missing texture, like a missing MTL file, is a warning: the material keeps its
/// colour. (Scans and downloads often lose their textures; the geometry still renders.)
#[test]
fn missing_texture() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "t.mtl", "newmtl x\nKd 1 1 1\nmap_Kd gone.png\n");
    let obj = write(dir.path(), "a.obj", &format!("mtllib t.mtl\nusemtl x\n{CUBE_FACES}"));
    let (ok, stderr) = run(&["--scene", &obj], dir.path());
    assert!(ok, "{stderr}");
    assert!(
        stderr.contains("warning: texture") && stderr.contains("gone.png"),
        "{stderr}"
    );
    let scene = speculum::scene::load_with(&obj, speculum::scene::Floor::None).unwrap();
    assert_eq!((scene.materials[0].texture, scene.textures.len()), (None, 0));
}

/// A texture that is not PNG or JPEG (here a real BMP) is one error naming the file and
/// the supported formats; so is a scene file's missing texture.
#[test]
fn texture_of_an_unsupported_format() {
    let dir = tempfile::tempdir().unwrap();
    // A 2x2 24-bit BMP: file header, BITMAPINFOHEADER, two rows padded to 8 bytes.
    let mut bmp = Vec::new();
    bmp.extend(b"BM");
    bmp.extend(70u32.to_le_bytes());
    bmp.extend(0u32.to_le_bytes());
    bmp.extend(54u32.to_le_bytes());
    for v in [40u32, 2, 2] {
        bmp.extend(v.to_le_bytes());
    }
    bmp.extend(1u16.to_le_bytes());
    bmp.extend(24u16.to_le_bytes());
    for v in [0u32, 16, 2835, 2835, 0, 0] {
        bmp.extend(v.to_le_bytes());
    }
    bmp.extend([10u8, 20, 30, 40, 50, 60, 0, 0, 70, 80, 90, 100, 110, 120, 0, 0]);
    std::fs::write(dir.path().join("t.png"), &bmp).unwrap();
    write(dir.path(), "t.mtl", "newmtl x\nKd 1 1 1\nmap_Kd t.png\n");
    let obj = write(dir.path(), "a.obj", &format!("mtllib t.mtl\nusemtl x\n{CUBE_FACES}"));
    assert_fails(
        &["--scene", &obj],
        dir.path(),
        &[
            "invalid texture",
            "t.png",
            "unsupported texture format Bmp",
            "PNG, JPEG",
        ],
    );
    let toml = write(
        dir.path(),
        "s.toml",
        "[camera]\nposition = [0.0, 1.0, 3.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 50.0\n\
         [sun]\ndirection = [0.0, 1.0, 0.0]\ncolor = [1.0, 1.0, 1.0]\nintensity = 1.0\n\
         [[materials]]\nname = \"m\"\nbase_color = [1.0, 1.0, 1.0]\nroughness = 0.5\ntexture = \"none.jpg\"\n\
         [[instance]]\nplane = [1.0, 1.0]\nmaterial = \"m\"\n",
    );
    assert_fails(&["--scene", &toml], dir.path(), &["cannot read texture", "none.jpg"]);
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
        let out = common::speculum(["render", "--frames", "1", "--width", w, "--height", h])
            .dir(dir.path())
            .run();
        assert!(!out.ok());
        let stderr = out.stderr;
        assert!(!stderr.contains("panicked"), "{stderr}");
        assert!(stderr.contains(&format!("resolution {w}x{h}")), "{stderr}");
        assert!(!dir.path().join("frame.png").exists());
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
    }
}

/// Frame counts are bounded: 0 frames, or 4294967295 (which would run for days), fail
/// at once with the bound; nothing is written.
#[test]
fn frame_counts_out_of_bounds() {
    let dir = tempfile::tempdir().unwrap();
    for (flag, v) in [
        ("--frames", "0"),
        ("--frames", "4294967295"),
        ("--warmup", "4294967295"),
    ] {
        let started = std::time::Instant::now();
        let args = ["render", flag, v, "--width", "32", "--height", "32"];
        let (ok, stderr) = run_raw(&args, dir.path());
        assert!(!ok && stderr.contains(&format!("{flag} {v} is outside")), "{stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        assert!(started.elapsed().as_secs() < 30, "refused at once");
        assert!(!dir.path().join("frame.png").exists());
    }
    let (ok, stderr) = run_raw(&["bench", "modes", "--rounds", "4294967295"], dir.path());
    assert!(!ok && stderr.contains("--rounds 4294967295 is outside"), "{stderr}");
}

/// Runs the binary with exactly `args` in `dir`; returns (success, stderr).
fn run_raw(args: &[&str], dir: &Path) -> (bool, String) {
    let (code, stderr) = common::speculum_in(args, dir);
    (code == 0, stderr)
}

/// Device limits are checked before any buffer is bound: a 6000x6000 frame (its pixel
/// lists exceed lavapipe's 128 MiB storage range) and a 1.5M triangle soup (its vertex
/// buffer does) are refused with one line naming the limit and the device, and no
/// validation message.
#[test]
fn sizes_beyond_device_limits() {
    let dir = tempfile::tempdir().unwrap();
    // On a device whose limits hold these sizes (NVIDIA: 2^31 - 1 workgroups, 4 GiB
    // ranges) there is nothing to refuse: the case is skipped there, never on lavapipe.
    let limits = common::context().limits;
    if limits.max_storage_buffer_range as u64 >= 6000 * 6000 * 4 {
        println!("skipped: this device's limits hold a 6000x6000 frame");
        return;
    }
    let (ok, stderr) = run_raw(
        &[
            "render",
            "--width",
            "6000",
            "--height",
            "6000",
            "--frames",
            "1",
            "--validation",
        ],
        dir.path(),
    );
    assert!(!ok, "{stderr}");
    assert!(!stderr.contains("[vulkan") && !stderr.contains("panicked"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("a 6000x6000 frame") && stderr.contains("beyond maxStorageBufferRange"),
        "{stderr}"
    );
    assert!(!dir.path().join("frame.png").exists());
    if limits.max_storage_buffer_range as u64 >= 1_500_000 * 3 * 32 {
        println!("skipped: this device's storage range holds a 1.5M-triangle soup");
        return;
    }
    let (ok, stderr) = run_raw(
        &["bench", "lbvh", "--tris", "1500000", "--repeats", "1", "--validation"],
        dir.path(),
    );
    assert!(!ok, "{stderr}");
    assert!(!stderr.contains("[vulkan") && !stderr.contains("panicked"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("maxStorageBufferRange"), "{stderr}");
}

/// Outputs are checked before rendering: a `.jpg` output, a missing folder for the
/// timings or the fail mask fail at once and leave no file (not even the PNG).
#[test]
fn bad_output_paths_fail_before_rendering() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&[&str], &str); 3] = [
        (&["--out", "o.jpg"], "o.jpg"),
        (&["--timings", "no/such/dir/t.json"], "does not exist"),
        (&["--fail-mask", "no/such/dir/m.png"], "does not exist"),
    ];
    for (args, needle) in cases {
        let mut all = vec![
            "render", "--frames", "1", "--warmup", "0", "--width", "32", "--height", "32",
        ];
        all.extend_from_slice(args);
        let (ok, stderr) = run_raw(&all, dir.path());
        assert!(!ok && stderr.contains(needle), "{args:?}: {stderr}");
        assert_eq!(stderr.lines().count(), 1, "{stderr}");
        let left: Vec<_> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert!(left.is_empty(), "{args:?} left {left:?}");
    }
}

/// An exposure so large that ACES's x * x overflows f32 renders white, not NaN black.
#[test]
fn absurd_exposure_renders_white() {
    let dir = tempfile::tempdir().unwrap();
    let settings = write(dir.path(), "s.json", r#"{"exposure": 1e20}"#);
    let (ok, stderr) = run(&["--settings", &settings, "--mode", "raster"], dir.path());
    assert!(ok, "{stderr}");
    let img = image::open(dir.path().join("out.png")).unwrap().to_rgba8();
    let lit = img
        .pixels()
        .filter(|p| p[0] == 255 && p[1] == 255 && p[2] == 255)
        .count();
    let black = img.pixels().filter(|p| p[0] == 0 && p[1] == 0 && p[2] == 0).count();
    let n = (img.width() * img.height()) as usize;
    assert!(lit > n / 2 && black < n / 4, "{lit} white and {black} black of {n}");
}

/// A settings file must be a JSON object: an array is not read as width, height, ...
#[test]
fn settings_file_must_be_an_object() {
    let dir = tempfile::tempdir().unwrap();
    let settings = write(dir.path(), "s.json", "[1, 2, 3]");
    assert_fails(
        &["--settings", &settings],
        dir.path(),
        &["s.json", "JSON object", "array"],
    );
}

/// The settings file's width and height hold unless a flag is given.
#[test]
fn settings_file_resolution_is_not_overridden_by_defaults() {
    let dir = tempfile::tempdir().unwrap();
    let settings = write(dir.path(), "s.json", r#"{"width": 40, "height": 24}"#);
    let out = dir.path().join("a.png");
    let base = [
        "render",
        "--frames",
        "1",
        "--warmup",
        "0",
        "--settings",
        &settings,
        "--out",
    ];
    let (ok, stderr) = run_raw(&[&base[..], &[out.to_str().unwrap()]].concat(), dir.path());
    assert!(ok, "{stderr}");
    assert_eq!(image::image_dimensions(&out).unwrap(), (40, 24));
    let (ok, stderr) = run_raw(
        &[&base[..], &[out.to_str().unwrap(), "--width", "56"]].concat(),
        dir.path(),
    );
    assert!(ok, "{stderr}");
    assert_eq!(
        image::image_dimensions(&out).unwrap(),
        (56, 24),
        "a flag given overrides the file"
    );
}

/// `--reference` and `bench modes` below SSIM's 11x11 window fail before rendering.
#[test]
fn reference_below_ssim_window_fails_first() {
    let dir = tempfile::tempdir().unwrap();
    let (ok, stderr) = run_raw(&["render", "--reference", "--width", "8", "--height", "64"], dir.path());
    assert!(
        !ok && stderr.contains("SSIM needs images of at least 11x11"),
        "{stderr}"
    );
    assert!(!dir.path().join("frame.png").exists());
    let (ok, stderr) = run_raw(&["bench", "modes", "--width", "10", "--height", "10"], dir.path());
    assert!(
        !ok && stderr.contains("SSIM needs images of at least 11x11"),
        "{stderr}"
    );
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
}

/// Out-of-range MTL values are clamped with one warning per material naming the MTL
/// file; the render succeeds.
#[test]
fn out_of_range_mtl_values_warn_once_per_material() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "w.mtl",
        "newmtl hot\nKd 7 7 7\nNs -5\nnewmtl fine\nKd 0.5 0.5 0.5\n",
    );
    let obj = write(dir.path(), "w.obj", &format!("mtllib w.mtl\nusemtl hot\n{CUBE_FACES}"));
    let (ok, stderr) = run(&["--scene", &obj], dir.path());
    assert!(ok, "{stderr}");
    let warnings: Vec<&str> = stderr.lines().filter(|l| l.starts_with("warning: ")).collect();
    assert_eq!(warnings.len(), 1, "{stderr}");
    assert!(
        warnings[0].contains("'hot'")
            && warnings[0].contains("w.mtl")
            && warnings[0].contains("Kd 7 7 7")
            && warnings[0].contains("Ns -5"),
        "{stderr}"
    );
}

/// A material that cannot be used names its MTL file, not a path made from the material.
#[test]
fn bad_material_names_its_mtl_file() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "n.mtl", "newmtl broken\nKd nan 0.5 0.5\n");
    let obj = write(
        dir.path(),
        "n.obj",
        &format!("mtllib n.mtl\nusemtl broken\n{CUBE_FACES}"),
    );
    assert_fails(&["--scene", &obj], dir.path(), &["n.mtl", "'broken'", "non-finite"]);
}

/// A file-read error says the OS message once.
#[test]
fn os_messages_are_said_once() {
    let dir = tempfile::tempdir().unwrap();
    let (ok, stderr) = run(&["--scene", "missing.obj"], dir.path());
    assert!(!ok);
    assert_eq!(stderr.matches("os error 2").count(), 1, "{stderr}");
}

/// Argument errors keep clap's usage text, and the first line says what is wrong.
#[test]
fn argument_errors_say_what_is_wrong_first() {
    let dir = tempfile::tempdir().unwrap();
    for (args, needle) in [
        (&["render", "--widht", "5"][..], "--widht"),
        (&["render", "--mode", "fast"][..], "fast"),
        (&["render", "--width", "wide"][..], "wide"),
    ] {
        let (ok, stderr) = run_raw(args, dir.path());
        let first = stderr.lines().next().unwrap_or_default();
        assert!(
            !ok && first.starts_with("error: ") && first.contains(needle),
            "{args:?}: {stderr}"
        );
    }
    // The mode's values are listed in the help.
    let help = common::speculum(["render", "--help"]).run().stdout;
    for word in [
        "raster",
        "hybrid",
        "provenance",
        "room",
        "offscreen",
        "mirrors",
        "spheres",
    ] {
        assert!(help.contains(word), "render --help lacks {word}: {help}");
    }
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
        let out = common::speculum(["compare"]).arg(&a).arg(dir.path().join(b)).run();
        (out.ok(), out.stderr, out.stdout)
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

/// Scene files: a bad field names the file and its line, an unsupported extension lists
/// the supported ones, a missing model names its path; each one line, exit 1.
#[test]
fn bad_scene_files() {
    let dir = tempfile::tempdir().unwrap();
    let bad = write(
        dir.path(),
        "bad.toml",
        "[camera]\nposition = [0, 1, 5]\ntarget = [0, 0, 0]\nfovv = 50\n",
    );
    assert_fails(&["--scene", &bad], dir.path(), &["bad.toml", "line 4", "fovv"]);
    let xyz = write(dir.path(), "m.xyz", "0 0 0\n");
    assert_fails(
        &["--scene", &xyz],
        dir.path(),
        &["unsupported scene format '.xyz'", ".toml, .obj, .gltf, .glb, .ply"],
    );
    let room = include_str!("../../assets/scenes/room.toml");
    let missing = write(
        dir.path(),
        "missing.toml",
        &format!("{room}\n[[instance]]\nmodel = \"nowhere/teapot.obj\"\n"),
    );
    assert_fails(
        &["--scene", &missing],
        dir.path(),
        &["nowhere/teapot.obj", "No such file"],
    );
}

/// A scene file places an OBJ model (moved, scaled, its material replaced) among
/// primitives, and renders.
#[test]
fn scene_file_with_a_model_renders() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "cube.obj", CUBE_FACES);
    let room = include_str!("../../assets/scenes/room.toml");
    let scene = write(
        dir.path(),
        "mine.toml",
        &format!("{room}\n[[instance]]\nmodel = \"cube.obj\"\nmaterial = \"gold\"\ntranslate = [0, 2, 0]\nscale = [2, 2, 1]\n"),
    );
    let (ok, stderr) = run(&["--scene", &scene], dir.path());
    assert!(ok, "{stderr}");
    let s = speculum::scene::load(&scene).unwrap();
    let base = speculum::scene::builtin::room().unwrap();
    assert_eq!(s.triangle_count(), base.triangle_count() + 2);
    assert_eq!(s.name, "room", "the file's name");
}

/// View flags set the camera and sun: the report holds the effective camera, which
/// renders the same image again through a scene file's values; bad views are one line.
#[test]
fn view_flags_set_and_report_the_camera() {
    let dir = tempfile::tempdir().unwrap();
    let view = [
        "--camera-pos",
        "-3,2.5,6",
        "--camera-target",
        "0,1,-1",
        "--fov",
        "65",
        "--sun-dir",
        "0.5,0.6,0.2",
    ];
    let out = dir.path().join("v.png");
    let json = dir.path().join("v.json");
    let mut args = vec![
        "render", "--frames", "1", "--warmup", "0", "--width", "64", "--height", "48",
    ];
    args.extend_from_slice(&view);
    args.extend_from_slice(&["--out", out.to_str().unwrap(), "--timings", json.to_str().unwrap()]);
    let (ok, stderr) = run_raw(&args, dir.path());
    assert!(ok, "{stderr}");
    let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(r["camera"]["position"], serde_json::json!([-3.0, 2.5, 6.0]));
    assert_eq!(r["camera"]["fov_y_deg"], 65.0);
    let sun: Vec<f64> = serde_json::from_value(r["sun_direction"].clone()).unwrap();
    assert!(
        (sun.iter().map(|v| v * v).sum::<f64>() - 1.0).abs() < 1e-5,
        "normalized: {sun:?}"
    );
    // The default view renders a different image.
    let default_out = dir.path().join("out.png"); // where `run` renders
    let (ok, stderr) = run(&[], dir.path());
    assert!(ok, "{stderr}");
    assert_ne!(std::fs::read(&out).unwrap(), std::fs::read(&default_out).unwrap());
    for (flag, v, needle) in [
        ("--fov", "0", "--fov 0 is outside"),
        ("--sun-dir", "0,0,0", "no direction"),
        ("--camera-pos", "0,1,-1", "same point"),
    ] {
        let extra: &[&str] = if flag == "--camera-pos" {
            &["--camera-target", "0,1,-1"]
        } else {
            &[]
        };
        assert_fails(&[&[flag, v][..], extra].concat(), dir.path(), &[needle]);
    }
    let (ok, stderr) = run(&["--camera-pos", "1,2"], dir.path());
    assert!(
        !ok && stderr.lines().next().unwrap().contains("three finite numbers"),
        "{stderr}"
    );
}

/// A bare model is a usable scene: it stands on a mirror floor (the default) that
/// shows its reflection, on a matte one, or alone (`--floor`); `--floor` with a scene
/// that is not a bare model is refused.
#[test]
fn bare_models_stand_on_a_floor() {
    let dir = tempfile::tempdir().unwrap();
    let obj = write(
        dir.path(),
        "q.obj",
        &format!("v 0 1 0\nv 1 1 0\nv 1 2 0\nv 0 2 0\n{}", "f 1 2 3\nf 1 3 4\n"),
    );
    let reflective = |floor: Option<&str>| {
        let json = dir.path().join("t.json");
        let mut args = vec!["--scene", obj.as_str(), "--timings", json.to_str().unwrap()];
        if let Some(f) = floor {
            args.extend_from_slice(&["--floor", f]);
        }
        let (ok, stderr) = run(&args, dir.path());
        assert!(ok, "{stderr}");
        let r: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
        (
            r["reflective_pixels"].as_u64().unwrap(),
            r["traced_pixels"].as_u64().unwrap(),
        )
    };
    let (mirror, traced) = reflective(None);
    assert!(
        mirror > 64 * 48 / 4 && traced > 0,
        "a mirror floor fills the view: {mirror}, {traced}"
    );
    assert_eq!(reflective(Some("mirror")).0, mirror);
    assert_eq!(reflective(Some("matte")).0, 0);
    assert_eq!(reflective(Some("none")).0, 0);
    use speculum::scene::{load_with, Floor};
    let alone = load_with(&obj, Floor::None).unwrap();
    let floored = load_with(&obj, Floor::Matte).unwrap();
    assert_eq!(floored.triangle_count(), alone.triangle_count() + 2);
    assert!(
        floored.bounds().0.y < 1.0 && floored.bounds().0.y > 0.999,
        "just under the model"
    );
    assert_fails(
        &["--scene", "room", "--floor", "none"],
        dir.path(),
        &["--floor is for a bare model"],
    );
}

/// A PLY file, ASCII or binary, loads to the same triangles (fan-triangulated polygons)
/// as the equivalent OBJ; a bare PLY renders on the mirror floor; a broken one is one
/// error line.
#[test]
fn ply_ascii_and_binary_load_like_obj() {
    use speculum::scene::{load_with, Floor};
    let dir = tempfile::tempdir().unwrap();
    let v = [
        [0.0f32, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.5, 0.5, 1.0],
    ];
    let faces: [&[u32]; 3] = [&[0, 1, 2, 3], &[0, 1, 4], &[1, 2, 4]];
    let mut obj = String::new();
    for p in v {
        obj += &format!("v {} {} {}\n", p[0], p[1], p[2]);
    }
    for f in faces {
        obj += &format!(
            "f {}\n",
            f.iter().map(|i| (i + 1).to_string()).collect::<Vec<_>>().join(" ")
        );
    }
    let obj = write(dir.path(), "m.obj", &obj);
    let header = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex 5\nproperty float x\nproperty float y\nproperty float z\n\
             element face 3\nproperty list uchar int vertex_indices\nend_header\n"
        )
    };
    let mut ascii = header("ascii");
    for p in v {
        ascii += &format!("{} {} {}\n", p[0], p[1], p[2]);
    }
    for f in faces {
        ascii += &format!(
            "{} {}\n",
            f.len(),
            f.iter().map(|i| i.to_string()).collect::<Vec<_>>().join(" ")
        );
    }
    let ascii = write(dir.path(), "a.ply", &ascii);
    let mut binary = header("binary_little_endian").into_bytes();
    for p in v {
        for c in p {
            binary.extend_from_slice(&c.to_le_bytes());
        }
    }
    for f in faces {
        binary.push(f.len() as u8);
        for &i in f {
            binary.extend_from_slice(&(i as i32).to_le_bytes());
        }
    }
    std::fs::write(dir.path().join("b.ply"), &binary).unwrap();
    let binary = dir.path().join("b.ply").display().to_string();
    let corners = |s: &speculum::scene::Scene| -> Vec<[f32; 3]> {
        s.indices.iter().map(|&i| s.vertices[i as usize].position).collect()
    };
    let want = corners(&load_with(&obj, Floor::None).unwrap());
    assert_eq!(want.len(), 3 * 4, "a quad and two triangles");
    for ply in [&ascii, &binary] {
        let s = load_with(ply, Floor::None).unwrap();
        assert_eq!(corners(&s), want, "{ply}");
    }
    let (ok, stderr) = run(&["--scene", &binary], dir.path());
    assert!(ok, "{stderr}");
    let broken = write(
        dir.path(),
        "x.ply",
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n",
    );
    assert_fails(&["--scene", &broken], dir.path(), &["x.ply"]);
}

/// The glTF document of `gltf_loads_node_transforms_and_materials`: a triangle under a
/// child node (scale 2) of a translated root node, a metal and a plain material.
fn gltf_json(buffer_uri: Option<&str>) -> String {
    let uri = buffer_uri.map(|u| format!(r#""uri": "{u}", "#)).unwrap_or_default();
    format!(
        r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0]}}],
 "nodes": [{{"translation": [10.0, 0.0, 0.0], "children": [1]}}, {{"scale": [2.0, 2.0, 2.0], "mesh": 0}}],
 "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}, "indices": 1, "material": 0}}]}}],
 "materials": [{{"name": "gold", "pbrMetallicRoughness": {{"baseColorFactor": [1.0, 0.7, 0.2, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.1}}}}],
 "buffers": [{{{uri}"byteLength": 44}}],
 "bufferViews": [{{"buffer": 0, "byteOffset": 0, "byteLength": 36}}, {{"buffer": 0, "byteOffset": 36, "byteLength": 6}}],
 "accessors": [{{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]}},
               {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}}]}}"#
    )
}

/// glTF (external buffer) and GLB (embedded) load the node hierarchy's transforms and
/// the metal's material, render as bare models, and a broken file is one error line.
#[test]
fn gltf_loads_node_transforms_and_materials() {
    use speculum::scene::{load_with, Floor};
    let dir = tempfile::tempdir().unwrap();
    let mut bin: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    bin.extend([0u16, 1, 2].iter().flat_map(|i| i.to_le_bytes()));
    bin.extend([0u8; 2]); // pad to 44 bytes (a multiple of 4)
    std::fs::write(dir.path().join("tri.bin"), &bin).unwrap();
    let gltf = write(dir.path(), "tri.gltf", &gltf_json(Some("tri.bin")));
    let glb = common::showcase::container(gltf_json(None).as_bytes(), &bin);
    std::fs::write(dir.path().join("tri.glb"), &glb).unwrap();
    let glb = dir.path().join("tri.glb").display().to_string();
    for file in [&gltf, &glb] {
        let s = load_with(file, Floor::None).unwrap();
        assert_eq!(s.triangle_count(), 1, "{file}");
        let (lo, hi) = s.bounds();
        assert_eq!(
            (lo, hi),
            (glam::Vec3::new(10.0, 0.0, 0.0), glam::Vec3::new(12.0, 2.0, 0.0)),
            "{file}"
        );
        let m = &s.materials[s.vertices[0].material as usize];
        assert_eq!(
            (m.name.as_str(), m.albedo, m.roughness, m.metallic),
            ("gold", glam::Vec3::new(1.0, 0.7, 0.2), 0.1, 1.0)
        );
        assert_eq!(m.reflectivity, 1.0, "the roughness cut-offs judge a glTF material");
        let (ok, stderr) = run(&["--scene", file], dir.path());
        assert!(ok, "{file}: {stderr}");
    }
    let broken = write(dir.path(), "x.gltf", "{\"asset\": 3}");
    assert_fails(&["--scene", &broken], dir.path(), &["x.gltf"]);
}

/// Dynamic-scene inputs: a time step that is not positive, a sequence folder that
/// cannot be written (a file, or under one), a contact sheet of fewer than six frames:
/// one error line each, before any GPU work, and nothing written.
#[test]
fn dynamic_scene_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let zero = write(dir.path(), "dt0.json", "{\"sim_dt\": 0.0}");
    assert_fails(
        &["--scene", "drop", "--settings", &zero],
        dir.path(),
        &["sim_dt 0", "(0, 1]"],
    );
    let negative = write(dir.path(), "dtn.json", "{\"sim_dt\": -0.01}");
    assert_fails(
        &["--scene", "drop", "--settings", &negative],
        dir.path(),
        &["sim_dt -0.01"],
    );
    let file = write(dir.path(), "plain.txt", "x");
    assert_fails(
        &["--scene", "drop", "--sequence", &file],
        dir.path(),
        &["plain.txt", "not a folder"],
    );
    let under = format!("{file}/seq");
    assert_fails(
        &["--scene", "drop", "--sequence", &under],
        dir.path(),
        &["plain.txt", "does not exist"],
    );
    assert_fails(
        &["--scene", "drop", "--contact-sheet", "sheet.png"],
        dir.path(),
        &["--contact-sheet", "at least 6 frames"],
    );
    assert!(!dir.path().join("out.png").exists() && !dir.path().join("sheet.png").exists());
}

/// `--bodies`: 0 and 10,000,000 are out of range, and a scene without a [spawn] table
/// takes none; one error line each, before any GPU work.
#[test]
fn bodies_out_of_range_or_without_a_spawn() {
    let dir = tempfile::tempdir().unwrap();
    assert_fails(
        &["--scene", "stress", "--bodies", "0"],
        dir.path(),
        &["--bodies 0", "1..=4000"],
    );
    assert_fails(
        &["--scene", "stress", "--bodies", "10000000"],
        dir.path(),
        &["--bodies 10000000", "1..=4000"],
    );
    assert_fails(&["--scene", "room", "--bodies", "10"], dir.path(), &["[spawn]", "room"]);
    let (ok, stderr) = run(&["--scene", "stress", "--bodies", "7"], dir.path());
    assert!(ok, "{stderr}");
}

/// `--spp` counts the rays of the `rt` reference or of an `rt` frame: given to a run
/// with neither (a hybrid frame without `--reference`) it is refused in one line instead
/// of being ignored.
#[test]
fn spp_without_a_reference_or_rt_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    assert_fails(
        &["--scene", "glossy", "--spp", "16"],
        dir.path(),
        &["--spp", "--reference", "hybrid"],
    );
    assert_fails(
        &["--scene", "glossy", "--spp", "16", "--mode", "ssr"],
        dir.path(),
        &["--spp", "ssr"],
    );
    assert!(!dir.path().join("out.png").exists());
}
