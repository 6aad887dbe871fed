//! Built-in scenes generated in code, modelled on the test scenes of LightCluster (Wiesenhütter et al. 2013):
//!
//! - `cornell`: a Cornell box (2 x 2 x 2 m, open at the front) with two boxes and a sphere, 32 lights at
//!   random positions with random `L_att` in [0.6, 1.6] (the paper's Fig. 8);
//! - `arcade`: a Sponza-like two-storey arcade, 30 m long, with 80 lights in circles of eight in the side
//!   arcades, `L_att` = 7 and `z_far` = 30 (Fig. 7, Dabrovic Sponza);
//! - `restaurant`: a room with two tables with candle stands, wall lamps and a chandelier, 14 lights with
//!   `L_att` = 2 (Fig. 9).
//!
//! Everything is in metres with +Y up. Every object is a closed solid (boxes, capped cylinders, spheres, tori,
//! extruded arches) with outward normals and counter-clockwise winding seen from outside, so back-face culling,
//! shadow maps and inside/outside tests all work. UVs are in metres along each surface. The scenes stay small
//! (a few thousand to ~20k triangles) because the software rasterizer is vertex-bound.
//!
//! No light sits inside or right on top of geometry: a light enclosed by a solid would be completely shadowed.

use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};
use std::path::Path;

use glam::{Quat, Vec3};

use super::random::{warm_color, SplitMix64};
use super::shapes::{add_arch, add_block, add_box, add_cylinder, add_sphere, add_torus, place, Arch, SceneBuilder};
use super::{Camera, Mesh, PointLight, Scene};
use crate::error::LoadError;

/// Names of the built-in scenes.
pub const NAMES: &[&str] = &["cornell", "arcade", "restaurant"];

/// Build a built-in scene with its light set.
pub fn build(name: &str) -> Result<Scene, LoadError> {
    let mut scene = match name {
        "cornell" => cornell(),
        "arcade" => arcade(),
        "restaurant" => restaurant(),
        _ => return Err(LoadError::UnknownBuiltin { name: name.to_string(), choices: NAMES.join(", ") }),
    };
    scene.finalize(Path::new(name))?;
    Ok(scene)
}

/// The light set from the paper for a built-in scene (the lights [`build`] gives it), without building the
/// geometry. `None` for a name that is not a built-in scene.
pub fn paper_lights(name: &str) -> Option<Vec<PointLight>> {
    match name {
        "cornell" => Some(cornell_lights()),
        "arcade" => Some(arcade_lights()),
        "restaurant" => Some(restaurant_lights()),
        _ => None,
    }
}

// ---------------------------------------------------------------------------------------------------------------
// Scene assembly
// ---------------------------------------------------------------------------------------------------------------

/// The solid objects inside the Cornell box, shared by the geometry and the light placement.
enum Solid {
    Box { center: Vec3, half: Vec3, yaw: f32 },
    Sphere { center: Vec3, radius: f32 },
}

impl Solid {
    /// True when `p` is inside the solid grown by `margin`.
    fn contains(&self, p: Vec3, margin: f32) -> bool {
        match *self {
            Solid::Box { center, half, yaw } => {
                let local = Quat::from_rotation_y(-yaw) * (p - center);
                local.abs().cmple(half + Vec3::splat(margin)).all()
            }
            Solid::Sphere { center, radius } => p.distance(center) <= radius + margin,
        }
    }
}

/// The tall box (left, turned), the short box (right, back) and the sphere (right, front).
fn cornell_solids() -> [Solid; 3] {
    [
        Solid::Box { center: Vec3::new(-0.38, 0.6, -0.3), half: Vec3::new(0.28, 0.6, 0.28), yaw: 0.3 },
        Solid::Box { center: Vec3::new(0.42, 0.28, -0.38), half: Vec3::splat(0.28), yaw: -0.3 },
        Solid::Sphere { center: Vec3::new(0.35, 0.3, 0.42), radius: 0.3 },
    ]
}

/// Half the room's size: the inside is x, z in [-1, 1], y in [0, 2].
const CORNELL_HALF: f32 = 1.0;

fn cornell() -> Scene {
    let mut b = SceneBuilder::new();
    let white = b.material("white", Vec3::new(0.73, 0.71, 0.68), 0.0, 1.0);
    let red = b.material("red", Vec3::new(0.63, 0.065, 0.05), 0.0, 1.0);
    let green = b.material("green", Vec3::new(0.14, 0.45, 0.091), 0.0, 1.0);
    let object = b.material("object", Vec3::new(0.75, 0.74, 0.72), 0.15, 40.0);

    // Walls are 5 cm thick boxes outside the 2 m room, so their inner faces face the room.
    let (h, t) = (CORNELL_HALF, 0.05);
    add_block(b.mesh("floor", white), Vec3::new(-h - t, -t, -h - t), Vec3::new(h + t, 0.0, h));
    add_block(b.mesh("ceiling", white), Vec3::new(-h - t, 2.0 * h, -h - t), Vec3::new(h + t, 2.0 * h + t, h));
    add_block(b.mesh("back wall", white), Vec3::new(-h, 0.0, -h - t), Vec3::new(h, 2.0 * h, -h));
    add_block(b.mesh("left wall", red), Vec3::new(-h - t, 0.0, -h), Vec3::new(-h, 2.0 * h, h));
    add_block(b.mesh("right wall", green), Vec3::new(h, 0.0, -h), Vec3::new(h + t, 2.0 * h, h));

    let objects = b.mesh("objects", object);
    for solid in cornell_solids() {
        match solid {
            Solid::Box { center, half, yaw } => add_box(objects, center, half, yaw),
            Solid::Sphere { center, radius } => add_sphere(objects, center, radius, 48, 24),
        }
    }

    // From the front, framing the 2 m opening with a 40 degree vertical field of view.
    let camera = Camera::look_at(Vec3::new(0.0, 1.0, 3.75), Vec3::new(0.0, 1.0, 0.0), 40f32.to_radians(), 0.05, 10.0);
    b.finish("cornell", cornell_lights(), camera)
}

/// 32 lights at seeded random positions in the room, at least 10 cm from the walls and 8 cm from the objects,
/// with random `L_att` in [0.6, 1.6] (LightCluster Fig. 8). With the room full of overlapping lights an
/// intensity of 3 gives the lit surfaces a median radiance of ~0.7 and ~2 near lights (measured without
/// shadows), bright but not blown out after tone mapping.
fn cornell_lights() -> Vec<PointLight> {
    const COUNT: usize = 32;
    const INTENSITY: f32 = 3.0;
    let solids = cornell_solids();
    let mut rng = SplitMix64::new(0xC0FFEE);
    let inner = CORNELL_HALF - 0.1;
    let mut lights = Vec::with_capacity(COUNT);
    while lights.len() < COUNT {
        let p = Vec3::new(rng.range(-inner, inner), rng.range(0.1, 2.0 * CORNELL_HALF - 0.1), rng.range(-inner, inner));
        if solids.iter().any(|s| s.contains(p, 0.08)) {
            continue;
        }
        let range = rng.range(0.6, 1.6);
        lights.push(PointLight::new(p, warm_color(&mut rng), INTENSITY, range));
    }
    lights
}

// ---------------------------------------------------------------------------------------------------------------
// Arcade (Sponza-like)
// ---------------------------------------------------------------------------------------------------------------

/// Half the arcade's length along X (inside the end walls).
const ARCADE_HALF_LENGTH: f32 = 15.0;
/// The colonnades stand on z = ±4: the nave is 8 m wide.
const COLONNADE_Z: f32 = 4.0;
/// The inner face of the outer walls: the side arcades are 3 m deep.
const OUTER_WALL_Z: f32 = 7.0;
const WALL_THICKNESS: f32 = 0.3;
/// Columns every 2.5 m, twelve per row, so the bay centres fall on x = 0, ±2.5, ..., ±12.5.
const COLUMN_SPACING: f32 = 2.5;
const COLUMNS_PER_ROW: usize = 12;
/// Heights of the ground storey: capital top (where the arches spring), arch top, gallery floor.
const GROUND_SPRING: f32 = 3.24;
const GROUND_ARCH_TOP: f32 = 4.7;
const GALLERY_FLOOR: f32 = 5.0;
/// Heights of the gallery storey.
const GALLERY_SPRING: f32 = 7.6;
const GALLERY_ARCH_TOP: f32 = 9.0;
const ARCADE_TOP: f32 = 9.3;

fn column_x(k: usize) -> f32 {
    -COLUMN_SPACING * (COLUMNS_PER_ROW as f32 - 1.0) * 0.5 + COLUMN_SPACING * k as f32
}

fn arcade() -> Scene {
    let mut b = SceneBuilder::new();
    let floor = b.material("floor", Vec3::new(0.5, 0.45, 0.4), 0.1, 24.0);
    let wall = b.material("wall", Vec3::new(0.72, 0.64, 0.52), 0.0, 1.0);
    let stone = b.material("stone", Vec3::new(0.78, 0.74, 0.66), 0.0, 1.0);
    let marble = b.material("marble", Vec3::new(0.86, 0.84, 0.8), 0.25, 48.0);
    let red = b.material("red banner", Vec3::new(0.6, 0.08, 0.06), 0.0, 1.0);
    let blue = b.material("blue banner", Vec3::new(0.08, 0.16, 0.5), 0.0, 1.0);
    let bronze = b.material("bronze", Vec3::new(0.45, 0.3, 0.15), 0.5, 64.0);

    arcade_shell(&mut b, floor, wall, stone);
    for side in [-1.0, 1.0] {
        arcade_ground_storey(&mut b, side, marble, stone);
        arcade_gallery_storey(&mut b, side, marble, stone);
        arcade_banners(&mut b, side, red, blue);
    }
    // A statue on a plinth in the middle of the nave, to catch the light from both arcades.
    add_block(b.mesh("plinth", stone), Vec3::new(-0.6, 0.0, -0.6), Vec3::new(0.6, 0.9, 0.6));
    let statue = b.mesh("statue", bronze);
    add_cylinder(statue, Vec3::new(0.0, 0.9, 0.0), 0.18, 0.9, 16);
    add_sphere(statue, Vec3::new(0.0, 2.15, 0.0), 0.35, 24, 12);

    // From the -X end, down the nave, at eye height; z_far 30 as in the paper's Sponza measurements.
    let camera = Camera::look_at(
        Vec3::new(-ARCADE_HALF_LENGTH + 0.8, 1.7, 0.0),
        Vec3::new(0.0, 2.6, 0.0),
        60f32.to_radians(),
        0.05,
        30.0,
    );
    b.finish("arcade", arcade_lights(), camera)
}

/// Floor, outer side walls and end walls; the nave has no roof.
fn arcade_shell(b: &mut SceneBuilder, floor: usize, wall: usize, stone: usize) {
    let (l, w, t) = (ARCADE_HALF_LENGTH, OUTER_WALL_Z, WALL_THICKNESS);
    add_block(b.mesh("floor", floor), Vec3::new(-l - t, -0.2, -w - t), Vec3::new(l + t, 0.0, w + t));
    let walls = b.mesh("walls", wall);
    for side in [-1.0, 1.0] {
        add_block(walls, Vec3::new(-l - t, 0.0, w * side), Vec3::new(l + t, ARCADE_TOP, (w + t) * side));
        add_block(walls, Vec3::new(l * side, 0.0, -w), Vec3::new((l + t) * side, ARCADE_TOP, w));
    }
    // Pilasters on the outer walls opposite the columns, where the aisles' transverse arches rest.
    let pilasters = b.mesh("pilasters", stone);
    for side in [-1.0f32, 1.0] {
        for k in 0..COLUMNS_PER_ROW {
            let center = Vec3::new(column_x(k), GROUND_SPRING * 0.5, (OUTER_WALL_Z - 0.1) * side);
            add_box(pilasters, center, Vec3::new(0.3, GROUND_SPRING * 0.5, 0.1), 0.0);
        }
    }
}

/// A column: square plinth, round shaft, square capital, standing on `base`.
fn add_column(mesh: &mut Mesh, base: Vec3, plinth: f32, radius: f32, shaft: f32, capital: f32) {
    add_box(mesh, base + Vec3::Y * 0.08, Vec3::new(plinth, 0.08, plinth), 0.0);
    add_cylinder(mesh, base + Vec3::Y * 0.16, radius, shaft, 20);
    add_box(mesh, base + Vec3::Y * (0.16 + shaft + 0.12), Vec3::new(capital, 0.12, capital), 0.0);
}

/// One row of arches along X on the colonnade line `z`, springing from the capitals (half width `capital`),
/// with the spandrels between the end columns and the end walls filled.
fn add_arch_row(mesh: &mut Mesh, z: f32, capital: f32, spring: f32, top: f32, depth: f32) {
    for k in 0..COLUMNS_PER_ROW - 1 {
        let (x0, x1) = (column_x(k), column_x(k + 1));
        let arch = Arch { outer: (x0, x1), inner: (x0 + capital, x1 - capital), spring, top, depth, segments: 16 };
        add_arch(mesh, &place(Vec3::new(0.0, 0.0, z), 0.0), &arch);
    }
    let end = column_x(COLUMNS_PER_ROW - 1);
    for side in [-1.0, 1.0] {
        let (a, b) = (end * side, ARCADE_HALF_LENGTH * side);
        add_block(mesh, Vec3::new(a.min(b), spring, z - depth * 0.5), Vec3::new(a.max(b), top, z + depth * 0.5));
    }
}

/// The ground storey on one side (`side` = ±1): columns, the arches towards the nave, the transverse arches
/// across the aisle (they split it into bays and cast the interesting shadows) and the gallery floor on top.
fn arcade_ground_storey(b: &mut SceneBuilder, side: f32, marble: usize, stone: usize) {
    let z = COLONNADE_Z * side;
    let capital = 0.34;
    let columns = b.mesh("columns", marble);
    for k in 0..COLUMNS_PER_ROW {
        add_column(columns, Vec3::new(column_x(k), 0.0, z), capital, 0.22, GROUND_SPRING - 0.4, capital);
    }
    let arches = b.mesh("arches", stone);
    add_arch_row(arches, z, capital, GROUND_SPRING, GROUND_ARCH_TOP, 0.5);

    // Transverse arches from each column to the pilaster opposite: local X runs from the nave outwards.
    let yaw = -FRAC_PI_2 * side;
    for k in 0..COLUMNS_PER_ROW {
        let arch = Arch {
            outer: (COLONNADE_Z, OUTER_WALL_Z),
            inner: (COLONNADE_Z + capital, OUTER_WALL_Z - 0.2),
            spring: GROUND_SPRING,
            top: GROUND_ARCH_TOP,
            depth: 0.4,
            segments: 16,
        };
        add_arch(arches, &place(Vec3::new(column_x(k), 0.0, 0.0), yaw), &arch);
    }

    // The gallery floor: the ceiling of the aisle, resting on the arches.
    let (z0, z1) = ((COLONNADE_Z - 0.3) * side, OUTER_WALL_Z * side);
    let slab_min = Vec3::new(-ARCADE_HALF_LENGTH, GROUND_ARCH_TOP, z0.min(z1));
    let slab_max = Vec3::new(ARCADE_HALF_LENGTH, GALLERY_FLOOR, z0.max(z1));
    add_block(b.mesh("slabs", stone), slab_min, slab_max);
}

/// The gallery storey on one side: lighter columns, arches, a balustrade between the columns and a roof over
/// the gallery.
fn arcade_gallery_storey(b: &mut SceneBuilder, side: f32, marble: usize, stone: usize) {
    let z = COLONNADE_Z * side;
    let capital = 0.28;
    let columns = b.mesh("columns", marble);
    for k in 0..COLUMNS_PER_ROW {
        let base = Vec3::new(column_x(k), GALLERY_FLOOR, z);
        add_column(columns, base, capital, 0.17, GALLERY_SPRING - GALLERY_FLOOR - 0.4, capital);
    }
    let arches = b.mesh("arches", stone);
    add_arch_row(arches, z, capital, GALLERY_SPRING, GALLERY_ARCH_TOP, 0.4);

    // Balustrade: balusters every ~0.3 m between the column plinths, under a handrail.
    let balustrade = b.mesh("balustrade", stone);
    let rail_height = 0.9;
    for k in 0..COLUMNS_PER_ROW - 1 {
        let (x0, x1) = (column_x(k) + capital, column_x(k + 1) - capital);
        let shaft = 0.17;
        let count = ((x1 - x0) / 0.3).floor().max(1.0) as usize;
        for i in 0..count {
            let x = x0 + (i as f32 + 0.5) * (x1 - x0) / count as f32;
            let center = Vec3::new(x, GALLERY_FLOOR + rail_height * 0.5, z);
            add_box(balustrade, center, Vec3::new(0.05, rail_height * 0.5, 0.05), 0.0);
        }
        // The handrail runs from shaft to shaft, above the plinths.
        let (r0, r1) = (column_x(k) + shaft, column_x(k + 1) - shaft);
        let rail = Vec3::new((r0 + r1) * 0.5, GALLERY_FLOOR + rail_height + 0.05, z);
        add_box(balustrade, rail, Vec3::new((r1 - r0) * 0.5, 0.05, 0.1), 0.0);
    }

    let (z0, z1) = ((COLONNADE_Z - 0.25) * side, OUTER_WALL_Z * side);
    let roof_min = Vec3::new(-ARCADE_HALF_LENGTH, GALLERY_ARCH_TOP, z0.min(z1));
    let roof_max = Vec3::new(ARCADE_HALF_LENGTH, ARCADE_TOP, z0.max(z1));
    add_block(b.mesh("slabs", stone), roof_min, roof_max);
}

/// Cloth banners hanging from the balustrade into the nave, alternating red and blue, for some colour.
fn arcade_banners(b: &mut SceneBuilder, side: f32, red: usize, blue: usize) {
    let z = (COLONNADE_Z - 0.4) * side;
    for (i, x) in [-7.5f32, -2.5, 2.5, 7.5].into_iter().enumerate() {
        let material = if i % 2 == 0 { red } else { blue };
        let name = if material == red { "red banners" } else { "blue banners" };
        let center = Vec3::new(x, (3.9 + GALLERY_FLOOR + 0.9) * 0.5, z);
        add_box(b.mesh(name, material), center, Vec3::new(0.5, (GALLERY_FLOOR + 0.9 - 3.9) * 0.5, 0.02), 0.0);
    }
}

/// The arcade's paper light set (LightCluster Fig. 7): ten circles of eight lights, radius 0.14 m at 1.8 m (as in
/// the Sponza layout: the radius that brings the cluster counts near the paper's Table 1),
/// five in each aisle, centred in the bays at x = 0, ±5, ±10 and in the middle of the aisle's depth; `L_att` = 7.
/// Intensity 8 gives the lit surfaces a median radiance of ~0.45 and ~1.4 in the aisles near the circles
/// (measured without shadows); the middle of the nave, 5 m from the circles, stays dim (~0.05) as in Sponza.
fn arcade_lights() -> Vec<PointLight> {
    const RANGE: f32 = 7.0;
    const INTENSITY: f32 = 8.0;
    const RADIUS: f32 = 0.14;
    const HEIGHT: f32 = 1.8;
    let aisle_middle = (COLONNADE_Z + OUTER_WALL_Z) * 0.5;
    let mut lights = Vec::with_capacity(80);
    for side in [-1.0f32, 1.0] {
        for x in [-10.0f32, -5.0, 0.0, 5.0, 10.0] {
            let center = Vec3::new(x, HEIGHT, aisle_middle * side);
            for i in 0..8 {
                let angle = FRAC_PI_4 * i as f32;
                let p = center + Vec3::new(angle.cos(), 0.0, angle.sin()) * RADIUS;
                lights.push(PointLight::new(p, Vec3::new(1.0, 0.9, 0.75), INTENSITY, RANGE));
            }
        }
    }
    lights
}

// ---------------------------------------------------------------------------------------------------------------
// Restaurant
// ---------------------------------------------------------------------------------------------------------------

/// The room's inside: x in [-4, 4], z in [-3, 3], y in [0, 3].
const ROOM_HALF_X: f32 = 4.0;
const ROOM_HALF_Z: f32 = 3.0;
const ROOM_HEIGHT: f32 = 3.0;
const TABLE_HEIGHT: f32 = 0.75;
/// The two tables' centres on the floor.
const TABLES: [Vec3; 2] = [Vec3::new(-1.5, 0.0, 0.45), Vec3::new(1.5, 0.0, -0.45)];
/// Wall lamps on the long walls: x positions, on both walls.
const WALL_LAMP_X: [f32; 2] = [-2.5, 2.5];
const WALL_LAMP_HEIGHT: f32 = 2.0;
/// The chandelier hangs in the middle of the room, between the tables; its candle ring is this high, low
/// enough for its lights (`L_att` = 2) to reach the table tops.
const CHANDELIER_RING: f32 = 1.68;
const CHANDELIER_RADIUS: f32 = 0.4;
/// Lights sit this far above a candle's top: close enough to read as the flame, far enough that the candle
/// does not shadow a wide cone straight below.
const FLAME_ABOVE_CANDLE: f32 = 0.06;

struct RestaurantMaterials {
    wood: usize,
    dark_wood: usize,
    cloth: usize,
    brass: usize,
    wax: usize,
}

fn restaurant() -> Scene {
    let mut b = SceneBuilder::new();
    let m = RestaurantMaterials {
        wood: b.material("wood floor", Vec3::new(0.55, 0.38, 0.22), 0.15, 32.0),
        dark_wood: b.material("dark wood", Vec3::new(0.3, 0.17, 0.08), 0.1, 24.0),
        cloth: b.material("table cloth", Vec3::new(0.85, 0.84, 0.8), 0.0, 1.0),
        brass: b.material("brass", Vec3::new(0.62, 0.46, 0.2), 0.6, 64.0),
        wax: b.emissive_material("candle wax", Vec3::new(0.9, 0.87, 0.78), Vec3::new(0.3, 0.2, 0.08)),
    };
    let plaster = b.material("plaster", Vec3::new(0.78, 0.7, 0.58), 0.0, 1.0);
    let ceiling = b.material("ceiling", Vec3::new(0.85, 0.84, 0.8), 0.0, 1.0);
    let wine = b.material("wine red", Vec3::new(0.45, 0.06, 0.08), 0.0, 1.0);
    let painting = b.material("painting", Vec3::new(0.2, 0.35, 0.45), 0.05, 16.0);

    restaurant_room(&mut b, m.wood, plaster, ceiling);
    for (i, &center) in TABLES.iter().enumerate() {
        add_table(&mut b, center, &m);
        // Chairs on the long sides, facing the table.
        for dz in [-0.75f32, 0.75] {
            for dx in [-0.35, 0.35] {
                add_chair(b.mesh("chairs", m.dark_wood), center + Vec3::new(dx, 0.0, dz), Vec3::Z * dz.signum());
            }
        }
        // A chair at the head of the table, turned 90 degrees, away from the room's middle.
        let head = if i == 0 { -1.0 } else { 1.0 };
        add_chair(b.mesh("chairs", m.dark_wood), center + Vec3::new(head * 0.95, 0.0, 0.0), Vec3::X * head);
    }
    for z in [-1.0f32, 1.0] {
        for x in WALL_LAMP_X {
            add_wall_lamp(&mut b, Vec3::new(x, WALL_LAMP_HEIGHT, ROOM_HALF_Z * z), -z, &m);
        }
    }
    add_chandelier(&mut b, &m);

    // A sideboard against the far end wall and two paintings, so the walls are not bare.
    add_block(b.mesh("sideboard", wine), Vec3::new(ROOM_HALF_X - 0.5, 0.0, -1.2), Vec3::new(ROOM_HALF_X, 0.95, 1.2));
    for x in [-2.5f32, 2.5] {
        let center = Vec3::new(x * 0.5, 1.7, -ROOM_HALF_Z + 0.02);
        add_box(b.mesh("paintings", painting), center, Vec3::new(0.5, 0.35, 0.02), 0.0);
    }

    // From the corner by the door, over the first table towards the second.
    let camera = Camera::look_at(
        Vec3::new(-ROOM_HALF_X + 0.3, 1.65, ROOM_HALF_Z - 0.3),
        Vec3::new(1.0, 0.9, -0.8),
        60f32.to_radians(),
        0.05,
        15.0,
    );
    b.finish("restaurant", restaurant_lights(), camera)
}

/// Floor, four walls and ceiling, 15 cm thick, around the room.
fn restaurant_room(b: &mut SceneBuilder, floor: usize, walls: usize, ceiling: usize) {
    let (x, z, h, t) = (ROOM_HALF_X, ROOM_HALF_Z, ROOM_HEIGHT, 0.15);
    add_block(b.mesh("floor", floor), Vec3::new(-x - t, -t, -z - t), Vec3::new(x + t, 0.0, z + t));
    add_block(b.mesh("ceiling", ceiling), Vec3::new(-x - t, h, -z - t), Vec3::new(x + t, h + t, z + t));
    let mesh = b.mesh("walls", walls);
    for s in [-1.0f32, 1.0] {
        add_block(mesh, Vec3::new(-x, 0.0, z * s), Vec3::new(x, h, (z + t) * s));
        add_block(mesh, Vec3::new(x * s, 0.0, -z - t), Vec3::new((x + t) * s, h, z + t));
    }
}

/// The candle stand's candle tops, relative to the table's centre on the floor: a taller middle candle and
/// two on the arms along X.
fn candle_tops() -> [Vec3; 3] {
    // The cross arm's top, on which the side cups stand.
    let arm = TABLE_HEIGHT + 0.35;
    let candle = 0.02 + 0.12;
    [Vec3::new(-0.16, arm + candle, 0.0), Vec3::new(0.0, arm + 0.06 + candle, 0.0), Vec3::new(0.16, arm + candle, 0.0)]
}

/// A table with a cloth-covered top, four legs and a three-armed brass candle stand.
fn add_table(b: &mut SceneBuilder, center: Vec3, m: &RestaurantMaterials) {
    let top = Vec3::new(0.7, 0.025, 0.45);
    add_box(b.mesh("table tops", m.cloth), center + Vec3::Y * (TABLE_HEIGHT - top.y), top, 0.0);
    let legs = b.mesh("table legs", m.dark_wood);
    for (sx, sz) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        let p = center + Vec3::new(sx * (top.x - 0.08), (TABLE_HEIGHT - 0.05) * 0.5, sz * (top.z - 0.08));
        add_box(legs, p, Vec3::new(0.035, (TABLE_HEIGHT - 0.05) * 0.5, 0.035), 0.0);
    }

    // Candle stand: foot, stem, cross arm, three cups; the middle cup on a short extension of the stem.
    let stand = b.mesh("candle stands", m.brass);
    let on_table = center + Vec3::Y * TABLE_HEIGHT;
    add_cylinder(stand, on_table, 0.08, 0.02, 20);
    add_cylinder(stand, on_table + Vec3::Y * 0.02, 0.012, 0.4, 10);
    add_box(stand, on_table + Vec3::Y * 0.34, Vec3::new(0.17, 0.01, 0.01), 0.0);
    let cup_bases = candle_tops().map(|top| center + top - Vec3::Y * 0.14);
    for cup in cup_bases {
        add_cylinder(stand, cup, 0.025, 0.02, 12);
    }
    let wax = b.mesh("candles", m.wax);
    for cup in cup_bases {
        add_cylinder(wax, cup + Vec3::Y * 0.02, 0.011, 0.12, 10);
    }
}

/// A chair standing at `floor`: seat, four legs and a backrest on the `back` side (a unit vector along X or Z,
/// pointing away from the table).
fn add_chair(mesh: &mut Mesh, floor: Vec3, back: Vec3) {
    let (seat_half, seat_height) = (0.22, 0.46);
    add_box(mesh, floor + Vec3::Y * seat_height, Vec3::new(seat_half, 0.025, seat_half), 0.0);
    let side = Vec3::new(back.z, 0.0, back.x);
    for (a, c) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
        let offset = (back * a + side * c) * (seat_half - 0.03);
        add_box(mesh, floor + offset + Vec3::Y * (seat_height * 0.5), Vec3::new(0.02, seat_height * 0.5, 0.02), 0.0);
    }
    let backrest_center = floor + back * (seat_half - 0.02) + Vec3::Y * (seat_height + 0.3);
    let backrest_half = back.abs() * 0.02 + side.abs() * seat_half + Vec3::Y * 0.27;
    add_box(mesh, backrest_center, backrest_half, 0.0);
}

/// A wall lamp on the wall at `at` (on the wall plane), its arm reaching 0.25 m into the room along `out`
/// (±Z) to a cup with a candle-like bulb; the light sits just above it (see [`wall_lamp_light`]).
fn add_wall_lamp(b: &mut SceneBuilder, at: Vec3, out: f32, m: &RestaurantMaterials) {
    let brass = b.mesh("wall lamps", m.brass);
    let dir = Vec3::Z * out;
    add_box(brass, at + dir * 0.015, Vec3::new(0.06, 0.1, 0.015), 0.0);
    add_box(brass, at + dir * 0.14 - Vec3::Y * 0.05, Vec3::new(0.012, 0.012, 0.11), 0.0);
    let cup = at + dir * 0.25 - Vec3::Y * 0.06;
    add_cylinder(brass, cup, 0.025, 0.04, 12);
    add_cylinder(b.mesh("candles", m.wax), cup + Vec3::Y * 0.04, 0.012, 0.08, 10);
}

fn wall_lamp_light(at: Vec3, out: f32) -> Vec3 {
    at + Vec3::Z * out * 0.25 + Vec3::Y * (-0.06 + 0.04 + 0.08 + FLAME_ABOVE_CANDLE)
}

/// A chandelier: a rod from the ceiling, a brass ring with four spokes and four candles on the ring.
fn add_chandelier(b: &mut SceneBuilder, m: &RestaurantMaterials) {
    let brass = b.mesh("chandelier", m.brass);
    let rod_bottom = CHANDELIER_RING - 0.05;
    add_cylinder(brass, Vec3::Y * rod_bottom, 0.015, ROOM_HEIGHT - rod_bottom, 10);
    add_torus(brass, Vec3::Y * CHANDELIER_RING, CHANDELIER_RADIUS, 0.02, 32, 8);
    for i in 0..4 {
        // Spokes run between the candles so they do not sit right under a light.
        let yaw = FRAC_PI_4 * (2 * i + 1) as f32;
        // `place` turns local +X by `yaw` about +Y; the spoke's middle must turn the same way.
        let mid = Quat::from_rotation_y(yaw) * Vec3::X * (CHANDELIER_RADIUS * 0.5);
        add_box(brass, mid + Vec3::Y * CHANDELIER_RING, Vec3::new(CHANDELIER_RADIUS * 0.5, 0.01, 0.01), yaw);
    }
    for p in chandelier_candle_bases() {
        add_cylinder(b.mesh("chandelier", m.brass), p, 0.035, 0.03, 12);
        add_cylinder(b.mesh("candles", m.wax), p + Vec3::Y * 0.03, 0.011, 0.08, 10);
    }
}

/// Where the chandelier's candle cups stand on the ring: on the four axis directions.
fn chandelier_candle_bases() -> [Vec3; 4] {
    [0.0f32, FRAC_PI_2, PI, 3.0 * FRAC_PI_2]
        .map(|a| Vec3::new(a.cos() * CHANDELIER_RADIUS, CHANDELIER_RING + 0.02, a.sin() * CHANDELIER_RADIUS))
}

/// The restaurant's 14 lights (LightCluster Fig. 9), all with `L_att` = 2: three candles on each table,
/// four wall lamps and four chandelier candles. Intensities (measured without shadows): the candles light the
/// table cloths to ~0.8-1.6; the wall lamps make a pool of ~0.4-1 on the wall around them; the chandelier,
/// brighter, lights the ceiling around it. With `L_att` = 2 much of the room stays dim, as in the paper.
fn restaurant_lights() -> Vec<PointLight> {
    const RANGE: f32 = 2.0;
    let candle = Vec3::new(1.0, 0.72, 0.42);
    let lamp = Vec3::new(1.0, 0.82, 0.6);
    let mut lights = Vec::with_capacity(14);
    for center in TABLES {
        for top in candle_tops() {
            lights.push(PointLight::new(center + top + Vec3::Y * FLAME_ABOVE_CANDLE, candle, 4.0, RANGE));
        }
    }
    for z in [-1.0f32, 1.0] {
        for x in WALL_LAMP_X {
            let at = Vec3::new(x, WALL_LAMP_HEIGHT, ROOM_HALF_Z * z);
            lights.push(PointLight::new(wall_lamp_light(at, -z), lamp, 8.0, RANGE));
        }
    }
    for base in chandelier_candle_bases() {
        let flame = base + Vec3::Y * (0.03 + 0.08 + FLAME_ABOVE_CANDLE);
        lights.push(PointLight::new(flame, candle, 8.0, RANGE));
    }
    lights
}
