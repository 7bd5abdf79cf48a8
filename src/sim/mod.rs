//! What moves on the CPU: the rigid bodies' simulation (`rigid`, rapier3d) whose poses
//! `sim.transform` applies to the dynamic geometry on the GPU every frame. Cloth is
//! stepped on the GPU (`passes::sim_cloth`); its description and particle layout are
//! the scene's (`scene::cloth`).

pub mod rigid;
