//! glTF animations and skins: a skinned, animated file is read into a rig whose pose
//! at a time is what its keys say, and its skinned meshes become the scene's animated
//! model; the sample character (`assets/models/figure.glb`, made by
//! `tests/common/figure.rs`) plays on the GPU as the CPU poses it; a bad animation or
//! skin, or a bad way to play one, is refused before any GPU work in one line naming
//! what is wrong.

use crate::common;

use glam::{Mat4, Quat, Vec3};
use std::path::Path;
use std::time::Duration;

/// One triangle skinned to two joints (node 1, and node 2 beneath it, one up), node 2
/// turning a quarter about z over a second (linear rotation keys).
struct File {
    times: [f32; 2],
    rotations: [[f32; 4]; 2],
    joints: [[u16; 4]; 3],
    /// Extra JSON: `"nodes"` and `"skins"` and the animation channel's target node.
    nodes: &'static str,
    skin_joints: &'static str,
    target: usize,
    /// Output accessor count (2 for two keys).
    outputs: usize,
    joints_1: bool,
}

impl Default for File {
    fn default() -> Self {
        let quarter = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
        File {
            times: [0.0, 1.0],
            rotations: [[0.0, 0.0, 0.0, 1.0], quarter.to_array()],
            joints: [[0, 0, 0, 0], [1, 0, 0, 0], [0, 1, 0, 0]],
            nodes: r#"[{"mesh": 0, "skin": 0}, {"children": [2]}, {"translation": [0, 1, 0]}]"#,
            skin_joints: "[1, 2]",
            target: 2,
            outputs: 2,
            joints_1: false,
        }
    }
}

impl File {
    fn write(&self, dir: &Path, name: &str) {
        let f32s = |v: &[f32]| v.iter().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>();
        let mut bin = f32s(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]); // 0: positions, 36
        bin.extend([0u8, 0, 1, 0, 2, 0, 0, 0]); // 36: indices, 6 (+2)
        bin.extend(self.joints.iter().flatten().flat_map(|j| j.to_le_bytes())); // 44: joints, 24
        let weights = [1.0f32, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.5, 0.5, 0.0, 0.0];
        bin.extend(f32s(&weights)); // 68: weights, 48
        let ibm = [Mat4::IDENTITY, Mat4::from_translation(Vec3::new(0.0, -1.0, 0.0))];
        bin.extend(ibm.iter().flat_map(|m| f32s(&m.to_cols_array()))); // 116: 128
        bin.extend(f32s(&self.times)); // 244: 8
        bin.extend(f32s(&self.rotations.concat())); // 252: 32
        std::fs::write(dir.join(format!("{name}.bin")), &bin).unwrap();
        let view = |offset: usize, length: usize| {
            format!(r#"{{"buffer": 0, "byteOffset": {offset}, "byteLength": {length}}}"#)
        };
        let views = [
            view(0, 36),
            view(36, 6),
            view(44, 24),
            view(68, 48),
            view(116, 128),
            view(244, 8),
            view(252, 32),
        ];
        let joints_1 = if self.joints_1 {
            r#", "JOINTS_1": 2, "WEIGHTS_1": 3"#
        } else {
            ""
        };
        let json = format!(
            r#"{{"asset": {{"version": "2.0"}}, "scene": 0, "scenes": [{{"nodes": [0, 1]}}], "nodes": {nodes},
            "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0, "JOINTS_0": 2, "WEIGHTS_0": 3{joints_1}}}, "indices": 1}}]}}],
            "skins": [{{"joints": {skin_joints}, "inverseBindMatrices": 4}}],
            "animations": [{{"name": "turn", "channels": [{{"sampler": 0, "target": {{"node": {target}, "path": "rotation"}}}}],
                "samplers": [{{"input": 5, "output": 6, "interpolation": "LINEAR"}}]}}],
            "buffers": [{{"uri": "{name}.bin", "byteLength": {len}}}], "bufferViews": [{views}],
            "accessors": [
                {{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3", "min": [0,0,0], "max": [1,1,0]}},
                {{"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}},
                {{"bufferView": 2, "componentType": 5123, "count": 3, "type": "VEC4"}},
                {{"bufferView": 3, "componentType": 5126, "count": 3, "type": "VEC4"}},
                {{"bufferView": 4, "componentType": 5126, "count": 2, "type": "MAT4"}},
                {{"bufferView": 5, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0], "max": [1]}},
                {{"bufferView": 6, "componentType": 5126, "count": {outputs}, "type": "VEC4"}}]}}"#,
            nodes = self.nodes,
            skin_joints = self.skin_joints,
            target = self.target,
            len = bin.len(),
            views = views.join(", "),
            outputs = self.outputs,
        );
        std::fs::write(dir.join(name), json).unwrap();
    }
}

fn render(dir: &Path, file: &str) -> (i32, String) {
    let out = common::speculum([
        "render", "--scene", file, "--width", "64", "--height", "48", "--frames", "1", "--quiet",
    ])
    .dir(dir)
    .limit(Duration::from_secs(60))
    .run();
    (out.code, out.stderr)
}

/// The file's rig: three nodes, node 2 beneath node 1, one skin of two joints with
/// their inverse bind matrices, one animation ("turn") whose pose half way is node 2
/// turned an eighth about z; the skinned vertices move as their joints say. The
/// skinned triangle is the scene's animated model (the static part is the floor
/// alone), and it renders without a warning.
#[test]
fn a_skinned_animated_gltf_is_read_into_its_rig() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    File::default().write(d, "ok.gltf");
    let scene = speculum::scene::load(d.join("ok.gltf").to_str().unwrap()).unwrap();
    let animated = scene.animated.as_ref().expect("an animated model");
    assert_eq!(
        (animated.vertices.len(), animated.indices.len(), scene.triangle_count()),
        (3, 3, 2)
    );
    let rig = &animated.rig;
    assert_eq!(rig.parents, [None, None, Some(1)]);
    assert_eq!((rig.animations.len(), rig.skins.len()), (1, 1));
    let anim = &rig.animations[0];
    assert_eq!((anim.name.as_deref(), anim.duration()), (Some("turn"), 1.0));
    let world = rig.world(Some(anim), 0.5);
    let eighth = Mat4::from_translation(Vec3::Y) * Mat4::from_quat(Quat::from_rotation_z(std::f32::consts::FRAC_PI_4));
    assert!(world[2].abs_diff_eq(eighth, 1e-5), "{:?}", world[2]);
    // Vertex 2 (0, 1, 0) is half joint 0 (node 1, still) and half joint 1 (node 2, turned
    // about its own origin, which is where the vertex is): it stays put; at the end of
    // the turn vertex 1 (1, 0, 0), all joint 0's, stays, and a point of joint 1 at
    // (1, 1, 0) swings to (0, 2, 0).
    let m = rig.joint_matrices(&rig.skins[0], &rig.world(Some(anim), 1.0), Mat4::IDENTITY);
    let skin = |p: Vec3, j: [u16; 4], w: [f32; 4]| speculum::scene::animation::skin_vertex(p, Vec3::Z, j, w, &m).0;
    assert!(skin(Vec3::X, [0, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]).abs_diff_eq(Vec3::X, 1e-5));
    assert!(skin(Vec3::Y, [0, 1, 0, 0], [0.5, 0.5, 0.0, 0.0]).abs_diff_eq(Vec3::Y, 1e-5));
    assert!(
        skin(Vec3::new(1.0, 1.0, 0.0), [1, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]).abs_diff_eq(Vec3::new(0.0, 2.0, 0.0), 1e-5)
    );
    let (code, err) = render(d, "ok.gltf");
    assert_eq!((code, err.as_str()), (0, ""));
}

/// A bad animation or skin is refused before any GPU work, in one line that names
/// the problem, and writes nothing.
#[test]
fn bad_animations_and_skins_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(File, &str); 10] = [
        (
            File {
                times: [1.0, 0.5],
                ..File::default()
            },
            "key times do not increase",
        ),
        (
            File {
                times: [0.0, f32::NAN],
                ..File::default()
            },
            "key time 1 is not finite",
        ),
        (
            File {
                rotations: [[0.0, 0.0, 0.0, 1.0], [f32::INFINITY, 0.0, 0.0, 1.0]],
                ..File::default()
            },
            "is not finite",
        ),
        (
            File {
                rotations: [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]],
                ..File::default()
            },
            "animation 0 ('turn') channel 0 (rotation): key 1's quaternion (0, 0, 0, 0) cannot be normalised",
        ),
        (
            File {
                joints: [[0, 0, 0, 0], [5, 0, 0, 0], [0, 1, 0, 0]],
                ..File::default()
            },
            "vertex 1: joint 5, but its skin has 2",
        ),
        (
            File {
                outputs: 1,
                ..File::default()
            },
            "2 key times but 1 values",
        ),
        (
            File {
                joints_1: true,
                ..File::default()
            },
            "more than four joint influences",
        ),
        (
            File {
                nodes: r#"[{"mesh": 0, "skin": 0}, {"children": [2]}, {"children": [1]}]"#,
                ..File::default()
            },
            "cycle",
        ),
        (
            File {
                skin_joints: "[1, 9]",
                ..File::default()
            },
            "skin 0's joints names node 9, but there are 3",
        ),
        (
            File {
                target: 9,
                ..File::default()
            },
            "animation 0 channel 0's target names node 9, but there are 3",
        ),
    ];
    for (k, (file, says)) in cases.into_iter().enumerate() {
        let name = format!("bad{k}.gltf");
        file.write(d, &name);
        let (code, err) = render(d, &name);
        let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(code, 1, "case {k}: {err}");
        assert!(
            lines.len() == 1 && lines[0].contains(says),
            "case {k} should say '{says}': {err}"
        );
        assert!(!d.join("frame.png").exists(), "case {k} wrote a frame");
    }
}

/// The sample character, as `--scene` takes it bare.
pub const FIGURE: &str = "assets/models/figure.glb";

#[test]
fn shipped_figure_is_the_generated_one() {
    let shipped = std::fs::read(FIGURE).unwrap();
    assert!(
        shipped == common::figure::glb(),
        "{FIGURE} is stale: run `cargo run --example figure`"
    );
}

/// The figure read back: 21 joints in one skin, two animations ("walk" plays), about
/// 2,700 triangles all animated (the static part is the mirror floor), each vertex's
/// weights summing to 1; at rest it stands as the file's bind pose says.
#[test]
fn the_figure_is_an_animated_model() {
    let scene = speculum::scene::load(FIGURE).unwrap();
    let a = scene.animated.as_ref().unwrap();
    assert_eq!((a.joints.len(), a.rig.animations.len(), a.playing), (21, 2, 0));
    assert_eq!(a.rig.animations[0].name.as_deref(), Some("walk"));
    let tris = a.indices.len() / 3;
    assert!((2000..4000).contains(&tris), "{tris} triangles");
    assert_eq!(scene.triangle_count(), 2, "the floor alone is static");
    for f in &a.influences {
        assert!((f.weights.iter().sum::<f32>() - 1.0).abs() < 1e-6);
    }
    // At rest (no animation) every joint's matrix is the identity: the bind pose.
    let rest = a.rig.world(None, 0.0);
    for m in a.rig.joint_matrices(&a.rig.skins[0], &rest, Mat4::IDENTITY) {
        assert!(m.abs_diff_eq(Mat4::IDENTITY, 1e-6), "{m:?}");
    }
}

/// The figure walking on the GPU: at frames 1, 30 and 60 the world-space vertices
/// `sim.skin` wrote are the CPU's posing (`Animated::posed`, `skin_vertex`) at that
/// frame's time within 1e-5 of their size + 1e-5, and the dynamic BVH (built at frame
/// 1, refit since) finds brute force's hits over them
/// (`trace::dynamic_bvh_matches_brute_force`); the figure moves between the frames.
#[test]
fn the_figure_plays_as_the_cpu_poses_it() {
    let ctx = common::context();
    let scene = speculum::scene::load(FIGURE).unwrap();
    let a = scene.animated.as_ref().unwrap();
    let settings = speculum::Settings {
        width: 64,
        height: 48,
        mode: speculum::settings::Mode::Raster,
        ..Default::default()
    };
    let mut r = speculum::Renderer::new(&ctx, &scene, &settings).unwrap();
    let first = scene.dynamic_meshes().animated_vertices;
    let mut seen = Vec::new();
    for frame in 1..=60u64 {
        r.render_frame().unwrap();
        if ![1, 30, 60].contains(&frame) {
            continue;
        }
        let t = a.time((frame - 1) as f64 * settings.sim_dt as f64);
        assert_eq!(r.animation_time(), Some(t));
        let want = a.posed(t, r.origin());
        let got = r.read_dynamic_vertices().unwrap().unwrap();
        for (i, (g, w)) in got[first..].iter().zip(&want).enumerate() {
            let (g, w) = (Vec3::from(g.position), Vec3::from(w.position));
            assert!(
                (g - w).length() <= 1e-5 * w.length() + 1e-5,
                "frame {frame} vertex {i}: {g} vs {w}"
            );
        }
        let indices = scene.dynamic_meshes().indices;
        crate::trace::dynamic_bvh_matches_brute_force(&ctx, &r, (&got, &indices), 1.0, frame);
        seen.push(want);
    }
    let moved = |a: &[speculum::gpu_types::GpuVertex], b: &[speculum::gpu_types::GpuVertex]| {
        a.iter()
            .zip(b)
            .map(|(p, q)| (Vec3::from(p.position) - Vec3::from(q.position)).length())
            .fold(0.0f32, f32::max)
    };
    assert!(moved(&seen[0], &seen[1]) > 0.1 && moved(&seen[1], &seen[2]) > 0.1);
    assert_eq!(ctx.validation_messages(), 0);
}

/// A scene file plays its model's animation by name, at its speed, looping or not,
/// where its instance places it; `--time` starts the clock later: a renderer started
/// at 0.25 s poses the figure as one that has run 15 frames from 0.
#[test]
fn scene_files_and_flags_choose_how_it_plays() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::copy(FIGURE, d.join("figure.glb")).unwrap();
    let text = "[camera]\nposition = [0, 2, 6]\ntarget = [0, 0, 0]\nfov = 50\n\
                [sun]\ndirection = [0, 1, 0]\ncolor = [1, 1, 1]\nintensity = 2\n\
                [[materials]]\nname = \"m\"\nbase_color = [0.5, 0.5, 0.5]\nroughness = 0.5\n\
                [[instance]]\nplane = [8, 8]\nmaterial = \"m\"\n\
                [[instance]]\nmodel = \"figure.glb\"\ntranslate = [1, 0, 0]\nanimation = \"wave\"\nspeed = 2\nloop = false\n";
    std::fs::write(d.join("s.toml"), text).unwrap();
    let scene = speculum::scene::load(d.join("s.toml").to_str().unwrap()).unwrap();
    let a = scene.animated.as_ref().unwrap();
    assert_eq!((a.playing, a.speed, a.looping), (1, 2.0, false));
    assert!(a.placement.abs_diff_eq(Mat4::from_translation(Vec3::X), 0.0));
    assert_eq!(a.time(5.0), a.duration(), "not looping: held at the end");
    let ctx = common::context();
    let mut figure = speculum::scene::load(FIGURE).unwrap();
    let settings = speculum::Settings {
        width: 32,
        height: 24,
        mode: speculum::settings::Mode::Raster,
        ..Default::default()
    };
    let mut from_zero = speculum::Renderer::new(&ctx, &figure, &settings).unwrap();
    for _ in 0..16 {
        from_zero.render_frame().unwrap();
    }
    figure.animated.as_mut().unwrap().start = 15.0 * settings.sim_dt;
    let mut later = speculum::Renderer::new(&ctx, &figure, &settings).unwrap();
    later.render_frame().unwrap();
    let (a, b) = (
        from_zero.read_dynamic_vertices().unwrap().unwrap(),
        later.read_dynamic_vertices().unwrap().unwrap(),
    );
    for (p, q) in a.iter().zip(&b) {
        assert!((Vec3::from(p.position) - Vec3::from(q.position)).length() < 1e-5);
    }
    assert_eq!(ctx.validation_messages(), 0);
}

/// Bad ways to play are refused before any GPU work in one line, writing nothing: an
/// animation the model does not have (by name or index), a time that is not finite,
/// `--time` on a scene that does not move so, and in a scene file an unknown
/// animation, a speed that is not finite, animation keys on a primitive or on a
/// model without animations, a second animated model, and an animated model as a
/// rigid body.
#[test]
fn bad_ways_to_play_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::copy(FIGURE, d.join("figure.glb")).unwrap();
    File::default().write(d, "plain.gltf");
    std::fs::write(d.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let head = "[camera]\nposition = [0, 2, 6]\ntarget = [0, 0, 0]\nfov = 50\n\
                [sun]\ndirection = [0, 1, 0]\ncolor = [1, 1, 1]\nintensity = 2\n\
                [[materials]]\nname = \"m\"\nbase_color = [0.5, 0.5, 0.5]\nroughness = 0.5\n\
                [[instance]]\nplane = [8, 8]\nmaterial = \"m\"\n";
    let files = [
        (
            "[[instance]]\nmodel = \"figure.glb\"\nanimation = \"run\"\n",
            "no animation named 'run' (it has: 0 'walk', 1 'wave')",
        ),
        (
            "[[instance]]\nmodel = \"figure.glb\"\nspeed = nan\n",
            "speed NaN is not finite",
        ),
        (
            "[[instance]]\nbox = [1, 1, 1]\nmaterial = \"m\"\nloop = true\n",
            "are for an animated model",
        ),
        (
            "[[instance]]\nmodel = \"tri.obj\"\nanimation = 0\n",
            "'tri.obj' has none",
        ),
        (
            "[[body]]\nmodel = \"figure.glb\"\nmaterial = \"m\"\ntranslate = [0, 2, 0]\n",
            "body 1: 'figure.glb' is animated; an animated model plays as an [[instance]]",
        ),
        (
            "[[instance]]\nmodel = \"figure.glb\"\n[[instance]]\nmodel = \"plain.gltf\"\n",
            "a second animated model ('plain.gltf')",
        ),
    ];
    let mut cases: Vec<(Vec<String>, &str)> = Vec::new();
    for (k, (body, says)) in files.iter().enumerate() {
        std::fs::write(d.join(format!("bad{k}.toml")), format!("{head}{body}")).unwrap();
        cases.push((vec!["--scene".into(), format!("bad{k}.toml")], says));
    }
    let flags: [(&[&str], &str); 4] = [
        (
            &["--scene", "figure.glb", "--animation", "7"],
            "--animation: the model has no animation 7",
        ),
        (
            &["--scene", "figure.glb", "--time", "nan"],
            "--time NaN is not a finite number",
        ),
        (
            &["--scene", "room", "--time", "1"],
            "need a scene with an animated model; 'room' has none",
        ),
        (
            &["--scene", "tri.obj", "--animation", "walk"],
            "need a scene with an animated model",
        ),
    ];
    cases.extend(
        flags
            .iter()
            .map(|(a, s)| (a.iter().map(|x| x.to_string()).collect(), *s)),
    );
    for (k, (args, says)) in cases.iter().enumerate() {
        let out = common::speculum(["render", "--width", "32", "--height", "24", "--frames", "1", "--quiet"])
            .args(args)
            .dir(d)
            .limit(Duration::from_secs(60))
            .run();
        let lines: Vec<&str> = out.stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(out.code, 1, "case {k}: {}", out.stderr);
        assert!(
            lines.len() == 1 && lines[0].contains(says),
            "case {k} should say '{says}': {}",
            out.stderr
        );
        assert!(!d.join("frame.png").exists(), "case {k} wrote a frame");
    }
}
