//! Shared test helpers: a validated context that checks for validation messages when
//! dropped, random inputs, the binary runner.
#![allow(dead_code)]

pub mod figure;
pub mod showcase;

use speculum::vk::{Context, ContextDesc};
use std::cell::Cell;
use std::sync::{Arc, RwLock, RwLockReadGuard, RwLockWriteGuard};

/// The machine the tests share: every GPU context and every run of the binary holds it
/// shared (`shared`); a test that times things holds it alone (`alone`), so no other
/// test's threads preempt lavapipe's between two timestamps. (In one test binary the
/// harness runs tests of every module side by side.)
static MACHINE: RwLock<()> = RwLock::new(());

thread_local! {
    /// This thread holds `MACHINE` alone: what it starts needs no shared hold.
    static ALONE: Cell<bool> = const { Cell::new(false) };
}

/// A shared hold on the machine, or none while this thread holds it alone.
fn shared() -> Option<RwLockReadGuard<'static, ()>> {
    (!ALONE.get()).then(|| MACHINE.read().unwrap_or_else(|e| e.into_inner()))
}

/// The machine to this test alone while the guard lives (no other test's GPU context
/// or binary run side by side): for tests whose assertions read timings.
pub struct Alone(#[allow(dead_code)] RwLockWriteGuard<'static, ()>);

pub fn alone() -> Alone {
    let guard = MACHINE.write().unwrap_or_else(|e| e.into_inner());
    ALONE.set(true);
    Alone(guard)
}

impl Drop for Alone {
    fn drop(&mut self) {
        ALONE.set(false);
    }
}

/// A context with validation and synchronization validation on (always, in tests).
pub fn context() -> GpuTest {
    context_with(ContextDesc::default())
}

/// `context` with `desc`'s choices (kernel specializations), validation on and the
/// test's device.
pub fn context_with(desc: ContextDesc) -> GpuTest {
    let share = shared();
    GpuTest(
        Context::new(&ContextDesc {
            validation: true,
            device: std::env::var("SPECULUM_TEST_DEVICE").ok(),
            ..desc
        })
        .expect("a Vulkan device with validation layers (run tools/test, which installs them)"),
        share,
    )
}

/// A test's GPU context, which fails the test when it is dropped if the validation
/// layer reported anything in the test's life (wgpu's `#[gpu_test]` idea: no test can
/// forget to check). Locals declared after it are dropped first, so messages from
/// their destruction count too. Derefs to the context.
pub struct GpuTest(Arc<Context>, Option<RwLockReadGuard<'static, ()>>);

impl std::ops::Deref for GpuTest {
    type Target = Arc<Context>;
    fn deref(&self) -> &Arc<Context> {
        &self.0
    }
}

impl Drop for GpuTest {
    fn drop(&mut self) {
        // A test already failing is not failed twice (that would abort the run).
        if !std::thread::panicking() {
            assert_eq!(
                self.0.validation_messages(),
                0,
                "validation messages were reported (see stderr)"
            );
        }
    }
}

/// `n` random G-buffer material ids below `ids`, each `MATERIAL_NONE` (sky) with
/// probability `p_none`.
pub fn random_material_ids(rng: &mut impl rand::Rng, n: usize, p_none: f64, ids: u32) -> Vec<u32> {
    (0..n)
        .map(|_| {
            if rng.random_bool(p_none) {
                speculum::shader_defines::MATERIAL_NONE
            } else {
                rng.random_range(0..ids)
            }
        })
        .collect()
}

/// A random G-buffer of `n` pixels: depths across the view range, unit normals in every
/// direction (facing away included) with random reflectivity in w, and material ids
/// (15% sky).
pub struct RandomGBuffer {
    pub depth: Vec<f32>,
    /// The normals as the GPU reads them (rounded through RGBA16F).
    pub normal: Vec<[f32; 4]>,
    /// The RGBA16F texels to upload.
    pub normal_bytes: Vec<u8>,
    pub material: Vec<u32>,
}

pub fn random_gbuffer(rng: &mut impl rand::Rng, n: usize) -> RandomGBuffer {
    let depth: Vec<f32> = (0..n).map(|_| rng.random_range(0.90..0.9995f32)).collect();
    let normal: Vec<[f32; 4]> = (0..n)
        .map(|_| {
            let v = glam::Vec3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            )
            .normalize_or(glam::Vec3::Y);
            [v.x, v.y, v.z, rng.random_range(0.0..1.0)]
        })
        .collect();
    let normal_bytes = speculum::cpu_ref::f32_to_rgba16f(&normal);
    let normal = speculum::gpu_types::rgba16f_to_f32(&normal_bytes);
    let material = random_material_ids(rng, n, 0.15, 4);
    RandomGBuffer {
        depth,
        normal,
        normal_bytes,
        material,
    }
}

/// `settings`' frame over the built-in `room` (its camera and sun) and its extent.
pub fn room_frame(settings: &speculum::Settings) -> (speculum::gpu_types::FrameUniforms, ash::vk::Extent2D) {
    settings.validate().unwrap();
    let scene = speculum::scene::builtin::room().unwrap();
    let extent = ash::vk::Extent2D {
        width: settings.width,
        height: settings.height,
    };
    (speculum::renderer::frame_uniforms(&scene, settings), extent)
}

/// A G-buffer of `extent` holding `g` (and `albedo`, RGBA8 texels, when given), in
/// `SHADER_READ_ONLY_OPTIMAL`.
pub fn upload_gbuffer(
    ctx: &Arc<Context>,
    extent: ash::vk::Extent2D,
    g: &RandomGBuffer,
    albedo: Option<&[u8]>,
) -> speculum::passes::GBuffer {
    let gb = speculum::passes::GBuffer::new(ctx, extent).unwrap();
    let ro = ash::vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL;
    gb.depth.write(bytemuck::cast_slice(&g.depth), ro).unwrap();
    gb.normal.write(&g.normal_bytes, ro).unwrap();
    gb.material.write(bytemuck::cast_slice(&g.material), ro).unwrap();
    if let Some(a) = albedo {
        gb.albedo.write(a, ro).unwrap();
    }
    gb
}

/// A `size`² D32 shadow map holding `depth`, in `SHADER_READ_ONLY_OPTIMAL`.
pub fn shadow_map_image(ctx: &Arc<Context>, size: u32, depth: &[f32]) -> speculum::vk::Image {
    let map = speculum::vk::Image::new(
        ctx,
        "test.shadow",
        ash::vk::Extent2D {
            width: size,
            height: size,
        },
        ash::vk::Format::D32_SFLOAT,
        ash::vk::ImageUsageFlags::SAMPLED | ash::vk::ImageUsageFlags::TRANSFER_DST,
    )
    .unwrap();
    map.write(
        bytemuck::cast_slice(depth),
        ash::vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
    )
    .unwrap();
    map
}

/// The G-buffer's metallic (the motion target's w) for the four material ids of
/// `random_gbuffer` (a dielectric, a metal and two blends), each texel off by a little
/// (it is per texel), 0 on the sky; written to `gb` (motion 0), and returned as the
/// GPU reads it (rounded through RGBA16F).
pub fn random_metallic(rng: &mut impl rand::Rng, gb: &speculum::passes::GBuffer, material: &[u32]) -> Vec<f32> {
    let texels: Vec<[f32; 4]> = material
        .iter()
        .map(|&id| {
            let m = match id {
                speculum::shader_defines::MATERIAL_NONE => 0.0,
                id => [0.0, 1.0, 0.37, 0.81][id as usize % 4] * rng.random_range(0.9..1.0f32),
            };
            [0.0, 0.0, 0.0, m]
        })
        .collect();
    let bytes = speculum::cpu_ref::f32_to_rgba16f(&texels);
    gb.motion
        .write(&bytes, ash::vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL)
        .unwrap();
    speculum::gpu_types::rgba16f_to_f32(&bytes)
        .iter()
        .map(|t| t[3])
        .collect()
}

/// The frame uniform buffer (binding 0 of the screen-space kernels) holding `frame`.
pub fn frame_ubo(ctx: &Arc<Context>, frame: &speculum::gpu_types::FrameUniforms) -> speculum::vk::Buffer {
    speculum::vk::Buffer::with_data(
        ctx,
        "test.frame",
        ash::vk::BufferUsageFlags::UNIFORM_BUFFER,
        bytemuck::bytes_of(frame),
    )
    .unwrap()
}

/// A deterministic RNG per test, so a failure reproduces.
pub fn rng(seed: u64) -> rand::rngs::StdRng {
    use rand::SeedableRng;
    rand::rngs::StdRng::seed_from_u64(seed)
}

/// A run of the `speculum` binary, the one way tests run it: validation on
/// (`SPECULUM_VALIDATION=1`), in the test's folder when `dir` is given, and killed
/// with a failed test when it outlives its time limit (a hang or an unbounded read
/// fails instead of stalling the suite).
pub struct Speculum {
    cmd: std::process::Command,
    limit: std::time::Duration,
    what: String,
}

/// `speculum ARGS`, to be run with `.run()` (more arguments, a folder, a time limit or
/// environment first, as wanted).
pub fn speculum<S: AsRef<std::ffi::OsStr>>(args: impl IntoIterator<Item = S>) -> Speculum {
    let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_speculum"));
    cmd.env("SPECULUM_VALIDATION", "1");
    let mut run = Speculum {
        cmd,
        limit: std::time::Duration::from_secs(300),
        what: String::new(),
    };
    run = run.args(args);
    run
}

/// What a run printed and how it ended.
pub struct Output {
    /// The exit code (-1 when a signal ended it).
    pub code: i32,
    pub stdout: String,
    pub stderr: String,
}

impl Output {
    pub fn ok(&self) -> bool {
        self.code == 0
    }
}

impl Speculum {
    pub fn arg(mut self, a: impl AsRef<std::ffi::OsStr>) -> Self {
        self.what += &format!(" {}", a.as_ref().to_string_lossy());
        self.cmd.arg(a);
        self
    }

    pub fn args<S: AsRef<std::ffi::OsStr>>(mut self, args: impl IntoIterator<Item = S>) -> Self {
        for a in args {
            self = self.arg(a);
        }
        self
    }

    /// Runs in `dir` (relative paths in the arguments are read there).
    pub fn dir(mut self, dir: &std::path::Path) -> Self {
        self.cmd.current_dir(dir);
        self
    }

    pub fn env(mut self, key: &str, value: impl AsRef<std::ffi::OsStr>) -> Self {
        self.cmd.env(key, value);
        self
    }

    pub fn env_remove(mut self, key: &str) -> Self {
        self.cmd.env_remove(key);
        self
    }

    /// Fails the test when the run takes longer than `limit` (300 s unless set).
    pub fn limit(mut self, limit: std::time::Duration) -> Self {
        self.limit = limit;
        self
    }

    /// Runs to the end (stdin closed), its output read as it comes.
    pub fn run(mut self) -> Output {
        use std::io::Read;
        use std::process::Stdio;
        let _share = shared();
        let mut child = self
            .cmd
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("runs the speculum binary");
        // Both pipes drain on their own threads, so a chatty run cannot block on a full pipe.
        let drain = |mut pipe: Box<dyn Read + Send>| {
            std::thread::spawn(move || {
                let mut bytes = Vec::new();
                let _ = pipe.read_to_end(&mut bytes);
                String::from_utf8_lossy(&bytes).into_owned()
            })
        };
        let stdout = drain(Box::new(child.stdout.take().unwrap()));
        let stderr = drain(Box::new(child.stderr.take().unwrap()));
        let start = std::time::Instant::now();
        let status = loop {
            if let Some(status) = child.try_wait().unwrap() {
                break status;
            }
            if start.elapsed() > self.limit {
                let _ = child.kill();
                let _ = child.wait();
                panic!("speculum{} still running after {:?}", self.what, self.limit);
            }
            std::thread::sleep(std::time::Duration::from_millis(10));
        };
        Output {
            code: status.code().unwrap_or(-1),
            stdout: stdout.join().unwrap(),
            stderr: stderr.join().unwrap(),
        }
    }
}

/// Runs the `speculum` binary with exactly `args` in `dir`; returns (exit code, stderr).
pub fn speculum_in(args: &[&str], dir: &std::path::Path) -> (i32, String) {
    let out = speculum(args).dir(dir).run();
    (out.code, out.stderr)
}

/// The pixel (x right, y down) that world point `w` lands on in a frame rendered with
/// `frame`'s camera.
pub fn pixel_of(frame: &speculum::gpu_types::FrameUniforms, w: glam::Vec3) -> glam::IVec2 {
    use glam::Vec4Swizzles;
    let c = frame.view_proj * w.extend(1.0);
    let ndc = c.xy() / c.w;
    let res = glam::Vec2::new(frame.resolution[0] as f32, frame.resolution[1] as f32);
    ((ndc * 0.5 + 0.5) * res).floor().as_ivec2()
}
