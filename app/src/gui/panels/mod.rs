//! The panels around the 3D view.

pub mod technique;

pub use technique::*;
