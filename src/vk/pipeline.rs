//! Compute and graphics pipelines with push descriptors; the set layout is reflected
//! from SPIR-V (niagara-style). Resources are bound by name (`Bind`): each binding of
//! the shader takes the resource given under its name (`spirv::Binding`), whatever the
//! order they are given in, and its kind is checked against the shader; a binding left
//! without its resource fails the bind. A pipeline is typed by
//! its push-constant struct `P`: the block size reflected from SPIR-V must equal
//! `size_of::<P>()` when it is created, and `dispatch`/`bind` accept only a `P`.
//! `dispatch` is the one entry point of a compute pass: bind, push, dispatch.

use super::buffer::Buffer;
use super::context::Context;
use super::image::{Image, Sampler};
use super::spirv::{self, Binding, Reflection};
use crate::error::{Error, Result, VkContext};
use ash::vk;
use bytemuck::Pod;
use std::any::TypeId;
use std::sync::Arc;

/// How many workgroups a dispatch runs.
#[derive(Clone, Copy)]
pub enum Groups<'a> {
    /// Exactly these workgroup counts.
    Exact([u32; 3]),
    /// Enough workgroups to cover this many invocations per axis (the shader
    /// bounds-checks the rest).
    Cover([u32; 3]),
    /// A `VkDispatchIndirectCommand` at the start of this buffer, written on the GPU.
    Indirect(&'a Buffer),
    /// A `VkDispatchIndirectCommand` at this byte offset (a multiple of 4) of the buffer.
    IndirectAt(&'a Buffer, u64),
}

/// A resource and the name of the shader binding it is for: the GLSL variable's name,
/// or an anonymous block's name in snake_case (`spirv::Binding`).
pub type Bind<'a> = (&'static str, Resource<'a>);

/// One resource to bind.
#[derive(Clone, Copy)]
pub enum Resource<'a> {
    /// A storage or uniform buffer (the shader decides which).
    Buffer(&'a Buffer),
    /// A storage image in `GENERAL` layout.
    StorageImage(&'a Image),
    /// A combined image sampler in `SHADER_READ_ONLY_OPTIMAL` layout.
    Sampled(&'a Image, &'a Sampler),
    /// `Sampled` through the image's `data_view` (a texture array's UNORM view).
    SampledData(&'a Image, &'a Sampler),
    /// A uniform texel buffer (`utextureBuffer`).
    Texels(&'a super::TexelView),
    /// A top-level acceleration structure (`accelerationStructureEXT`).
    Accel(&'a super::accel::Accel),
}

/// A descriptor as `vkCmdPushDescriptorSetKHR` takes it.
enum Info {
    Buffer(vk::DescriptorBufferInfo),
    Image(vk::DescriptorImageInfo),
    Texels(vk::BufferView),
    Accel(vk::AccelerationStructureKHR),
}

/// A shader given by name (for errors) and SPIR-V bytes.
pub type Shader = (&'static str, &'static [u8]);

/// How to build a graphics pipeline (dynamic rendering, no vertex input: vertices are
/// pulled from storage buffers).
pub struct GraphicsDesc<'a> {
    pub vertex: Shader,
    /// `None` for depth-only passes.
    pub fragment: Option<Shader>,
    pub color_formats: &'a [vk::Format],
    pub depth_format: vk::Format,
    /// (constant, slope) depth bias, for shadow maps.
    pub depth_bias: Option<(f32, f32)>,
}

/// A pipeline, its layout and its push-descriptor set layout; freed on drop.
pub struct Pipeline {
    ctx: Arc<Context>,
    name: &'static str,
    pub raw: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    set_layout: vk::DescriptorSetLayout,
    bindings: Vec<Binding>,
    bind_point: vk::PipelineBindPoint,
    stages: vk::ShaderStageFlags,
    /// The push-constant struct the pipeline was created for.
    push_type: TypeId,
    push_size: u32,
    /// Workgroup size of a compute pipeline.
    pub local_size: [u32; 3],
}

pub(super) struct Module {
    pub(super) raw: vk::ShaderModule,
    pub(super) reflection: Reflection,
}

pub(super) fn module(ctx: &Context, (name, bytes): Shader) -> Result<Module> {
    let words = spirv::words(name, bytes)?;
    let reflection = spirv::reflect(name, &words)?;
    let info = vk::ShaderModuleCreateInfo::default().code(&words);
    let raw = unsafe { ctx.device.create_shader_module(&info, None) }.vk("vkCreateShaderModule")?;
    Ok(Module { raw, reflection })
}

/// Merges the bindings of several stages: a slot must have the same kind and name in
/// every stage that uses it, and a name one slot only.
pub(super) fn merge(
    name: &str,
    stages: &[(vk::ShaderStageFlags, &Reflection)],
) -> Result<Vec<(Binding, vk::ShaderStageFlags)>> {
    let mut all: Vec<(Binding, vk::ShaderStageFlags)> = Vec::new();
    for (stage, r) in stages {
        for b in &r.bindings {
            match all.iter_mut().find(|e| e.0.slot == b.slot || e.0.name == b.name) {
                Some(e) if e.0 == *b => e.1 |= *stage,
                Some(e) => {
                    let (a, b) = (&e.0, b);
                    return Err(Error::Pipeline(format!(
                        "pipeline {name}: binding {} is {:?} `{}` in one stage and binding {} {:?} `{}` in another",
                        a.slot, a.kind, a.name, b.slot, b.kind, b.name
                    )));
                }
                None => all.push((b.clone(), *stage)),
            }
        }
    }
    all.sort_by_key(|e| e.0.slot);
    Ok(all)
}

/// Checks that the push-constant struct `P` is what the shaders declare and that the
/// device allows it; returns its size.
pub(super) fn push_size<P: Pod>(ctx: &Context, name: &str, reflections: &[&Reflection]) -> Result<u32> {
    let declared = reflections.iter().map(|r| r.push_size).max().unwrap_or(0);
    let size = std::mem::size_of::<P>() as u32;
    if size != declared {
        return Err(Error::Pipeline(format!(
            "pipeline {name}: the shader's push-constant block is {declared} B but {} is {size} B",
            std::any::type_name::<P>()
        )));
    }
    if size > ctx.limits.max_push_constants_size {
        return Err(Error::Pipeline(format!(
            "pipeline {name}: {size} B of push constants exceed this device's maxPushConstantsSize {}",
            ctx.limits.max_push_constants_size
        )));
    }
    Ok(size)
}

impl Pipeline {
    /// A pipeline made elsewhere in `vk/` (the ray-tracing one) from its parts; it
    /// owns them from here.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn from_parts<P: Pod>(
        (ctx, name): (&Arc<Context>, &'static str),
        raw: vk::Pipeline,
        (set_layout, layout): (vk::DescriptorSetLayout, vk::PipelineLayout),
        bindings: &[(Binding, vk::ShaderStageFlags)],
        bind_point: vk::PipelineBindPoint,
        stages: vk::ShaderStageFlags,
        push_size: u32,
    ) -> Self {
        Self {
            ctx: ctx.clone(),
            name,
            raw,
            layout,
            set_layout,
            bindings: bindings.iter().map(|b| b.0.clone()).collect(),
            bind_point,
            stages,
            push_type: TypeId::of::<P>(),
            push_size,
            local_size: [1, 1, 1],
        }
    }

    pub(super) fn ctx(&self) -> &Arc<Context> {
        &self.ctx
    }

    pub(super) fn layouts(
        ctx: &Context,
        name: &str,
        bindings: &[(Binding, vk::ShaderStageFlags)],
        push_stages: vk::ShaderStageFlags,
        push_size: u32,
    ) -> Result<(vk::DescriptorSetLayout, vk::PipelineLayout)> {
        let vk_bindings: Vec<_> = bindings
            .iter()
            .map(|(b, st)| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.slot)
                    .descriptor_type(b.kind)
                    .descriptor_count(1)
                    .stage_flags(*st)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default()
            .flags(vk::DescriptorSetLayoutCreateFlags::PUSH_DESCRIPTOR_KHR)
            .bindings(&vk_bindings);
        let set_layout =
            unsafe { ctx.device.create_descriptor_set_layout(&info, None) }.vk("vkCreateDescriptorSetLayout")?;
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(push_stages)
            .size(push_size)];
        let set_layouts = [set_layout];
        let mut info = vk::PipelineLayoutCreateInfo::default().set_layouts(&set_layouts);
        if push_size > 0 {
            info = info.push_constant_ranges(&ranges);
        }
        let layout = unsafe { ctx.device.create_pipeline_layout(&info, None) }.vk("vkCreatePipelineLayout")?;
        ctx.set_name(layout, name);
        Ok((set_layout, layout))
    }

    /// A compute pipeline from one module, pushed constants of type `P` (`()`: none).
    pub fn compute<P: Pod>(ctx: &Arc<Context>, name: &'static str, shader: Shader) -> Result<Self> {
        Self::compute_specialized::<P>(ctx, name, shader, &[])
    }

    /// A compute pipeline whose specialization constants `constant_id = i` (32-bit:
    /// uint, int, float bits, or bool as 0/1) take `constants[i]`. A variant selected
    /// this way is compiled without the code it does not use; lavapipe, which runs
    /// both sides of every branch, pays for any code left in, taken or not.
    pub fn compute_specialized<P: Pod>(
        ctx: &Arc<Context>,
        name: &'static str,
        shader: Shader,
        constants: &[u32],
    ) -> Result<Self> {
        let m = module(ctx, shader)?;
        let push_size = match push_size::<P>(ctx, name, &[&m.reflection]) {
            Ok(size) => size,
            Err(e) => {
                unsafe { ctx.device.destroy_shader_module(m.raw, None) };
                return Err(e);
            }
        };
        let entries: Vec<vk::SpecializationMapEntry> = (0..constants.len() as u32)
            .map(|i| {
                vk::SpecializationMapEntry::default()
                    .constant_id(i)
                    .offset(4 * i)
                    .size(4)
            })
            .collect();
        let spec = vk::SpecializationInfo::default()
            .map_entries(&entries)
            .data(bytemuck::cast_slice(constants));
        let stage = vk::ShaderStageFlags::COMPUTE;
        let bindings = merge(name, &[(stage, &m.reflection)])?;
        let result = Self::layouts(ctx, name, &bindings, stage, push_size).and_then(|(set_layout, layout)| {
            let info = vk::ComputePipelineCreateInfo::default()
                .stage(
                    vk::PipelineShaderStageCreateInfo::default()
                        .stage(stage)
                        .module(m.raw)
                        .name(c"main")
                        .specialization_info(&spec),
                )
                .layout(layout);
            let raw = unsafe {
                ctx.device
                    .create_compute_pipelines(vk::PipelineCache::null(), &[info], None)
            }
            .map_err(|(_, r)| r)
            .vk("vkCreateComputePipelines")?[0];
            ctx.set_name(raw, name);
            Ok(Self {
                ctx: ctx.clone(),
                name,
                raw,
                layout,
                set_layout,
                bindings: bindings.iter().map(|b| b.0.clone()).collect(),
                bind_point: vk::PipelineBindPoint::COMPUTE,
                stages: stage,
                push_type: TypeId::of::<P>(),
                push_size,
                local_size: m.reflection.local_size.unwrap_or([1, 1, 1]),
            })
        });
        unsafe { ctx.device.destroy_shader_module(m.raw, None) };
        result
    }

    /// A graphics pipeline for dynamic rendering: triangle lists, no culling (scenes
    /// may mix windings; shaders make normals face the viewer), depth test LESS.
    pub fn graphics<P: Pod>(ctx: &Arc<Context>, name: &'static str, desc: &GraphicsDesc<'_>) -> Result<Self> {
        let vs = module(ctx, desc.vertex)?;
        let fs = match desc.fragment.map(|f| module(ctx, f)).transpose() {
            Ok(fs) => fs,
            Err(e) => {
                unsafe { ctx.device.destroy_shader_module(vs.raw, None) };
                return Err(e);
            }
        };
        let mut reflections = vec![(vk::ShaderStageFlags::VERTEX, &vs.reflection)];
        let mut stage_infos = vec![vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::VERTEX)
            .module(vs.raw)
            .name(c"main")];
        let mut push_stages = vk::ShaderStageFlags::VERTEX;
        if let Some(fs) = &fs {
            reflections.push((vk::ShaderStageFlags::FRAGMENT, &fs.reflection));
            stage_infos.push(
                vk::PipelineShaderStageCreateInfo::default()
                    .stage(vk::ShaderStageFlags::FRAGMENT)
                    .module(fs.raw)
                    .name(c"main"),
            );
            push_stages |= vk::ShaderStageFlags::FRAGMENT;
        }
        let result = merge(name, &reflections).and_then(|bindings| {
            let stage_reflections: Vec<&Reflection> = reflections.iter().map(|r| r.1).collect();
            let push_size = push_size::<P>(ctx, name, &stage_reflections)?;
            let (set_layout, layout) = Self::layouts(ctx, name, &bindings, push_stages, push_size)?;
            let raw = graphics_pipeline(ctx, desc, &stage_infos, layout)?;
            ctx.set_name(raw, name);
            Ok(Self {
                ctx: ctx.clone(),
                name,
                raw,
                layout,
                set_layout,
                bindings: bindings.iter().map(|b| b.0.clone()).collect(),
                bind_point: vk::PipelineBindPoint::GRAPHICS,
                stages: push_stages,
                push_type: TypeId::of::<P>(),
                push_size,
                local_size: [1, 1, 1],
            })
        });
        unsafe {
            ctx.device.destroy_shader_module(vs.raw, None);
            if let Some(fs) = fs {
                ctx.device.destroy_shader_module(fs.raw, None);
            }
        }
        result
    }

    /// Binds the pipeline, pushes its descriptors (each binding the resource named for
    /// it in `resources`, in any order; a resource for a binding the compiler removed as
    /// unused is passed over) and its push constants `P` (the type the pipeline was
    /// created with). Graphics passes draw after it. Panics, naming the pipeline and
    /// the binding, when a binding has no resource or one of another kind, or when two
    /// resources are given one name.
    pub fn bind<P: Pod>(&self, cmd: vk::CommandBuffer, resources: &[Bind<'_>], push: &P) {
        assert!(
            TypeId::of::<P>() == self.push_type,
            "pipeline created for other push constants than {}",
            std::any::type_name::<P>()
        );
        let push = bytemuck::bytes_of(push);
        debug_assert_eq!(push.len() as u32, self.push_size);
        let infos = self.descriptor_infos(resources);
        // An acceleration structure is written through a struct chained to its write.
        let mut accels: Vec<vk::WriteDescriptorSetAccelerationStructureKHR<'_>> = infos
            .iter()
            .filter_map(|(_, _, info)| match info {
                Info::Accel(a) => Some(
                    vk::WriteDescriptorSetAccelerationStructureKHR::default()
                        .acceleration_structures(std::slice::from_ref(a)),
                ),
                _ => None,
            })
            .collect();
        let mut accels = accels.iter_mut();
        let writes: Vec<vk::WriteDescriptorSet<'_>> = infos
            .iter()
            .map(|(b, ty, info)| {
                let w = vk::WriteDescriptorSet::default()
                    .dst_binding(*b)
                    .descriptor_type(*ty)
                    .descriptor_count(1);
                match info {
                    Info::Buffer(i) => w.buffer_info(std::slice::from_ref(i)),
                    Info::Image(i) => w.image_info(std::slice::from_ref(i)),
                    Info::Texels(v) => w.texel_buffer_view(std::slice::from_ref(v)),
                    Info::Accel(_) => w.push_next(accels.next().expect("one per acceleration structure")),
                }
            })
            .collect();
        let device = &self.ctx.device;
        // SAFETY: `cmd` is recording; every write references a live resource.
        unsafe {
            device.cmd_bind_pipeline(cmd, self.bind_point, self.raw);
            if !writes.is_empty() {
                self.ctx
                    .push_descriptor
                    .cmd_push_descriptor_set(cmd, self.bind_point, self.layout, 0, &writes);
            }
            if !push.is_empty() {
                device.cmd_push_constants(cmd, self.layout, self.stages, 0, push);
            }
        }
    }

    /// Each binding's descriptor: the resource named for it (see `bind`).
    fn descriptor_infos(&self, resources: &[Bind<'_>]) -> Vec<(u32, vk::DescriptorType, Info)> {
        let pipeline = self.name;
        for (i, (n, _)) in resources.iter().enumerate() {
            assert!(
                resources[..i].iter().all(|(m, _)| m != n),
                "pipeline {pipeline}: two resources given for `{n}`"
            );
        }
        self.bindings
            .iter()
            .map(|binding| {
                let (b, ty, name) = (binding.slot, binding.kind, binding.name.as_str());
                let resource = &resources
                    .iter()
                    .find(|(n, _)| *n == name)
                    .unwrap_or_else(|| {
                        let given: Vec<_> = resources.iter().map(|r| r.0).collect();
                        panic!("pipeline {pipeline}: binding {b} `{name}` ({ty:?}) has no resource; given {given:?}")
                    })
                    .1;
                let info = match (resource, ty) {
                    (
                        Resource::Buffer(buf),
                        vk::DescriptorType::STORAGE_BUFFER | vk::DescriptorType::UNIFORM_BUFFER,
                    ) => Info::Buffer(buf.info()),
                    (Resource::StorageImage(img), vk::DescriptorType::STORAGE_IMAGE) => Info::Image(
                        vk::DescriptorImageInfo::default()
                            .image_view(img.view)
                            .image_layout(vk::ImageLayout::GENERAL),
                    ),
                    (
                        Resource::Sampled(img, s) | Resource::SampledData(img, s),
                        vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
                    ) => {
                        let view = match resource {
                            Resource::SampledData(..) => img.data_view,
                            _ => img.view,
                        };
                        assert!(
                            view != vk::ImageView::null(),
                            "pipeline {pipeline}: binding {b} `{name}`: the image has no such view"
                        );
                        Info::Image(
                            vk::DescriptorImageInfo::default()
                                .image_view(view)
                                .sampler(s.raw)
                                .image_layout(vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL),
                        )
                    }
                    (Resource::Texels(view), vk::DescriptorType::UNIFORM_TEXEL_BUFFER) => Info::Texels(view.raw),
                    (Resource::Accel(a), vk::DescriptorType::ACCELERATION_STRUCTURE_KHR) => Info::Accel(a.raw),
                    _ => panic!(
                        "pipeline {pipeline}: binding {b} `{name}` wants {ty:?}, a different kind of resource was given"
                    ),
                };
                (b, ty, info)
            })
            .collect()
    }

    /// Workgroups that cover `size` invocations per axis.
    pub fn groups_covering(&self, size: [u32; 3]) -> [u32; 3] {
        [0, 1, 2].map(|i| size[i].div_ceil(self.local_size[i]))
    }

    /// Binds, pushes and dispatches: the one way a compute pass runs a kernel. Direct
    /// counts must be within the device's `maxComputeWorkGroupCount` (the renderer
    /// checks its sizes against it when it is created).
    pub fn dispatch<P: Pod>(&self, cmd: vk::CommandBuffer, resources: &[Bind<'_>], push: &P, groups: Groups<'_>) {
        self.bind(cmd, resources, push);
        let device = &self.ctx.device;
        let direct = match groups {
            Groups::Exact(g) => g,
            Groups::Cover(size) => self.groups_covering(size),
            Groups::Indirect(args) | Groups::IndirectAt(args, _) => {
                let offset = match groups {
                    Groups::IndirectAt(_, offset) => offset,
                    _ => 0,
                };
                assert!(
                    offset.is_multiple_of(4) && offset + 12 <= args.size,
                    "indirect arguments at {offset} of {} bytes",
                    args.size
                );
                // SAFETY: `cmd` is recording; `args` holds a VkDispatchIndirectCommand at `offset`.
                unsafe { device.cmd_dispatch_indirect(cmd, args.raw, offset) };
                return;
            }
        };
        let max = self.ctx.limits.max_compute_work_group_count;
        assert!(
            (0..3).all(|i| direct[i] <= max[i]),
            "dispatch of {direct:?} workgroups exceeds maxComputeWorkGroupCount {max:?}"
        );
        // SAFETY: `cmd` is recording with this pipeline bound.
        unsafe { device.cmd_dispatch(cmd, direct[0], direct[1], direct[2]) };
    }
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        unsafe {
            self.ctx.device.destroy_pipeline(self.raw, None);
            self.ctx.device.destroy_pipeline_layout(self.layout, None);
            self.ctx.device.destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// The graphics pipeline of `desc` over `stages` with `layout` (the fixed-function
/// state `Pipeline::graphics` documents; viewport and scissor dynamic).
fn graphics_pipeline(
    ctx: &Context,
    desc: &GraphicsDesc<'_>,
    stages: &[vk::PipelineShaderStageCreateInfo<'_>],
    layout: vk::PipelineLayout,
) -> Result<vk::Pipeline> {
    let vertex_input = vk::PipelineVertexInputStateCreateInfo::default();
    let assembly = vk::PipelineInputAssemblyStateCreateInfo::default().topology(vk::PrimitiveTopology::TRIANGLE_LIST);
    let viewport = vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1);
    let (bias_on, bias_c, bias_s) = desc.depth_bias.map_or((false, 0.0, 0.0), |(c, s)| (true, c, s));
    let raster = vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(vk::CullModeFlags::NONE)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .depth_bias_enable(bias_on)
        .depth_bias_constant_factor(bias_c)
        .depth_bias_slope_factor(bias_s)
        .line_width(1.0);
    let multisample =
        vk::PipelineMultisampleStateCreateInfo::default().rasterization_samples(vk::SampleCountFlags::TYPE_1);
    let depth = vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(true)
        .depth_write_enable(true)
        .depth_compare_op(vk::CompareOp::LESS);
    let attachments: Vec<_> = desc
        .color_formats
        .iter()
        .map(|_| vk::PipelineColorBlendAttachmentState::default().color_write_mask(vk::ColorComponentFlags::RGBA))
        .collect();
    let blend = vk::PipelineColorBlendStateCreateInfo::default().attachments(&attachments);
    let dynamic_states = [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];
    let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&dynamic_states);
    let mut rendering = vk::PipelineRenderingCreateInfo::default()
        .color_attachment_formats(desc.color_formats)
        .depth_attachment_format(desc.depth_format);
    let info = vk::GraphicsPipelineCreateInfo::default()
        .stages(stages)
        .vertex_input_state(&vertex_input)
        .input_assembly_state(&assembly)
        .viewport_state(&viewport)
        .rasterization_state(&raster)
        .multisample_state(&multisample)
        .depth_stencil_state(&depth)
        .color_blend_state(&blend)
        .dynamic_state(&dynamic)
        .layout(layout)
        .push_next(&mut rendering);
    Ok(unsafe {
        ctx.device
            .create_graphics_pipelines(vk::PipelineCache::null(), &[info], None)
    }
    .map_err(|(_, r)| r)
    .vk("vkCreateGraphicsPipelines")?[0])
}
