//! Typed errors of the core. The app turns them into friendly messages; the core never panics on user input.

use std::path::PathBuf;

/// Loading a scene file (OBJ, glTF) failed.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    #[error("{path}: file not found")]
    NotFound { path: PathBuf },
    #[error("{path}: cannot read: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("{path}: unsupported file type (expected .obj, .gltf or .glb)")]
    UnsupportedFormat { path: PathBuf },
    #[error("{path}: broken OBJ file: {reason}")]
    Obj { path: PathBuf, reason: String },
    #[error("{path}: broken glTF file: {reason}")]
    Gltf { path: PathBuf, reason: String },
    #[error("{path}: {reason}")]
    InvalidData { path: PathBuf, reason: String },
    #[error("unknown built-in scene '{name}' (choose one of: {choices})")]
    UnknownBuiltin { name: String, choices: String },
    #[error("invalid unit scale {scale} (must be a finite number > 0)")]
    InvalidScale { scale: f32 },
}

/// A light layout spec (`random:1024:1.5:7`, `circles:10:8:7`, ...) could not be parsed or applied.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum LayoutError {
    #[error("invalid light layout '{spec}': {reason}")]
    Invalid { spec: String, reason: String },
    #[error("light layout '{spec}' asks for {count} lights; the limit is {max}")]
    TooManyLights { spec: String, count: usize, max: usize },
    #[error("scene '{scene}' has no paper light layout (paper layouts exist for: {known})")]
    NoPaperLayout { scene: String, known: String },
}

/// Creating or using the GPU failed.
#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error("no GPU adapter found (on a machine without a GPU install Mesa lavapipe: apt-get install mesa-vulkan-drivers libvulkan1)")]
    NoAdapter,
    #[error("the GPU adapter {0} has no compute shaders, which ShadowLab needs (Vulkan, Metal, DirectX 12, or OpenGL 4.3 and later)")]
    NoCompute(String),
    #[error("the GPU adapter refused to create a device: {0}")]
    RequestDevice(String),
    #[error("GPU error: {0}")]
    Validation(String),
    #[error("the GPU ran out of memory: {0} (lower the image size, shadow-map resolution or batch memory)")]
    OutOfMemory(String),
    #[error("reading back a GPU buffer failed: {0}")]
    Readback(String),
    #[error("invalid render settings: {0}")]
    InvalidSettings(String),
    #[error("the GPU device was lost ({0}): nothing more can be drawn with it")]
    DeviceLost(String),
}
