//! The scene model: meshes in world space, materials, textures, point lights, a camera and bounds.
//!
//! Every loader (OBJ, glTF, built-in generators) produces a [`Scene`]; the renderer only ever sees this.
//! All positions are in world space (node transforms are baked at load) and in metres after the unit scale.

pub mod builtin;
pub mod chunks;
mod gltf_data;
pub mod gltf_loader;
pub mod layout;
mod load;
pub mod obj_loader;
pub mod proxy;
pub mod random;
mod shapes;
pub mod texture;

use std::path::{Path, PathBuf};

use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use serde::{Deserialize, Serialize};

use crate::error::LoadError;
pub use crate::math::Aabb;

/// Where a scene came from, so a scene file can re-create it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum SceneSource {
    Builtin(String),
    File { path: PathBuf, unit_scale: f32 },
}

/// A triangle mesh in world space. `normals` and `uvs` have one entry per position.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub name: String,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    /// A second UV channel, for a material's textures on another set than the base colour's (empty: none,
    /// read as zeros).
    pub uvs1: Vec<Vec2>,
    /// Triangle list.
    pub indices: Vec<u32>,
    /// Index into [`Scene::materials`].
    pub material: usize,
}

impl Mesh {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Area-weighted smooth vertex normals, used when a file has none.
    pub fn generate_normals(&mut self) {
        let mut normals = vec![Vec3::ZERO; self.positions.len()];
        for tri in self.indices.chunks_exact(3) {
            let [a, b, c] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
            let n = (self.positions[b] - self.positions[a]).cross(self.positions[c] - self.positions[a]);
            normals[a] += n;
            normals[b] += n;
            normals[c] += n;
        }
        self.normals = normals.into_iter().map(|n| n.try_normalize().unwrap_or(Vec3::Y)).collect();
    }
}

/// A material: base colour (linear RGBA factor times an optional sRGB texture) and emission (linear RGB).
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: String,
    pub base_color: Vec4,
    /// Index into [`Scene::textures`].
    pub base_color_texture: Option<usize>,
    pub emissive: Vec3,
    /// Index into [`Scene::textures`] of an sRGB emissive texture that multiplies `emissive` (glTF
    /// `emissiveTexture`).
    pub emissive_texture: Option<usize>,
    /// Index into [`Scene::textures`] of an ambient-occlusion texture (glTF `occlusionTexture`, red channel,
    /// linear) and its strength: the ambient term is multiplied by `1 + strength * (ao - 1)`.
    pub occlusion_texture: Option<(usize, f32)>,
    /// The emissive / occlusion texture is mapped with the mesh's second UV channel ([`Mesh::uvs1`]) instead
    /// of the base colour's (glTF: it names another `texCoord` set or another `KHR_texture_transform`).
    pub emissive_uv1: bool,
    pub occlusion_uv1: bool,
    /// Blinn-Phong specular colour (linear) and exponent; zero specular means pure Lambert.
    pub specular: Vec3,
    pub shininess: f32,
    /// Fragments whose alpha (base colour times texture) is below this are cut out (glTF `alphaMode` MASK and
    /// `alphaCutoff`; OBJ/MTL cut-outs at 0.5); 0: opaque, alpha ignored (glTF OPAQUE, and BLEND, which is
    /// drawn opaque). Shadow maps alpha-test cut-out chunks too; the ray tracer's BVH does not (the caster stays
    /// whole there).
    pub alpha_cutoff: f32,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: "default".into(),
            base_color: Vec4::new(0.8, 0.8, 0.8, 1.0),
            base_color_texture: None,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            occlusion_texture: None,
            emissive_uv1: false,
            occlusion_uv1: false,
            specular: Vec3::ZERO,
            shininess: 32.0,
            alpha_cutoff: 0.5,
        }
    }
}

/// A decoded texture: RGBA8, sRGB encoded.
#[derive(Clone, Debug)]
pub struct TextureImage {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub rgba8: Vec<u8>,
}

/// The cone of a spot light (glTF `KHR_lights_punctual` semantics): full intensity within `inner_angle` of
/// `direction`, nothing beyond `outer_angle`, a smooth falloff between (the cone's softness).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Spot {
    /// Unit direction the spot points to.
    pub direction: Vec3,
    /// Half-angle of full intensity, radians, `0 <= inner <= outer`.
    pub inner_angle: f32,
    /// Half-angle of the cone, radians, at most pi/2.
    pub outer_angle: f32,
}

impl Spot {
    /// A spot aimed from `position` at `target` with the cone's half-angle and its soft fraction (0: hard edge).
    pub fn aimed(position: Vec3, target: Vec3, outer_angle: f32, softness: f32) -> Spot {
        let outer = outer_angle.clamp(0.0, std::f32::consts::FRAC_PI_2);
        Spot {
            direction: (target - position).normalize_or(Vec3::NEG_Y),
            inner_angle: outer * (1.0 - softness.clamp(0.0, 1.0)),
            outer_angle: outer,
        }
    }

    pub fn is_valid(&self) -> bool {
        self.direction.is_finite()
            && (self.direction.length() - 1.0).abs() < 1e-3
            && self.inner_angle.is_finite()
            && self.outer_angle.is_finite()
            && 0.0 <= self.inner_angle
            && self.inner_angle <= self.outer_angle
            && self.outer_angle <= std::f32::consts::FRAC_PI_2 + 1e-6
    }

    /// `(scale, offset)` of the cone's falloff: factor = saturate(cos(angle) * scale + offset)^2 (glTF's
    /// reference form; a zero-width falloff is a hard edge).
    pub fn scale_offset(&self) -> (f32, f32) {
        let cos_outer = self.outer_angle.cos();
        let cos_inner = self.inner_angle.cos();
        let scale = 1.0 / (cos_inner - cos_outer).max(1e-4);
        (scale, -cos_outer * scale)
    }

    /// The cone's factor towards the unit direction `dir` (from the light).
    pub fn factor(&self, dir: Vec3) -> f32 {
        let (scale, offset) = self.scale_offset();
        let t = (dir.dot(self.direction) * scale + offset).clamp(0.0, 1.0);
        t * t
    }
}

/// Most directional lights a scene keeps (the rest are dropped by the loader with a warning).
pub const MAX_DIRECTIONAL_LIGHTS: usize = 4;

/// A light at infinity: parallel rays along `direction` with irradiance `illuminance` (W/m² in the renderer's
/// units: glTF's lux over the loader's lumens per watt) on a surface facing it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DirectionalLight {
    /// The direction the light travels (unit length): from the light towards the scene.
    pub direction: Vec3,
    /// Linear RGB colour.
    pub color: Vec3,
    pub illuminance: f32,
}

impl DirectionalLight {
    /// True when every field is finite, the direction is not zero and the illuminance and colour are >= 0.
    pub fn is_valid(&self) -> bool {
        self.direction.is_finite()
            && self.direction.length_squared() > 1e-12
            && self.color.is_finite()
            && self.color.min_element() >= 0.0
            && self.illuminance.is_finite()
            && self.illuminance >= 0.0
    }
}

/// The direction of travel of a sun's light from the sun's azimuth (degrees from -Z towards +X) and elevation
/// (degrees above the horizon, +Y up): the convention of the app's Lights panel and the CLI's `--sun`.
pub fn sun_direction(azimuth_deg: f32, elevation_deg: f32) -> Vec3 {
    let (az, el) = (azimuth_deg.to_radians(), elevation_deg.to_radians());
    -Vec3::new(el.cos() * az.sin(), el.sin(), -el.cos() * az.cos())
}

/// The azimuth and elevation (degrees) of the sun a light travelling along `direction` comes from (the inverse
/// of [`sun_direction`]).
pub fn sun_angles(direction: Vec3) -> (f32, f32) {
    let s = -direction.normalize_or(Vec3::NEG_Y);
    (s.x.atan2(-s.z).to_degrees(), s.y.clamp(-1.0, 1.0).asin().to_degrees())
}

/// A point light, omnidirectional or a spot. Radiance falls off smoothly to zero at `range` (the papers' `L_att`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointLight {
    pub position: Vec3,
    /// Linear RGB colour.
    pub color: Vec3,
    pub intensity: f32,
    /// Attenuation range `L_att` in world units: the light contributes nothing beyond it.
    pub range: f32,
    /// The cone when the light is a spot light.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spot: Option<Spot>,
}

impl PointLight {
    pub fn new(position: Vec3, color: Vec3, intensity: f32, range: f32) -> Self {
        PointLight { position, color, intensity, range, spot: None }
    }
    /// The same light as a spot with this cone.
    pub fn with_spot(self, spot: Spot) -> Self {
        PointLight { spot: Some(spot), ..self }
    }
    /// True when every field is finite and range/intensity (and the cone) are usable.
    pub fn is_valid(&self) -> bool {
        self.position.is_finite()
            && self.color.is_finite()
            && self.intensity.is_finite()
            && self.range.is_finite()
            && self.range > 0.0
            && self.intensity >= 0.0
            && self.color.min_element() >= 0.0
            && self.spot.is_none_or(|s| s.is_valid())
    }
    /// The spot cone's factor towards the unit direction `dir` from the light (1 for omnidirectional lights).
    pub fn cone_factor(&self, dir: Vec3) -> f32 {
        self.spot.map_or(1.0, |s| s.factor(dir))
    }
}

/// The light falloff, shared by the shaders (`common.wgsl: attenuation`) and the tests:
/// a windowed inverse square, `saturate(1 - (d/L_att)^4)^2 / (1 + d^2)`, which is exactly zero at `L_att`.
pub fn attenuation(distance: f32, range: f32) -> f32 {
    if distance >= range {
        return 0.0;
    }
    let r = distance / range;
    let window = (1.0 - r * r * r * r).clamp(0.0, 1.0);
    window * window / (1.0 + distance * distance)
}

/// A perspective camera. `orientation` rotates the camera's local axes (looking down -Z, +Y up) into world.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Camera {
    pub position: Vec3,
    pub orientation: Quat,
    /// Vertical field of view in radians.
    pub fov_y: f32,
    pub near: f32,
    /// Far plane; also the `z_far` of LightCluster's view-adaptive clustering.
    pub z_far: f32,
}

impl Camera {
    pub fn look_at(position: Vec3, target: Vec3, fov_y: f32, near: f32, z_far: f32) -> Camera {
        let forward = (target - position).try_normalize().unwrap_or(Vec3::NEG_Z);
        // A view matrix looking at target, inverted, gives the camera's world orientation.
        let up = if forward.abs().dot(Vec3::Y) > 0.999 { Vec3::Z } else { Vec3::Y };
        let view = crate::math::look_to_rh(position, forward, up);
        let (_, rot, _) = view.inverse().to_scale_rotation_translation();
        Camera { position, orientation: rot, fov_y, near, z_far }
    }
    pub fn forward(&self) -> Vec3 {
        self.orientation * Vec3::NEG_Z
    }
    pub fn up(&self) -> Vec3 {
        self.orientation * Vec3::Y
    }
    pub fn right(&self) -> Vec3 {
        self.orientation * Vec3::X
    }
    pub fn view_from_world(&self) -> Mat4 {
        crate::math::look_to_rh(self.position, self.forward(), self.up())
    }
    /// Right-handed perspective with wgpu's 0..1 depth range.
    pub fn clip_from_view(&self, aspect: f32) -> Mat4 {
        crate::math::perspective_rh(self.fov_y, aspect, self.near, self.z_far)
    }
    pub fn clip_from_world(&self, aspect: f32) -> Mat4 {
        self.clip_from_view(aspect) * self.view_from_world()
    }
    /// A camera that sees all of `bounds` from the front (+Z side), slightly above.
    pub fn framing(bounds: &Aabb) -> Camera {
        Camera::framing_from(bounds, Vec3::Z)
    }
    /// A camera that sees all of `bounds` from the side `side` (a horizontal unit vector), slightly above.
    pub fn framing_from(bounds: &Aabb, side: Vec3) -> Camera {
        let c = bounds.center();
        let radius = (bounds.size().length() * 0.5).max(1e-3);
        let fov_y = 50f32.to_radians();
        let dist = radius / (fov_y * 0.5).tan();
        let pos = c + Vec3::new(0.0, radius * 0.25, 0.0) + side * dist;
        Camera::look_at(pos, c, fov_y, (dist - radius).max(dist * 1e-3).max(1e-3) * 0.05, dist + radius * 2.0)
    }
    pub fn is_valid(&self) -> bool {
        self.position.is_finite()
            && self.orientation.is_finite()
            && self.fov_y.is_finite()
            && self.fov_y > 0.0
            && self.fov_y < std::f32::consts::PI
            && self.near > 0.0
            && self.z_far > self.near
            && self.z_far.is_finite()
    }
}

/// A loaded scene, ready for the renderer.
#[derive(Clone, Debug)]
pub struct Scene {
    pub name: String,
    pub source: SceneSource,
    pub meshes: Vec<Mesh>,
    pub materials: Vec<Material>,
    pub textures: Vec<TextureImage>,
    pub lights: Vec<PointLight>,
    /// Lights at infinity (a glTF sun): shaded by the renderer's directional-light service for every direct
    /// technique (`services/directional.rs`, a layer above the scene), at most [`MAX_DIRECTIONAL_LIGHTS`].
    pub directional: Vec<DirectionalLight>,
    pub camera: Camera,
    pub bounds: Aabb,
    /// Recoverable problems met while loading (missing MTL, missing texture, ...), for the user to see.
    pub warnings: Vec<String>,
}

impl Scene {
    /// Whether the scene's camera is the loaders' framing of its bounds (the model brought no camera).
    pub fn camera_is_framing(&self) -> bool {
        self.camera == Camera::framing(&self.bounds)
    }

    pub fn triangle_count(&self) -> usize {
        self.meshes.iter().map(Mesh::triangle_count).sum()
    }

    /// Recompute `bounds` from the meshes.
    pub fn update_bounds(&mut self) {
        let mut b = Aabb::EMPTY;
        for m in &self.meshes {
            // Only finite points: a vertex no triangle uses may still hold inf (a file with `1e39` in it).
            for &p in m.positions.iter().filter(|p| p.is_finite()) {
                b.extend(p);
            }
        }
        if b.is_empty() {
            b = Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) };
        }
        self.bounds = b;
    }

    /// Finish a freshly loaded scene: drop degenerate/NaN triangles, generate missing normals, compute bounds.
    /// Loaders call this last. Returns an error when no triangle is left.
    pub fn finalize(&mut self, path_for_errors: &Path) -> Result<(), LoadError> {
        let material_count = self.materials.len();
        for mesh in &mut self.meshes {
            let n = mesh.positions.len();
            if mesh.material >= material_count {
                mesh.material = 0;
            }
            // Drop triangles with out-of-range indices or non-finite positions.
            let before = mesh.indices.len() / 3;
            let positions = &mesh.positions;
            let kept: Vec<u32> = mesh
                .indices
                .chunks_exact(3)
                .filter(|t| t.iter().all(|&i| (i as usize) < n && positions[i as usize].is_finite()))
                .flatten()
                .copied()
                .collect();
            if kept.len() / 3 != before {
                self.warnings.push(format!(
                    "mesh '{}': dropped {} triangles with invalid indices or non-finite positions",
                    mesh.name,
                    before - kept.len() / 3
                ));
            }
            mesh.indices = kept;
            if mesh.uvs.len() != n {
                mesh.uvs = vec![Vec2::ZERO; n];
            }
            if !mesh.uvs1.is_empty() && mesh.uvs1.len() != n {
                mesh.uvs1.clear();
            }
            for uv in &mut mesh.uvs1 {
                if !uv.is_finite() {
                    *uv = Vec2::ZERO;
                }
            }
            let normals_ok = mesh.normals.len() == n && mesh.normals.iter().all(|v| v.is_finite());
            if !normals_ok {
                mesh.generate_normals();
            } else {
                for v in &mut mesh.normals {
                    *v = v.try_normalize().unwrap_or(Vec3::Y);
                }
            }
            for uv in &mut mesh.uvs {
                if !uv.is_finite() {
                    *uv = Vec2::ZERO;
                }
            }
        }
        self.meshes.retain(|m| !m.indices.is_empty());
        if self.meshes.is_empty() {
            return Err(LoadError::InvalidData {
                path: path_for_errors.to_path_buf(),
                reason: "the file contains no triangles".into(),
            });
        }
        if self.materials.is_empty() {
            self.materials.push(Material::default());
        }
        self.lights.retain(PointLight::is_valid);
        self.update_bounds();
        Ok(())
    }
}
