//! The animated sample character (`assets/models/figure.glb`): a jointed figure of 21
//! joints (hips, spine, chest, neck, head; each side a clavicle, upper arm, forearm,
//! hand, thigh, shin, foot and toe) skinned by tubes along its bones, 2,964
//! triangles: a blue suit and a chrome head and hands. Two animations: "walk" (one
//! second, looping in place: legs and arms swinging by linear keys, the hips bobbing
//! on a cubic spline, the head nodding by step keys) and "wave" (two seconds: the right
//! arm raised and waving). `cargo run --example figure` writes the shipped file; the
//! tests build the same bytes and check them, and play them.

use super::showcase::{container, view};
use glam::{Mat4, Quat, Vec3};
use serde_json::{json, Value};

/// Joint names, parents and rest translations (relative to the parent).
pub const JOINTS: [(&str, Option<usize>, [f32; 3]); 21] = [
    ("hips", None, [0.0, 0.95, 0.0]),
    ("spine", Some(0), [0.0, 0.15, 0.0]),
    ("chest", Some(1), [0.0, 0.2, 0.0]),
    ("neck", Some(2), [0.0, 0.2, 0.0]),
    ("head", Some(3), [0.0, 0.08, 0.0]),
    ("clavicle.l", Some(2), [0.1, 0.15, 0.0]),
    ("upper_arm.l", Some(5), [0.12, 0.0, 0.0]),
    ("forearm.l", Some(6), [0.0, -0.28, 0.0]),
    ("hand.l", Some(7), [0.0, -0.25, 0.0]),
    ("clavicle.r", Some(2), [-0.1, 0.15, 0.0]),
    ("upper_arm.r", Some(9), [-0.12, 0.0, 0.0]),
    ("forearm.r", Some(10), [0.0, -0.28, 0.0]),
    ("hand.r", Some(11), [0.0, -0.25, 0.0]),
    ("thigh.l", Some(0), [0.1, -0.05, 0.0]),
    ("shin.l", Some(13), [0.0, -0.42, 0.0]),
    ("foot.l", Some(14), [0.0, -0.4, 0.0]),
    ("toe.l", Some(15), [0.0, -0.04, 0.12]),
    ("thigh.r", Some(0), [-0.1, -0.05, 0.0]),
    ("shin.r", Some(17), [0.0, -0.42, 0.0]),
    ("foot.r", Some(18), [0.0, -0.4, 0.0]),
    ("toe.r", Some(19), [0.0, -0.04, 0.12]),
];

/// Each joint's position in the bind (rest) pose.
pub fn bind_positions() -> Vec<Vec3> {
    let mut at: Vec<Vec3> = Vec::new();
    for (_, parent, t) in JOINTS {
        at.push(parent.map_or(Vec3::ZERO, |p| at[p]) + Vec3::from(t));
    }
    at
}

/// Vertices around a bone, with their joints and weights.
#[derive(Default)]
struct Skinned {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    joints: Vec<[u16; 4]>,
    weights: Vec<[f32; 4]>,
    indices: Vec<u32>,
}

impl Skinned {
    fn vertex(&mut self, p: Vec3, n: Vec3, joints: [u16; 4], weights: [f32; 4]) -> u32 {
        self.positions.push(p);
        self.normals.push(n);
        self.joints.push(joints);
        self.weights.push(weights);
        self.positions.len() as u32 - 1
    }

    /// A capped tube of `radius` (from `r0` to `r1` along it) from `a` to `b` on joint
    /// `joint`, blended towards `before` in its first half and `after` in its second
    /// (half weight at each end), 10 around and 6 along.
    #[allow(clippy::too_many_arguments)]
    fn bone(&mut self, a: Vec3, b: Vec3, (r0, r1): (f32, f32), joint: u16, before: Option<u16>, after: Option<u16>) {
        let (around, along) = (10u32, 6u32);
        let d = (b - a).normalize();
        let e1 = d.any_orthonormal_vector();
        let e2 = d.cross(e1);
        let weigh = |t: f32| -> ([u16; 4], [f32; 4]) {
            match (before, after) {
                (Some(p), _) if t < 0.5 => ([joint, p, 0, 0], [0.5 + t, 0.5 - t, 0.0, 0.0]),
                (_, Some(c)) if t > 0.5 => ([joint, c, 0, 0], [1.5 - t, t - 0.5, 0.0, 0.0]),
                _ => ([joint, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]),
            }
        };
        let first = self.positions.len() as u32;
        for r in 0..=along {
            let t = r as f32 / along as f32;
            let (j, w) = weigh(t);
            let radius = r0 + (r1 - r0) * t;
            for s in 0..around {
                let angle = std::f32::consts::TAU * s as f32 / around as f32;
                let n = e1 * angle.cos() + e2 * angle.sin();
                self.vertex(a + (b - a) * t + n * radius, n, j, w);
            }
        }
        for r in 0..along {
            for s in 0..around {
                let (p, q) = (first + r * around + s, first + r * around + (s + 1) % around);
                self.indices.extend([p, q, p + around, q, q + around, p + around]);
            }
        }
        // Caps: a fan over each end ring.
        for (ring, tip, n, t) in [(0, a - d * r0 * 0.5, -d, 0.0), (along, b + d * r1 * 0.5, d, 1.0)] {
            let (j, w) = weigh(t);
            let base = self.positions.len() as u32;
            for s in 0..around {
                let p = self.positions[(first + ring * around + s) as usize];
                self.vertex(p, n, j, w);
            }
            let centre = self.vertex(tip, n, j, w);
            for s in 0..around {
                let (p, q) = (base + s, base + (s + 1) % around);
                let tri = if ring == 0 { [centre, q, p] } else { [centre, p, q] };
                self.indices.extend(tri);
            }
        }
    }

    /// A sphere of `radius` at `centre` on joint `joint` alone (16 around, 10 rings).
    fn ball(&mut self, centre: Vec3, radius: f32, joint: u16) {
        let m = speculum::scene::TriMesh::sphere(radius, 16, 10);
        let base = self.positions.len() as u32;
        for (p, n) in m.positions.iter().zip(&m.normals) {
            self.vertex(centre + *p, *n, [joint, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]);
        }
        self.indices.extend(m.indices.iter().map(|i| base + i));
    }
}

/// The suit (torso, arms, legs, feet) and the chrome parts (head, hands).
fn body() -> (Skinned, Skinned) {
    let at = bind_positions();
    let (mut suit, mut chrome) = (Skinned::default(), Skinned::default());
    // Torso: hips → spine → chest → neck.
    suit.bone(at[0] - Vec3::Y * 0.05, at[1], (0.13, 0.14), 0, None, Some(1));
    suit.bone(at[1], at[2], (0.14, 0.16), 1, Some(0), Some(2));
    suit.bone(at[2], at[3], (0.16, 0.07), 2, Some(1), Some(3));
    chrome.ball(at[4] + Vec3::Y * 0.1, 0.11, 4);
    for side in [0, 4] {
        let (upper, fore, hand) = (6 + side, 7 + side, 8 + side);
        suit.bone(
            at[upper],
            at[fore],
            (0.05, 0.045),
            upper as u16,
            None,
            Some(fore as u16),
        );
        suit.bone(
            at[fore],
            at[hand],
            (0.045, 0.035),
            fore as u16,
            Some(upper as u16),
            None,
        );
        chrome.ball(at[hand] - Vec3::Y * 0.05, 0.045, hand as u16);
    }
    for side in [0, 4] {
        let (thigh, shin, foot, toe) = (13 + side, 14 + side, 15 + side, 16 + side);
        suit.bone(
            at[thigh],
            at[shin],
            (0.075, 0.06),
            thigh as u16,
            None,
            Some(shin as u16),
        );
        suit.bone(at[shin], at[foot], (0.06, 0.045), shin as u16, Some(thigh as u16), None);
        suit.bone(
            at[foot] + Vec3::Z * -0.04,
            at[toe],
            (0.045, 0.04),
            foot as u16,
            None,
            None,
        );
        suit.bone(at[toe], at[toe] + Vec3::Z * 0.06, (0.04, 0.03), toe as u16, None, None);
    }
    (suit, chrome)
}

/// A joint's keyed rotations about `axis` by `degrees(t)` at `times`.
fn rotations(axis: Vec3, times: &[f32], degrees: impl Fn(f32) -> f32) -> Vec<[f32; 4]> {
    times
        .iter()
        .map(|&t| Quat::from_axis_angle(axis, degrees(t).to_radians()).to_array())
        .collect()
}

/// (joint, path, interpolation, key times, values) of the two animations.
type Track = (usize, &'static str, &'static str, Vec<f32>, Vec<Vec<f32>>);

fn walk() -> Vec<Track> {
    use std::f32::consts::TAU;
    let times: Vec<f32> = (0..=16).map(|k| k as f32 / 16.0).collect();
    let rot = |joint: usize, axis: Vec3, f: &dyn Fn(f32) -> f32| -> Track {
        let values = rotations(axis, &times, f).into_iter().map(|q| q.to_vec()).collect();
        (joint, "rotation", "LINEAR", times.clone(), values)
    };
    let mut tracks = Vec::new();
    for (side, phase) in [(0usize, 0.0f32), (4, 0.5)] {
        let s = move |t: f32| (TAU * (t + phase)).sin();
        tracks.push(rot(13 + side, Vec3::X, &move |t| -30.0 * s(t)));
        tracks.push(rot(14 + side, Vec3::X, &move |t| 40.0 * s(t + 0.3).max(0.0)));
        tracks.push(rot(6 + side, Vec3::X, &move |t| 25.0 * s(t)));
        tracks.push(rot(7 + side, Vec3::X, &move |t| -20.0 - 10.0 * s(t)));
    }
    tracks.push(rot(2, Vec3::Y, &|t| 8.0 * (TAU * t).sin()));
    // The hips bob twice a step: a cubic spline through five keys, flat tangents.
    let bob_times: Vec<f32> = (0..=4).map(|k| k as f32 / 4.0).collect();
    let bob = bob_times
        .iter()
        .flat_map(|&t| {
            let y = JOINTS[0].2[1] + 0.025 * (2.0 * TAU * t).cos();
            [vec![0.0; 3], vec![0.0, y, 0.0], vec![0.0; 3]]
        })
        .collect();
    tracks.push((0, "translation", "CUBICSPLINE", bob_times, bob));
    // The head nods between two poses, half a second each.
    let nod = vec![0.0, 0.5, 1.0];
    let nods = rotations(Vec3::X, &nod, |t| if t == 0.5 { -6.0 } else { 4.0 });
    tracks.push((
        4,
        "rotation",
        "STEP",
        nod,
        nods.into_iter().map(|q| q.to_vec()).collect(),
    ));
    tracks
}

fn wave() -> Vec<Track> {
    let times: Vec<f32> = (0..=8).map(|k| k as f32 / 4.0).collect();
    let raise = rotations(Vec3::Z, &times, |t| -150.0 * (t * 2.0).min(1.0));
    let waving = rotations(Vec3::Z, &times, |t| 30.0 * (std::f32::consts::TAU * t).sin());
    let list = |v: Vec<[f32; 4]>| v.into_iter().map(|q| q.to_vec()).collect();
    vec![
        (10, "rotation", "LINEAR", times.clone(), list(raise)),
        (11, "rotation", "LINEAR", times, list(waving)),
    ]
}

/// The figure as GLB bytes.
pub fn glb() -> Vec<u8> {
    let (suit, chrome) = body();
    let mut bin = Vec::new();
    let (mut views, mut accessors) = (Vec::new(), Vec::<Value>::new());
    let f32s = |v: &[f32]| v.iter().flat_map(|f| f.to_le_bytes()).collect::<Vec<u8>>();
    let mut accessor = |bytes: Vec<u8>, component: u32, count: usize, kind: &str, extra: Value| {
        let v = view(&mut bin, &mut views, &bytes, None);
        let mut a = json!({"bufferView": v, "componentType": component, "count": count, "type": kind});
        if let (Value::Object(a), Value::Object(e)) = (&mut a, extra) {
            a.extend(e);
        }
        accessors.push(a);
        accessors.len() - 1
    };
    let mut primitives = Vec::new();
    for (part, material) in [(&suit, 0), (&chrome, 1)] {
        let (lo, hi) = part
            .positions
            .iter()
            .fold((Vec3::MAX, Vec3::MIN), |(l, h), p| (l.min(*p), h.max(*p)));
        let flat = |v: &[Vec3]| v.iter().flat_map(|p| p.to_array()).collect::<Vec<f32>>();
        let n = part.positions.len();
        let bounds = json!({"min": lo.to_array(), "max": hi.to_array()});
        let pos = accessor(f32s(&flat(&part.positions)), 5126, n, "VEC3", bounds);
        let nor = accessor(f32s(&flat(&part.normals)), 5126, n, "VEC3", json!({}));
        let joints = part.joints.iter().flatten().flat_map(|j| j.to_le_bytes()).collect();
        let jnt = accessor(joints, 5123, n, "VEC4", json!({}));
        let wgt = accessor(f32s(&part.weights.concat()), 5126, n, "VEC4", json!({}));
        let indices = part.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let idx = accessor(indices, 5125, part.indices.len(), "SCALAR", json!({}));
        primitives.push(
            json!({"attributes": {"POSITION": pos, "NORMAL": nor, "JOINTS_0": jnt, "WEIGHTS_0": wgt},
            "indices": idx, "material": material}),
        );
    }
    let ibm: Vec<f32> = bind_positions()
        .iter()
        .flat_map(|p| Mat4::from_translation(-*p).to_cols_array())
        .collect();
    let ibm = accessor(f32s(&ibm), 5126, JOINTS.len(), "MAT4", json!({}));
    let mut animations = Vec::new();
    for (name, tracks) in [("walk", walk()), ("wave", wave())] {
        let (mut channels, mut samplers) = (Vec::new(), Vec::new());
        for (joint, path, interpolation, times, values) in tracks {
            let (lo, hi) = (times[0], *times.last().unwrap());
            let input = accessor(
                f32s(&times),
                5126,
                times.len(),
                "SCALAR",
                json!({"min": [lo], "max": [hi]}),
            );
            let kind = if values[0].len() == 4 { "VEC4" } else { "VEC3" };
            let output = accessor(f32s(&values.concat()), 5126, values.len(), kind, json!({}));
            channels.push(json!({"sampler": samplers.len(), "target": {"node": joint + 1, "path": path}}));
            samplers.push(json!({"input": input, "output": output, "interpolation": interpolation}));
        }
        animations.push(json!({"name": name, "channels": channels, "samplers": samplers}));
    }
    let mut nodes = vec![json!({"name": "figure", "mesh": 0, "skin": 0})];
    for (k, (name, _, t)) in JOINTS.iter().enumerate() {
        let children: Vec<usize> = (JOINTS.iter().enumerate())
            .filter(|(_, j)| j.1 == Some(k))
            .map(|(c, _)| c + 1)
            .collect();
        let mut node = json!({"name": name, "translation": t});
        if !children.is_empty() {
            node["children"] = json!(children);
        }
        nodes.push(node);
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let doc = json!({
        "asset": {"version": "2.0", "generator": "speculum tests/common/figure.rs"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": nodes,
        "meshes": [{"name": "figure", "primitives": primitives}],
        "skins": [{"joints": (1..=JOINTS.len()).collect::<Vec<_>>(), "inverseBindMatrices": ibm, "skeleton": 1}],
        "animations": animations,
        "materials": [
            {"name": "suit", "pbrMetallicRoughness": {"baseColorFactor": [0.16, 0.3, 0.75, 1.0],
             "metallicFactor": 0.0, "roughnessFactor": 0.5}},
            {"name": "chrome", "pbrMetallicRoughness": {"baseColorFactor": [0.95, 0.93, 0.88, 1.0],
             "metallicFactor": 1.0, "roughnessFactor": 0.04}}
        ],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}]
    });
    container(&serde_json::to_vec(&doc).unwrap(), &bin)
}
