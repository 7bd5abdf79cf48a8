//! Rust/GLSL shared structs: member names and byte offsets in the compiled SPIR-V
//! (std430/std140 as glslang laid them out) equal the `#[repr(C)]` Rust offsets.

use speculum::gpu_types::{FrameUniforms, GpuMaterial, GpuVertex, Hit, Ray, TraversalNode, TraversalTri};
use speculum::passes::compose::ComposePush;
use speculum::shaders;
use speculum::vk::spirv::{reflect, words, Reflection};
use speculum::vk::Shader;
use std::mem::{offset_of, size_of};

fn reflected((name, spv): Shader) -> Reflection {
    reflect(name, &words(name, spv).unwrap()).unwrap()
}

macro_rules! rust_layout {
    ($ty:ty { $($field:ident),* $(,)? }) => {
        vec![$((stringify!($field).to_string(), offset_of!($ty, $field) as u32)),*]
    };
}

fn check(r: &Reflection, glsl_name: &str, rust: Vec<(String, u32)>) {
    let glsl = r
        .structs
        .get(glsl_name)
        .unwrap_or_else(|| panic!("struct {glsl_name} not found in SPIR-V"));
    assert_eq!(
        glsl, &rust,
        "layout of {glsl_name} differs between GLSL (left) and Rust (right)"
    );
}

/// `Vertex` (std430 storage buffer): offsets and array stride.
#[test]
fn vertex_layout_matches_glsl() {
    let r = reflected(shaders::GBUFFER_VERT);
    check(
        &r,
        "Vertex",
        rust_layout!(GpuVertex {
            position,
            material,
            normal,
            object
        }),
    );
    assert_eq!(r.array_strides["Vertex"] as usize, size_of::<GpuVertex>());
}

/// `Material` (std430 storage buffer): offsets and array stride.
#[test]
fn material_layout_matches_glsl() {
    let r = reflected(shaders::GBUFFER_FRAG);
    check(
        &r,
        "Material",
        rust_layout!(GpuMaterial {
            albedo,
            roughness,
            reflectivity,
            texture_layer,
            metallic,
            roughness_layer
        }),
    );
    assert_eq!(r.array_strides["Material"] as usize, size_of::<GpuMaterial>());
}

/// `Influence` (std430 storage buffer, `sim.skin`): offsets and array stride.
#[test]
fn influence_layout_matches_glsl() {
    use speculum::gpu_types::GpuInfluence;
    let r = reflected(shaders::SIM_SKIN_COMP);
    check(&r, "Influence", rust_layout!(GpuInfluence { joints, pad, weights }));
    assert_eq!(r.array_strides["Influence"] as usize, size_of::<GpuInfluence>());
}

/// The tracer's structs (std430): the BVH's `TraversalNode` and `TraversalTri` as the
/// fit writes them and `rt.trace` reads them, `Ray` and `Hit` as `rt.trace` reads and
/// writes them: offsets and strides.
#[test]
fn tracer_layouts_match_glsl() {
    let bvh = [
        (
            "TraversalNode",
            rust_layout!(TraversalNode {
                lo0,
                child0,
                hi0,
                child1,
                lo1,
                parent,
                hi1,
                unused
            }),
            size_of::<TraversalNode>(),
        ),
        (
            "TraversalTri",
            rust_layout!(TraversalTri {
                a,
                id,
                b,
                parent,
                c,
                _pad0
            }),
            size_of::<TraversalTri>(),
        ),
    ];
    // The traversal reads these as texels (traverse.glsl's fetch_node, fetch_triangle:
    // the same words in the same order); tests/suite/trace.rs checks what it reads.
    for shader in [shaders::LBVH_FIT_COMP, shaders::LBVH_REFIT_LEAVES_COMP] {
        let r = reflected(shader);
        for (name, layout, stride) in &bvh {
            check(&r, name, layout.clone());
            assert_eq!(r.array_strides[*name] as usize, *stride, "{name}");
        }
    }
    let r = reflected(shaders::RT_TRACE_COMP);
    check(
        &r,
        "Ray",
        rust_layout!(Ray {
            origin,
            tmin,
            dir,
            tmax
        }),
    );
    check(&r, "Hit", rust_layout!(Hit { t, prim, u, v }));
    assert_eq!(r.array_strides["Ray"] as usize, size_of::<Ray>());
    assert_eq!(r.array_strides["Hit"] as usize, size_of::<Hit>());
}

/// `FrameUniforms` (std140 uniform block) in every shader that declares it.
#[test]
fn frame_uniforms_layout_matches_glsl() {
    let rust = rust_layout!(FrameUniforms {
        view_proj,
        inv_view_proj,
        light_view_proj,
        view,
        proj,
        camera_pos,
        light_dir,
        light_color,
        sky_zenith,
        sky_horizon,
        resolution,
        shadow_map_size,
        pcf_radius,
        shadow_bias,
        exposure,
        ambient,
        shadow_band,
        frame_index,
        reflection_rays,
        mirror_roughness,
        rough_roughness,
        sample_stream,
        glossy,
        _pad0,
        _pad1,
    });
    for shader in [
        shaders::GBUFFER_VERT,
        shaders::LIGHT_DIRECT_COMP,
        shaders::SHADOW_MAP_VERT,
        shaders::SHADOW_CLASSIFY_COMP,
        shaders::SHADOW_TRACE_COMP,
    ] {
        check(&reflected(shader), "FrameUniforms", rust.clone());
    }
}

/// `ComposePush` (push constants).
#[test]
fn compose_push_layout_matches_glsl() {
    let r = reflected(shaders::COMPOSE_COMP);
    check(
        &r,
        "ComposePush",
        rust_layout!(ComposePush {
            size,
            exposure,
            mode,
            reflective_min
        }),
    );
}

/// The push-constant block's size is reflected (pipelines check their push type
/// against it): 20 B for compose, 12 B for the fit's triangle count, key width and order
/// switch, 4 B
/// for the refit's triangle count and for light.direct's visibility switch.
#[test]
fn push_block_sizes_are_reflected() {
    assert_eq!(
        reflected(shaders::COMPOSE_COMP).push_size as usize,
        size_of::<ComposePush>()
    );
    assert_eq!(reflected(shaders::LBVH_FIT_COMP).push_size, 12);
    assert_eq!(reflected(shaders::LBVH_REFIT_LEAVES_COMP).push_size, 4);
    assert_eq!(
        reflected(shaders::REFLECT_BLUR_COMP).push_size,
        16,
        "ivec2 axis, int radius, int band"
    );
    assert_eq!(reflected(shaders::LIGHT_DIRECT_COMP).push_size, 4);
}

/// The reflection itself: a layout mismatch is detected (the check can fail).
#[test]
fn layout_check_detects_a_mismatch() {
    let r = reflected(shaders::GBUFFER_FRAG);
    let wrong = vec![("albedo".to_string(), 0), ("roughness".to_string(), 16)];
    let result = std::panic::catch_unwind(|| check(&r, "Material", wrong));
    assert!(result.is_err());
}

/// Descriptor reflection sees light.direct's bindings in order with their kinds and
/// the names they are bound by.
#[test]
fn light_direct_bindings_are_reflected() {
    use ash::vk::DescriptorType as D;
    let r = reflected(shaders::LIGHT_DIRECT_COMP);
    let got: Vec<_> = r.bindings.iter().map(|b| (b.slot, b.kind, b.name.as_str())).collect();
    assert_eq!(
        got,
        [
            (0, D::UNIFORM_BUFFER, "frame"),
            (1, D::COMBINED_IMAGE_SAMPLER, "gb_depth"),
            (2, D::COMBINED_IMAGE_SAMPLER, "gb_normal"),
            (3, D::COMBINED_IMAGE_SAMPLER, "gb_albedo"),
            (4, D::COMBINED_IMAGE_SAMPLER, "gb_material"),
            (5, D::COMBINED_IMAGE_SAMPLER, "shadow_map"),
            (6, D::STORAGE_IMAGE, "lit"),
            (7, D::COMBINED_IMAGE_SAMPLER, "gb_motion"),
            (8, D::STORAGE_IMAGE, "visibility"),
        ]
    );
    assert_eq!(
        r.local_size,
        Some([speculum::shader_defines::WG_2D, speculum::shader_defines::WG_2D, 1])
    );
}

/// rt.trace's BVH nodes and triangles are uniform texel buffers (`utextureBuffer`), not
/// sampled images: an image of dim Buffer reflects as its own kind.
#[test]
fn rt_trace_reads_the_bvh_as_texel_buffers() {
    use ash::vk::DescriptorType as D;
    let r = reflected(shaders::RT_TRACE_COMP);
    // The vertices and indices (3, 4, 6, 7) serve only hit attributes: unused here.
    let got: Vec<_> = r.bindings.iter().map(|b| (b.slot, b.kind, b.name.as_str())).collect();
    assert_eq!(
        got,
        [
            (0, D::STORAGE_BUFFER, "rays"),
            (1, D::STORAGE_BUFFER, "hits"),
            (2, D::UNIFORM_TEXEL_BUFFER, "s_nodes"),
            (5, D::UNIFORM_TEXEL_BUFFER, "d_nodes"),
            (8, D::UNIFORM_TEXEL_BUFFER, "s_tris"),
            (9, D::UNIFORM_TEXEL_BUFFER, "d_tris")
        ]
    );
}

/// Every binding of every shader has a name to be bound by, one binding a name (the
/// reflection refuses a module otherwise); an anonymous block is named by its block in
/// snake_case.
#[test]
fn every_binding_has_a_name() {
    assert!(shaders::ALL.len() >= 40, "{} shaders", shaders::ALL.len());
    for &shader in shaders::ALL {
        let r = reflected(shader);
        for b in &r.bindings {
            let ok = !b.name.is_empty()
                && b.name
                    .chars()
                    .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '_');
            assert!(ok, "{}: binding {} is named {:?}", shader.0, b.slot, b.name);
        }
    }
    // `buffer TileCounts { .. };` in compact_count.comp.
    let names: Vec<_> = reflected(shaders::COMPACT_COUNT_COMP)
        .bindings
        .into_iter()
        .map(|b| b.name)
        .collect();
    assert_eq!(names, ["mask", "tile_counts"]);
    assert_eq!(speculum::vk::spirv::snake_case("TileCounts"), "tile_counts");
    assert_eq!(speculum::vk::spirv::snake_case("lit"), "lit");
}
