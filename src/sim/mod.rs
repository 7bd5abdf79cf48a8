//! What moves: the rigid bodies' simulation (`rigid`, rapier3d on the CPU) whose poses
//! `sim.transform` applies to the dynamic geometry on the GPU every frame.

pub mod cloth;
pub mod rigid;
