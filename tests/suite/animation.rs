//! glTF animations and skins (issue 41, first step): a skinned, animated file is read
//! into a rig whose pose at a time is what its keys say, and renders (in its bind pose,
//! with a warning that it does not play yet); a bad animation or skin is refused
//! before any GPU work in one line naming what is wrong.

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
/// turned an eighth about z; the skinned vertices move as their joints say. It renders,
/// saying that the animation does not play yet.
#[test]
fn a_skinned_animated_gltf_is_read_into_its_rig() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    File::default().write(d, "ok.gltf");
    let scene = speculum::scene::load(d.join("ok.gltf").to_str().unwrap()).unwrap();
    let rig = scene.rig.as_ref().expect("a rig");
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
    assert_eq!(code, 0, "{err}");
    assert!(
        err.contains("1 animation(s) and 1 skin(s) read and checked; they do not play yet"),
        "{err}"
    );
}

/// A bad animation or skin is refused before any GPU work, in one line that names
/// the problem, and writes nothing.
#[test]
fn bad_animations_and_skins_are_refused_in_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let cases: [(File, &str); 9] = [
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
