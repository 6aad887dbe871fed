//! glTF 2.0 loading with the `gltf` crate.
//!
//! The document is parsed and validated by `gltf`; buffers, images and accessor data are read here rather
//! than with `gltf::import` and the `gltf` reader, because those fail on a single missing image, panic on a
//! few malformed inputs (bad percent-escapes in URIs, accessor strides smaller than the element, mismatched
//! accessor types in debug builds) and do not report which part of the file is broken. Every byte range is
//! bounds-checked here, so a broken file gives a [`LoadError::Gltf`] with the reason.
//!
//! Conventions:
//! - Node transforms are baked into positions and normals (normal matrix = inverse transpose); nodes with a
//!   mirroring transform (negative determinant) get their triangle winding flipped so front faces stay front.
//! - `unit_scale` multiplies world positions, light positions and ranges, and the camera's clip planes.
//! - Base colour factor and emissive are linear; the base colour texture is sRGB. Materials are Lambertian
//!   (metallic/roughness are ignored).
//! - `KHR_lights_punctual` point and spot lights (cone angles as given, direction down the node's -Z) keep their
//!   colour; their intensity is photometric (candela, lm/sr) and becomes the renderer's radiometric intensity
//!   (W/sr, what `PointLight::intensity` is: radiance = albedo/pi x intensity x falloff x cos) through the
//!   luminous efficacy of 683 lm/W ([`LUMENS_PER_WATT`]). A light without a `range` gets the diagonal of the
//!   scene bounds as its range, so it reaches the whole scene while the renderer's windowed falloff still ends
//!   at a finite distance. Directional lights are skipped with a warning.

/// A texture's mapping: its `TEXCOORD_n` set and its `KHR_texture_transform` (offset, rotation, scale).
#[derive(Clone, Copy, Debug, PartialEq)]
struct UvMapping {
    set: u32,
    transform: Option<([f32; 2], f32, [f32; 2])>,
}

impl UvMapping {
    /// The gltf crate parses KHR_texture_transform only on `textureInfo`s; an occlusion texture's is read from
    /// its raw extension JSON, with the extension's defaults.
    fn of_occlusion(info: &gltf::material::OcclusionTexture<'_>) -> UvMapping {
        let Some(t) = info.extension_value("KHR_texture_transform") else {
            return UvMapping { set: info.tex_coord(), transform: None };
        };
        let pair = |key: &str, default: [f32; 2]| {
            t.get(key)
                .and_then(|v| v.as_array())
                .and_then(|a| Some([a.first()?.as_f64()? as f32, a.get(1)?.as_f64()? as f32]))
                .unwrap_or(default)
        };
        let rotation = t.get("rotation").and_then(|v| v.as_f64()).unwrap_or(0.0) as f32;
        let set =
            t.get("texCoord").and_then(|v| v.as_u64()).map_or(info.tex_coord(), |s| s.min(u32::MAX as u64) as u32);
        UvMapping { set, transform: Some((pair("offset", [0.0, 0.0]), rotation, pair("scale", [1.0, 1.0]))) }
    }

    fn of(info: &gltf::texture::Info<'_>) -> UvMapping {
        let t = info.texture_transform();
        UvMapping {
            set: t.as_ref().and_then(|t| t.tex_coord()).unwrap_or_else(|| info.tex_coord()),
            transform: t.map(|t| (t.offset(), t.rotation(), t.scale())),
        }
    }
}

/// The two UV channels a material's primitives get: channel 0 maps the base colour texture (set 0 when it has
/// none), channel 1 the first emissive or occlusion texture mapped differently (another set or another
/// transform); a third mapping falls back to channel 0 with a warning. Decided per material, so every
/// primitive of it agrees.
#[derive(Clone, Debug, PartialEq)]
struct UvChannels {
    base: UvMapping,
    second: Option<UvMapping>,
    emissive_uv1: bool,
    occlusion_uv1: bool,
    /// Textures that fit neither channel: (name, set).
    unmapped: Vec<(&'static str, u32)>,
}

impl UvChannels {
    fn of(material: &gltf::Material<'_>) -> UvChannels {
        let base = material
            .pbr_metallic_roughness()
            .base_color_texture()
            .map_or(UvMapping { set: 0, transform: None }, |i| UvMapping::of(&i));
        let mut c = UvChannels { base, second: None, emissive_uv1: false, occlusion_uv1: false, unmapped: Vec::new() };
        let others = [
            ("emissive", material.emissive_texture().map(|i| UvMapping::of(&i))),
            ("occlusion", material.occlusion_texture().map(|i| UvMapping::of_occlusion(&i))),
        ];
        for (name, mapping) in others {
            let Some(m) = mapping else { continue };
            let on_second = if m == c.base {
                false
            } else if c.second.is_none_or(|s| s == m) {
                c.second = Some(m);
                true
            } else {
                c.unmapped.push((name, m.set));
                false
            };
            match name {
                "emissive" => c.emissive_uv1 = on_second,
                _ => c.occlusion_uv1 = on_second,
            }
        }
        c
    }
}

/// Luminous efficacy (lm/W) of the glTF lights' photometric units: the peak of the photopic curve at 555 nm,
/// the conversion the glTF exporters (Blender's among them) use between watts and candela.
pub const LUMENS_PER_WATT: f32 = 683.0;

use std::collections::{HashMap, HashSet};
use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3, Vec4};
use gltf::mesh::{Mode, Semantic};

use super::gltf_data::{check_glb_header, load_buffers, read_indices, read_vec2, read_vec3, view_bytes, ImageSource};
use super::texture::decode_parallel;
use super::{Aabb, Camera, Material, Mesh, PointLight, Scene, SceneSource};
use crate::error::LoadError;

/// Required extensions that change how geometry or textures are stored; without support the meshes would be
/// garbage or every texture missing, so the file is refused with the extension named, before anything else.
const UNSUPPORTED_GEOMETRY_EXTENSIONS: &[&str] = &[
    "KHR_draco_mesh_compression",
    "EXT_meshopt_compression",
    "KHR_meshopt_compression",
    "KHR_texture_basisu",
    "EXT_texture_webp",
    "EXT_texture_avif",
];

/// Extensions this loader reads (the `gltf` crate's validation does not know every one of them).
const UNDERSTOOD_EXTENSIONS: &[&str] =
    &["KHR_lights_punctual", "KHR_materials_emissive_strength", "KHR_mesh_quantization", "KHR_texture_transform"];

/// Load a `.gltf` (external or embedded buffers) or `.glb` file: every mesh of the default scene with its node
/// transform baked, base colour factor/texture, emissive, and `KHR_lights_punctual` point lights.
pub fn load_gltf(path: &Path, unit_scale: f32) -> Result<Scene, LoadError> {
    let bytes = std::fs::read(path).map_err(|source| match source.kind() {
        std::io::ErrorKind::NotFound => LoadError::NotFound { path: path.to_path_buf() },
        _ => LoadError::Io { path: path.to_path_buf(), source },
    })?;
    // The reading below is bounds-checked, but the `gltf` crate's document accessors still `unwrap` in places
    // that rely on its validation; a file that slips through must not take the program down.
    match std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| load_from_bytes(path, &bytes, unit_scale))) {
        Ok(result) => result,
        Err(panic) => {
            let detail = panic
                .downcast_ref::<String>()
                .map(String::as_str)
                .or_else(|| panic.downcast_ref::<&str>().copied())
                .unwrap_or("unknown error");
            Err(LoadError::Gltf { path: path.to_path_buf(), reason: format!("malformed data ({detail})") })
        }
    }
}

fn load_from_bytes(path: &Path, bytes: &[u8], unit_scale: f32) -> Result<Scene, LoadError> {
    let error = |reason: String| LoadError::Gltf { path: path.to_path_buf(), reason };
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(error("the file is empty".into()));
    }
    check_glb_header(bytes).map_err(error)?;
    let gltf::Gltf { document, blob } =
        gltf::Gltf::from_slice_without_validation(bytes).map_err(|e| error(e.to_string()))?;
    // The extensions first: a Draco or BasisU file is refused by name, not by what validation makes of its
    // accessors without buffer views or its textures without a core source.
    for ext in document.extensions_required() {
        if UNSUPPORTED_GEOMETRY_EXTENSIONS.contains(&ext) {
            return Err(error(format!("the file requires the unsupported extension {ext}")));
        }
    }
    validate(&document).map_err(error)?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let buffers = load_buffers(&document, dir, blob).map_err(error)?;

    let mut loader = Loader {
        document: &document,
        buffers: &buffers,
        dir,
        unit_scale,
        scene: Scene {
            name: path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "gltf".into()),
            source: SceneSource::File { path: path.to_path_buf(), unit_scale },
            meshes: Vec::new(),
            materials: Vec::new(),
            textures: Vec::new(),
            lights: Vec::new(),
            directional: Vec::new(),
            camera: Camera::framing(&Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) }),
            bounds: Aabb::EMPTY,
            warnings: Vec::new(),
        },
        default_material: None,
        lights_without_range: Vec::new(),
        warned_light_limit: false,
        camera: None,
        warned: HashSet::new(),
    };
    for ext in document.extensions_required() {
        if !UNSUPPORTED_GEOMETRY_EXTENSIONS.contains(&ext) && !loader.understands(ext) {
            loader.warn(format!("the file requires extension {ext}, which is not supported; it is ignored"));
        }
    }
    loader.load_materials();
    loader.walk_nodes().map_err(error)?;

    // Lights without a range reach across the whole scene (see the module documentation).
    let bounds = Aabb::from_points(loader.scene.meshes.iter().flat_map(|m| m.positions.iter().copied()));
    let diagonal = if bounds.is_empty() { 0.0 } else { bounds.size().length() };
    let default_range = if diagonal.is_finite() && diagonal > 0.0 { diagonal } else { 1.0 };
    for &i in &loader.lights_without_range {
        loader.scene.lights[i].range = default_range;
    }

    let Loader { mut scene, camera, .. } = loader;
    scene.finalize(path)?;
    scene.camera = camera
        .map(|c| c.complete(&scene.bounds))
        .filter(Camera::is_valid)
        .unwrap_or_else(|| Camera::framing(&scene.bounds));
    Ok(scene)
}

/// `gltf::Gltf::from_slice`'s validation, preceded by the one check it relies on without making it (its
/// POSITION `min`/`max` hook indexes the accessor list unchecked and panics on a bad index).
fn validate(document: &gltf::Document) -> Result<(), String> {
    use gltf::json::validation::{Checked, Validate};
    let root = document.as_json();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            if let Some(index) = primitive.attributes.get(&Checked::Valid(gltf::Semantic::Positions)) {
                if index.value() >= root.accessors.len() {
                    return Err(format!("mesh {m} primitive {p}: POSITION accessor {} does not exist", index.value()));
                }
            }
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |path, error| {
        let path = path().to_string();
        // An extension the crate does not know but this loader reads (KHR_mesh_quantization: integer and
        // normalised attributes, dequantised by the node transforms) is not an error here.
        let understood = path.starts_with("extensionsRequired")
            && root
                .extensions_required
                .get(index_of(&path))
                .is_some_and(|e| UNDERSTOOD_EXTENSIONS.contains(&e.as_str()));
        if !understood {
            errors.push(format!("{path}: {error}"));
        }
    });
    match errors.len() {
        0 => Ok(()),
        n => Err(format!(
            "invalid glTF: {}{}",
            errors.iter().take(3).cloned().collect::<Vec<_>>().join("; "),
            if n > 3 { format!(" (and {} more)", n - 3) } else { String::new() }
        )),
    }
}

/// The index in a validation path like `extensionsRequired[2]` (0 when there is none).
fn index_of(path: &str) -> usize {
    path.rsplit_once('[').and_then(|(_, i)| i.trim_end_matches(']').parse().ok()).unwrap_or(0)
}

/// A perspective camera found in the node tree; `z_far` is `None` for an infinite projection.
struct FileCamera {
    world: Mat4,
    fov_y: f32,
    near: f32,
    z_far: Option<f32>,
}

impl FileCamera {
    fn complete(&self, bounds: &Aabb) -> Camera {
        let (_, orientation, position) = self.world.to_scale_rotation_translation();
        // An infinite far plane is replaced by one just past the farthest corner of the scene.
        let z_far = self.z_far.unwrap_or_else(|| {
            let farthest = (bounds.center() - position).length() + bounds.size().length() * 0.5;
            farthest * 1.5
        });
        Camera { position, orientation: orientation.normalize(), fov_y: self.fov_y, near: self.near, z_far }
    }
}

struct Loader<'a> {
    document: &'a gltf::Document,
    buffers: &'a [Vec<u8>],
    dir: &'a Path,
    unit_scale: f32,
    scene: Scene,
    /// Index of the default material in `scene.materials`, added when a primitive has no material.
    default_material: Option<usize>,
    /// Indices into `scene.lights` of lights whose file gives no range.
    lights_without_range: Vec<usize>,
    /// The light-limit warning was given.
    warned_light_limit: bool,
    camera: Option<FileCamera>,
    warned: HashSet<String>,
}

impl Loader<'_> {
    /// Record a warning once (a mesh instanced by many nodes would repeat its warnings).
    fn warn(&mut self, message: String) {
        if self.warned.insert(message.clone()) {
            log::warn!("{message}");
            self.scene.warnings.push(message);
        }
    }

    fn understands(&self, extension: &str) -> bool {
        UNDERSTOOD_EXTENSIONS.contains(&extension)
    }

    /// One scene material per glTF material, in file order, with their base colour textures.
    fn load_materials(&mut self) {
        // Decode each image used as a base colour texture once, in parallel.
        let mut images: Vec<usize> = Vec::new();
        for material in self.document.materials() {
            let base = material.pbr_metallic_roughness().base_color_texture().map(|i| i.texture());
            let emissive = material.emissive_texture().map(|i| i.texture());
            let occlusion = material.occlusion_texture().map(|i| i.texture());
            for texture in base.into_iter().chain(emissive).chain(occlusion) {
                let image = texture.source().index();
                if !images.contains(&image) {
                    images.push(image);
                }
            }
        }
        let sources: Vec<ImageSource> = images.iter().map(|&i| self.image_source(i)).collect();
        let dir = self.dir;
        let decoded = decode_parallel(&sources, |source| source.load(dir));
        let mut texture_of_image: HashMap<usize, usize> = HashMap::new();
        for (&image, result) in images.iter().zip(decoded) {
            match result {
                Ok(texture) => {
                    self.scene.textures.push(texture);
                    texture_of_image.insert(image, self.scene.textures.len() - 1);
                }
                Err(e) => self.warn(format!("image {image}: {e}; the material is used without its texture")),
            }
        }

        for material in self.document.materials() {
            let pbr = material.pbr_metallic_roughness();
            let texture =
                pbr.base_color_texture().and_then(|info| texture_of_image.get(&info.texture().source().index()));
            let strength = material.emissive_strength().unwrap_or(1.0);
            let emissive_texture =
                material.emissive_texture().and_then(|info| texture_of_image.get(&info.texture().source().index()));
            let occlusion_texture = material.occlusion_texture().and_then(|info| {
                let strength = info.strength();
                texture_of_image
                    .get(&info.texture().source().index())
                    .map(|&t| (t, if strength.is_finite() { strength.clamp(0.0, 1.0) } else { 1.0 }))
            });
            let name_for_warning = material.name().unwrap_or("(unnamed)").to_string();
            let channels = UvChannels::of(&material);
            let alpha_cutoff = match material.alpha_mode() {
                gltf::material::AlphaMode::Opaque => 0.0,
                gltf::material::AlphaMode::Mask => {
                    material.alpha_cutoff().filter(|c| c.is_finite()).unwrap_or(0.5).clamp(0.0, 1.0)
                }
                gltf::material::AlphaMode::Blend => {
                    self.warn(format!(
                        "material {name_for_warning}: alphaMode BLEND is drawn opaque (ShadowLab has no transparency)"
                    ));
                    0.0
                }
            };
            self.scene.materials.push(Material {
                alpha_cutoff,
                name: material
                    .name()
                    .map(str::to_string)
                    .unwrap_or_else(|| format!("material_{}", self.scene.materials.len())),
                base_color: Vec4::from(pbr.base_color_factor()).max(Vec4::ZERO),
                base_color_texture: texture.copied(),
                emissive: (Vec3::from(material.emissive_factor()) * strength).max(Vec3::ZERO),
                emissive_texture: emissive_texture.copied(),
                occlusion_texture,
                emissive_uv1: channels.emissive_uv1,
                occlusion_uv1: channels.occlusion_uv1,
                specular: Vec3::ZERO,
                shininess: Material::default().shininess,
            });
        }
    }

    /// Where image `index` comes from, resolved up front so decoding can run on other threads.
    fn image_source(&self, index: usize) -> ImageSource {
        let json = &self.document.as_json().images[index];
        let name = json.name.clone().or_else(|| json.uri.clone()).unwrap_or_else(|| format!("image_{index}"));
        if let Some(uri) = &json.uri {
            return ImageSource::Uri { name, uri: uri.clone() };
        }
        let bytes = json
            .buffer_view
            .and_then(|view| self.document.views().nth(view.value()))
            .ok_or_else(|| "the image has neither a URI nor a buffer view".to_string())
            .and_then(|view| view_bytes(&view, self.buffers).map(<[u8]>::to_vec));
        ImageSource::Embedded { name, bytes }
    }

    /// Walk the default scene (or the first one, or all root nodes when the file has no scene).
    fn walk_nodes(&mut self) -> Result<(), String> {
        let document = self.document;
        let roots: Vec<gltf::Node> = match document.default_scene().or_else(|| document.scenes().next()) {
            Some(scene) => scene.nodes().collect(),
            None => {
                let mut is_child = vec![false; document.nodes().len()];
                for node in document.nodes() {
                    for child in node.children() {
                        is_child[child.index()] = true;
                    }
                }
                document.nodes().filter(|n| !is_child[n.index()]).collect()
            }
        };
        let mut visited = vec![false; document.nodes().len()];
        // Depth-first with an explicit stack: node trees from files can be deep (or, when broken, cyclic).
        let mut stack: Vec<(gltf::Node, Mat4)> = roots.into_iter().rev().map(|n| (n, Mat4::IDENTITY)).collect();
        while let Some((node, parent)) = stack.pop() {
            if std::mem::replace(&mut visited[node.index()], true) {
                self.warn(format!("node {} is reached twice (a cycle or shared child); skipped", node.index()));
                continue;
            }
            let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
            if let Some(mesh) = node.mesh() {
                self.add_mesh(&node, &mesh, world)?;
            }
            if let Some(light) = node.light() {
                self.add_light(&node, &light, world);
            }
            if let Some(camera) = node.camera() {
                if let (None, gltf::camera::Projection::Perspective(p)) = (&self.camera, camera.projection()) {
                    self.camera = Some(FileCamera {
                        world: Mat4::from_scale(Vec3::splat(self.unit_scale)) * world,
                        fov_y: p.yfov(),
                        near: p.znear() * self.unit_scale,
                        z_far: p.zfar().map(|f| f * self.unit_scale),
                    });
                }
            }
            let children: Vec<gltf::Node> = node.children().collect();
            stack.extend(children.into_iter().rev().map(|child| (child, world)));
        }
        Ok(())
    }

    fn add_light(&mut self, node: &gltf::Node, light: &gltf::khr_lights_punctual::Light, world: Mat4) {
        let name = light.name().or(node.name()).unwrap_or("unnamed").to_string();
        // The renderer's light limit holds for files too: the rest are dropped, once, with a warning.
        let max = crate::scene::layout::MAX_LIGHTS;
        if self.scene.lights.len() >= max {
            if self.scene.lights.len() == max && !self.warned_light_limit {
                self.warned_light_limit = true;
                self.warn(format!("more than {max} lights: the rest are skipped (the limit of every layout)"));
            }
            return;
        }
        // Candela to W/sr; a NaN, infinite or negative intensity (the renderer refuses those) becomes 0.
        let intensity = light.intensity() / LUMENS_PER_WATT;
        let intensity = if intensity.is_finite() && intensity >= 0.0 {
            intensity
        } else {
            self.warn(format!("light '{name}': intensity {} is not a finite value >= 0; 0 used", light.intensity()));
            0.0
        };
        match light.kind() {
            gltf::khr_lights_punctual::Kind::Point => {
                let position = world.transform_point3(Vec3::ZERO) * self.unit_scale;
                let range = light.range().map(|r| r * self.unit_scale);
                if range.is_none() {
                    self.lights_without_range.push(self.scene.lights.len());
                }
                let light = PointLight::new(position, Vec3::from(light.color()), intensity, range.unwrap_or(0.0));
                self.scene.lights.push(light);
            }
            gltf::khr_lights_punctual::Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                let position = world.transform_point3(Vec3::ZERO) * self.unit_scale;
                // A glTF light shines down its node's -Z axis.
                let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z);
                let half_pi = std::f32::consts::FRAC_PI_2;
                let (inner, outer) = (inner_cone_angle, outer_cone_angle);
                let valid =
                    inner.is_finite() && outer.is_finite() && 0.0 <= inner && inner <= outer && outer <= half_pi;
                if !valid {
                    self.warn(format!(
                        "spot light '{name}': cone angles {inner}..{outer} are outside 0 <= inner <= outer <= pi/2; clamped"
                    ));
                }
                let outer = if outer.is_finite() { outer.clamp(0.0, half_pi) } else { std::f32::consts::FRAC_PI_4 };
                let inner = if inner.is_finite() { inner.clamp(0.0, outer) } else { 0.0 };
                let range = light.range().map(|r| r * self.unit_scale);
                if range.is_none() {
                    self.lights_without_range.push(self.scene.lights.len());
                }
                let spot = crate::scene::Spot { direction, inner_angle: inner, outer_angle: outer };
                let light = PointLight::new(position, Vec3::from(light.color()), intensity, range.unwrap_or(0.0))
                    .with_spot(spot);
                self.scene.lights.push(light);
            }
            gltf::khr_lights_punctual::Kind::Directional => {
                let max = crate::scene::MAX_DIRECTIONAL_LIGHTS;
                if self.scene.directional.len() >= max {
                    self.warn(format!("directional light '{name}' skipped: at most {max} directional lights"));
                    return;
                }
                // Lux over the same lumens per watt as the point lights' candela; it shines down -Z.
                let direction = world.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z);
                let light = crate::scene::DirectionalLight {
                    direction,
                    color: Vec3::from(light.color()),
                    illuminance: intensity,
                };
                if light.is_valid() {
                    self.scene.directional.push(light);
                } else {
                    self.warn(format!("directional light '{name}': colour or direction not usable; skipped"));
                }
            }
        }
    }

    /// One texture mapping's UVs of a primitive: its `TEXCOORD_n` with its transform applied (empty when the
    /// primitive has no such set).
    fn read_uvs(&mut self, primitive: &gltf::Primitive, mapping: UvMapping, label: &str) -> Result<Vec<Vec2>, String> {
        let set = mapping.set;
        let mut uvs = match primitive.get(&Semantic::TexCoords(set)) {
            Some(accessor) => {
                read_vec2(&accessor, self.buffers).map_err(|e| format!("{label}, TEXCOORD_{set}: {e}"))?
            }
            None => Vec::new(),
        };
        if let Some(([ox, oy], r, [sx, sy])) = mapping.transform {
            // uv' = T(offset) R(rotation) S(scale) uv, as the extension defines it.
            let (sin, cos) = r.sin_cos();
            if [ox, oy, r, sx, sy].iter().all(|v| v.is_finite()) {
                for uv in &mut uvs {
                    let (u, v) = (uv.x * sx, uv.y * sy);
                    *uv = Vec2::new(cos * u + sin * v + ox, -sin * u + cos * v + oy);
                }
            } else {
                self.warn(format!("{label}: a non-finite KHR_texture_transform is ignored"));
            }
        }
        Ok(uvs)
    }

    fn add_mesh(&mut self, node: &gltf::Node, mesh: &gltf::Mesh, world: Mat4) -> Result<(), String> {
        let mesh_name =
            mesh.name().or(node.name()).map(str::to_string).unwrap_or_else(|| format!("mesh_{}", mesh.index()));
        let to_world = Mat4::from_scale(Vec3::splat(self.unit_scale)) * world;
        let normal_matrix = Mat3::from_mat4(world).inverse().transpose();
        let mirrored = Mat3::from_mat4(world).determinant() < 0.0;
        for primitive in mesh.primitives() {
            let label = format!("mesh '{mesh_name}' primitive {}", primitive.index());
            if primitive.mode() != Mode::Triangles {
                self.warn(format!("{label}: skipped {:?} primitive (only TRIANGLES are supported)", primitive.mode()));
                continue;
            }
            let Some(position_accessor) = primitive.get(&Semantic::Positions) else {
                self.warn(format!("{label}: skipped (no POSITION attribute)"));
                continue;
            };
            let positions =
                read_vec3(&position_accessor, self.buffers).map_err(|e| format!("{label}, POSITION: {e}"))?;
            let vertex_count = positions.len();

            let mut normals = match primitive.get(&Semantic::Normals) {
                Some(accessor) => read_vec3(&accessor, self.buffers).map_err(|e| format!("{label}, NORMAL: {e}"))?,
                None => Vec::new(),
            };
            if !normals.is_empty() && normals.len() != vertex_count {
                self.warn(format!("{label}: NORMAL count differs from POSITION count; normals regenerated"));
                normals.clear();
            }

            let material = primitive.material();
            // KHR_texture_transform: it may override the texcoord set, and its affine map is baked into the UVs.
            let channels = UvChannels::of(&material);
            for (name, set) in &channels.unmapped {
                self.warn(format!(
                    "{label}: the {name} texture's mapping (TEXCOORD_{set}) is a third one; ShadowLab keeps two UV \
                     channels and maps it with the base colour's (TEXCOORD_{})",
                    channels.base.set
                ));
            }
            let uv_set = channels.base.set;
            let mut uvs = self.read_uvs(&primitive, channels.base, &label)?;
            let mut uvs1 = match channels.second {
                Some(m) => self.read_uvs(&primitive, m, &label)?,
                None => Vec::new(),
            };
            if !uvs1.is_empty() && uvs1.len() != vertex_count {
                self.warn(format!("{label}: the second UV set's count differs from POSITION count; ignored"));
                uvs1.clear();
            }
            if !uvs.is_empty() && uvs.len() != vertex_count {
                self.warn(format!("{label}: TEXCOORD_{uv_set} count differs from POSITION count; ignored"));
                uvs.clear();
            }

            let mut indices = match primitive.indices() {
                Some(accessor) => {
                    read_indices(&accessor, self.buffers).map_err(|e| format!("{label}, indices: {e}"))?
                }
                None => (0..vertex_count as u32).collect(),
            };
            if indices.len() % 3 != 0 {
                self.warn(format!(
                    "{label}: index count {} is not a multiple of 3; extra indices dropped",
                    indices.len()
                ));
                indices.truncate(indices.len() / 3 * 3);
            }
            if mirrored {
                for tri in indices.chunks_exact_mut(3) {
                    tri.swap(1, 2);
                }
            }

            let material = match material.index() {
                Some(i) if i < self.document.materials().len() => i,
                _ => *self.default_material.get_or_insert_with(|| {
                    self.scene.materials.push(Material::default());
                    self.scene.materials.len() - 1
                }),
            };
            self.scene.meshes.push(Mesh {
                name: format!("{mesh_name}#{}", primitive.index()),
                positions: positions.into_iter().map(|p| to_world.transform_point3(p)).collect(),
                // A singular transform gives NaN normals, which `Scene::finalize` regenerates from the geometry.
                normals: normals.into_iter().map(|n| (normal_matrix * n).normalize()).collect(),
                uvs,
                uvs1,
                indices,
                material,
            });
        }
        Ok(())
    }
}
