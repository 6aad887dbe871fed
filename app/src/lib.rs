//! ShadowLab's app crate: the command line (`cli`) and the interactive egui app (`gui`).

pub mod cli;
pub mod equal_terms;
pub mod figure;
pub mod files;
pub mod gui;
pub mod measure;
pub mod plot;
pub mod rounds;
pub mod rsm_picture;
pub mod sequence;
pub mod tradeoff;
