//! The mesh-building kit of the built-in scenes: a scene builder (meshes by material), placement, and shapes
//! (rectangles, boxes, cylinders, spheres, tori, arches) with outward normals and UVs.

use std::f32::consts::{PI, TAU};

use glam::{Affine3A, Quat, Vec2, Vec3};

use super::{Aabb, Camera, Material, Mesh, PointLight, Scene, SceneSource};

/// Collects materials and meshes; one mesh per named part (walls, columns, ...), each with one material.
pub(super) struct SceneBuilder {
    pub(super) materials: Vec<Material>,
    pub(super) meshes: Vec<Mesh>,
}

impl SceneBuilder {
    pub(super) fn new() -> Self {
        SceneBuilder { materials: Vec::new(), meshes: Vec::new() }
    }

    /// A Lambertian material, with a Blinn-Phong highlight when `specular` > 0.
    pub(super) fn material(&mut self, name: &str, rgb: Vec3, specular: f32, shininess: f32) -> usize {
        self.materials.push(Material {
            name: name.into(),
            base_color: rgb.extend(1.0),
            base_color_texture: None,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            occlusion_texture: None,
            specular: Vec3::splat(specular),
            shininess,
            alpha_cutoff: 0.0,
            ..Material::default()
        });
        self.materials.len() - 1
    }

    /// A material that glows (candle wax, lamp shades): emission is only seen, it lights nothing.
    pub(super) fn emissive_material(&mut self, name: &str, rgb: Vec3, emissive: Vec3) -> usize {
        let id = self.material(name, rgb, 0.0, 1.0);
        self.materials[id].emissive = emissive;
        id
    }

    /// The mesh called `name`, created with `material` on first use.
    pub(super) fn mesh(&mut self, name: &str, material: usize) -> &mut Mesh {
        let index = match self.meshes.iter().position(|m| m.name == name) {
            Some(i) => i,
            None => {
                self.meshes.push(Mesh { name: name.into(), material, ..Mesh::default() });
                self.meshes.len() - 1
            }
        };
        &mut self.meshes[index]
    }

    pub(super) fn finish(self, name: &str, lights: Vec<PointLight>, camera: Camera) -> Scene {
        Scene {
            name: name.into(),
            source: SceneSource::Builtin(name.into()),
            meshes: self.meshes,
            materials: self.materials,
            textures: Vec::new(),
            lights,
            directional: Vec::new(),
            camera,
            // `finalize` computes the bounds.
            bounds: Aabb::EMPTY,
            warnings: Vec::new(),
        }
    }
}

/// A placement: rotation about +Y by `yaw` radians, then a translation.
pub(super) fn place(position: Vec3, yaw: f32) -> Affine3A {
    Affine3A::from_rotation_translation(Quat::from_rotation_y(yaw), position)
}

// ---------------------------------------------------------------------------------------------------------------
// Primitives. Each takes local-space geometry and a rigid transform (rotation + translation, so normals
// transform like directions).
// ---------------------------------------------------------------------------------------------------------------

/// Append a vertex in local space; returns its index.
pub(super) fn vertex(mesh: &mut Mesh, xf: &Affine3A, p: Vec3, n: Vec3, uv: Vec2) -> u32 {
    mesh.positions.push(xf.transform_point3(p));
    mesh.normals.push(xf.transform_vector3(n).normalize_or(Vec3::Y));
    mesh.uvs.push(uv);
    (mesh.positions.len() - 1) as u32
}

/// Append a triangle, wound counter-clockwise as seen from the side its vertex normals point to. Deriving the
/// winding from the normals keeps every primitive consistent; zero-area triangles (sphere poles, arches whose
/// opening touches the outline) are skipped.
pub(super) fn triangle(mesh: &mut Mesh, a: u32, b: u32, c: u32) {
    let [pa, pb, pc] = [a, b, c].map(|i| mesh.positions[i as usize]);
    let geometric = (pb - pa).cross(pc - pa);
    if geometric.length_squared() < 1e-14 {
        return;
    }
    let shading: Vec3 = [a, b, c].iter().map(|&i| mesh.normals[i as usize]).sum();
    if geometric.dot(shading) >= 0.0 {
        mesh.indices.extend([a, b, c]);
    } else {
        mesh.indices.extend([a, c, b]);
    }
}

/// A quad `a b c d` (in order around its outline) as two triangles.
pub(super) fn quad(mesh: &mut Mesh, [a, b, c, d]: [u32; 4]) {
    triangle(mesh, a, b, c);
    triangle(mesh, a, c, d);
}

/// A flat rectangle from `origin` spanned by `u` and `v`, facing `normal`; UVs in metres.
pub(super) fn add_rect(mesh: &mut Mesh, xf: &Affine3A, origin: Vec3, u: Vec3, v: Vec3, normal: Vec3) {
    let (lu, lv) = (u.length(), v.length());
    let corners = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
    let ids = corners.map(|(s, t)| vertex(mesh, xf, origin + u * s + v * t, normal, Vec2::new(s * lu, t * lv)));
    quad(mesh, ids);
}

/// A box centred at `center` with half extents `half`, turned by `yaw` about +Y. Flat per-face normals.
pub(super) fn add_box(mesh: &mut Mesh, center: Vec3, half: Vec3, yaw: f32) {
    let xf = place(center, yaw);
    let h = half;
    // For each face: its normal and two edge directions (scaled by the half extents) spanning it.
    let faces = [
        (Vec3::X, Vec3::Z * h.z, Vec3::Y * h.y),
        (Vec3::NEG_X, Vec3::Z * h.z, Vec3::Y * h.y),
        (Vec3::Y, Vec3::X * h.x, Vec3::Z * h.z),
        (Vec3::NEG_Y, Vec3::X * h.x, Vec3::Z * h.z),
        (Vec3::Z, Vec3::X * h.x, Vec3::Y * h.y),
        (Vec3::NEG_Z, Vec3::X * h.x, Vec3::Y * h.y),
    ];
    for (n, u, v) in faces {
        let face_center = n * h;
        add_rect(mesh, &xf, face_center - u - v, u * 2.0, v * 2.0, n);
    }
}

/// An axis-aligned box from its min and max corners.
pub(super) fn add_block(mesh: &mut Mesh, min: Vec3, max: Vec3) {
    add_box(mesh, (min + max) * 0.5, (max - min) * 0.5, 0.0);
}

/// A vertical capped cylinder standing on `base`, smooth sides, flat caps.
pub(super) fn add_cylinder(mesh: &mut Mesh, base: Vec3, radius: f32, height: f32, segments: u32) {
    let xf = place(base, 0.0);
    let ring = |i: u32| {
        let a = TAU * i as f32 / segments as f32;
        Vec3::new(a.cos(), 0.0, a.sin())
    };
    // Sides: the seam vertex is duplicated so U runs 0..circumference.
    let mut previous: Option<(u32, u32)> = None;
    for i in 0..=segments {
        let dir = ring(i);
        let u = radius * TAU * i as f32 / segments as f32;
        let bottom = vertex(mesh, &xf, dir * radius, dir, Vec2::new(u, 0.0));
        let top = vertex(mesh, &xf, dir * radius + Vec3::Y * height, dir, Vec2::new(u, height));
        if let Some((pb, pt)) = previous {
            quad(mesh, [pb, bottom, top, pt]);
        }
        previous = Some((bottom, top));
    }
    for (y, normal) in [(height, Vec3::Y), (0.0, Vec3::NEG_Y)] {
        let center = vertex(mesh, &xf, Vec3::Y * y, normal, Vec2::ZERO);
        let rim: Vec<u32> = (0..segments)
            .map(|i| {
                let p = ring(i) * radius;
                vertex(mesh, &xf, p + Vec3::Y * y, normal, Vec2::new(p.x, p.z))
            })
            .collect();
        for i in 0..rim.len() {
            triangle(mesh, center, rim[i], rim[(i + 1) % rim.len()]);
        }
    }
}

/// A UV sphere with smooth normals.
pub(super) fn add_sphere(mesh: &mut Mesh, center: Vec3, radius: f32, segments: u32, rings: u32) {
    let xf = place(center, 0.0);
    let columns = segments + 1;
    let first = mesh.positions.len() as u32;
    for r in 0..=rings {
        let polar = PI * r as f32 / rings as f32;
        for s in 0..=segments {
            let azimuth = TAU * s as f32 / segments as f32;
            let n = Vec3::new(polar.sin() * azimuth.cos(), polar.cos(), polar.sin() * azimuth.sin());
            let uv = Vec2::new(azimuth * radius, polar * radius);
            vertex(mesh, &xf, n * radius, n, uv);
        }
    }
    for r in 0..rings {
        for s in 0..segments {
            let a = first + r * columns + s;
            quad(mesh, [a, a + 1, a + 1 + columns, a + columns]);
        }
    }
}

/// A torus lying in the horizontal plane around `center`: a ring of radius `major`, tube radius `minor`.
pub(super) fn add_torus(mesh: &mut Mesh, center: Vec3, major: f32, minor: f32, segments: u32, sides: u32) {
    let xf = place(center, 0.0);
    let columns = sides + 1;
    let first = mesh.positions.len() as u32;
    for s in 0..=segments {
        let around = TAU * s as f32 / segments as f32;
        let dir = Vec3::new(around.cos(), 0.0, around.sin());
        for t in 0..=sides {
            let tube = TAU * t as f32 / sides as f32;
            let n = dir * tube.cos() + Vec3::Y * tube.sin();
            let p = dir * major + n * minor;
            vertex(mesh, &xf, p, n, Vec2::new(around * major, tube * minor));
        }
    }
    for s in 0..segments {
        for t in 0..sides {
            let a = first + s * columns + t;
            quad(mesh, [a, a + 1, a + 1 + columns, a + columns]);
        }
    }
}

/// An arch: a block spanning `outer` along local X from `spring` up to `top`, `depth` thick along local Z
/// (centred on z = 0), with a semicircular opening from `inner.0` to `inner.1` springing at `spring`.
/// `inner` must lie within `outer` and the crown below `top`.
pub(super) struct Arch {
    pub(super) outer: (f32, f32),
    pub(super) inner: (f32, f32),
    pub(super) spring: f32,
    pub(super) top: f32,
    pub(super) depth: f32,
    pub(super) segments: u32,
}

/// An extruded arch (see [`Arch`]), placed by `xf`: the archivolt between two columns, or across an aisle.
pub(super) fn add_arch(mesh: &mut Mesh, xf: &Affine3A, arch: &Arch) {
    let (x0, x1) = arch.outer;
    let center = Vec2::new((arch.inner.0 + arch.inner.1) * 0.5, arch.spring);
    let radius = (arch.inner.1 - arch.inner.0) * 0.5;
    let rise = arch.top - arch.spring;
    let half_depth = arch.depth * 0.5;

    // Angles around the opening, with the outline's two top corners added so every step from the opening out
    // to the outline stays on one side of the outline (convex quads).
    let mut angles: Vec<f32> = (0..=arch.segments).map(|i| PI * i as f32 / arch.segments as f32).collect();
    angles.push(rise.atan2(x1 - center.x));
    angles.push(rise.atan2(x0 - center.x));
    angles.sort_by(f32::total_cmp);
    angles.dedup_by(|a, b| (*a - *b).abs() < 1e-5);

    // The point of the outline seen from the opening's centre at `angle`.
    let outline = |angle: f32| {
        let dir = Vec2::new(angle.cos(), angle.sin());
        let mut t = f32::INFINITY;
        if dir.x > 1e-6 {
            t = t.min((x1 - center.x) / dir.x);
        }
        if dir.x < -1e-6 {
            t = t.min((x0 - center.x) / dir.x);
        }
        if dir.y > 1e-6 {
            t = t.min(rise / dir.y);
        }
        center + dir * t
    };
    let opening = |angle: f32| center + Vec2::new(angle.cos(), angle.sin()) * radius;

    // Front and back faces: quads between the opening and the outline.
    for (z, normal) in [(half_depth, Vec3::Z), (-half_depth, Vec3::NEG_Z)] {
        let at = |mesh: &mut Mesh, p: Vec2| vertex(mesh, xf, p.extend(z), normal, p);
        for pair in angles.windows(2) {
            let ids = [
                at(mesh, opening(pair[0])),
                at(mesh, outline(pair[0])),
                at(mesh, outline(pair[1])),
                at(mesh, opening(pair[1])),
            ];
            quad(mesh, ids);
        }
    }

    // The underside of the opening (intrados), smooth, its normals pointing to the opening's centre.
    for pair in angles.windows(2) {
        let ids = [pair[0], pair[1]].map(|angle| {
            let p = opening(angle);
            let n = -Vec2::new(angle.cos(), angle.sin());
            let u = angle * radius;
            [half_depth, -half_depth].map(|z| vertex(mesh, xf, p.extend(z), n.extend(0.0), Vec2::new(u, z)))
        });
        quad(mesh, [ids[0][0], ids[1][0], ids[1][1], ids[0][1]]);
    }

    // The flat outline: top, both ends and the two bottom pieces beside the opening.
    let d = Vec3::Z * arch.depth;
    let back = |x: f32, y: f32| Vec3::new(x, y, -half_depth);
    add_rect(mesh, xf, back(x0, arch.top), Vec3::X * (x1 - x0), d, Vec3::Y);
    add_rect(mesh, xf, back(x1, arch.spring), Vec3::Y * rise, d, Vec3::X);
    add_rect(mesh, xf, back(x0, arch.spring), Vec3::Y * rise, d, Vec3::NEG_X);
    add_rect(mesh, xf, back(x0, arch.spring), Vec3::X * (arch.inner.0 - x0), d, Vec3::NEG_Y);
    add_rect(mesh, xf, back(arch.inner.1, arch.spring), Vec3::X * (x1 - arch.inner.1), d, Vec3::NEG_Y);
}

// ---------------------------------------------------------------------------------------------------------------
// Cornell box
// ---------------------------------------------------------------------------------------------------------------
