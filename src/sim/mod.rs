//! What moves on the CPU: the rigid bodies' simulation (`rigid`, rapier3d) whose poses
//! `sim.transform` applies to the dynamic geometry on the GPU every frame.
//!
//! What moves, everywhere (docs/architecture.md, "What moves"): described by the scene
//! (`scene::bodies`, `scene::cloth`, `scene::animation`, `scene::gltf_rig`,
//! `scene::animated`); stepped here (rigid bodies) and on the GPU (`passes::sim_transform`,
//! `passes::sim_cloth`, `passes::sim_skin`); followed by the tracers' moving structures
//! (`tracers::lbvh::dynamic`, `tracers::lbvh::rigid`, `tracers::khr`); held on the GPU by
//! the renderer (`renderer/gpu_scene.rs`); mirrored by `cpu_ref::sim` and
//! `cpu_ref::cloth` (and `scene::animation::skin_vertex` for the skin).

pub mod rigid;
