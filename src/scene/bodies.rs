//! Rigid bodies: their shapes, placements and a scene's `[spawn]` of many.

use glam::{Quat, Vec3};

/// The collider and mesh of a rigid body, in its own space (centred on its centre of
/// mass).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BodyShape {
    Sphere {
        radius: f32,
    },
    /// Full extents.
    Cuboid {
        size: Vec3,
    },
    /// `Scene::body_meshes[mesh]` (centred on the origin), colliding as its convex hull
    /// (`hull`) or as the triangle mesh itself; `radius` bounds it.
    Mesh {
        mesh: u32,
        hull: bool,
        radius: f32,
    },
}

/// A rigid body of the dynamic geometry: simulated (`sim::rigid`), its mesh moved to
/// its pose every frame, its triangles in the dynamic BVH.
#[derive(Clone, Debug, PartialEq)]
pub struct Body {
    pub shape: BodyShape,
    /// An index into `Scene::materials`.
    pub material: u32,
    /// kg per cubic unit.
    pub density: f32,
    /// Bounciness in [0, 1] (averaged with what it hits).
    pub restitution: f32,
    pub friction: f32,
    /// The initial pose and motion (world units per second; radians per second about
    /// the world axes).
    pub position: Vec3,
    pub rotation: Quat,
    pub velocity: Vec3,
    pub angular_velocity: Vec3,
}

impl Body {
    /// Radius of the body's bounding sphere.
    pub fn radius(&self) -> f32 {
        match self.shape {
            BodyShape::Sphere { radius } => radius,
            BodyShape::Cuboid { size } => 0.5 * size.length(),
            BodyShape::Mesh { radius, .. } => radius,
        }
    }
}

/// Most bodies a scene may spawn (`Spawn::count`, `--bodies`): what lavapipe's
/// 128 MiB `maxStorageBufferRange` holds. 4,000 bodies make about 1.9M dynamic
/// triangles, whose BVH nodes take 124 MiB; 5,000 need 148 MiB (20,000, the old
/// maximum, was refused by the device at buffer creation).
pub const MAX_BODIES: u32 = 4_000;

/// A grid of bodies a scene file asks for (`[spawn]`): the scalability test of the
/// dynamic geometry (`stress`). Bodies alternate between balls of radius `size` and
/// cubes of edge 1.6 `size`, take `materials` by a fixed hash, and start in layers of
/// ceil(cbrt(count))² on a grid `4 size` apart whose lowest layer is centred on
/// `center`, each slightly offset and turned (a fixed hash of its index), at rest.
#[derive(Clone, Debug, PartialEq)]
pub struct Spawn {
    pub count: u32,
    pub size: f32,
    pub center: Vec3,
    pub materials: Vec<u32>,
}

impl Spawn {
    pub fn bodies(&self) -> Vec<Body> {
        let side = (self.count as f64).cbrt().ceil().max(1.0) as u32;
        let spacing = 4.0 * self.size;
        // A fixed hash of (index, salt) in [0, 1).
        let hash = |k: u32, salt: u32| {
            let mut x = k.wrapping_mul(0x9E37_79B9) ^ salt.wrapping_mul(0x85EB_CA6B);
            x ^= x >> 16;
            x = x.wrapping_mul(0x7FEB_352D);
            x ^= x >> 15;
            (x >> 8) as f32 / (1u32 << 24) as f32
        };
        (0..self.count)
            .map(|k| {
                let (x, z, y) = (k % side, (k / side) % side, k / (side * side));
                let half = 0.5 * (side - 1) as f32;
                let jitter = Vec3::new(hash(k, 1) - 0.5, 0.0, hash(k, 2) - 0.5) * (0.2 * spacing);
                let position = self.center
                    + Vec3::new(
                        (x as f32 - half) * spacing,
                        y as f32 * spacing + self.size,
                        (z as f32 - half) * spacing,
                    )
                    + jitter;
                let shape = if k % 2 == 0 {
                    BodyShape::Sphere { radius: self.size }
                } else {
                    BodyShape::Cuboid {
                        size: Vec3::splat(1.6 * self.size),
                    }
                };
                Body {
                    shape,
                    material: self.materials
                        [(hash(k, 5) * self.materials.len() as f32) as usize % self.materials.len()],
                    density: 1000.0,
                    restitution: 0.3,
                    friction: 0.5,
                    position,
                    rotation: Quat::from_euler(glam::EulerRot::YXZ, 6.3 * hash(k, 3), 3.2 * hash(k, 4), 0.0),
                    velocity: Vec3::ZERO,
                    angular_velocity: Vec3::ZERO,
                }
            })
            .collect()
    }
}
