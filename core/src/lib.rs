//! ShadowLab's core: scenes, the many-light renderer and its shadow techniques, measurement. No UI code.

pub mod accel;
pub mod compare;
pub mod contract;
pub mod error;
pub mod fingerprint;
pub mod scene;
pub mod services;

pub use error::{GpuError, LayoutError, LoadError};
pub use scene::{Aabb, Camera, Material, Mesh, PointLight, Scene, SceneSource, TextureImage};
pub mod gpu;
pub mod math;
pub mod renderer;
pub mod shaders;
pub mod technique;
pub mod timing;
pub mod vpl;

pub use gpu::GpuContext;
pub use renderer::{AutoExposure, FrameReport, RenderSettings, Renderer, ToneMap};
