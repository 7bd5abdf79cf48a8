//! `sim.rigid`: the scene's rigid bodies stepped by rapier3d (CPU) at a fixed time step.
//! The static geometry is one fixed triangle-mesh collider; each body is a ball or a
//! cuboid. Deterministic: the same scene stepped k times gives the same poses (rapier
//! runs single-threaded here, in the same order every time).

use crate::error::{Error, Result};
use crate::scene::{BodyShape, Scene};
use glam::{Mat4, Vec3};
use rapier3d::prelude::*;

/// Gravity, world units per second squared (the scenes are in metres, y up).
pub const GRAVITY: Vec3 = Vec3::new(0.0, -9.81, 0.0);

/// A scene's rigid bodies and the static world they collide with.
pub struct RigidWorld {
    bodies: RigidBodySet,
    colliders: ColliderSet,
    handles: Vec<RigidBodyHandle>,
    pipeline: PhysicsPipeline,
    islands: IslandManager,
    broad_phase: DefaultBroadPhase,
    narrow_phase: NarrowPhase,
    impulse_joints: ImpulseJointSet,
    multibody_joints: MultibodyJointSet,
    soft_bodies: SoftBodySet,
    ccd: CCDSolver,
    params: IntegrationParameters,
    steps: u64,
    /// The bodies and colliders as built, for `reset`.
    initial: (RigidBodySet, ColliderSet),
}

impl RigidWorld {
    /// The world of `scene` at its initial state, stepped `dt` seconds at a time.
    pub fn new(scene: &Scene, dt: f32) -> Result<Self> {
        Self::relative_to(scene, dt, Vec3::ZERO)
    }

    /// `new` in coordinates relative to `origin` (the renderer's: a scene far from the
    /// world origin keeps its precision); `poses` are then relative too.
    pub fn relative_to(scene: &Scene, dt: f32, origin: Vec3) -> Result<Self> {
        let mut bodies = RigidBodySet::new();
        let mut colliders = ColliderSet::new();
        let vertices: Vec<Vector> = scene.vertices.iter().map(|v| Vec3::from(v.position) - origin).collect();
        let triangles: Vec<[u32; 3]> = scene.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        let ground = ColliderBuilder::trimesh(vertices, triangles)
            .map_err(|e| Error::BadGeometry {
                source_name: scene.name.clone(),
                detail: format!("the static geometry is no collider for the bodies: {e}"),
            })?
            .friction(0.6)
            .build();
        colliders.insert(ground);
        let mut handles = Vec::with_capacity(scene.bodies.len());
        for b in &scene.bodies {
            let body = RigidBodyBuilder::dynamic()
                .translation(b.position - origin)
                .rotation(b.rotation.to_scaled_axis())
                .linvel(b.velocity)
                .angvel(b.angular_velocity)
                .ccd_enabled(true)
                .build();
            let h = bodies.insert(body);
            let shape = match b.shape {
                BodyShape::Sphere { radius } => ColliderBuilder::ball(radius),
                BodyShape::Cuboid { size } => ColliderBuilder::cuboid(0.5 * size.x, 0.5 * size.y, 0.5 * size.z),
                BodyShape::Mesh { mesh, hull, .. } => {
                    let m = &scene.body_meshes[mesh as usize];
                    let bad = |what: &str| Error::BadGeometry {
                        source_name: scene.name.clone(),
                        detail: format!("a body's mesh makes no {what} collider"),
                    };
                    if hull {
                        ColliderBuilder::convex_hull(&m.positions).ok_or_else(|| bad("convex hull"))?
                    } else {
                        let tris = m.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
                        ColliderBuilder::trimesh(m.positions.clone(), tris).map_err(|_| bad("triangle-mesh"))?
                    }
                }
            };
            let collider = shape
                .density(b.density)
                .restitution(b.restitution)
                .friction(b.friction)
                .build();
            colliders.insert_with_parent(collider, h, &mut bodies);
            handles.push(h);
        }
        let params = IntegrationParameters {
            dt,
            ..IntegrationParameters::default()
        };
        Ok(Self {
            initial: (bodies.clone(), colliders.clone()),
            bodies,
            colliders,
            handles,
            pipeline: PhysicsPipeline::new(),
            islands: IslandManager::new(),
            broad_phase: DefaultBroadPhase::new(),
            narrow_phase: NarrowPhase::new(),
            impulse_joints: ImpulseJointSet::new(),
            multibody_joints: MultibodyJointSet::new(),
            soft_bodies: SoftBodySet::new(),
            ccd: CCDSolver::new(),
            params,
            steps: 0,
        })
    }

    /// Advances the world by one time step.
    pub fn step(&mut self) {
        self.pipeline.step(
            GRAVITY,
            &self.params,
            &mut self.islands,
            &mut self.broad_phase,
            &mut self.narrow_phase,
            &mut self.bodies,
            &mut self.colliders,
            &mut self.impulse_joints,
            &mut self.multibody_joints,
            &mut self.soft_bodies,
            &mut self.ccd,
            &(),
            &(),
        );
        self.steps += 1;
    }

    /// Back to the initial state, as `new` left it (the solver's caches too, so the
    /// steps that follow repeat those after `new`).
    pub fn reset(&mut self) {
        (self.bodies, self.colliders) = self.initial.clone();
        self.pipeline = PhysicsPipeline::new();
        self.islands = IslandManager::new();
        self.broad_phase = DefaultBroadPhase::new();
        self.narrow_phase = NarrowPhase::new();
        self.impulse_joints = ImpulseJointSet::new();
        self.multibody_joints = MultibodyJointSet::new();
        self.soft_bodies = SoftBodySet::new();
        self.ccd = CCDSolver::new();
        self.steps = 0;
    }

    /// Time steps taken since the initial state.
    pub fn steps(&self) -> u64 {
        self.steps
    }

    /// Each body's object-to-world transform (rigid: rotation then translation).
    pub fn poses(&self) -> Vec<Mat4> {
        self.handles
            .iter()
            .map(|&h| {
                let b = &self.bodies[h];
                Mat4::from_rotation_translation(*b.rotation(), b.translation())
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Body, Material, SceneBuilder, TriMesh};
    use glam::Quat;

    fn ball_over_floor() -> Scene {
        let mut b = SceneBuilder::new("ball");
        let m = b.material(Material::new("m", [0.5; 3], 0.5, 0.0));
        b.mesh(TriMesh::quad(10.0, 10.0), Mat4::IDENTITY, m);
        b.body(Body {
            shape: BodyShape::Sphere { radius: 0.5 },
            material: m,
            density: 1.0,
            restitution: 0.0,
            friction: 0.5,
            position: Vec3::new(0.0, 3.0, 0.0),
            rotation: Quat::IDENTITY,
            velocity: Vec3::ZERO,
            angular_velocity: Vec3::ZERO,
        });
        b.build().unwrap()
    }

    /// A cube given as a mesh rests on the floor at half its edge, as its convex hull
    /// and as the triangle mesh itself.
    #[test]
    fn mesh_bodies_rest_on_the_floor() {
        for hull in [true, false] {
            let mut b = SceneBuilder::new("mesh body");
            let m = b.material(Material::new("m", [0.5; 3], 0.5, 0.0));
            b.mesh(TriMesh::quad(10.0, 10.0), Mat4::IDENTITY, m);
            let mesh = b.body_mesh(TriMesh::cuboid(Vec3::ONE));
            b.body(Body {
                shape: BodyShape::Mesh {
                    mesh,
                    hull,
                    radius: 0.87,
                },
                material: m,
                density: 1000.0,
                restitution: 0.0,
                friction: 0.5,
                position: Vec3::new(0.0, 2.0, 0.0),
                rotation: Quat::IDENTITY,
                velocity: Vec3::ZERO,
                angular_velocity: Vec3::ZERO,
            });
            let scene = b.build().unwrap();
            let mut w = RigidWorld::new(&scene, 1.0 / 60.0).unwrap();
            for _ in 0..240 {
                w.step();
            }
            let y = w.poses()[0].w_axis.y;
            assert!((y - 0.5).abs() < 0.05, "hull {hull}: rests at {y}");
        }
    }

    /// A ball falls freely (y = y0 - g t^2 / 2 until it lands, within 2%), comes to
    /// rest on the floor at its radius, and two worlds stepped alike agree exactly.
    #[test]
    fn a_ball_falls_lands_and_steps_deterministically() {
        let scene = ball_over_floor();
        let dt = 1.0 / 60.0;
        let mut w = RigidWorld::new(&scene, dt).unwrap();
        for _ in 0..20 {
            w.step();
        }
        let t = 20.0 * dt;
        let y = w.poses()[0].w_axis.y;
        let free = 3.0 - 0.5 * 9.81 * t * t;
        assert!((y - free).abs() < 0.02 * 3.0, "after {t} s: {y}, free fall says {free}");
        for _ in 0..280 {
            w.step();
        }
        let rest = w.poses()[0].w_axis.y;
        assert!((rest - 0.5).abs() < 0.02, "at rest at {rest}");
        let mut again = RigidWorld::new(&scene, dt).unwrap();
        for _ in 0..300 {
            again.step();
        }
        assert_eq!(again.poses(), w.poses());
        assert_eq!(w.steps(), 300);
        again.reset();
        assert_eq!(again.poses()[0].w_axis.y, 3.0);
        for _ in 0..300 {
            again.step();
        }
        assert_eq!(again.poses(), w.poses(), "a reset world repeats its steps");
    }
}
