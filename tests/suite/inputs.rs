//! Bounded reads (issue 20, class 4): every input is a regular file read with a size
//! bound that fits its kind (`speculum::error::bounds`), so an endless input
//! (`/dev/zero`, here behind a name with the right extension) or a huge one is refused
//! at once with one line naming it, never read until memory runs out. Runs the real
//! `speculum` binary, each run killed (and the test failed) after 30 s.

use crate::common;

use std::path::Path;
use std::process::Command;
use std::time::Duration;

/// Runs `speculum ARGS` in `dir`; returns (exit code, stderr), failing after 30 s (an
/// unbounded read would run on).
fn speculum(args: &[&str], dir: &Path) -> (i32, String) {
    let out = common::speculum(args).dir(dir).limit(Duration::from_secs(30)).run();
    (out.code, out.stderr)
}

/// A one-frame render, small and silent.
const QUICK: [&str; 7] = ["--width", "64", "--height", "48", "--frames", "1", "--quiet"];

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
    // A FIFO: refused by its kind, not opened (opening one waits for a writer).
    let fifo = d.join("fifo.toml");
    if Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()) {
        assert_refused(
            &["render", "--scene", "fifo.toml"],
            d,
            &["scene file", "a FIFO", device],
        );
    } else {
        eprintln!("SKIPPED: no mkfifo here; the FIFO input case did not run");
    }
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
    let small = ["--tris", "100", "--rays-file", "big.bin"];
    for (args, needles) in [
        (
            &["render", "--scene", "big.toml"][..],
            ["scene file", "more than the 16 MiB"],
        ),
        (
            &["render", "--scene", "big.obj"][..],
            ["OBJ file", "more than the 1024 MiB"],
        ),
        (
            &["render", "--settings", "big.json"][..],
            ["settings file", "more than the 16 MiB"],
        ),
        (
            &["compare", "big.png", "big.png"][..],
            ["image", "more than the 256 MiB"],
        ),
        (
            &[&["bench", "lbvh"][..], &small].concat()[..],
            ["rays file", "more than the 1024 MiB"],
        ),
    ] {
        assert_refused(args, d, &needles);
    }
    // At the bound itself a file is read (and then judged on its contents).
    sparse("edge.json", speculum::error::bounds::TEXT);
    let (code, err) = speculum(&["render", "--settings", "edge.json"], d);
    assert_eq!(code, 1);
    assert!(!err.contains("more than"), "{err}");
}

/// A scene file whose camera, sun, sky or materials hold what the flags refuse is
/// refused the same way (issue 20, class 6); out-of-range material factors are clamped
/// with one warning, as MTL values are.
#[test]
fn scene_files_are_checked_like_flags() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let scene = |camera: &str, sun: &str, extra: &str, material: &str| {
        format!(
            "name = \"t\"\n[camera]\n{camera}\n[sun]\n{sun}\n{extra}\n[[materials]]\nname = \"m\"\n{material}\n\
             [[instance]]\nplane = [4.0, 4.0]\nmaterial = \"m\"\n"
        )
    };
    let cam = "position = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 50.0\nnear = 0.1\nfar = 50.0";
    let sun = "direction = [0.3, 0.8, 0.4]\ncolor = [1.0, 1.0, 1.0]\nintensity = 3.0";
    let mat = "base_color = [0.5, 0.5, 0.5]\nroughness = 0.2\nreflectivity = 0.5";
    // (what to replace, with what, in the camera or the sun; the error it gives).
    let camera = [
        ("[0.0, 2.0, 5.0]", "[nan, 2.0, 5.0]", "not finite"),
        ("[0.0, 2.0, 5.0]", "[inf, 2.0, 5.0]", "not finite"),
        ("[0.0, 2.0, 5.0]", "[1e39, 2.0, 5.0]", "not finite"),
        ("[0.0, 2.0, 5.0]", "[1e30, 2.0, 5.0]", "beyond 1e7 units"),
        ("fov = 50.0", "fov = 0.0", "field of view 0 is outside"),
        ("fov = 50.0", "fov = 180.0", "field of view 180 is outside"),
        ("fov = 50.0", "fov = -5.0", "field of view -5 is outside"),
        ("near = 0.1", "near = 0.0", "0 < near < far"),
        ("far = 50.0", "far = inf", "0 < near < far"),
    ];
    let sun_cases = [
        ("[0.3, 0.8, 0.4]", "[0.0, 0.0, 0.0]", "has no direction"),
        ("intensity = 3.0", "intensity = nan", "sun intensity NaN"),
    ];
    let mut cases: Vec<(String, &str)> = Vec::new();
    for (from, to, needle) in camera {
        cases.push((scene(&cam.replace(from, to), sun, "", mat), needle));
    }
    for (from, to, needle) in sun_cases {
        cases.push((scene(cam, &sun.replace(from, to), "", mat), needle));
    }
    let sky = "[sky]\nzenith = [nan, 0.5, 0.5]\nhorizon = [0.5, 0.5, 0.5]";
    cases.push((scene(cam, sun, sky, mat), "sky zenith colour"));
    cases.push((
        scene(cam, sun, "", &format!("{mat}\nmetallic = nan")),
        "must be finite numbers",
    ));
    // A roughness texture that is missing, or not an image.
    std::fs::write(d.join("rough.png"), "not a png").unwrap();
    cases.push((
        scene(cam, sun, "", &format!("{mat}\nroughness_texture = \"gone.png\"")),
        "gone.png",
    ));
    cases.push((
        scene(cam, sun, "", &format!("{mat}\nroughness_texture = \"rough.png\"")),
        "not an image file",
    ));
    for (i, (text, needle)) in cases.iter().enumerate() {
        let name = format!("s{i}.toml");
        std::fs::write(d.join(&name), text).unwrap();
        assert_refused(
            &["render", "--scene", &name, "--width", "64", "--height", "48"],
            d,
            &[needle, &name],
        );
        assert_refused(
            &["bench", "modes", "--scene", &name, "--width", "64", "--height", "48"],
            d,
            &[needle],
        );
    }
    // Out-of-range factors: clamped, with one warning naming the material and file.
    std::fs::write(
        d.join("clamp.toml"),
        scene(
            cam,
            sun,
            "",
            "base_color = [2.0, 0.5, 0.5]\nroughness = -1.0\nreflectivity = 5.0",
        ),
    )
    .unwrap();
    let (code, err) = speculum(&[&["render", "--scene", "clamp.toml"][..], &QUICK].concat(), d);
    assert_eq!(code, 0, "{err}");
    let warnings: Vec<&str> = err.lines().filter(|l| l.starts_with("warning:")).collect();
    assert_eq!(warnings.len(), 1, "{err}");
    for n in [
        "material 'm'",
        "base colour red 2 clamped to 1",
        "roughness -1 clamped to 0",
        "reflectivity 5 clamped to 1",
        "clamp.toml",
    ] {
        assert!(warnings[0].contains(n), "'{n}' not in {}", warnings[0]);
    }
    // The flags' own edge cases.
    let small = ["--width", "64", "--height", "48"];
    assert_refused(
        &[&["render", "--fov", "1e-30"][..], &small].concat(),
        d,
        &["--fov 0.000000000000000000000000000001 is outside"],
    );
    assert_refused(
        &[&["render", "--camera-pos", "1e30,1e30,1e30"][..], &small].concat(),
        d,
        &["beyond 1e7 units"],
    );
}

/// Issue 20's smaller defects (class 8), each one line and exit 1.
#[test]
fn small_defects_give_clear_lines() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // Suite baselines: a wrong or missing schema, or no cases.
    let base = |schema: &str, cases: &str| {
        format!("{{{schema}\"kind\": \"bench.suite\", \"suite_version\": 1, \"cases\": [{cases}]}}")
    };
    let case =
        "{\"id\": \"x\", \"passes_ms\": {\"frame\": {\"median\": 1.0, \"p10\": 1.0, \"p90\": 1.0, \"samples\": 1}}}";
    for (name, text, needle) in [
        ("b99.json", base("\"schema\": 99, ", case), "schema 99"),
        ("bnone.json", base("", case), "schema missing"),
        ("bempty.json", base("\"schema\": 1, ", ""), "no cases"),
    ] {
        std::fs::write(d.join(name), text).unwrap();
        assert_refused(
            &["bench", "suite", "--quick", "--compare", name, "--baseline", name],
            d,
            &[needle, name],
        );
    }
    // A sweep file's TOML error is one line, with its line number.
    std::fs::write(d.join("sweep.toml"), "scenes = [\"room\"]\n[axes\nx = 1\n").unwrap();
    assert_refused(&["tune", "sweep.toml"], d, &["sweep file", "line 2"]);
    assert_refused(&["bench", "lbvh", "--tris", "100", "--rays", "0"], d, &["--rays"]);
    // Past a rays file's bound: refused before 1.3 GB of rays a set are made.
    assert_refused(
        &["bench", "lbvh", "--tris", "100", "--rays", "40000000"],
        d,
        &["--rays 40000000", "1 to 33554432"],
    );
    assert_refused(&["bench", "lbvh", "--tris", "0"], d, &["--tris 0", "1 to"]);
    assert_refused(&["bench", "lbvh", "--surface", "17"], d, &["--surface 17", "18 to"]);
    // The refilled walk's shapes: SHARE:RAYS, each in its range.
    for (shape, needle) in [
        ("0:4", "1 to 64"),
        ("65:4", "1 to 64"),
        ("4:0", "1 to 1024"),
        ("4", "SHARE:RAYS"),
        ("4:x", "SHARE:RAYS"),
    ] {
        let args = ["bench", "lbvh", "--tris", "100", "--refill", "4:4", shape];
        assert_refused(&args, d, &[&format!("--refill {shape}:"), needle]);
    }
    // A ray with tmin > tmax says so.
    let ray: Vec<u8> = [0.0f32, 0.0, 0.0, 0.0, 0.0, 1.0, 5.0, 1.0]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    std::fs::write(d.join("r.bin"), ray).unwrap();
    assert_refused(
        &["bench", "lbvh", "--tris", "100", "--rays-file", "r.bin"],
        d,
        &["ray 0", "tmin > tmax"],
    );
    // An OBJ with a byte that is not UTF-8 in a comment loads.
    let mut obj = b"# caf\xe9 \xff\n".to_vec();
    obj.extend_from_slice(b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    std::fs::write(d.join("latin1.obj"), obj).unwrap();
    let (code, err) = speculum(&[&["render", "--scene", "latin1.obj"][..], &QUICK].concat(), d);
    assert_eq!(code, 0, "{err}");
}

/// Sizes that would exhaust memory or time are refused before anything is made
/// (issue 20, class 7): a sphere tessellated 100,000 x 100,000, a sweep range of a
/// billion steps, a grid of 10^10 points, more bodies than the device's buffers hold.
#[test]
fn sizes_are_bounded_before_anything_is_made() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(
        d.join("ball.toml"),
        "[camera]\nposition = [0.0, 2.0, 5.0]\ntarget = [0.0, 0.0, 0.0]\nfov = 50.0\nnear = 0.1\nfar = 50.0\n\
         [sun]\ndirection = [0.3, 0.8, 0.4]\ncolor = [1.0, 1.0, 1.0]\nintensity = 3.0\n\
         [[materials]]\nname = \"m\"\nbase_color = [0.5, 0.5, 0.5]\nroughness = 0.5\n\
         [[instance]]\nsphere = 1.0\nsegments = 100000\nrings = 100000\nmaterial = \"m\"\n",
    )
    .unwrap();
    assert_refused(
        &["render", "--scene", "ball.toml"],
        d,
        &["segments in 3..=1024", "ball.toml"],
    );
    std::fs::write(
        d.join("sweep.toml"),
        "scenes = [\"room\"]\n[axes]\nssr_stride = { min = 1, max = 16, steps = 1000000000 }\n",
    )
    .unwrap();
    assert_refused(&["tune", "sweep.toml"], d, &["1000000000 steps", "100000 points"]);
    std::fs::write(
        d.join("grid.toml"),
        "scenes = [\"room\"]\n[axes]\nssr_stride = { min = 1, max = 16, steps = 100000 }\n\
         ssr_thickness = { min = 0.01, max = 1, steps = 100000 }\n",
    )
    .unwrap();
    assert_refused(&["tune", "grid.toml"], d, &["a grid of 10000000000 points"]);
    assert_refused(
        &["render", "--scene", "stress", "--bodies", "5000"],
        d,
        &["--bodies 5000", "1..=4000"],
    );
}

/// A one-triangle glTF (`t.gltf` + `t.bin`) with the given accessors, buffer views,
/// nodes and images; the defaults make a valid file.
fn gltf(dir: &Path, name: &str, accessors: &str, views: &str, nodes: &str, extra: &str) {
    let mut bin: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    bin.extend([0u8, 0, 1, 0, 2, 0, 0, 0]);
    std::fs::write(dir.join("t.bin"), &bin).unwrap();
    let json = format!(
        "{{\"asset\": {{\"version\": \"2.0\"}}, \"scene\": 0, \"scenes\": [{{\"nodes\": [0]}}], \"nodes\": {nodes},\
         \"meshes\": [{{\"primitives\": [{{\"attributes\": {{\"POSITION\": 0}}, \"indices\": 1, \"material\": 0}}]}}],\
         \"buffers\": [{{\"uri\": \"t.bin\", \"byteLength\": 44}}], \"bufferViews\": {views}, \"accessors\": {accessors}{extra}}}"
    );
    std::fs::write(dir.join(name), json).unwrap();
}

const VIEWS: &str =
    "[{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 36}, {\"buffer\": 0, \"byteOffset\": 36, \"byteLength\": 6}]";
const POSITIONS: &str = "{\"bufferView\": 0, \"componentType\": 5126, \"count\": 3, \"type\": \"VEC3\", \"min\": [0,0,0], \"max\": [1,1,0]}";
const INDICES: &str = "{\"bufferView\": 1, \"componentType\": 5123, \"count\": 3, \"type\": \"SCALAR\"}";
const NODES: &str = "[{\"mesh\": 0}]";
const MATERIALS: &str = ", \"materials\": [{\"pbrMetallicRoughness\": {\"baseColorFactor\": [0.8, 0.8, 0.8, 1]}}]";

/// glTF is checked before it is trusted (issue 20, class 5): what panicked inside the
/// `gltf` crate or hung is one error line; a missing buffer names its file; a missing
/// texture is a warning and the model renders untextured, as with OBJ.
#[test]
fn gltf_is_checked_before_it_is_trusted() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let accessors = |p: &str, i: &str| format!("[{p}, {i}]");
    gltf(d, "ok.gltf", &accessors(POSITIONS, INDICES), VIEWS, NODES, MATERIALS);
    let (code, err) = speculum(&[&["render", "--scene", "ok.gltf"][..], &QUICK].concat(), d);
    assert_eq!(code, 0, "the valid file renders: {err}");
    // (accessors, what the error says): an index out of range, an index accessor of
    // floats, POSITION as VEC2 and as unsigned bytes.
    let pos_vec2 = POSITIONS
        .replace("VEC3", "VEC2")
        .replace("[0,0,0]", "[0,0]")
        .replace("[1,1,0]", "[1,1]");
    let cases = [
        (
            accessors(POSITIONS, INDICES),
            "POSITION\": 5",
            "attribute Positions names accessor 5, but there are 2",
        ),
        (
            accessors(POSITIONS, &INDICES.replace("5123", "5126")),
            "",
            "indices: accessor 1 is Scalar F32",
        ),
        (accessors(&pos_vec2, INDICES), "", "attributes[\"POSITION\"]"),
        (
            accessors(&POSITIONS.replace("5126", "5121"), INDICES),
            "",
            "Positions: accessor 0 is Vec3 U8",
        ),
    ];
    for (i, (acc, to, needle)) in cases.iter().enumerate() {
        let name = format!("bad{i}.gltf");
        gltf(d, &name, acc, VIEWS, NODES, MATERIALS);
        if !to.is_empty() {
            let text = std::fs::read_to_string(d.join(&name))
                .unwrap()
                .replace("POSITION\": 0", to);
            std::fs::write(d.join(&name), text).unwrap();
        }
        assert_refused(&["render", "--scene", &name], d, &[needle, &name]);
    }
    // byteStride smaller than the element.
    let strided = VIEWS.replace("\"byteLength\": 36}", "\"byteLength\": 36, \"byteStride\": 4}");
    gltf(
        d,
        "stride.gltf",
        &accessors(POSITIONS, INDICES),
        &strided,
        NODES,
        MATERIALS,
    );
    assert_refused(&["render", "--scene", "stride.gltf"], d, &["byteStride 4"]);
    // A node that is its own descendant: refused at once, not walked forever.
    gltf(
        d,
        "cycle.gltf",
        &accessors(POSITIONS, INDICES),
        VIEWS,
        "[{\"mesh\": 0, \"children\": [1]}, {\"children\": [0]}]",
        MATERIALS,
    );
    assert_refused(&["render", "--scene", "cycle.gltf"], d, &["cycle"]);
    // A missing buffer file is named.
    std::fs::write(
        d.join("nobin.gltf"),
        std::fs::read_to_string(d.join("ok.gltf"))
            .unwrap()
            .replace("t.bin", "missing.bin"),
    )
    .unwrap();
    assert_refused(&["render", "--scene", "nobin.gltf"], d, &["missing.bin"]);
    // A missing texture: one warning, and the model renders.
    let textured = ", \"materials\": [{\"pbrMetallicRoughness\": {\"baseColorTexture\": {\"index\": 0}}}],\
         \"textures\": [{\"source\": 0}], \"images\": [{\"uri\": \"gone.png\"}]";
    gltf(d, "notex.gltf", &accessors(POSITIONS, INDICES), VIEWS, NODES, textured);
    let (code, err) = speculum(&[&["render", "--scene", "notex.gltf"][..], &QUICK].concat(), d);
    assert_eq!(code, 0, "{err}");
    let warnings: Vec<&str> = err.lines().filter(|l| l.starts_with("warning:")).collect();
    assert!(warnings.len() == 1 && warnings[0].contains("image 0"), "{err}");
}

/// A glTF material's `metallicRoughnessTexture` becomes its roughness texture: a second
/// scene texture even where the same image is its base colour too, holding the
/// image's bytes as they are, marked as data (read through the array's UNORM view, no
/// sRGB decode), and the material's reflectivity is 1 (the factor alone does not say how
/// rough it is).
#[test]
fn gltf_metallic_roughness_texture_is_read_as_data() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let img = image::RgbaImage::from_fn(4, 4, |x, y| image::Rgba([10, (x * 60 + y * 3) as u8, 200, 255]));
    img.save(d.join("mr.png")).unwrap();
    let extra = ", \"materials\": [{\"pbrMetallicRoughness\": {\"baseColorTexture\": {\"index\": 0}, \
                 \"metallicRoughnessTexture\": {\"index\": 0}, \"roughnessFactor\": 1.0}}], \
                 \"textures\": [{\"source\": 0}], \"images\": [{\"uri\": \"mr.png\"}]";
    gltf(d, "t.gltf", &format!("[{POSITIONS}, {INDICES}]"), VIEWS, NODES, extra);
    let scene = speculum::scene::load(d.join("t.gltf").to_str().unwrap()).unwrap();
    let m = &scene.materials[0];
    let (colour, rough) = (m.texture.unwrap() as usize, m.roughness_texture.unwrap() as usize);
    assert_ne!(colour, rough, "the data texture is a texture of its own");
    assert_eq!((m.roughness, m.reflectivity), (1.0, 1.0));
    let (c, r) = (&scene.textures[colour].image, &scene.textures[rough].image);
    assert_eq!(c, &img, "the base colour is the image as it is");
    assert_eq!(r, &img, "the data are the image's bytes");
    assert!(!scene.textures[colour].data && scene.textures[rough].data);
}
