//! The scene on the GPU: its static meshes, materials and textures, and the moving
//! geometry of a scene with bodies (their simulation, the world-space vertices the
//! `sim.*` passes write, and the BVH over them). Everything is relative to the
//! renderer's origin (`view::render_origin`).

use crate::error::Result;
use crate::gpu_types::{GpuMaterial, GpuVertex};
use crate::passes::sim_cloth::ClothState;
use crate::passes::sim_skin::{self, Skinned};
use crate::passes::sim_transform::{self, RigidBodies};
use crate::passes::{SceneGeometry, Surfaces};
use crate::scene::animated::Animated;
use crate::scene::{texture, Scene};
use crate::settings::Settings;
use crate::sim::rigid::RigidWorld;
use crate::tracers::khr::{BodyRange, DynamicLayout};
use crate::tracers::lbvh::dynamic::DynamicBvh;
use crate::tracers::lbvh::rigid::{self, RigidKeys, RigidLayout};
use crate::tracers::lbvh::{self, Geometry, TriangleTexels};
use crate::tracers::Traceable;
use crate::vk::barrier::{self, access};
use crate::vk::{Buffer, Context, Image, Sampler};
use ash::vk;
use glam::Vec3;
use std::sync::Arc;

/// Indexed triangles on the GPU, as the raster passes draw them and the BVH builder and
/// traversal read them: world-space vertices (relative to the renderer's origin), their
/// texture coordinates, indices.
pub(super) struct MeshBuffers {
    pub vertices: Buffer,
    pub uvs: Buffer,
    pub indices: Buffer,
    pub index_count: u32,
    /// `vertices` and `indices` as the BVH kernels read them.
    texels: TriangleTexels,
}

impl MeshBuffers {
    /// `vertices` (already made, with `lbvh::VERTEX_USAGE`) with `uvs` and `indices`
    /// uploaded beside them.
    fn new(ctx: &Arc<Context>, name: &str, vertices: Buffer, uvs: &[[f32; 2]], indices: &[u32]) -> Result<Self> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let index_buffer = lbvh::index_buffer(
            ctx,
            &format!("{name}.indices"),
            vk::BufferUsageFlags::INDEX_BUFFER,
            indices,
        )?;
        Ok(Self {
            texels: TriangleTexels::new(ctx, &vertices, &index_buffer)?,
            vertices,
            uvs: Buffer::with_data(ctx, &format!("{name}.uvs"), storage, bytemuck::cast_slice(uvs))?,
            indices: index_buffer,
            index_count: indices.len() as u32,
        })
    }

    pub fn geometry(&self) -> SceneGeometry<'_> {
        SceneGeometry {
            vertices: &self.vertices,
            previous: &self.vertices,
            uvs: &self.uvs,
            indices: &self.indices,
            index_count: self.index_count,
        }
    }

    /// The triangles as the BVH builder and the traversal read them.
    pub fn triangles(&self) -> Geometry<'_> {
        Geometry {
            vertices: &self.vertices,
            indices: &self.indices,
            texels: &self.texels,
            tri_count: self.index_count / 3,
        }
    }
}

/// The scene's static buffers and textures on the GPU.
pub(super) struct SceneBuffers {
    pub mesh: MeshBuffers,
    pub materials: Buffer,
    textures: Image,
    texture_sampler: Sampler,
}

impl SceneBuffers {
    /// Uploads `scene`'s static geometry moved by `-origin`, its materials and textures.
    pub fn upload(ctx: &Arc<Context>, scene: &Scene, origin: Vec3) -> Result<Self> {
        let storage = vk::BufferUsageFlags::STORAGE_BUFFER;
        let materials: Vec<GpuMaterial> = scene.materials.iter().map(|m| m.gpu()).collect();
        let shifted;
        let vertices = if origin == Vec3::ZERO {
            &scene.vertices
        } else {
            shifted = scene
                .vertices
                .iter()
                .map(|v| GpuVertex {
                    position: (Vec3::from(v.position) - origin).to_array(),
                    ..*v
                })
                .collect::<Vec<_>>();
            &shifted
        };
        let vertices = Buffer::with_data(
            ctx,
            "scene.vertices",
            lbvh::VERTEX_USAGE | crate::vk::accel::input_usage(ctx),
            bytemuck::cast_slice(vertices),
        )?;
        Ok(Self {
            mesh: MeshBuffers::new(ctx, "scene", vertices, &scene.uvs, &scene.indices)?,
            materials: Buffer::with_data(ctx, "scene.materials", storage, bytemuck::cast_slice(&materials))?,
            textures: upload_textures(ctx, scene)?,
            texture_sampler: Sampler::trilinear_repeat(ctx, "scene.texture_sampler")?,
        })
    }

    /// The surfaces, with the dynamic geometry's texture coordinates when there is any.
    pub fn surfaces<'a>(&'a self, dynamic: Option<&'a DynamicGeometry>) -> Surfaces<'a> {
        Surfaces {
            materials: &self.materials,
            uvs: [&self.mesh.uvs, dynamic.map_or(&self.mesh.uvs, |d| &d.mesh.uvs)],
            textures: &self.textures,
            sampler: &self.texture_sampler,
        }
    }
}

/// The scene's textures as one array texture (`scene::texture`): layers of the largest
/// texture's power-of-two size (capped by `texture::LAYER_MAX` and the device), each
/// with its mip chain; one white 1x1 layer when the scene has none.
fn upload_textures(ctx: &Arc<Context>, scene: &Scene) -> Result<Image> {
    let max = texture::LAYER_MAX.min(1 << ctx.limits.max_image_dimension2_d.ilog2());
    let (size, chains) = texture::layers(&scene.textures, max);
    let chains: Vec<Vec<&[u8]>> = chains
        .iter()
        .map(|chain| chain.iter().map(|level| level.as_raw().as_slice()).collect())
        .collect();
    Image::texture_array(ctx, "scene.textures", size, &chains)
}

/// The bodies' triangle ranges in the dynamic numbering with the first body of the same
/// shape (`BodyShape`: the same object-space triangles), and the deformable range (the
/// cloths' and the animated model's triangles): what the vendor tracer builds its
/// bottom levels over.
pub(super) fn khr_ranges(scene: &Scene) -> (Vec<BodyRange>, Option<(u32, u32)>) {
    let mut first_of_shape = std::collections::HashMap::new();
    let mut first_tri = 0u32;
    let mut bodies = Vec::with_capacity(scene.bodies.len());
    for (i, b) in scene.bodies.iter().enumerate() {
        let tris = (scene.body_mesh(b).indices.len() / 3) as u32;
        // Debug prints an f32 exactly (the shortest text that reads back as it).
        let shape_of = *first_of_shape.entry(format!("{:?}", b.shape)).or_insert(i as u32);
        bodies.push(BodyRange {
            first_tri,
            tris,
            shape_of,
        });
        first_tri += tris;
    }
    // The animated model's triangles follow the cloths': one deformable range.
    let deformable: u32 = scene.cloths.iter().map(|c| 2 * (c.resolution - 1).pow(2)).sum::<u32>()
        + scene.animated.as_ref().map_or(0, |a| a.indices.len() as u32 / 3);
    (bodies, (deformable > 0).then_some((first_tri, deformable)))
}

/// The moving geometry of a dynamic scene: its simulation (`sim.rigid` on the host),
/// the rigid bodies' vertices and poses (`sim.transform`), the cloths (`sim.cloth`),
/// the animated model and its clock (`sim.skin`), the world-space vertices those
/// write, and the BVH over them.
pub(super) struct DynamicGeometry {
    pub world: RigidWorld,
    pub rigid: RigidBodies,
    /// The world-space vertices `sim.transform` and `sim.cloth` write.
    pub mesh: MeshBuffers,
    pub cloths: Vec<ClothState>,
    /// The animated model on the GPU, and as the scene has it (its clock and rig).
    pub animated: Option<(Skinned, Animated)>,
    pub bvh: DynamicBvh,
    /// `khr_ranges` of the scene.
    pub khr_ranges: (Vec<BodyRange>, Option<(u32, u32)>),
    /// `refit_rebuild_every`, or 1 where the LBVH rebuilds every frame.
    pub rebuild_every: u32,
    /// The world-space vertices of the frame before the last step (`keep_previous`),
    /// whether the last frame recorded moved them from there (else nothing moved), and
    /// whether the vertices hold a step's result at all (not before the first step
    /// after creation or a reset: there is no frame before to move from).
    previous: Buffer,
    moved: bool,
    stepped: bool,
    /// The renderer's origin and the time step (for the animated model's matrices).
    origin: Vec3,
    dt: f64,
}

impl DynamicGeometry {
    /// The dynamic geometry of `scene`, simulated relative to `origin` (the renderer's),
    /// its initial poses written for the first frame.
    pub fn new(ctx: &Arc<Context>, scene: &Scene, settings: &Settings, origin: Vec3) -> Result<Self> {
        let meshes = scene.dynamic_meshes();
        let vertex_count = meshes.rigid_vertices as u32;
        ctx.check_limit(
            || "the dynamic geometry".to_string(),
            vertex_count as u64,
            "vertices",
            "sim.transform's dispatch (65535 workgroups)",
            sim_transform::MAX_VERTICES as u64,
        )?;
        let tris = (meshes.indices.len() / 3) as u32;
        let world_vertices = Buffer::new(
            ctx,
            "dynamic.vertices",
            std::mem::size_of_val(meshes.vertices.as_slice()) as u64,
            lbvh::VERTEX_USAGE | vk::BufferUsageFlags::TRANSFER_SRC | crate::vk::accel::input_usage(ctx),
            gpu_allocator::MemoryLocation::GpuOnly,
        )?;
        let mut cloths = Vec::new();
        let mut base = vertex_count;
        for c in &scene.cloths {
            cloths.push(ClothState::new(ctx, c, settings.sim_dt, base, origin)?);
            base += c.resolution * c.resolution;
        }
        let animated = match &scene.animated {
            Some(a) => {
                ctx.check_limit(
                    || "the animated model".to_string(),
                    a.vertices.len() as u64,
                    "vertices",
                    "sim.skin's dispatch (65535 workgroups)",
                    sim_skin::MAX_VERTICES as u64,
                )?;
                let first = meshes.animated_vertices as u32;
                let gpu = Skinned::new(ctx, &a.vertices, &a.influences, a.joints.len(), first)?;
                Some((gpu, a.clone()))
            }
            None => None,
        };
        // Refit (cloth only, unless `cloth_rebuild`): rigid bodies move too far apart.
        let refit = scene.bodies.is_empty() && !settings.cloth_rebuild;
        let mut bvh = DynamicBvh::new(ctx, tris, refit, settings.refit_rebuild_every)?;
        // Rigid bodies alone: rebuilt from the bodies' order and each body's own.
        if rigid::applies(scene, settings.rigid_order) {
            let layout = RigidLayout::new(&meshes.vertices, &meshes.indices, scene.bodies.len() as u32)?;
            bvh = bvh.with_rigid(RigidKeys::new(ctx, &layout)?);
        }
        let previous = Buffer::new(
            ctx,
            "dynamic.previous",
            world_vertices.size,
            vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::TRANSFER_DST,
            gpu_allocator::MemoryLocation::GpuOnly,
        )?;
        let mut dynamic = Self {
            world: RigidWorld::relative_to(scene, settings.sim_dt, origin)?,
            rigid: RigidBodies::new(ctx, &meshes.vertices, vertex_count, scene.bodies.len())?,
            mesh: MeshBuffers::new(ctx, "dynamic", world_vertices, &meshes.uvs, &meshes.indices)?,
            cloths,
            animated,
            bvh,
            khr_ranges: khr_ranges(scene),
            rebuild_every: if refit { settings.refit_rebuild_every } else { 1 },
            previous,
            moved: false,
            stepped: false,
            origin,
            dt: settings.sim_dt as f64,
        };
        dynamic.rigid.write(0, &dynamic.world.poses());
        dynamic.pose_model(0);
        Ok(dynamic)
    }

    /// Frame slots (one staging buffer each for the poses and the joints); the GPU
    /// must be idle.
    pub fn set_slots(&mut self, n: usize) -> Result<()> {
        self.rigid.set_slots(n)?;
        if let Some((gpu, _)) = &mut self.animated {
            gpu.set_slots(n)?;
        }
        Ok(())
    }

    /// Writes the animated model's matrices at the current step for the frame
    /// recorded with `slot` (the first frame after a reset shows the start).
    fn pose_model(&mut self, slot: usize) {
        let elapsed = self.world.steps() as f64 * self.dt;
        if let Some((gpu, a)) = &mut self.animated {
            gpu.write(slot, &a.matrices(a.time(elapsed), self.origin));
        }
    }

    /// The animation's time of the frame last recorded (after `step`), if the scene
    /// has an animated model.
    pub fn animation_time(&self) -> Option<f32> {
        let a = &self.animated.as_ref()?.1;
        Some(a.time(self.world.steps().saturating_sub(1) as f64 * self.dt))
    }

    /// Back to the initial state: the world, the cloths, and a fresh build next frame.
    pub fn reset(&mut self) -> Result<()> {
        self.world.reset();
        let poses = self.world.poses();
        for slot in 0..self.rigid.slots() {
            self.rigid.write(slot, &poses);
        }
        for c in &self.cloths {
            c.reset()?;
        }
        for slot in 0..self.rigid.slots() {
            self.pose_model(slot);
        }
        self.bvh.reset();
        self.stepped = false;
        Ok(())
    }

    /// Records the copy of the world-space vertices as they are (the last frame's)
    /// before this frame's step rewrites them, for the G-buffer's motion; or, `stepped`
    /// false (paused), nothing: this frame's geometry is the last one's. The first
    /// step (after creation or a reset) has no frame before it: no motion.
    pub fn keep_previous(&mut self, device: &ash::Device, cmd: vk::CommandBuffer, stepped: bool) {
        self.moved = stepped && self.stepped;
        self.stepped |= stepped;
        if !self.moved {
            return;
        }
        // RAW on the vertices (the last step's writes), WAR on the copy (the last
        // frame's vertex shaders read it).
        barrier::global(device, cmd, access::ALL_READ_WRITE, access::TRANSFER_WRITE_READ);
        let region = vk::BufferCopy::default().size(self.mesh.vertices.size);
        // SAFETY: `cmd` is recording; both buffers are this scene's, live and of the
        // vertices' size; the barrier above orders the copy.
        unsafe { device.cmd_copy_buffer(cmd, self.mesh.vertices.raw, self.previous.raw, &[region]) };
        // RAW: the G-buffer's vertex shader reads the copy. (The step's own leading
        // barrier waits for the copy's reads before it rewrites the vertices.)
        barrier::global(device, cmd, access::TRANSFER_WRITE, access::ANY_SHADER_READ);
    }

    /// The moving geometry as the G-buffer draws it, with its motion since last frame.
    pub fn geometry(&self) -> SceneGeometry<'_> {
        SceneGeometry {
            previous: if self.moved {
                &self.previous
            } else {
                &self.mesh.vertices
            },
            ..self.mesh.geometry()
        }
    }

    /// The moving geometry as the vendor tracer builds it.
    pub fn khr_layout(&self) -> DynamicLayout<'_> {
        DynamicLayout {
            objects: self.rigid.objects(),
            object_vertices: self.rigid.vertex_count,
            world: self.mesh.triangles(),
            bodies: self.khr_ranges.0.clone(),
            cloth: self.khr_ranges.1,
            rebuild_every: self.rebuild_every,
        }
    }

    pub fn traceable(&self) -> Traceable<'_> {
        Traceable {
            bvh: &self.bvh.bvh,
            geometry: self.mesh.triangles(),
        }
    }

    /// One `sim.rigid` step, its poses written for the frame recorded with `slot`
    /// (whose previous frame has finished: nothing reads its staging poses).
    pub fn step(&mut self, slot: usize) {
        self.pose_model(slot);
        self.world.step();
        self.rigid.write(slot, &self.world.poses());
    }
}
