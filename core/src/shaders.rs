//! WGSL sources, loaded at compile time. A pass's module is its own file composed after the shared files it
//! uses (plain concatenation, no preprocessor), with [`wgsl!`](wgsl). The shared modules (`shaders/`)
//! and the renderer services' passes are listed here in [`MODULES`]; a technique's own WGSL lives in its folder
//! (`core/src/technique/<name>/*.wgsl`) and its modules are listed by its registry entry. A test validates
//! every module with naga and checks that every `.wgsl` file of the repository is used by one.

/// A composed WGSL module: its name, the files it is made of (paths from the repository root, in order) and
/// its source.
#[derive(Clone, Copy, Debug)]
pub struct WgslModule {
    pub name: &'static str,
    pub files: &'static [&'static str],
    pub source: &'static str,
}

/// `wgsl!("name", ["shaders/common.wgsl", "core/src/technique/x/shade.wgsl"])`: a [`WgslModule`] made of the
/// given files (paths from the repository root), concatenated in order at compile time.
macro_rules! wgsl {
    ($name:literal, [$($file:literal),+ $(,)?]) => {
        $crate::shaders::WgslModule {
            name: $name,
            files: &[$($file),+],
            source: concat!($(include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/../", $file))),+),
        }
    };
}
pub(crate) use wgsl;

pub const GBUFFER: WgslModule = wgsl!("gbuffer", ["shaders/material.wgsl", "shaders/gbuffer.wgsl"]);
pub const SHADOW_DEPTH: WgslModule = wgsl!("shadow_depth", ["shaders/material.wgsl", "shaders/shadow_depth.wgsl"]);
pub const AMBIENT: WgslModule = wgsl!("ambient", ["shaders/common.wgsl", "shaders/ambient.wgsl"]);
pub const TONEMAP: WgslModule =
    wgsl!("tonemap", ["shaders/common.wgsl", "shaders/display.wgsl", "shaders/tonemap.wgsl"]);
pub const EXPOSURE: WgslModule =
    wgsl!("exposure", ["shaders/common.wgsl", "shaders/display.wgsl", "shaders/exposure.wgsl"]);
pub const LIGHT_TILES_BUILD: WgslModule =
    wgsl!("light_tiles_build", ["shaders/common.wgsl", "shaders/light_tiles_build.wgsl"]);
pub const RAYTRACE_TEST: WgslModule =
    wgsl!("raytrace_test", ["shaders/raytrace_bvh.wgsl", "shaders/raytrace_test.wgsl"]);
pub const OVERLAY: WgslModule = wgsl!("overlay", ["shaders/overlay.wgsl"]);
pub const DEPTH_READBACK: WgslModule = wgsl!("depth_readback", ["shaders/depth_readback.wgsl"]);
pub const PARABOLOID_DEPTH: WgslModule =
    wgsl!("paraboloid_depth", ["shaders/vpl_basis.wgsl", "shaders/material.wgsl", "shaders/paraboloid_depth.wgsl"]);
pub const VPL_GATHER_UNSHADOWED: WgslModule = wgsl!(
    "vpl_gather_unshadowed",
    ["shaders/common.wgsl", "shaders/vpl_common.wgsl", "shaders/vpl_vis_none.wgsl", "shaders/vpl_gather.wgsl"]
);
pub const VPL_GATHER_RAYTRACED: WgslModule = wgsl!(
    "vpl_gather_raytraced",
    [
        "shaders/common.wgsl",
        "shaders/raytrace_bvh.wgsl",
        "shaders/vpl_common.wgsl",
        "shaders/vpl_vis_raytraced.wgsl",
        "shaders/vpl_gather.wgsl"
    ]
);
pub const VPL_GATHER_PARABOLOID: WgslModule = wgsl!(
    "vpl_gather_paraboloid",
    [
        "shaders/common.wgsl",
        "shaders/vpl_common.wgsl",
        "shaders/vpl_basis.wgsl",
        "shaders/vpl_vis_paraboloid.wgsl",
        "shaders/vpl_gather.wgsl"
    ]
);
pub const PER_LIGHT_SHADE: WgslModule = wgsl!(
    "per_light_shade",
    [
        "shaders/common.wgsl",
        "shaders/light_tiles.wgsl",
        "shaders/cube_shadow.wgsl",
        "shaders/per_light_shade.wgsl",
        "shaders/per_light_main.wgsl"
    ]
);
pub const VPL_BLUR: WgslModule = wgsl!("vpl_blur", ["shaders/common.wgsl", "shaders/vpl_blur.wgsl"]);

/// Every shared composed module (the renderer services' passes and the VPL gathers several techniques use).
/// The directional-light service (`services/directional.rs`): visibility by its orthographic map, or by rays.
pub const DIRECTIONAL_SHADOWMAP: WgslModule = wgsl!(
    "directional_shadowmap",
    ["shaders/common.wgsl", "shaders/directional_shadowmap.wgsl", "shaders/directional_light.wgsl"]
);
pub const DIRECTIONAL_TRACED: WgslModule = wgsl!(
    "directional_traced",
    [
        "shaders/common.wgsl",
        "shaders/raytrace_bvh.wgsl",
        "shaders/directional_traced.wgsl",
        "shaders/directional_light.wgsl"
    ]
);

pub const MODULES: &[WgslModule] = &[
    GBUFFER,
    SHADOW_DEPTH,
    AMBIENT,
    TONEMAP,
    EXPOSURE,
    LIGHT_TILES_BUILD,
    RAYTRACE_TEST,
    OVERLAY,
    DEPTH_READBACK,
    PARABOLOID_DEPTH,
    VPL_GATHER_UNSHADOWED,
    VPL_GATHER_RAYTRACED,
    VPL_GATHER_PARABOLOID,
    VPL_BLUR,
    PER_LIGHT_SHADE,
    DIRECTIONAL_SHADOWMAP,
    DIRECTIONAL_TRACED,
];
