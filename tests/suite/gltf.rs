//! The glTF showcase (`assets/models/showcase.glb`, made by `tests/common/showcase.rs`):
//! the shipped file is what the generator makes; its node hierarchy places the gold
//! sphere where the transforms say, seen in the G-buffer; the checker texture is
//! sampled per texel (its squares alternate along a row of pixels).

use crate::common;

use crate::common::{pixel_of, showcase};
use glam::{IVec2, Vec3};
use speculum::scene::{load_with, Floor};
use speculum::settings::Mode;
use speculum::{Renderer, Settings};

const SHOWCASE: &str = "assets/models/showcase.glb";

#[test]
fn shipped_showcase_is_the_generated_one() {
    let shipped = std::fs::read(SHOWCASE).unwrap();
    assert!(
        shipped == showcase::glb(),
        "{SHOWCASE} is stale: run `cargo run --example showcase`"
    );
}

#[test]
fn showcase_nodes_and_checker_texture_in_the_gbuffer() {
    let scene = load_with(SHOWCASE, Floor::Mirror).unwrap();
    let id = |name: &str| scene.materials.iter().position(|m| m.name == name).unwrap() as u32;
    let (gold, checker) = (id("gold"), id("checker"));
    // Hierarchy: showcase → metals (translate) → gold (translate, scale 0.45).
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for v in scene.vertices.iter().filter(|v| v.material == gold) {
        let p = Vec3::from(v.position);
        (lo, hi) = (lo.min(p), hi.max(p));
        let r = (p - showcase::GOLD_CENTER).length();
        assert!((r - showcase::GOLD_RADIUS).abs() < 1e-5, "gold vertex at radius {r}");
    }
    assert!((0.5 * (lo + hi) - showcase::GOLD_CENTER).length() < 1e-3, "{lo} {hi}");
    assert_eq!(scene.textures.len(), 2, "the PNG checker and the JPEG bricks");

    let ctx = common::context();
    let settings = Settings {
        width: 320,
        height: 180,
        mode: Mode::Raster,
        ..Default::default()
    };
    let mut r = Renderer::new(&ctx, &scene, &settings).unwrap();
    r.render_frame().unwrap();
    let t = &r.lighting.gbuffer.out;
    let depth: Vec<f32> = bytemuck::pod_collect_to_vec(&r.read_target(&t.depth).unwrap());
    let albedo = r.read_target(&t.albedo).unwrap();
    let material: Vec<u32> = bytemuck::pod_collect_to_vec(&r.read_target(&t.material).unwrap());
    let frame = *r.uniforms();
    let w = settings.width as i32;
    let at = |p: IVec2| (p.y * w + p.x) as usize;
    // The gold sphere's centre projects onto the gold sphere, whose surface is there.
    let p = pixel_of(&frame, showcase::GOLD_CENTER);
    assert_eq!(material[at(p)], gold, "pixel {p}");
    let hit = speculum::cpu_ref::shading::world_from_depth(&frame, p, depth[at(p)]);
    let r_hit = (hit - showcase::GOLD_CENTER).length();
    assert!(
        (r_hit - showcase::GOLD_RADIUS).abs() < 0.01,
        "G-buffer point {hit} at {r_hit} from the centre"
    );
    // A row across the backdrop above the objects: the two checker colours alternate.
    let y = pixel_of(&frame, Vec3::new(0.0, 1.55, -1.0)).y;
    let linear = |c: [u8; 3]| c.map(speculum::scene::texture::srgb_to_linear);
    let (a, b) = (linear(showcase::CHECKER_A), linear(showcase::CHECKER_B));
    let mut squares = Vec::new();
    for x in 0..w {
        let i = at(IVec2::new(x, y));
        if material[i] != checker {
            continue;
        }
        let got = speculum::cpu_ref::albedo_texel(&albedo[4 * i..4 * i + 4]).0.to_array();
        let dist = |want: [f32; 3]| (0..3).map(|c| (got[c] - want[c]).abs()).fold(0.0, f32::max);
        // Texels blend only across a square's edge; elsewhere the colour is one of two.
        let which = if dist(a) < 0.02 {
            'a'
        } else if dist(b) < 0.02 {
            'b'
        } else {
            continue;
        };
        if squares.last() != Some(&which) {
            squares.push(which);
        }
    }
    assert!(
        squares.len() >= (showcase::CHECKER_SQUARES - 1) as usize,
        "row {y}: squares {squares:?}"
    );
}

/// The gold metal tints its reflection: on the gold sphere, the blue/red ratio of the
/// frame (linear light) is well below that of the reflection the passes traced there
/// (the white box, the sky, the backdrop), far more than on the silver sphere, the
/// control; in `rt` and in `hybrid`.
#[test]
fn gold_tints_its_reflection_and_silver_does_not() {
    let scene = load_with(SHOWCASE, Floor::Mirror).unwrap();
    let id = |name: &str| scene.materials.iter().position(|m| m.name == name).unwrap() as u32;
    let ctx = common::context();
    for mode in [Mode::Rt, Mode::Hybrid] {
        let settings = Settings {
            width: 320,
            height: 180,
            mode,
            ..Default::default()
        };
        let mut r = Renderer::new(&ctx, &scene, &settings).unwrap();
        r.render_frame().unwrap();
        let material: Vec<u32> =
            bytemuck::pod_collect_to_vec(&r.read_target(&r.lighting.gbuffer.out.material).unwrap());
        let reflection: Vec<[f32; 4]> =
            bytemuck::pod_collect_to_vec(&r.reflections.merge.out.read(ash::vk::ImageLayout::GENERAL).unwrap());
        let out = r.read_output().unwrap();
        let linear = |c: u8| speculum::scene::texture::srgb_to_linear(c);
        // Median over a material's pixels of (frame b/r) / (reflection b/r).
        let tint = |m: u32| {
            let mut ratios: Vec<f32> = (0..material.len())
                .filter(|&i| material[i] == m && reflection[i][0] > 0.05 && reflection[i][2] > 0.05)
                .map(|i| {
                    let frame = linear(out[4 * i + 2]) / linear(out[4 * i]).max(1e-4);
                    frame / (reflection[i][2] / reflection[i][0])
                })
                .collect();
            ratios.sort_by(f32::total_cmp);
            assert!(ratios.len() > 300, "{mode:?}: {} pixels", ratios.len());
            ratios[ratios.len() / 2]
        };
        let (gold, silver) = (tint(id("gold")), tint(id("silver")));
        // Gold's F0 has blue/red 0.34, silver's 0.94: gold must tint far more than the
        // control, which loses some blue/red to the tonemap (bright blue sky channels
        // compress most) and its warm highlight (lavapipe: gold 0.35, silver 0.77).
        assert!(
            gold < 0.6 * silver && silver > 0.65,
            "{mode:?}: blue/red kept at {gold} of the reflection's on gold, {silver} on silver"
        );
    }
}
