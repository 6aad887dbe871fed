//! WGSL sources, loaded from `shaders/` at compile time. A pass's module is its own file composed after the
//! shared files it uses (plain concatenation, no preprocessor). `MODULES` lists every composed module; a test
//! validates each with naga and checks that every `.wgsl` file in `shaders/` is used.

pub const GBUFFER: &str =
    concat!(include_str!("../../shaders/material.wgsl"), include_str!("../../shaders/gbuffer.wgsl"));
pub const SHADOW_DEPTH: &str =
    concat!(include_str!("../../shaders/material.wgsl"), include_str!("../../shaders/shadow_depth.wgsl"));
pub const AMBIENT: &str =
    concat!(include_str!("../../shaders/common.wgsl"), include_str!("../../shaders/ambient.wgsl"));
pub const TONEMAP: &str = concat!(
    include_str!("../../shaders/common.wgsl"),
    include_str!("../../shaders/display.wgsl"),
    include_str!("../../shaders/tonemap.wgsl")
);
pub const EXPOSURE: &str = concat!(
    include_str!("../../shaders/common.wgsl"),
    include_str!("../../shaders/display.wgsl"),
    include_str!("../../shaders/exposure.wgsl")
);
pub const REFERENCE_SHADE: &str = concat!(
    include_str!("../../shaders/common.wgsl"),
    include_str!("../../shaders/light_tiles.wgsl"),
    include_str!("../../shaders/cube_shadow.wgsl"),
    include_str!("../../shaders/reference_shade.wgsl")
);
pub const LIGHTCLUSTER_SHADE: &str = concat!(
    include_str!("../../shaders/common.wgsl"),
    include_str!("../../shaders/light_tiles.wgsl"),
    include_str!("../../shaders/cube_shadow.wgsl"),
    include_str!("../../shaders/lightcluster_shade.wgsl")
);
pub const UNSHADOWED_SHADE: &str = concat!(
    include_str!("../../shaders/common.wgsl"),
    include_str!("../../shaders/light_tiles.wgsl"),
    include_str!("../../shaders/unshadowed_shade.wgsl")
);
pub const LIGHT_TILES_BUILD: &str =
    concat!(include_str!("../../shaders/common.wgsl"), include_str!("../../shaders/light_tiles_build.wgsl"));
pub const RAYTRACE_SHADOW: &str = concat!(
    include_str!("../../shaders/common.wgsl"),
    include_str!("../../shaders/light_tiles.wgsl"),
    include_str!("../../shaders/raytrace_bvh.wgsl"),
    include_str!("../../shaders/raytrace_shadow.wgsl")
);
pub const RAYTRACE_TEST: &str =
    concat!(include_str!("../../shaders/raytrace_bvh.wgsl"), include_str!("../../shaders/raytrace_test.wgsl"));
pub const INSM_TRIANGULATE: &str = include_str!("../../shaders/insm_triangulate.wgsl");
pub const OVERLAY: &str = include_str!("../../shaders/overlay.wgsl");
pub const PARABOLOID_DEPTH: &str = concat!(
    include_str!("../../shaders/vpl_basis.wgsl"),
    include_str!("../../shaders/material.wgsl"),
    include_str!("../../shaders/paraboloid_depth.wgsl")
);
pub const VPL_GATHER_UNSHADOWED: &str = concat!(
    include_str!("../../shaders/common.wgsl"),
    include_str!("../../shaders/vpl_common.wgsl"),
    include_str!("../../shaders/vpl_vis_none.wgsl"),
    include_str!("../../shaders/vpl_gather.wgsl")
);
pub const VPL_GATHER_RAYTRACED: &str = concat!(
    include_str!("../../shaders/common.wgsl"),
    include_str!("../../shaders/raytrace_bvh.wgsl"),
    include_str!("../../shaders/vpl_common.wgsl"),
    include_str!("../../shaders/vpl_vis_raytraced.wgsl"),
    include_str!("../../shaders/vpl_gather.wgsl")
);
pub const VPL_GATHER_PARABOLOID: &str = concat!(
    include_str!("../../shaders/common.wgsl"),
    include_str!("../../shaders/vpl_common.wgsl"),
    include_str!("../../shaders/vpl_basis.wgsl"),
    include_str!("../../shaders/vpl_vis_paraboloid.wgsl"),
    include_str!("../../shaders/vpl_gather.wgsl")
);
pub const VAL_GATHER: &str = concat!(
    include_str!("../../shaders/common.wgsl"),
    include_str!("../../shaders/vpl_common.wgsl"),
    include_str!("../../shaders/vpl_basis.wgsl"),
    include_str!("../../shaders/val_gather.wgsl")
);
pub const VAL_CSSM: &str = include_str!("../../shaders/val_cssm.wgsl");
pub const VAL_KMEANS: &str =
    concat!(include_str!("../../shaders/vpl_basis.wgsl"), include_str!("../../shaders/val_kmeans.wgsl"));
pub const VPL_BLUR: &str =
    concat!(include_str!("../../shaders/common.wgsl"), include_str!("../../shaders/vpl_blur.wgsl"));
pub const PATHTRACE: &str = concat!(
    include_str!("../../shaders/common.wgsl"),
    include_str!("../../shaders/raytrace_bvh.wgsl"),
    include_str!("../../shaders/vpl_basis.wgsl"),
    include_str!("../../shaders/pathtrace.wgsl")
);

pub const FUZZY_KMEANS: &str = include_str!("../../shaders/fuzzy_kmeans.wgsl");
pub const FUZZY_POINTS: &str =
    concat!(include_str!("../../shaders/common.wgsl"), include_str!("../../shaders/fuzzy_points.wgsl"));
pub const FUZZY_VISIBILITY: &str =
    concat!(include_str!("../../shaders/raytrace_bvh.wgsl"), include_str!("../../shaders/fuzzy_visibility.wgsl"));
pub const FUZZY_SHADE: &str = concat!(
    include_str!("../../shaders/common.wgsl"),
    include_str!("../../shaders/vpl_common.wgsl"),
    include_str!("../../shaders/fuzzy_shade.wgsl")
);

/// Every composed shader module: (name, the files it is made of, source).
pub const MODULES: &[(&str, &[&str], &str)] = &[
    ("gbuffer", &["material.wgsl", "gbuffer.wgsl"], GBUFFER),
    ("shadow_depth", &["material.wgsl", "shadow_depth.wgsl"], SHADOW_DEPTH),
    ("ambient", &["common.wgsl", "ambient.wgsl"], AMBIENT),
    ("tonemap", &["common.wgsl", "display.wgsl", "tonemap.wgsl"], TONEMAP),
    ("exposure", &["common.wgsl", "display.wgsl", "exposure.wgsl"], EXPOSURE),
    (
        "reference_shade",
        &["common.wgsl", "light_tiles.wgsl", "cube_shadow.wgsl", "reference_shade.wgsl"],
        REFERENCE_SHADE,
    ),
    ("overlay", &["overlay.wgsl"], OVERLAY),
    ("unshadowed_shade", &["common.wgsl", "light_tiles.wgsl", "unshadowed_shade.wgsl"], UNSHADOWED_SHADE),
    (
        "lightcluster_shade",
        &["common.wgsl", "light_tiles.wgsl", "cube_shadow.wgsl", "lightcluster_shade.wgsl"],
        LIGHTCLUSTER_SHADE,
    ),
    ("light_tiles_build", &["common.wgsl", "light_tiles_build.wgsl"], LIGHT_TILES_BUILD),
    (
        "raytrace_shadow",
        &["common.wgsl", "light_tiles.wgsl", "raytrace_bvh.wgsl", "raytrace_shadow.wgsl"],
        RAYTRACE_SHADOW,
    ),
    ("raytrace_test", &["raytrace_bvh.wgsl", "raytrace_test.wgsl"], RAYTRACE_TEST),
    ("insm_triangulate", &["insm_triangulate.wgsl"], INSM_TRIANGULATE),
    ("paraboloid_depth", &["vpl_basis.wgsl", "material.wgsl", "paraboloid_depth.wgsl"], PARABOLOID_DEPTH),
    (
        "vpl_gather_unshadowed",
        &["common.wgsl", "vpl_common.wgsl", "vpl_vis_none.wgsl", "vpl_gather.wgsl"],
        VPL_GATHER_UNSHADOWED,
    ),
    (
        "vpl_gather_raytraced",
        &["common.wgsl", "raytrace_bvh.wgsl", "vpl_common.wgsl", "vpl_vis_raytraced.wgsl", "vpl_gather.wgsl"],
        VPL_GATHER_RAYTRACED,
    ),
    (
        "vpl_gather_paraboloid",
        &["common.wgsl", "vpl_common.wgsl", "vpl_basis.wgsl", "vpl_vis_paraboloid.wgsl", "vpl_gather.wgsl"],
        VPL_GATHER_PARABOLOID,
    ),
    ("pathtrace", &["common.wgsl", "raytrace_bvh.wgsl", "vpl_basis.wgsl", "pathtrace.wgsl"], PATHTRACE),
    ("vpl_blur", &["common.wgsl", "vpl_blur.wgsl"], VPL_BLUR),
    ("val_kmeans", &["vpl_basis.wgsl", "val_kmeans.wgsl"], VAL_KMEANS),
    ("val_cssm", &["val_cssm.wgsl"], VAL_CSSM),
    ("val_gather", &["common.wgsl", "vpl_common.wgsl", "vpl_basis.wgsl", "val_gather.wgsl"], VAL_GATHER),
    ("fuzzy_kmeans", &["fuzzy_kmeans.wgsl"], FUZZY_KMEANS),
    ("fuzzy_points", &["common.wgsl", "fuzzy_points.wgsl"], FUZZY_POINTS),
    ("fuzzy_visibility", &["raytrace_bvh.wgsl", "fuzzy_visibility.wgsl"], FUZZY_VISIBILITY),
    ("fuzzy_shade", &["common.wgsl", "vpl_common.wgsl", "fuzzy_shade.wgsl"], FUZZY_SHADE),
];

/// Create a shader module from one of the sources above.
pub fn create_module(device: &wgpu::Device, label: &str, source: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}
