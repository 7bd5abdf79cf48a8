//! The library's one error type. Binaries wrap it in `anyhow`; every message is one
//! line that names the problem (a file, a value, a limit), never a panic.

use ash::vk;
use std::path::PathBuf;

/// Everything that can go wrong in the library.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A Vulkan call failed; `what` names the call.
    #[error("Vulkan call {what} failed: {result}")]
    Vulkan { what: &'static str, result: vk::Result },
    /// The Vulkan loader (libvulkan.so.1) could not be opened.
    #[error("cannot load the Vulkan loader: {0} (install libvulkan1 and a driver such as mesa-vulkan-drivers)")]
    Loader(String),
    /// No device is usable, or `--device` matched none.
    #[error("{0}")]
    NoDevice(String),
    /// Validation was asked for but the layer is not installed.
    #[error("validation requested but VK_LAYER_KHRONOS_validation is not installed (apt-get install vulkan-validationlayers)")]
    NoValidationLayer,
    /// GPU memory could not be allocated.
    #[error("GPU memory allocation for '{name}' failed: {source}")]
    Allocation {
        name: String,
        #[source]
        source: gpu_allocator::AllocationError,
    },
    /// A settings value is outside what the renderer supports.
    #[error("invalid setting: {0}")]
    Settings(String),
    /// Something the device cannot hold or run: a buffer beyond a range limit, a
    /// dispatch beyond the workgroup-count limit, an image beyond the image limit.
    #[error("{what} needs {size} {unit}, beyond {limit_name} = {limit} on {device}")]
    DeviceLimit {
        what: String,
        size: u64,
        unit: &'static str,
        limit: u64,
        limit_name: &'static str,
        device: String,
    },
    /// A pipeline whose shaders and Rust side disagree (push constants, bindings).
    #[error("{0}")]
    Pipeline(String),
    /// A BVH that cannot be built or traced as asked (no triangles, too many, no BVH).
    #[error("BVH: {0}")]
    Bvh(String),
    /// Inputs that cannot be used together (e.g. images of different sizes).
    #[error("{0}")]
    Input(String),
    /// The demo's window could not be opened or driven (no display, a window-system error).
    #[error("window: {0}")]
    Window(String),
    /// A scene name that no built-in scene has.
    #[error(
        "unknown scene '{name}' (built-in scenes: {known}; or give a path to a .toml scene file or an .obj, .gltf, .glb or .ply model)"
    )]
    UnknownScene { name: String, known: String },
    /// A file that should exist does not, or cannot be read.
    #[error("cannot read {what} '{path}': {source}")]
    Io {
        what: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    /// An OBJ, MTL or texture file that exists but is not valid.
    #[error("invalid {what} '{path}': {detail}")]
    BadAsset {
        what: &'static str,
        path: PathBuf,
        detail: String,
    },
    /// Geometry that cannot be rendered: no triangles, non-finite coordinates.
    #[error("invalid geometry in '{source_name}': {detail}")]
    BadGeometry { source_name: String, detail: String },
    /// A SPIR-V module the reflection code cannot read.
    #[error("SPIR-V module '{0}' is malformed: {1}")]
    Spirv(&'static str, String),
    /// Writing an output file failed.
    #[error("cannot write '{path}': {detail}")]
    Output { path: PathBuf, detail: String },
}

/// Shorthand used throughout the crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Size bounds of what Speculum reads, in bytes. An input beyond its kind's bound is
/// refused before it is read, so an endless or huge input (`/dev/zero`, a wrong path)
/// never fills memory; inputs must be regular files.
pub mod bounds {
    /// Scene files, settings files, sweep files, demo scripts, MTL files.
    pub const TEXT: u64 = 16 << 20;
    /// `tune`'s points CSV and `bench suite` baselines.
    pub const TABLE: u64 = 256 << 20;
    /// OBJ and PLY models (1.4M triangles, about lavapipe's limit, take ~100 MB as OBJ).
    pub const MODEL: u64 = 1 << 30;
    /// Textures and `compare`'s images (encoded).
    pub const IMAGE: u64 = 256 << 20;
    /// `bench lbvh --rays-file` (32 bytes a ray: 32M rays).
    pub const RAYS: u64 = 1 << 30;
}

/// What an existing path that is no regular file is, for messages: "a folder", "a
/// device", "a FIFO", "a socket" (or "not a file").
pub fn file_kind(m: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = m.file_type();
    if t.is_dir() {
        "a folder"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else if t.is_fifo() {
        "a FIFO"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a file"
    }
}

/// Opens file `path` for reading, or an error naming it as `what` ("scene file", ...):
/// it must be a regular file of at most `max` bytes (see `bounds`). The open file and
/// its size; a caller that only checks (a file another reader reads) drops the file.
pub fn open_bounded(path: &std::path::Path, what: &'static str, max: u64) -> Result<(std::fs::File, u64)> {
    let io = |source| Error::Io {
        what,
        path: path.into(),
        source,
    };
    // The kind before opening: opening a FIFO for reading waits for a writer.
    let meta = std::fs::metadata(path).map_err(io)?;
    if !meta.is_file() {
        return Err(refuse(
            path,
            what,
            format!("is {}, not a regular file", file_kind(&meta)),
        ));
    }
    if meta.len() > max {
        return Err(too_big(path, what, meta.len(), max));
    }
    Ok((std::fs::File::open(path).map_err(io)?, meta.len()))
}

fn refuse(path: &std::path::Path, what: &str, why: String) -> Error {
    Error::Input(format!("{what} '{}': {why}", path.display()))
}

fn too_big(path: &std::path::Path, what: &str, n: u64, max: u64) -> Error {
    refuse(
        path,
        what,
        format!("is {n} bytes, more than the {} MiB a {what} may have", max >> 20),
    )
}

/// The bytes of file `path`, bounded and checked as `open_bounded`.
pub fn read_file(path: &std::path::Path, what: &'static str, max: u64) -> Result<Vec<u8>> {
    use std::io::Read;
    let (file, len) = open_bounded(path, what, max)?;
    let mut bytes = Vec::with_capacity(len as usize);
    // Bounded again while reading: the file may grow after its size was read.
    file.take(max + 1).read_to_end(&mut bytes).map_err(|source| Error::Io {
        what,
        path: path.into(),
        source,
    })?;
    if bytes.len() as u64 > max {
        return Err(too_big(path, what, bytes.len() as u64, max));
    }
    Ok(bytes)
}

/// The text of file `path` (UTF-8), bounded as `read_file`.
pub fn read_text(path: &std::path::Path, what: &'static str, max: u64) -> Result<String> {
    String::from_utf8(read_file(path, what, max)?).map_err(|e| Error::Io {
        what,
        path: path.into(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()),
    })
}

/// Attaches the name of the Vulkan call to a `vk::Result`.
pub(crate) trait VkContext<T> {
    fn vk(self, what: &'static str) -> Result<T>;
}

impl<T> VkContext<T> for std::result::Result<T, vk::Result> {
    fn vk(self, what: &'static str) -> Result<T> {
        self.map_err(|result| Error::Vulkan { what, result })
    }
}
