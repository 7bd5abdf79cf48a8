//! The integration tests as one binary (one link, one file to carry to a GPU): each
//! module is one feature's tests, on lavapipe or the GPU, validation on. The window
//! tests (`tests/demo.rs`) stay apart: winit wants the main thread. Run one module with
//! `tools/test --test suite MODULE::` (e.g. `house::`).

#[path = "../common/mod.rs"]
mod common;

mod adaptive;
mod animation;
mod bad_input;
mod bench;
mod compact;
mod device;
mod dynamic;
mod gbuffer;
mod glossy;
mod gltf;
mod harness;
mod house;
mod inputs;
mod kernels;
mod khr;
mod layout;
mod lbvh;
mod links;
mod merge;
mod outputs;
mod reflections;
mod render;
mod reports;
mod rt_reflect;
mod scale;
mod shadows;
mod sim;
mod ssr;
mod stages;
mod timing;
mod trace;
mod tune;
