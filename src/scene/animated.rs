//! An animated model (`Animated`): the parts of a glTF file that its animations or its
//! skins move, kept in their own spaces with a joint palette, and the clock that plays
//! one of its animations. Skinned primitives are bound to their skin's joints; a mesh
//! that a node animation moves rigidly (its node, or an ancestor, is a channel's
//! target) is a skin of one joint, its node, weight 1: one pass (`sim.skin`) and one
//! refit serve both, where the rigid path would need an instance per node. The rest of
//! the file is static geometry.
//!
//! Time: a scene steps `sim_dt` seconds a frame; the animation's time at `elapsed`
//! seconds after the start is `start + speed * elapsed`, wrapped into its duration
//! when it loops and held at its ends when it does not.

use super::animation::{skin_vertex, Rig};
use super::TriMesh;
use crate::gpu_types::{GpuInfluence, GpuVertex};
use glam::{Mat4, Vec2, Vec3};
use std::collections::HashMap;

/// Joints in one model's palette at most: `GpuInfluence` holds 16-bit joint indices.
pub const MAX_JOINTS: usize = 1 << 16;

/// Which animation of a model plays: by index or by name (a scene file's `animation`,
/// the command line's `--animation`).
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(untagged)]
pub enum Choice {
    Index(u32),
    Name(String),
}

impl std::str::FromStr for Choice {
    type Err = std::convert::Infallible;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(s.parse().map_or_else(|_| Choice::Name(s.to_string()), Choice::Index))
    }
}

/// A model's animated parts and how they play.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Animated {
    pub rig: Rig,
    /// Bind-pose vertices in their mesh's space (`object` 0), with their materials.
    pub vertices: Vec<GpuVertex>,
    pub uvs: Vec<[f32; 2]>,
    /// Triangles, indexing `vertices`.
    pub indices: Vec<u32>,
    /// Each vertex's joints (indices into `joints`) and weights.
    pub influences: Vec<GpuInfluence>,
    /// The joint palette: each joint's node and the matrix from the vertices' space to
    /// the node's (a skin joint's inverse bind matrix; the identity for a rigid mesh).
    pub joints: Vec<(usize, Mat4)>,
    /// Where the model stands in the scene (a scene file's instance transform).
    pub placement: Mat4,
    /// The animation that plays (index into `rig.animations`).
    pub playing: usize,
    /// Seconds of animation per second of scene time (may be negative or zero).
    pub speed: f32,
    pub looping: bool,
    /// The animation's time at the first frame, seconds.
    pub start: f32,
    /// (skin, or `None` for a rigid node's own joint; node) → first palette entry.
    palette_of: HashMap<(Option<usize>, usize), u16>,
}

impl Animated {
    /// An empty model over `rig` (which has at least one animation), playing its first
    /// animation from its start, looping, at speed 1.
    pub fn new(rig: Rig) -> Self {
        Self {
            rig,
            placement: Mat4::IDENTITY,
            speed: 1.0,
            looping: true,
            ..Default::default()
        }
    }

    /// The palette entries of skin `skin` (its joints, added on first use): the first;
    /// `None` when they would not fit `MAX_JOINTS`.
    pub fn skin_joints(&mut self, skin: usize) -> Option<u16> {
        let s = &self.rig.skins[skin];
        let new: Vec<(usize, Mat4)> = s.joints.iter().copied().zip(s.inverse_bind.iter().copied()).collect();
        self.palette((Some(skin), 0), new)
    }

    /// The palette entry that moves a mesh of node `node` rigidly (added on first use);
    /// `None` when it would not fit `MAX_JOINTS`.
    pub fn node_joint(&mut self, node: usize) -> Option<u16> {
        self.palette((None, node), vec![(node, Mat4::IDENTITY)])
    }

    fn palette(&mut self, key: (Option<usize>, usize), new: Vec<(usize, Mat4)>) -> Option<u16> {
        if let Some(&first) = self.palette_of.get(&key) {
            return Some(first);
        }
        if self.joints.len() + new.len() > MAX_JOINTS {
            return None;
        }
        let first = self.joints.len() as u16;
        self.joints.extend(new);
        self.palette_of.insert(key, first);
        Some(first)
    }

    /// Adds `mesh` (in its own space) of material `material`, vertex `i` influenced by
    /// `influences[i]`.
    pub fn push(&mut self, mesh: &TriMesh, material: u32, influences: &[GpuInfluence]) {
        let base = self.vertices.len() as u32;
        self.vertices
            .extend(mesh.positions.iter().zip(&mesh.normals).map(|(p, n)| GpuVertex {
                position: p.to_array(),
                material,
                normal: n.to_array(),
                object: 0,
            }));
        let uv = |i: usize| mesh.uvs.get(i).copied().unwrap_or(Vec2::ZERO).to_array();
        self.uvs.extend((0..mesh.positions.len()).map(uv));
        self.indices.extend(mesh.indices.iter().map(|i| base + i));
        self.influences.extend_from_slice(influences);
    }

    /// Plays `choice` (an index, or a name of `rig.animations`); names what there is
    /// when it is not one.
    pub fn select(&mut self, choice: &Choice) -> Result<(), String> {
        let animations = &self.rig.animations;
        let found = match choice {
            Choice::Index(i) => Some(*i as usize).filter(|&i| i < animations.len()),
            Choice::Name(name) => animations.iter().position(|a| a.name.as_deref() == Some(name)),
        };
        let Some(index) = found else {
            let names: Vec<String> = (self.rig.animations.iter().enumerate())
                .map(|(i, a)| a.name.as_deref().map_or(format!("{i}"), |n| format!("{i} '{n}'")))
                .collect();
            let what = match choice {
                Choice::Index(i) => format!("animation {i}"),
                Choice::Name(n) => format!("animation named '{n}'"),
            };
            return Err(format!("the model has no {what} (it has: {})", names.join(", ")));
        };
        self.playing = index;
        Ok(())
    }

    /// The playing animation's length, seconds.
    pub fn duration(&self) -> f32 {
        self.rig.animations[self.playing].duration()
    }

    /// The animation's time `elapsed` seconds after the first frame.
    pub fn time(&self, elapsed: f64) -> f32 {
        let t = self.start as f64 + self.speed as f64 * elapsed;
        let d = self.duration() as f64;
        let t = if d <= 0.0 {
            0.0
        } else if self.looping {
            t.rem_euclid(d)
        } else {
            t.clamp(0.0, d)
        };
        t as f32
    }

    /// The palette's matrices at animation time `t`, in the scene moved by `-origin`.
    pub fn matrices(&self, t: f32, origin: Vec3) -> Vec<Mat4> {
        let world = self.rig.world(Some(&self.rig.animations[self.playing]), t);
        let to_scene = Mat4::from_translation(-origin) * self.placement;
        self.joints
            .iter()
            .map(|&(node, m)| to_scene * world[node] * m)
            .collect()
    }

    /// The vertices posed at time `t` in the scene (moved by `-origin`): the CPU
    /// reference of `sim.skin` over this model.
    pub fn posed(&self, t: f32, origin: Vec3) -> Vec<GpuVertex> {
        let m = self.matrices(t, origin);
        self.vertices
            .iter()
            .zip(&self.influences)
            .map(|(v, f)| {
                let (p, n) = skin_vertex(
                    Vec3::from(v.position),
                    Vec3::from(v.normal),
                    f.joint_indices(),
                    f.weights,
                    &m,
                );
                GpuVertex {
                    position: p.to_array(),
                    normal: n.to_array(),
                    ..*v
                }
            })
            .collect()
    }

    /// Why the model cannot play, in one line: a rig that fails `Rig::check`, no
    /// animation to play, a speed or start that is not finite, a palette of more than
    /// `MAX_JOINTS`, an influence per vertex missing, a joint past the palette, weights
    /// that are not finite and non-negative, a triangle past the vertices, a placement
    /// that is not finite.
    pub fn check(&self) -> Result<(), String> {
        self.rig.check()?;
        if self.playing >= self.rig.animations.len() {
            return Err(format!(
                "animation {} does not exist (there are {})",
                self.playing,
                self.rig.animations.len()
            ));
        }
        if !(self.speed.is_finite() && self.start.is_finite() && self.placement.is_finite()) {
            return Err("the animation's speed, start time and placement must be finite".into());
        }
        if self.joints.len() > MAX_JOINTS {
            return Err(format!("{} joints (at most {MAX_JOINTS})", self.joints.len()));
        }
        if self.influences.len() != self.vertices.len() || self.uvs.len() != self.vertices.len() {
            return Err(format!(
                "{} vertices but {} influences and {} texture coordinates",
                self.vertices.len(),
                self.influences.len(),
                self.uvs.len()
            ));
        }
        for (i, f) in self.influences.iter().enumerate() {
            if let Some(j) = f.joint_indices().iter().find(|&&j| j as usize >= self.joints.len()) {
                return Err(format!("vertex {i}: joint {j}, but there are {}", self.joints.len()));
            }
            if f.weights.iter().any(|w| !w.is_finite() || *w < 0.0) {
                return Err(format!("vertex {i}: weights {:?} must be finite and >= 0", f.weights));
            }
        }
        let finite = |v: &GpuVertex| v.position.iter().chain(&v.normal).all(|c| c.is_finite());
        if let Some(i) = self.vertices.iter().position(|v| !finite(v)) {
            return Err(format!("vertex {i} is not finite"));
        }
        if let Some(&i) = self.indices.iter().find(|&&i| i as usize >= self.vertices.len()) {
            return Err(format!("index {i} is past the {} vertices", self.vertices.len()));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::animation::skinned_tube;

    fn tube() -> Animated {
        let (mesh, influences, rig) = skinned_tube(8, 6, 3);
        let mut a = Animated::new(rig);
        let base = a.skin_joints(0);
        assert_eq!(
            (base, a.skin_joints(0)),
            (Some(0), Some(0)),
            "a skin's joints are added once"
        );
        assert_eq!(a.node_joint(7), Some(3));
        assert_eq!(a.node_joint(7), Some(3));
        a.joints.pop();
        a.push(&mesh, 2, &influences);
        a
    }

    /// Looping wraps the time into the animation, not looping holds its ends, and the
    /// speed and start scale and shift it.
    #[test]
    fn the_clock_loops_or_holds() {
        let mut a = tube();
        assert_eq!(a.duration(), 1.0);
        assert!((a.time(2.25) - 0.25).abs() < 1e-6);
        a.looping = false;
        assert_eq!(a.time(2.25), 1.0);
        (a.start, a.speed) = (0.5, -1.0);
        assert_eq!(a.time(2.0), 0.0);
        a.looping = true;
        assert!((a.time(0.75) - 0.75).abs() < 1e-6, "{}", a.time(0.75));
    }

    /// Names and indices select; an unknown one lists what there is.
    #[test]
    fn animations_are_chosen_by_index_or_name() {
        let mut a = tube();
        assert_eq!(a.select(&"sway".parse().unwrap()), Ok(()));
        assert_eq!(a.select(&Choice::Index(0)), Ok(()));
        let e = a.select(&"walk".parse().unwrap()).unwrap_err();
        assert!(e.contains("no animation named 'walk'") && e.contains("0 'sway'"), "{e}");
        let e = a.select(&Choice::Index(3)).unwrap_err();
        assert!(e.contains("animation 3") && e.contains("0 'sway'"), "{e}");
    }

    /// The posed vertices are the bind pose at time 0 and move off it at a quarter
    /// second (the sway's peak), placed and shifted by the origin.
    #[test]
    fn posing_follows_the_clock_and_placement() {
        let mut a = tube();
        a.check().unwrap();
        let bind: Vec<Vec3> = a.vertices.iter().map(|v| Vec3::from(v.position)).collect();
        let at0 = a.posed(0.0, Vec3::ZERO);
        for (v, b) in at0.iter().zip(&bind) {
            assert!((Vec3::from(v.position) - *b).length() < 1e-5);
        }
        let peak = a.posed(0.25, Vec3::ZERO);
        let top = peak.last().unwrap().position;
        assert!(Vec3::from(top).x.abs() > 0.1, "{top:?}");
        a.placement = Mat4::from_translation(Vec3::new(5.0, 0.0, 0.0));
        let moved = a.posed(0.25, Vec3::new(1.0, 0.0, 0.0));
        let d = Vec3::from(moved.last().unwrap().position) - Vec3::from(top);
        assert!((d - Vec3::new(4.0, 0.0, 0.0)).length() < 1e-5, "{d}");
    }

    /// Each broken part is named.
    #[test]
    fn broken_models_are_refused_in_one_line() {
        let mut a = tube();
        a.influences[5] = GpuInfluence::new([0, 9, 0, 0], [0.5, 0.5, 0.0, 0.0]);
        assert!(a.check().unwrap_err().contains("vertex 5: joint 9"));
        let mut a = tube();
        a.influences[2].weights[1] = f32::NAN;
        assert!(a.check().unwrap_err().contains("vertex 2: weights"));
        let mut a = tube();
        a.speed = f32::INFINITY;
        assert!(a.check().unwrap_err().contains("finite"));
        let mut a = tube();
        a.indices[4] = a.vertices.len() as u32;
        assert!(a.check().unwrap_err().contains("past the"));
        let mut a = tube();
        a.influences.pop();
        assert!(a.check().unwrap_err().contains("influences"));
    }
}
