//! glTF animations and skins on the CPU: read, checked and evaluated; the renderer
//! plays them through `scene::animated` and the skinning pass (`sim.skin`), which this
//! file's `skin_vertex` is the CPU reference of. A `Rig` is a file's node hierarchy with
//! each node's rest transform, its animations (keyframed translation, rotation and
//! scale: step, linear with rotations slerped, and cubic-spline interpolation, as the
//! glTF 2.0 specification's appendix C defines them) and its skins (joints and inverse
//! bind matrices). `Rig::world` poses the hierarchy at a time, `Rig::joint_matrices`
//! gives a skin's matrices from that, and `skin_vertex` is the linear blend skinning of
//! one vertex: the CPU reference of the skinning pass (`sim.skin`).

use crate::gpu_types::GpuInfluence;
use glam::{Mat3, Mat4, Quat, Vec3, Vec4};

/// The deepest node hierarchy a rig may have (root = depth 1): the pose walk and the
/// skin's matrices stay bounded, and a deeper file is refused in one line.
pub const MAX_DEPTH: usize = 128;

/// Keyframes per sampler at most (about 4 hours at 60 keys a second).
pub const MAX_KEYS: usize = 1 << 20;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    Step,
    Linear,
    /// Hermite spline: each key holds (in-tangent, value, out-tangent).
    CubicSpline,
}

/// What a channel animates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Path {
    Translation,
    /// A unit quaternion (x, y, z, w).
    Rotation,
    Scale,
}

/// A node's transform as translation, rotation, scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
}

impl Trs {
    pub const IDENTITY: Trs = Trs {
        translation: Vec3::ZERO,
        rotation: Quat::IDENTITY,
        scale: Vec3::ONE,
    };

    pub fn matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
}

/// Keyframes: increasing times (seconds) and their values, xyz or xyzw in a `Vec4`;
/// three values per time for `CubicSpline`.
#[derive(Clone, Debug, PartialEq)]
pub struct Sampler {
    pub times: Vec<f32>,
    pub values: Vec<Vec4>,
    pub interpolation: Interpolation,
}

impl Sampler {
    /// Why the sampler cannot be played, if it cannot: no keys, too many, times that
    /// are not finite or do not increase, a value count that is not the times' (three
    /// times for a cubic spline), values that are not finite.
    pub fn check(&self) -> Result<(), String> {
        let n = self.times.len();
        if n == 0 || n > MAX_KEYS {
            return Err(format!("has {n} keyframes (1..={MAX_KEYS})"));
        }
        let per = if self.interpolation == Interpolation::CubicSpline {
            3
        } else {
            1
        };
        if self.values.len() != per * n {
            return Err(format!(
                "has {n} key times but {} values ({} expected)",
                self.values.len(),
                per * n
            ));
        }
        if let Some(k) = self.times.iter().position(|t| !t.is_finite()) {
            return Err(format!("key time {k} is not finite"));
        }
        if let Some(k) = (1..n).find(|&k| self.times[k] <= self.times[k - 1]) {
            return Err(format!(
                "key times do not increase ({} then {} at key {k})",
                self.times[k - 1],
                self.times[k]
            ));
        }
        if let Some(k) = self.values.iter().position(|v| !v.is_finite()) {
            return Err(format!("value {k} is not finite"));
        }
        Ok(())
    }

    /// Why a rotation channel's keys cannot be played, if they cannot: a key whose
    /// quaternion has no direction (all zero, or too short to normalise), between which
    /// and its neighbours every pose would be NaN. (A cubic spline's tangents may be zero.)
    pub fn check_rotations(&self) -> Result<(), String> {
        let cubic = self.interpolation == Interpolation::CubicSpline;
        let keys = self.values.len() / if cubic { 3 } else { 1 };
        for k in 0..keys {
            let q = self.values[if cubic { 3 * k + 1 } else { k }];
            if q.try_normalize().is_none() {
                return Err(format!(
                    "key {k}'s quaternion ({}, {}, {}, {}) cannot be normalised",
                    q.x, q.y, q.z, q.w
                ));
            }
        }
        Ok(())
    }

    /// The value at time `t` (clamped to the keys' span) for a channel of `path`: step,
    /// linear (rotations slerped along the shorter arc) or the cubic Hermite spline
    /// (rotations normalized after). A checked sampler.
    pub fn sample(&self, t: f32, path: Path) -> Vec4 {
        let n = self.times.len();
        let value = |k: usize| match self.interpolation {
            Interpolation::CubicSpline => self.values[3 * k + 1],
            _ => self.values[k],
        };
        if n == 1 || t <= self.times[0] {
            return value(0);
        }
        if t >= self.times[n - 1] {
            return value(n - 1);
        }
        // The key interval holding t: times[k] <= t < times[k + 1].
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let dt = t1 - t0;
        let s = ((t - t0) / dt).clamp(0.0, 1.0);
        match self.interpolation {
            Interpolation::Step => value(k),
            Interpolation::Linear if path == Path::Rotation => {
                let (a, b) = (Quat::from_vec4(value(k)), Quat::from_vec4(value(k + 1)));
                Vec4::from(a.normalize().slerp(b.normalize(), s))
            }
            Interpolation::Linear => value(k).lerp(value(k + 1), s),
            Interpolation::CubicSpline => {
                let (p0, m0) = (self.values[3 * k + 1], self.values[3 * k + 2] * dt);
                let (p1, m1) = (self.values[3 * (k + 1) + 1], self.values[3 * (k + 1)] * dt);
                let (s2, s3) = (s * s, s * s * s);
                let v = p0 * (2.0 * s3 - 3.0 * s2 + 1.0)
                    + m0 * (s3 - 2.0 * s2 + s)
                    + p1 * (-2.0 * s3 + 3.0 * s2)
                    + m1 * (s3 - s2);
                if path == Path::Rotation {
                    v.normalize_or(Vec4::W)
                } else {
                    v
                }
            }
        }
    }

    /// The last key's time.
    pub fn end(&self) -> f32 {
        self.times.last().copied().unwrap_or(0.0)
    }
}

/// One animated property of one node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Channel {
    pub node: usize,
    pub path: Path,
    pub sampler: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    pub name: Option<String>,
    pub samplers: Vec<Sampler>,
    pub channels: Vec<Channel>,
}

impl Animation {
    /// Its length in seconds: the last key of any sampler.
    pub fn duration(&self) -> f32 {
        self.samplers.iter().map(Sampler::end).fold(0.0, f32::max)
    }
}

/// A skin: its joints (nodes) and each joint's inverse bind matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct Skin {
    pub joints: Vec<usize>,
    pub inverse_bind: Vec<Mat4>,
}

/// A file's node hierarchy, animations and skins.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Rig {
    /// Each node's parent (`None`: a root).
    pub parents: Vec<Option<usize>>,
    /// Each node's transform when no animation moves it.
    pub rest: Vec<Trs>,
    pub animations: Vec<Animation>,
    pub skins: Vec<Skin>,
}

impl Rig {
    /// Why the rig cannot be played, if it cannot, in one line: a parent that is not a
    /// node or a cycle, a hierarchy deeper than `MAX_DEPTH`, a rest transform that is
    /// not finite, a channel whose node or sampler does not exist, a sampler that
    /// fails `Sampler::check`, a skin with no joints, a joint that is not a node or
    /// an inverse bind matrix per joint that is missing or not finite.
    pub fn check(&self) -> Result<(), String> {
        let n = self.parents.len();
        if self.rest.len() != n {
            return Err(format!("{n} nodes but {} rest transforms", self.rest.len()));
        }
        for (i, t) in self.rest.iter().enumerate() {
            if !(t.translation.is_finite() && t.rotation.is_finite() && t.scale.is_finite()) {
                return Err(format!("node {i}'s transform is not finite"));
            }
            if Vec4::from(t.rotation).try_normalize().is_none() {
                return Err(format!(
                    "node {i}'s rotation {:?} cannot be normalised",
                    t.rotation.to_array()
                ));
            }
        }
        for i in 0..n {
            let depth = self.depth(i)?;
            if depth > MAX_DEPTH {
                return Err(format!("node {i} is {depth} levels deep (at most {MAX_DEPTH})"));
            }
        }
        for (a, anim) in self.animations.iter().enumerate() {
            let name = anim
                .name
                .as_deref()
                .map_or(format!("animation {a}"), |s| format!("animation {a} ('{s}')"));
            for (s, sampler) in anim.samplers.iter().enumerate() {
                sampler.check().map_err(|e| format!("{name} sampler {s} {e}"))?;
            }
            for (c, ch) in anim.channels.iter().enumerate() {
                if ch.node >= n {
                    return Err(format!(
                        "{name} channel {c} targets node {}, but there are {n}",
                        ch.node
                    ));
                }
                if ch.sampler >= anim.samplers.len() {
                    return Err(format!(
                        "{name} channel {c} names sampler {}, but there are {}",
                        ch.sampler,
                        anim.samplers.len()
                    ));
                }
                if ch.path == Path::Rotation {
                    anim.samplers[ch.sampler]
                        .check_rotations()
                        .map_err(|e| format!("{name} channel {c} (rotation): {e}"))?;
                }
            }
        }
        for (s, skin) in self.skins.iter().enumerate() {
            if skin.joints.is_empty() {
                return Err(format!("skin {s} has no joints"));
            }
            if let Some(j) = skin.joints.iter().find(|&&j| j >= n) {
                return Err(format!("skin {s}'s joint {j} is not a node (there are {n})"));
            }
            if skin.inverse_bind.len() != skin.joints.len() {
                return Err(format!(
                    "skin {s} has {} joints but {} inverse bind matrices",
                    skin.joints.len(),
                    skin.inverse_bind.len()
                ));
            }
            if let Some(k) = skin.inverse_bind.iter().position(|m| !m.is_finite()) {
                return Err(format!("skin {s}'s inverse bind matrix {k} is not finite"));
            }
        }
        Ok(())
    }

    /// Node `i`'s depth (a root is 1), or the cycle or dangling parent that stops it.
    fn depth(&self, i: usize) -> Result<usize, String> {
        let n = self.parents.len();
        let (mut at, mut depth) = (i, 1);
        while let Some(p) = self.parents[at] {
            if p >= n {
                return Err(format!("node {at}'s parent {p} is not a node (there are {n})"));
            }
            depth += 1;
            if depth > n {
                return Err(format!("node {i} is its own ancestor: the hierarchy has a cycle"));
            }
            at = p;
        }
        Ok(depth)
    }

    /// Every node's transform at time `t` of `animation` (its rest transform where no
    /// channel of it moves it; at rest without an animation).
    pub fn local(&self, animation: Option<&Animation>, t: f32) -> Vec<Trs> {
        let mut local = self.rest.clone();
        if let Some(anim) = animation {
            for ch in &anim.channels {
                let v = anim.samplers[ch.sampler].sample(t, ch.path);
                let trs = &mut local[ch.node];
                match ch.path {
                    Path::Translation => trs.translation = v.truncate(),
                    Path::Rotation => trs.rotation = Quat::from_vec4(v).normalize(),
                    Path::Scale => trs.scale = v.truncate(),
                }
            }
        }
        local
    }

    /// Every node's world matrix at time `t` of `animation`: its ancestors' local
    /// matrices times its own. A checked rig.
    pub fn world(&self, animation: Option<&Animation>, t: f32) -> Vec<Mat4> {
        let local = self.local(animation, t);
        let n = self.parents.len();
        let mut world: Vec<Option<Mat4>> = vec![None; n];
        for i in 0..n {
            // The chain from the nearest posed ancestor down to i (bounded by MAX_DEPTH).
            let mut chain = vec![i];
            while let Some(p) = self.parents[*chain.last().unwrap()] {
                if world[p].is_some() {
                    break;
                }
                chain.push(p);
            }
            for &c in chain.iter().rev() {
                let parent = self.parents[c].and_then(|p| world[p]).unwrap_or(Mat4::IDENTITY);
                world[c] = Some(parent * local[c].matrix());
            }
        }
        world.into_iter().map(|m| m.unwrap_or(Mat4::IDENTITY)).collect()
    }

    /// Which nodes some animation moves: a channel's target and every node beneath
    /// one. A checked rig.
    pub fn moved(&self) -> Vec<bool> {
        let mut target = vec![false; self.parents.len()];
        for ch in self.animations.iter().flat_map(|a| &a.channels) {
            target[ch.node] = true;
        }
        (0..self.parents.len())
            .map(|i| {
                let mut at = Some(i);
                while let Some(n) = at {
                    if target[n] {
                        return true;
                    }
                    at = self.parents[n];
                }
                false
            })
            .collect()
    }

    /// The skinning matrices of `skin` from the nodes' `world` matrices: each joint's
    /// world matrix times its inverse bind matrix, in the world of the skinned mesh's
    /// node `mesh_world` (glTF: the mesh node's own transform is ignored; its
    /// skeleton's is used, so `mesh_world` is usually the identity).
    pub fn joint_matrices(&self, skin: &Skin, world: &[Mat4], mesh_world: Mat4) -> Vec<Mat4> {
        let into_mesh = mesh_world.inverse();
        skin.joints
            .iter()
            .zip(&skin.inverse_bind)
            .map(|(&j, ibm)| into_mesh * world[j] * *ibm)
            .collect()
    }
}

/// Linear blend skinning of one vertex (position, normal) by up to four joints and
/// their weights: the weighted sum of the joint matrices applied to the position, and
/// of their upper 3x3s (inverse transpose, for non-uniform scale) to the normal,
/// renormalized. Weights need not sum to 1: they are divided by their sum (a vertex
/// with no weight keeps its bind pose).
pub fn skin_vertex(p: Vec3, n: Vec3, joints: [u16; 4], weights: [f32; 4], matrices: &[Mat4]) -> (Vec3, Vec3) {
    let total: f32 = weights.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return (p, n);
    }
    let mut m = Mat4::ZERO;
    for (j, w) in joints.iter().zip(weights) {
        if w != 0.0 {
            m += matrices[*j as usize] * (w / total);
        }
    }
    let normal = Mat3::from_mat4(m).inverse().transpose() * n;
    (m.transform_point3(p), normal.normalize_or(n))
}

/// `mesh` skinned by `influences` (one per vertex) and `matrices` (`skin_vertex`).
pub fn skin_mesh(
    mesh: &crate::scene::TriMesh,
    influences: &[GpuInfluence],
    matrices: &[Mat4],
) -> crate::scene::TriMesh {
    let (positions, normals) = mesh
        .positions
        .iter()
        .zip(&mesh.normals)
        .zip(influences)
        .map(|((&p, &n), f)| skin_vertex(p, n, f.joint_indices(), f.weights, matrices))
        .unzip();
    crate::scene::TriMesh {
        positions,
        normals,
        ..mesh.clone()
    }
}

/// A generated skinned mesh: a tube (`segments` around, `rings` along, height 2, radius
/// 0.2, on the y axis from 0 up) bound to a chain of `joints` joints spaced evenly up
/// it (node k the child of node k - 1, k > 0), each vertex weighted to the two joints
/// nearest its height, linearly between them; its one animation ("sway", one second,
/// 17 linear keys) turns joint k about z by 0.4 sin(2 pi t) (k + 1) / joints radians,
/// so at t = 0 and 0.5 the tube stands straight. 2 x segments x rings triangles: the
/// animated-geometry benchmark's mesh (issue 41 asks for one of 200K or more).
pub fn skinned_tube(segments: u32, rings: u32, joints: u32) -> (crate::scene::TriMesh, Vec<GpuInfluence>, Rig) {
    let (height, radius) = (2.0f32, 0.2f32);
    let step = height / joints as f32;
    let mut mesh = crate::scene::TriMesh::default();
    let mut influences = Vec::new();
    for r in 0..=rings {
        let y = height * r as f32 / rings as f32;
        // The joint below y and the share of the one above.
        let at = (y / step).min(joints as f32 - 1.0);
        let (j, share) = (at.floor() as u16, at.fract());
        let above = (j + 1).min(joints as u16 - 1);
        for s in 0..segments {
            let a = std::f32::consts::TAU * s as f32 / segments as f32;
            let n = Vec3::new(a.cos(), 0.0, a.sin());
            mesh.positions.push(n * radius + Vec3::Y * y);
            mesh.normals.push(n);
            mesh.uvs
                .push(glam::Vec2::new(s as f32 / segments as f32, r as f32 / rings as f32));
            influences.push(GpuInfluence::new([j, above, 0, 0], [1.0 - share, share, 0.0, 0.0]));
        }
    }
    for r in 0..rings {
        for s in 0..segments {
            let (a, b) = (r * segments + s, r * segments + (s + 1) % segments);
            let (c, d) = (a + segments, b + segments);
            mesh.indices.extend([a, c, b, b, c, d]);
        }
    }
    let keys = 17;
    let times: Vec<f32> = (0..keys).map(|k| k as f32 / (keys - 1) as f32).collect();
    let animation = Animation {
        name: Some("sway".into()),
        samplers: (0..joints)
            .map(|k| Sampler {
                values: times
                    .iter()
                    .map(|t| {
                        let angle = 0.4 * (std::f32::consts::TAU * t).sin() * (k + 1) as f32 / joints as f32;
                        Vec4::from(Quat::from_rotation_z(angle))
                    })
                    .collect(),
                times: times.clone(),
                interpolation: Interpolation::Linear,
            })
            .collect(),
        channels: (0..joints as usize)
            .map(|k| Channel {
                node: k,
                path: Path::Rotation,
                sampler: k,
            })
            .collect(),
    };
    let rest = (0..joints)
        .map(|k| Trs {
            translation: if k == 0 { Vec3::ZERO } else { Vec3::Y * step },
            ..Trs::IDENTITY
        })
        .collect();
    let rig = Rig {
        parents: (0..joints as usize).map(|k| k.checked_sub(1)).collect(),
        rest,
        animations: vec![animation],
        skins: vec![Skin {
            joints: (0..joints as usize).collect(),
            inverse_bind: (0..joints)
                .map(|k| Mat4::from_translation(-Vec3::Y * step * k as f32))
                .collect(),
        }],
    };
    (mesh, influences, rig)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    fn rng(seed: u64) -> rand::rngs::StdRng {
        rand::rngs::StdRng::seed_from_u64(seed)
    }

    fn times(r: &mut impl Rng, n: usize) -> Vec<f32> {
        let mut t = r.random_range(-1.0..1.0f32);
        (0..n)
            .map(|_| {
                t += r.random_range(0.05..0.5f32);
                t
            })
            .collect()
    }

    fn random_quat(r: &mut impl Rng) -> Quat {
        let v = Vec4::new(
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
            r.random_range(-1.0..1.0),
        );
        Quat::from_vec4(v.normalize_or(Vec4::W))
    }

    /// Step holds each key until the next; linear passes through every key and
    /// blends between them by the time's share; both clamp outside the keys.
    #[test]
    fn step_and_linear_samplers_on_random_keys() {
        let mut r = rng(1);
        for _ in 0..50 {
            let n = r.random_range(1..12);
            let t = times(&mut r, n);
            let values: Vec<Vec4> = (0..n)
                .map(|_| Vec4::new(r.random(), r.random(), r.random(), 0.0) * 10.0)
                .collect();
            for interpolation in [Interpolation::Step, Interpolation::Linear] {
                let s = Sampler {
                    times: t.clone(),
                    values: values.clone(),
                    interpolation,
                };
                s.check().unwrap();
                for k in 0..n {
                    assert_eq!(s.sample(t[k], Path::Translation), values[k]);
                }
                assert_eq!(s.sample(t[0] - 5.0, Path::Scale), values[0]);
                assert_eq!(s.sample(t[n - 1] + 5.0, Path::Scale), values[n - 1]);
                for k in 0..n.saturating_sub(1) {
                    let a: f32 = r.random_range(0.0..1.0);
                    let x = t[k] + a * (t[k + 1] - t[k]);
                    let a = (x - t[k]) / (t[k + 1] - t[k]);
                    let want = match interpolation {
                        Interpolation::Step => values[k],
                        _ => values[k] * (1.0 - a) + values[k + 1] * a,
                    };
                    let got = s.sample(x, Path::Translation);
                    assert!(
                        (got - want).abs().max_element() < 1e-4,
                        "{interpolation:?} at {x}: {got} vs {want}"
                    );
                }
            }
        }
    }

    /// Linear rotation keys are slerped: unit quaternions, the angle from the first
    /// key growing in proportion to the time's share, along the shorter arc.
    #[test]
    fn rotations_are_slerped_along_the_shorter_arc() {
        let mut r = rng(2);
        for _ in 0..200 {
            let (a, mut b) = (random_quat(&mut r), random_quat(&mut r));
            if r.random_bool(0.5) {
                b = -b; // the same rotation, the other sign
            }
            let s = Sampler {
                times: vec![0.0, 1.0],
                values: vec![Vec4::from(a), Vec4::from(b)],
                interpolation: Interpolation::Linear,
            };
            let total = a.angle_between(b);
            let share: f32 = r.random_range(0.0..1.0);
            let q = Quat::from_vec4(s.sample(share, Path::Rotation));
            assert!((q.length() - 1.0).abs() < 1e-5);
            assert!(total <= std::f32::consts::PI + 1e-4, "the shorter arc");
            assert!((a.angle_between(q) - share * total).abs() < 2e-3, "{share} of {total}");
            assert!((q.angle_between(b) - (1.0 - share) * total).abs() < 2e-3);
        }
    }

    /// The cubic Hermite spline reproduces a cubic polynomial exactly when its keys
    /// hold the polynomial's values and (time-)derivatives as tangents.
    #[test]
    fn cubic_splines_reproduce_cubics() {
        let mut r = rng(3);
        for _ in 0..50 {
            let c: [Vec4; 4] = std::array::from_fn(|_| {
                Vec4::new(
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                    r.random_range(-1.0..1.0),
                    0.0,
                )
            });
            let f = |t: f32| c[0] + c[1] * t + c[2] * t * t + c[3] * t * t * t;
            let df = |t: f32| c[1] + c[2] * 2.0 * t + c[3] * 3.0 * t * t;
            let n = r.random_range(2..8);
            let t = times(&mut r, n);
            let values = t.iter().flat_map(|&x| [df(x), f(x), df(x)]).collect();
            let s = Sampler {
                times: t.clone(),
                values,
                interpolation: Interpolation::CubicSpline,
            };
            s.check().unwrap();
            for _ in 0..20 {
                let x = r.random_range(t[0]..t[n - 1]);
                let got = s.sample(x, Path::Translation);
                assert!((got - f(x)).abs().max_element() < 1e-3, "at {x}: {got} vs {}", f(x));
            }
        }
    }

    /// Bad samplers are refused, each in a line that says what is wrong.
    #[test]
    fn bad_samplers_are_refused() {
        let ok = Sampler {
            times: vec![0.0, 1.0],
            values: vec![Vec4::ZERO; 2],
            interpolation: Interpolation::Linear,
        };
        ok.check().unwrap();
        let cases = [
            (
                Sampler {
                    times: vec![],
                    values: vec![],
                    ..ok.clone()
                },
                "0 keyframes",
            ),
            (
                Sampler {
                    times: vec![0.0, 0.0],
                    ..ok.clone()
                },
                "do not increase",
            ),
            (
                Sampler {
                    times: vec![1.0, 0.5],
                    ..ok.clone()
                },
                "do not increase",
            ),
            (
                Sampler {
                    times: vec![0.0, f32::NAN],
                    ..ok.clone()
                },
                "not finite",
            ),
            (
                Sampler {
                    values: vec![Vec4::ZERO; 3],
                    ..ok.clone()
                },
                "3 values (2 expected)",
            ),
            (
                Sampler {
                    interpolation: Interpolation::CubicSpline,
                    ..ok.clone()
                },
                "2 values (6 expected)",
            ),
            (
                Sampler {
                    values: vec![Vec4::ZERO, Vec4::splat(f32::INFINITY)],
                    ..ok.clone()
                },
                "value 1 is not finite",
            ),
        ];
        for (s, says) in cases {
            let e = s.check().unwrap_err();
            assert!(e.contains(says) && !e.contains('\n'), "{e}");
        }
    }

    fn random_trs(r: &mut impl Rng) -> Trs {
        Trs {
            translation: Vec3::new(
                r.random_range(-2.0..2.0),
                r.random_range(-2.0..2.0),
                r.random_range(-2.0..2.0),
            ),
            rotation: random_quat(r),
            scale: Vec3::new(
                r.random_range(0.5..2.0),
                r.random_range(0.5..2.0),
                r.random_range(0.5..2.0),
            ),
        }
    }

    /// A random forest of nodes: each world matrix is its chain of local matrices from
    /// the root, multiplied out one by one; an animated node takes its channel's value.
    #[test]
    fn world_matrices_follow_the_hierarchy_and_the_channels() {
        let mut r = rng(4);
        let n = 40;
        let parents: Vec<Option<usize>> = (0..n)
            .map(|i| {
                if i == 0 || r.random_bool(0.2) {
                    None
                } else {
                    Some(r.random_range(0..i))
                }
            })
            .collect();
        let rest: Vec<Trs> = (0..n).map(|_| random_trs(&mut r)).collect();
        let moved = 7;
        let target = Vec3::new(1.0, 2.0, 3.0);
        let anim = Animation {
            name: None,
            samplers: vec![Sampler {
                times: vec![0.0, 2.0],
                values: vec![Vec4::ZERO, target.extend(0.0)],
                interpolation: Interpolation::Linear,
            }],
            channels: vec![Channel {
                node: moved,
                path: Path::Translation,
                sampler: 0,
            }],
        };
        let rig = Rig {
            parents: parents.clone(),
            rest: rest.clone(),
            animations: vec![anim],
            skins: vec![],
        };
        rig.check().unwrap();
        let world = rig.world(Some(&rig.animations[0]), 1.0);
        for (i, w) in world.iter().enumerate() {
            let mut m = Mat4::IDENTITY;
            let mut at = Some(i);
            while let Some(k) = at {
                let local = if k == moved {
                    Trs {
                        translation: target * 0.5,
                        ..rest[k]
                    }
                } else {
                    rest[k]
                };
                m = local.matrix() * m;
                at = parents[k];
            }
            let d = (*w - m).to_cols_array().iter().fold(0.0f32, |a, x| a.max(x.abs()));
            assert!(
                d < 1e-3 * (1.0 + m.to_cols_array().iter().fold(0.0f32, |a, x| a.max(x.abs()))),
                "node {i}: {d}"
            );
        }
    }

    /// Skinning: a vertex weighted to one joint moves by that joint's matrix; in
    /// general by the weighted blend of its joints' transforms of it (weights
    /// normalized), its normal unit length; weights all zero keep the bind pose.
    #[test]
    fn skinning_blends_the_joints() {
        let mut r = rng(5);
        let matrices: Vec<Mat4> = (0..20).map(|_| random_trs(&mut r).matrix()).collect();
        for _ in 0..500 {
            let p = Vec3::new(
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
                r.random_range(-1.0..1.0),
            );
            let n = Vec3::new(r.random_range(-1.0..1.0), r.random_range(-1.0..1.0), 1.0).normalize();
            let joints: [u16; 4] = std::array::from_fn(|_| r.random_range(0..20));
            let weights: [f32; 4] = std::array::from_fn(|_| {
                if r.random_bool(0.3) {
                    0.0
                } else {
                    r.random_range(0.0..1.0)
                }
            });
            let total: f32 = weights.iter().sum();
            let (q, m) = skin_vertex(p, n, joints, weights, &matrices);
            if total == 0.0 {
                assert_eq!((q, m), (p, n));
                continue;
            }
            let want: Vec3 = (0..4)
                .map(|k| matrices[joints[k] as usize].transform_point3(p) * (weights[k] / total))
                .sum();
            assert!((q - want).length() < 1e-4, "{q} vs {want}");
            assert!((m.length() - 1.0).abs() < 1e-4);
            let (one, _) = skin_vertex(p, n, [joints[0], 0, 0, 0], [0.7, 0.0, 0.0, 0.0], &matrices);
            assert!((one - matrices[joints[0] as usize].transform_point3(p)).length() < 1e-4);
        }
    }

    /// Bad rigs are refused in one line each: a cycle, a hierarchy past MAX_DEPTH, a
    /// channel on a missing node or sampler, a joint that is not a node, inverse bind
    /// matrices that are missing or not finite, a skin without joints.
    #[test]
    fn bad_rigs_are_refused() {
        let two = Rig {
            parents: vec![None, Some(0)],
            rest: vec![Trs::IDENTITY; 2],
            ..Default::default()
        };
        two.check().unwrap();
        let sampler = Sampler {
            times: vec![0.0],
            values: vec![Vec4::ZERO],
            interpolation: Interpolation::Step,
        };
        let anim = |node, sampler_index| Animation {
            name: Some("walk".into()),
            samplers: vec![sampler.clone()],
            channels: vec![Channel {
                node,
                path: Path::Scale,
                sampler: sampler_index,
            }],
        };
        let skin = |joints: Vec<usize>, inverse_bind: Vec<Mat4>| Skin { joints, inverse_bind };
        let deep = MAX_DEPTH + 1;
        let cases = [
            (
                Rig {
                    parents: vec![Some(1), Some(0)],
                    ..two.clone()
                },
                "cycle",
            ),
            (
                Rig {
                    parents: (0..deep).map(|i| i.checked_sub(1)).collect(),
                    rest: vec![Trs::IDENTITY; deep],
                    ..Default::default()
                },
                "levels deep",
            ),
            (
                Rig {
                    parents: vec![None, Some(5)],
                    ..two.clone()
                },
                "parent 5 is not a node",
            ),
            (
                Rig {
                    animations: vec![anim(2, 0)],
                    ..two.clone()
                },
                "animation 0 ('walk') channel 0 targets node 2",
            ),
            (
                Rig {
                    animations: vec![anim(1, 3)],
                    ..two.clone()
                },
                "names sampler 3",
            ),
            (
                Rig {
                    skins: vec![skin(vec![0, 4], vec![Mat4::IDENTITY; 2])],
                    ..two.clone()
                },
                "joint 4 is not a node",
            ),
            (
                Rig {
                    skins: vec![skin(vec![0, 1], vec![Mat4::IDENTITY])],
                    ..two.clone()
                },
                "2 joints but 1 inverse bind",
            ),
            (
                Rig {
                    skins: vec![skin(vec![0], vec![Mat4::NAN])],
                    ..two.clone()
                },
                "not finite",
            ),
            (
                Rig {
                    skins: vec![skin(vec![], vec![])],
                    ..two.clone()
                },
                "no joints",
            ),
            (
                Rig {
                    rest: vec![
                        Trs::IDENTITY,
                        Trs {
                            scale: Vec3::splat(f32::NAN),
                            ..Trs::IDENTITY
                        },
                    ],
                    ..two.clone()
                },
                "node 1's transform is not finite",
            ),
        ];
        for (rig, says) in cases {
            let e = rig.check().unwrap_err();
            assert!(e.contains(says) && !e.contains('\n'), "{says}: {e}");
        }
    }

    /// The generated tube: its triangle count; its rig checks; straight (t = 0, 0.5)
    /// it skins to its bind pose; at a quarter second its top has swayed off the axis
    /// toward -x while its foot stays put, and every ring keeps its radius about the
    /// bent axis within the blend's shrinkage (linear blend skinning pinches joints).
    #[test]
    fn the_skinned_tube_sways() {
        let (mesh, influences, rig) = skinned_tube(24, 40, 8);
        assert_eq!(mesh.indices.len() / 3, 2 * 24 * 40);
        assert_eq!((mesh.positions.len(), influences.len()), (24 * 41, 24 * 41));
        rig.check().unwrap();
        let anim = &rig.animations[0];
        let pose = |t: f32| {
            let m = rig.joint_matrices(&rig.skins[0], &rig.world(Some(anim), t), Mat4::IDENTITY);
            mesh.positions
                .iter()
                .zip(&influences)
                .map(|(p, f)| skin_vertex(*p, Vec3::Z, f.joint_indices(), f.weights, &m).0)
                .collect::<Vec<_>>()
        };
        for t in [0.0, 0.5] {
            for (p, q) in mesh.positions.iter().zip(pose(t)) {
                assert!((*p - q).length() < 1e-5, "t {t}: {p} -> {q}");
            }
        }
        let swayed = pose(0.25);
        let top: Vec3 = swayed[24 * 40..].iter().copied().sum::<Vec3>() / 24.0;
        let foot: Vec3 = swayed[..24].iter().copied().sum::<Vec3>() / 24.0;
        assert!(top.x < -0.3 && foot.length() < 1e-4, "top {top}, foot {foot}");
        for r in 0..=40 {
            let ring = &swayed[24 * r..24 * (r + 1)];
            let centre = ring.iter().copied().sum::<Vec3>() / 24.0;
            for q in ring {
                let d = (*q - centre).length();
                assert!((0.17..=0.2001).contains(&d), "ring {r}: radius {d}");
            }
        }
    }
}
