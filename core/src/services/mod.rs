//! The renderer's services: what every technique uses, so no technique holds a copy (the style's rule). Cube
//! and paraboloid shadow-map atlases and their shared draw ([`cube_shadows`]), the scene's light culling and
//! upload ([`lights`], [`light_tiles`]), the suns' shadows ([`directional`]), the VPL gather ([`vpl_gather`]),
//! per-light shadow maps and the per-light shading pass ([`per_light_shadows`], [`shade_pass`]), the overlay
//! drawing ([`overlay`]), the shared bind-group layouts ([`layouts`]), and what the renderer hands a technique
//! each frame ([`context`]). Above the scene, its BVH and the VPLs; below the techniques (`technique/`) and
//! the `Renderer` that drives them (`renderer/`).

pub mod context;
pub mod cube_atlas;
mod cube_draws;
pub mod cube_geometry;
pub mod cube_params;
pub mod cube_shadows;
pub mod directional;
pub mod gpu_data;
pub mod layouts;
pub mod light_tiles;
pub mod lights;
pub mod overlay;
pub mod per_light_shadows;
pub mod shade_pass;
pub mod vpl_gather;
pub mod work_counters;
