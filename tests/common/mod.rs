//! Shared test helpers: a validated context that checks for validation messages when
//! dropped, random inputs, the binary runner.
#![allow(dead_code)]

pub mod figure;
pub mod showcase;

use speculum::vk::{Context, ContextDesc};
use std::cell::RefCell;
use std::rc::{Rc, Weak};
use std::sync::{Arc, RwLock, RwLockReadGuard, RwLockWriteGuard};

/// A machine tests share: held shared by every GPU context and every run of the binary
/// (`share`), alone by a test whose assertions read timings (`alone`), so no other test's
/// threads preempt lavapipe's between two timestamps. (In one test binary the harness
/// runs tests of every module side by side, each on its own thread.)
///
/// A thread's shared holds are one hold: a thread that holds the machine and asks again
/// (a test holding `context()` that runs the binary) gets the same hold. std's `RwLock`
/// would take a second read, and a second read waits behind a writer already queued: a
/// thread holding a read that asks for another while an `alone()` test waits would stall
/// the two, and with them every test after (the first GPU run's stalled suite).
pub struct Machine(RwLock<()>);

/// A shared hold; the machine is released when the thread's last one drops.
pub type Share = Rc<RwLockReadGuard<'static, ()>>;

thread_local! {
    /// The machines this thread holds alone (by address): what it starts needs no share.
    static ALONE: RefCell<Vec<usize>> = const { RefCell::new(Vec::new()) };
    /// This thread's shared hold of each machine it holds shared, while any holder lives.
    static HELD: RefCell<Vec<(usize, Weak<RwLockReadGuard<'static, ()>>)>> =
        const { RefCell::new(Vec::new()) };
}

impl Machine {
    pub const fn new() -> Self {
        Self(RwLock::new(()))
    }

    fn key(&'static self) -> usize {
        self as *const Self as usize
    }

    /// This thread's shared hold (the one it has, or a new one), or none while this
    /// thread holds the machine alone.
    pub fn share(&'static self) -> Option<Share> {
        let key = self.key();
        if ALONE.with_borrow(|a| a.contains(&key)) {
            return None;
        }
        HELD.with_borrow_mut(|held| {
            held.retain(|(_, w)| w.strong_count() > 0);
            if let Some(hold) = held.iter().find(|(k, _)| *k == key).and_then(|(_, w)| w.upgrade()) {
                return Some(hold);
            }
            let hold = Rc::new(self.0.read().unwrap_or_else(|e| e.into_inner()));
            held.push((key, Rc::downgrade(&hold)));
            Some(hold)
        })
    }

    /// The machine to this thread alone while the guard lives. Asked while this thread
    /// holds it shared, it would wait for itself: that is a test's mistake, and fails it.
    pub fn alone(&'static self) -> Alone {
        let key = self.key();
        let sharing = HELD.with_borrow(|h| h.iter().any(|(k, w)| *k == key && w.strong_count() > 0));
        assert!(
            !sharing,
            "alone() asked while this test holds the machine shared (a context or a run)"
        );
        let guard = self.0.write().unwrap_or_else(|e| e.into_inner());
        ALONE.with_borrow_mut(|a| a.push(key));
        Alone(guard, key)
    }
}

/// The machine the tests share.
static MACHINE: Machine = Machine::new();

/// A shared hold on the machine, or none while this thread holds it alone.
fn shared() -> Option<Share> {
    MACHINE.share()
}

/// A shared hold on the machine for what a test runs itself (another program that
/// renders), or none while this thread holds it alone.
pub fn hold_shared() -> Option<Share> {
    shared()
}

/// A machine to one test alone while the guard lives.
pub struct Alone(#[allow(dead_code)] RwLockWriteGuard<'static, ()>, usize);

/// The machine to this test alone while the guard lives (no other test's GPU context
/// or binary run side by side): for tests whose assertions read timings.
pub fn alone() -> Alone {
    MACHINE.alone()
}

impl Drop for Alone {
    fn drop(&mut self) {
        let key = self.1;
        ALONE.with_borrow_mut(|a| a.retain(|k| *k != key));
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
pub struct GpuTest(Arc<Context>, Option<Share>);

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
