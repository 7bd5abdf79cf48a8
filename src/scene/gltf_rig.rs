//! A glTF file's rig (`animation::Rig`): its nodes' hierarchy and rest transforms, its
//! animations (translation, rotation and scale channels; morph-target weights are
//! skipped with a warning) and its skins, read through the `gltf` crate and checked
//! (`Rig::check`), with the skinned primitives' joint attributes: one set of four
//! influences (`JOINTS_0`/`WEIGHTS_0`; a second set is refused), every joint index
//! within its skin. Called inside `gltf::load`'s guard, after its index checks.

use super::animation::{Animation, Channel, Interpolation, Path, Rig, Sampler, Skin, Trs};
use glam::{Mat4, Quat, Vec3, Vec4};

/// The rig of `doc`, or `None` when it has neither animations nor skins; what it
/// skips goes to `warnings`.
pub fn read(
    doc: &gltf::Document,
    buffers: &[gltf::buffer::Data],
    warnings: &mut Vec<String>,
) -> Result<Option<Rig>, String> {
    if doc.animations().next().is_none() && doc.skins().next().is_none() {
        return Ok(None);
    }
    let get = |b: gltf::Buffer<'_>| buffers.get(b.index()).map(|d| &d.0[..]);
    let n = doc.nodes().count();
    let mut rig = Rig {
        parents: vec![None; n],
        rest: vec![Trs::IDENTITY; n],
        ..Default::default()
    };
    for node in doc.nodes() {
        for c in node.children() {
            rig.parents[c.index()] = Some(node.index());
        }
        let (t, r, s) = node.transform().decomposed();
        rig.rest[node.index()] = Trs {
            translation: Vec3::from(t),
            rotation: Quat::from_array(r),
            scale: Vec3::from(s),
        };
    }
    let mut morphs = 0;
    for anim in doc.animations() {
        let mut a = Animation {
            name: anim.name().map(str::to_string),
            samplers: Vec::new(),
            channels: Vec::new(),
        };
        for (c, channel) in anim.channels().enumerate() {
            let at = || format!("animation {} channel {c}", anim.index());
            let reader = channel.reader(get);
            let times: Vec<f32> = reader
                .read_inputs()
                .ok_or_else(|| format!("{}: its key times cannot be read", at()))?
                .collect();
            use gltf::animation::util::ReadOutputs as O;
            let (path, values): (Path, Vec<Vec4>) = match reader
                .read_outputs()
                .ok_or_else(|| format!("{}: its values cannot be read", at()))?
            {
                O::Translations(v) => (Path::Translation, v.map(|x| Vec3::from(x).extend(0.0)).collect()),
                O::Scales(v) => (Path::Scale, v.map(|x| Vec3::from(x).extend(0.0)).collect()),
                O::Rotations(v) => (Path::Rotation, v.into_f32().map(Vec4::from).collect()),
                O::MorphTargetWeights(_) => {
                    morphs += 1;
                    continue;
                }
            };
            use gltf::animation::Interpolation as I;
            let interpolation = match channel.sampler().interpolation() {
                I::Step => Interpolation::Step,
                I::Linear => Interpolation::Linear,
                I::CubicSpline => Interpolation::CubicSpline,
            };
            a.channels.push(Channel {
                node: channel.target().node().index(),
                path,
                sampler: a.samplers.len(),
            });
            a.samplers.push(Sampler {
                times,
                values,
                interpolation,
            });
        }
        rig.animations.push(a);
    }
    if morphs > 0 {
        warnings.push(format!(
            "{morphs} morph-target weight channel(s) ignored: Speculum plays node and skin animation only"
        ));
    }
    for skin in doc.skins() {
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        let inverse_bind = match skin.reader(get).read_inverse_bind_matrices() {
            Some(m) => m.map(|c| Mat4::from_cols_array_2d(&c)).collect(),
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        rig.skins.push(Skin { joints, inverse_bind });
    }
    rig.check()?;
    check_skinned_primitives(doc, &rig, buffers)?;
    Ok(Some(rig))
}

/// Every primitive of a skinned node has one set of influences whose joint indices
/// lie within its skin, and weights that are finite and not negative.
fn check_skinned_primitives(doc: &gltf::Document, rig: &Rig, buffers: &[gltf::buffer::Data]) -> Result<(), String> {
    for node in doc.nodes() {
        let (Some(mesh), Some(skin)) = (node.mesh(), node.skin()) else {
            continue;
        };
        let joints = rig.skins[skin.index()].joints.len();
        for (p, prim) in mesh.primitives().enumerate() {
            let at = format!("mesh {} primitive {p}", mesh.index());
            let second = prim
                .attributes()
                .any(|(s, _)| matches!(s, gltf::Semantic::Joints(1) | gltf::Semantic::Weights(1)));
            if second {
                return Err(format!(
                    "{at}: more than four joint influences per vertex (JOINTS_1/WEIGHTS_1) are not supported"
                ));
            }
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let (Some(js), Some(ws)) = (reader.read_joints(0), reader.read_weights(0)) else {
                return Err(format!("{at}: a skinned primitive without JOINTS_0 and WEIGHTS_0"));
            };
            let positions = reader.read_positions().map_or(0, |p| p.len());
            let (js, ws): (Vec<[u16; 4]>, Vec<[f32; 4]>) = (js.into_u16().collect(), ws.into_f32().collect());
            if js.len() != positions || ws.len() != positions {
                return Err(format!(
                    "{at}: {} joint sets and {} weight sets for {positions} positions",
                    js.len(),
                    ws.len()
                ));
            }
            for (v, j) in js.iter().enumerate() {
                if let Some(&bad) = j.iter().find(|&&j| j as usize >= joints) {
                    return Err(format!("{at} vertex {v}: joint {bad}, but its skin has {joints}"));
                }
            }
            for (v, w) in ws.iter().enumerate() {
                if w.iter().any(|w| !w.is_finite() || *w < 0.0) {
                    return Err(format!(
                        "{at} vertex {v}: weights {w:?} are not finite and non-negative"
                    ));
                }
            }
        }
    }
    Ok(())
}

/// `gltf::check_indices` for the animations and skins: channel targets and samplers, sampler
/// and inverse-bind accessors, joints and skeletons, nodes' skins.
pub(super) fn check_indices(
    j: &gltf::json::Root,
    within: impl Fn(String, usize, usize, &str) -> std::result::Result<(), String>,
) -> std::result::Result<(), String> {
    let (nodes, accessors) = (j.nodes.len(), j.accessors.len());
    for (ai, a) in j.animations.iter().enumerate() {
        for (ci, c) in a.channels.iter().enumerate() {
            let at = format!("animation {ai} channel {ci}");
            within(format!("{at}'s target"), c.target.node.value(), nodes, "node")?;
            within(at, c.sampler.value(), a.samplers.len(), "sampler")?;
        }
        for (si, s) in a.samplers.iter().enumerate() {
            let at = format!("animation {ai} sampler {si}");
            within(format!("{at}'s input"), s.input.value(), accessors, "accessor")?;
            within(format!("{at}'s output"), s.output.value(), accessors, "accessor")?;
        }
    }
    for (si, s) in j.skins.iter().enumerate() {
        for jn in &s.joints {
            within(format!("skin {si}'s joints"), jn.value(), nodes, "node")?;
        }
        if let Some(m) = &s.inverse_bind_matrices {
            within(
                format!("skin {si}'s inverse bind matrices"),
                m.value(),
                accessors,
                "accessor",
            )?;
        }
        if let Some(k) = &s.skeleton {
            within(format!("skin {si}'s skeleton"), k.value(), nodes, "node")?;
        }
    }
    for (ni, n) in j.nodes.iter().enumerate() {
        if let Some(s) = &n.skin {
            within(format!("node {ni}"), s.value(), j.skins.len(), "skin")?;
        }
    }
    Ok(())
}
