//! Light layouts: generators that place point lights in any scene, and the parser for the CLI's layout specs.
//!
//! | spec                       | meaning                                                                  |
//! |----------------------------|--------------------------------------------------------------------------|
//! | `random:COUNT:L_ATT[:SEED]`| `COUNT` lights uniformly inside the scene bounds shrunk by 5% per side   |
//! | `circles:N:PER:L_ATT`      | `N` circles of `PER` lights, in two rows along the longest horizontal axis|
//! | `grid:NXxNY:L_ATT`         | a horizontal `NX` x `NY` grid at one third of the bounds' height         |
//! | `paper`                    | the scene's light set from the papers (built-in scenes, Dabrovic Sponza) |
//! | `scene`                    | keep the lights that came with the scene                                 |
//!
//! `L_ATT` is the attenuation range of every light (see [`super::attenuation`]). At most [`MAX_LIGHTS`] lights;
//! zero lights is allowed (the renderer then shows ambient light only).
//!
//! Generation is deterministic: the same layout on the same scene always gives the same lights (a seeded
//! SplitMix64, no global randomness), so renders and benchmarks can be repeated.
//!
//! # Intensity
//!
//! The generated layouts pick one intensity for all their lights so that an image rendered with exposure 1 is
//! neither black nor blown out (see [`layout_intensity`]): lit surfaces should reach a radiance of roughly
//! [`TARGET_RADIANCE`], whether a surface is lit mostly by one light (sparse layouts) or by many overlapping
//! ones (dense layouts).

use std::fmt;
use std::str::FromStr;

use glam::Vec3;

use super::random::{warm_color, SplitMix64};
use super::{attenuation, builtin, Aabb, PointLight, Scene, SceneSource};
use crate::error::LayoutError;

/// The most lights a layout may ask for.
pub const MAX_LIGHTS: usize = 100_000;

/// The radiance a generated layout aims for on a lit surface of albedo [`REFERENCE_ALBEDO`] (before tone mapping).
pub const TARGET_RADIANCE: f32 = 0.8;

/// The albedo the intensity heuristics assume for the surfaces of an arbitrary scene.
pub const REFERENCE_ALBEDO: f32 = 0.7;

/// The Dabrovic Sponza light set of LightCluster (Fig. 7): 80 lights in circles of eight, `L_att` = 7.
pub const SPONZA_PAPER_RANGE: f32 = 7.0;

/// A way of placing point lights in a scene. Parse one from a spec with [`parse`] or `str::parse`.
#[derive(Clone, Debug, PartialEq)]
pub enum LightLayout {
    /// `count` lights at seeded uniform random positions inside the scene bounds (shrunk by 5% per side).
    Random { count: usize, range: f32, seed: u64 },
    /// `count` lights at seeded uniform random positions above the scene: over its footprint (shrunk by 5% per
    /// side), from its top up to half its height higher (a model on a floor lit from above, the INSM paper's
    /// outside-in scenes).
    Above { count: usize, range: f32, seed: u64 },
    /// `circles` horizontal circles of `per_circle` lights each, in two rows along the longest horizontal axis.
    Circles { circles: usize, per_circle: usize, range: f32 },
    /// A horizontal `nx` (along X) by `ny` (along Z) grid at one third of the bounds' height.
    Grid { nx: usize, ny: usize, range: f32 },
    /// The scene's own light set from the papers (built-in scenes, Dabrovic Sponza).
    Paper,
    /// The lights that came with the scene.
    Scene,
    /// One spot light at `position` aimed at `target`, cone half-angle `cone_deg` degrees (the outer 20 % of it
    /// soft), range `range`.
    Spot { position: Vec3, target: Vec3, cone_deg: f32, range: f32 },
}

impl LightLayout {
    /// How many lights the layout makes, when that does not depend on the scene. `None` when the product
    /// overflows (such a layout is rejected anyway) or for `paper` and `scene`.
    pub fn light_count(&self) -> Option<usize> {
        match *self {
            LightLayout::Random { count, .. } | LightLayout::Above { count, .. } => Some(count),
            LightLayout::Circles { circles, per_circle, .. } => circles.checked_mul(per_circle),
            LightLayout::Grid { nx, ny, .. } => nx.checked_mul(ny),
            LightLayout::Spot { .. } => Some(1),
            LightLayout::Paper | LightLayout::Scene => None,
        }
    }

    /// The same layout with `count` lights, for the layouts whose count is a free number (`random`, `above`):
    /// what `sweep --param lights=...` varies. `None` for the others.
    pub fn with_count(&self, count: usize) -> Option<LightLayout> {
        match *self {
            LightLayout::Random { range, seed, .. } => Some(LightLayout::Random { count, range, seed }),
            LightLayout::Above { range, seed, .. } => Some(LightLayout::Above { count, range, seed }),
            _ => None,
        }
    }

    /// The attenuation range of the generated lights, for the layouts that have one.
    pub fn range(&self) -> Option<f32> {
        match *self {
            LightLayout::Random { range, .. }
            | LightLayout::Above { range, .. }
            | LightLayout::Circles { range, .. }
            | LightLayout::Grid { range, .. }
            | LightLayout::Spot { range, .. } => Some(range),
            LightLayout::Paper | LightLayout::Scene => None,
        }
    }

    /// Check the limits that [`parse`] checks, for layouts built in code.
    pub fn validate(&self) -> Result<(), LayoutError> {
        let spec = self.to_string();
        if let Some(range) = self.range() {
            check_range(range).map_err(|reason| LayoutError::Invalid { spec: spec.clone(), reason })?;
        }
        let count = match self {
            LightLayout::Paper | LightLayout::Scene => return Ok(()),
            LightLayout::Spot { position, target, cone_deg, .. } => {
                let ok = position.is_finite()
                    && target.is_finite()
                    && position.distance(*target) > 1e-6
                    && cone_deg.is_finite()
                    && (0.0..=90.0).contains(cone_deg);
                if !ok {
                    return Err(LayoutError::Invalid {
                        spec,
                        reason: "a spot needs finite, distinct position and target and a cone of 0..=90 degrees".into(),
                    });
                }
                1
            }
            // An overflowing product is certainly too many.
            _ => self.light_count().unwrap_or(usize::MAX),
        };
        if count > MAX_LIGHTS {
            return Err(LayoutError::TooManyLights { spec, count, max: MAX_LIGHTS });
        }
        Ok(())
    }
}

/// Writes the canonical spec, which [`parse`] reads back to the same layout.
impl fmt::Display for LightLayout {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LightLayout::Random { count, range, seed } => write!(f, "random:{count}:{range}:{seed}"),
            LightLayout::Above { count, range, seed } => write!(f, "above:{count}:{range}:{seed}"),
            LightLayout::Circles { circles, per_circle, range } => write!(f, "circles:{circles}:{per_circle}:{range}"),
            LightLayout::Grid { nx, ny, range } => write!(f, "grid:{nx}x{ny}:{range}"),
            LightLayout::Paper => f.write_str("paper"),
            LightLayout::Scene => f.write_str("scene"),
            LightLayout::Spot { position: p, target: t, cone_deg, range } => {
                write!(f, "spot:{},{},{}:{},{},{}:{cone_deg}:{range}", p.x, p.y, p.z, t.x, t.y, t.z)
            }
        }
    }
}

impl FromStr for LightLayout {
    type Err = LayoutError;
    fn from_str(spec: &str) -> Result<Self, Self::Err> {
        parse(spec)
    }
}

const USAGE: &str =
    "expected random:COUNT:L_ATT[:SEED], above:COUNT:L_ATT[:SEED], circles:N:PER_CIRCLE:L_ATT, grid:NXxNY:L_ATT, \
                     spot:PX,PY,PZ:TX,TY,TZ:CONE_DEG:L_ATT, paper or scene";

/// Parse a layout spec such as `random:1024:1.5`, `random:1024:1.5:7`, `circles:10:8:7`, `grid:8x8:2`, `paper`
/// or `scene`. The kind is case-insensitive; surrounding whitespace is ignored.
pub fn parse(spec: &str) -> Result<LightLayout, LayoutError> {
    let invalid = |reason: String| LayoutError::Invalid { spec: spec.to_string(), reason };
    let mut parts = spec.trim().split(':');
    let kind = parts.next().unwrap_or_default().trim().to_ascii_lowercase();
    let args: Vec<&str> = parts.map(str::trim).collect();

    let layout = match kind.as_str() {
        "random" | "above" => {
            let usage = if kind == "random" { "random:COUNT:L_ATT[:SEED]" } else { "above:COUNT:L_ATT[:SEED]" };
            expect_fields(&args, 2, 3, usage).map_err(invalid)?;
            let count = parse_count(args[0], "COUNT").map_err(invalid)?;
            let range = parse_range(args[1]).map_err(invalid)?;
            let seed = match args.get(2) {
                Some(s) => s.parse::<u64>().map_err(|_| {
                    invalid(format!("SEED must be a whole number between 0 and {}, got '{s}'", u64::MAX))
                })?,
                None => 1,
            };
            if kind == "random" {
                LightLayout::Random { count, range, seed }
            } else {
                LightLayout::Above { count, range, seed }
            }
        }
        "circles" => {
            expect_fields(&args, 3, 3, "circles:N:PER_CIRCLE:L_ATT").map_err(invalid)?;
            let circles = parse_count(args[0], "N (the number of circles)").map_err(invalid)?;
            let per_circle = parse_count(args[1], "PER_CIRCLE").map_err(invalid)?;
            let range = parse_range(args[2]).map_err(invalid)?;
            LightLayout::Circles { circles, per_circle, range }
        }
        "grid" => {
            expect_fields(&args, 2, 2, "grid:NXxNY:L_ATT").map_err(invalid)?;
            let (nx, ny) = args[0]
                .split_once(['x', 'X'])
                .ok_or_else(|| invalid(format!("grid size must look like 8x8 (NXxNY), got '{}'", args[0])))?;
            let nx = parse_count(nx, "NX").map_err(invalid)?;
            let ny = parse_count(ny, "NY").map_err(invalid)?;
            let range = parse_range(args[1]).map_err(invalid)?;
            LightLayout::Grid { nx, ny, range }
        }
        "spot" => {
            expect_fields(&args, 4, 4, "spot:PX,PY,PZ:TX,TY,TZ:CONE_DEG:L_ATT").map_err(invalid)?;
            let vec3 = |text: &str, what: &str| -> Result<Vec3, String> {
                let v: Vec<f32> = text
                    .split(',')
                    .map(|x| x.trim().parse::<f32>())
                    .collect::<Result<_, _>>()
                    .map_err(|_| format!("{what} must be three numbers x,y,z, got '{text}'"))?;
                match v.as_slice() {
                    [x, y, z] => Ok(Vec3::new(*x, *y, *z)),
                    _ => Err(format!("{what} must be three numbers x,y,z, got '{text}'")),
                }
            };
            let position = vec3(args[0], "the position").map_err(invalid)?;
            let target = vec3(args[1], "the target").map_err(invalid)?;
            let cone_deg = args[2]
                .parse::<f32>()
                .map_err(|_| invalid(format!("CONE_DEG must be a number of degrees, got '{}'", args[2])))?;
            let range = parse_range(args[3]).map_err(invalid)?;
            LightLayout::Spot { position, target, cone_deg, range }
        }
        "paper" | "scene" => {
            expect_fields(&args, 0, 0, &kind).map_err(invalid)?;
            if kind == "paper" {
                LightLayout::Paper
            } else {
                LightLayout::Scene
            }
        }
        "" => return Err(invalid(format!("the spec is empty; {USAGE}"))),
        other => return Err(invalid(format!("unknown layout '{other}'; {USAGE}"))),
    };

    // Report the limit with the spec as the user wrote it.
    match layout.validate() {
        Err(LayoutError::TooManyLights { count, max, .. }) => {
            Err(LayoutError::TooManyLights { spec: spec.to_string(), count, max })
        }
        Err(LayoutError::Invalid { reason, .. }) => Err(invalid(reason)),
        Err(other) => Err(other),
        Ok(()) => Ok(layout),
    }
}

fn expect_fields(args: &[&str], min: usize, max: usize, form: &str) -> Result<(), String> {
    if (min..=max).contains(&args.len()) {
        return Ok(());
    }
    let expected = if min == max { format!("{min}") } else { format!("{min} to {max}") };
    Err(format!("expected {expected} field(s) after the layout name ({form}), got {}", args.len()))
}

/// A light count: a plain whole number. A number too big for `usize` saturates so it is reported as too many
/// lights rather than as garbage.
fn parse_count(s: &str, what: &str) -> Result<usize, String> {
    if !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit()) {
        return Ok(s.parse::<usize>().unwrap_or(usize::MAX));
    }
    Err(format!("{what} must be a whole number >= 0, got '{s}'"))
}

/// An attenuation range `L_att`: a finite number > 0 (Rust's float parser also accepts `nan` and `inf`).
fn parse_range(s: &str) -> Result<f32, String> {
    let value = s.parse::<f32>().map_err(|_| format!("L_ATT must be a number > 0 (the light range), got '{s}'"))?;
    check_range(value).map(|()| value).map_err(|_| format!("L_ATT must be a finite number > 0, got '{s}'"))
}

fn check_range(range: f32) -> Result<(), String> {
    if range.is_finite() && range > 0.0 {
        Ok(())
    } else {
        Err(format!("L_ATT must be a finite number > 0, got {range}"))
    }
}

/// The layout a scene without lights starts with (most OBJ files, many glTF models): 16 seeded lights inside
/// its bounds reaching a third of its diagonal, so the first image is lit rather than ambient-only.
pub fn default_for_unlit(scene: &Scene) -> LightLayout {
    let diagonal = usable_bounds(&scene.bounds).size().length();
    let range = (diagonal / 3.0).clamp(1e-3, 1e6);
    LightLayout::Random { count: 16, range, seed: 1 }
}

/// Place the lights of `layout` in `scene`. Deterministic: the same layout and scene give the same lights.
pub fn generate(layout: &LightLayout, scene: &Scene) -> Result<Vec<PointLight>, LayoutError> {
    layout.validate()?;
    let bounds = usable_bounds(&scene.bounds);
    let lights = match *layout {
        LightLayout::Random { count, range, seed } => random_lights(&bounds, count, range, seed),
        LightLayout::Above { count, range, seed } => random_lights(&above(&bounds), count, range, seed),
        LightLayout::Circles { circles, per_circle, range } => circle_lights(&bounds, circles, per_circle, range),
        LightLayout::Grid { nx, ny, range } => grid_lights(&bounds, nx, ny, range),
        LightLayout::Paper => paper_lights(scene)?,
        LightLayout::Scene => {
            // A scene assembled in code (or a future loader) must not bypass the limit either.
            if scene.lights.len() > MAX_LIGHTS {
                return Err(LayoutError::TooManyLights {
                    spec: "scene".into(),
                    count: scene.lights.len(),
                    max: MAX_LIGHTS,
                });
            }
            scene.lights.clone()
        }
        LightLayout::Spot { position, target, cone_deg, range } => {
            let intensity = layout_intensity(range, 1, 1.0 / light_volume(bounds.size()));
            let spot = crate::scene::Spot::aimed(position, target, cone_deg.to_radians(), 0.2);
            vec![PointLight::new(position, warm_white(), intensity, range).with_spot(spot)]
        }
    };
    Ok(lights)
}

/// The scene bounds, or a unit box when a scene has none (a hand-made scene that was never finalised).
fn usable_bounds(bounds: &Aabb) -> Aabb {
    if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
        Aabb { min: Vec3::splat(-1.0), max: Vec3::splat(1.0) }
    } else {
        *bounds
    }
}

/// The volume that a density is measured in: each side at least a tenth of the longest, so a flat scene does
/// not get an infinite light density.
fn light_volume(size: Vec3) -> f32 {
    let floor = (size.max_element() * 0.1).max(1e-3);
    size.max(Vec3::splat(floor)).element_product()
}

fn random_lights(bounds: &Aabb, count: usize, range: f32, seed: u64) -> Vec<PointLight> {
    // 5% in from every side keeps lights out of the walls that usually form a scene's bounds.
    let inset = bounds.size() * 0.05;
    let (lo, hi) = (bounds.min + inset, bounds.max - inset);
    let intensity = layout_intensity(range, 1, count as f32 / light_volume(hi - lo));
    let mut rng = SplitMix64::new(seed);
    (0..count)
        .map(|_| {
            let t = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
            PointLight::new(lo + (hi - lo) * t, warm_color(&mut rng), intensity, range)
        })
        .collect()
}

/// The box `above` fills (before `random_lights`' 5% inset): the scene's footprint, from its top to half its
/// height higher (at least a tenth of its widest side, so that a flat scene gets a slab, not a plane).
fn above(bounds: &Aabb) -> Aabb {
    let size = bounds.size();
    let depth = (0.5 * size.y).max(0.1 * size.x.max(size.z)).max(1e-3);
    // The inset takes 5% of the slab's height off its bottom: start that much lower (h = depth / 0.95, 0.05 h =
    // depth / 19), so that the lowest light is at the top.
    let min = Vec3::new(bounds.min.x, bounds.max.y - depth / 19.0, bounds.min.z);
    Aabb { min, max: Vec3::new(bounds.max.x, bounds.max.y + depth, bounds.max.z) }
}

/// Circles like LightCluster's Sponza layout: two rows of circles along the longest horizontal axis, at 30% of
/// the short extent either side of the centre and 15% up the bounds' height, spread over the middle 80%.
fn circle_lights(bounds: &Aabb, circles: usize, per_circle: usize, range: f32) -> Vec<PointLight> {
    let size = bounds.size();
    let center = bounds.center();
    // Work in (long, short) horizontal coordinates so the rows follow whichever axis is longer.
    let along_x = size.x >= size.z;
    let (long, short) = if along_x { (size.x, size.z) } else { (size.z, size.x) };
    let to_world = |l: f32, s: f32, y: f32| {
        if along_x {
            Vec3::new(center.x + l, y, center.z + s)
        } else {
            Vec3::new(center.x + s, y, center.z + l)
        }
    };
    let height = bounds.min.y + size.y * 0.15;
    let rows = [(circles.div_ceil(2), -0.3 * short), (circles / 2, 0.3 * short)];
    let widest_row = circles.div_ceil(2).max(1) as f32;
    let spacing = long * 0.8 / widest_row;
    let radius = 0.1 * spacing.min(short * 0.5);
    let intensity = layout_intensity(range, per_circle, (circles * per_circle) as f32 / light_volume(size));

    let mut lights = Vec::with_capacity(circles * per_circle);
    for (row_count, offset) in rows {
        let row_spacing = long * 0.8 / row_count.max(1) as f32;
        for i in 0..row_count {
            let l = -0.4 * long + (i as f32 + 0.5) * row_spacing;
            let circle_center = to_world(l, offset, height);
            lights.extend(circle(circle_center, radius, per_circle, range, intensity, warm_white()));
        }
    }
    lights
}

/// `n` lights evenly on a horizontal circle, the first on the +X side.
fn circle(center: Vec3, radius: f32, n: usize, range: f32, intensity: f32, color: Vec3) -> Vec<PointLight> {
    (0..n)
        .map(|i| {
            let angle = std::f32::consts::TAU * i as f32 / n as f32;
            let offset = Vec3::new(angle.cos(), 0.0, angle.sin()) * radius;
            PointLight::new(center + offset, color, intensity, range)
        })
        .collect()
}

/// Lights at the centres of an `nx` x `ny` grid of cells covering the bounds (so half a cell of margin).
fn grid_lights(bounds: &Aabb, nx: usize, ny: usize, range: f32) -> Vec<PointLight> {
    let size = bounds.size();
    let height = bounds.min.y + size.y / 3.0;
    let intensity = layout_intensity(range, 1, (nx * ny) as f32 / light_volume(size));
    let mut lights = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let x = bounds.min.x + (i as f32 + 0.5) / nx as f32 * size.x;
            let z = bounds.min.z + (j as f32 + 0.5) / ny as f32 * size.z;
            lights.push(PointLight::new(Vec3::new(x, height, z), warm_white(), intensity, range));
        }
    }
    lights
}

/// The paper light set: built-in scenes keep their own, a scene named like Sponza gets LightCluster's 80.
fn paper_lights(scene: &Scene) -> Result<Vec<PointLight>, LayoutError> {
    if let SceneSource::Builtin(name) = &scene.source {
        if let Some(lights) = builtin::paper_lights(name) {
            return Ok(lights);
        }
    }
    if scene.name.to_ascii_lowercase().contains("sponza") {
        return Ok(sponza_paper_lights(&usable_bounds(&scene.bounds)));
    }
    Err(LayoutError::NoPaperLayout {
        scene: scene.name.clone(),
        known: format!(
            "{} (built-in) and Dabrovic Sponza (a scene whose name contains 'sponza')",
            builtin::NAMES.join(", ")
        ),
    })
}

/// Dabrovic Sponza's size along X in metres (bounds about x[-17.40, 17.42]).
const SPONZA_SIZE_X: f32 = 34.82;

/// The intensity of the Sponza paper lights. Measured without shadows on the OBJ's surfaces (albedo 0.7), the
/// lit surfaces get a median radiance of ~0.4 and ~1.5 near the circles (90th percentile); the built-in arcade
/// uses the same value for its copy of this layout.
const SPONZA_PAPER_INTENSITY: f32 = 8.0;

/// LightCluster's Dabrovic Sponza light set (Fig. 7): 80 lights, circles of eight with radius 0.14 m at 1.5 m
/// above the floor, five circles in each ground-floor side arcade, `L_att` = 7. The paper does not give the
/// circles' radius; 0.14 m gives exactly the paper's cluster counts for `d_init` 0.1 / 0.3 / 0.5 / 1.6,
/// 80 / 44 / 26 / 10 (Table 1), with the camera down the nave at x = -14 and `z_far` = 30.
///
/// Positions come from the OBJ (in metres): the floor is at y = 0.09, the ground-floor columns of the two
/// colonnades stand at x = ±2.2, ±6.6 and ±11.1 (corner piers) on z = ±2.85, and the side arcades run from the
/// columns to the inner walls at z = ±7.2. The circles sit in the middle of the arcades (z = ±5.2), centred on
/// the bays: between the columns (x = 0, ±4.4, ±8.85).
///
/// The model is centred on the origin, so a scene loaded with another unit scale is matched by scaling the
/// positions and the range by the ratio of its size to the size in metres.
fn sponza_paper_lights(bounds: &Aabb) -> Vec<PointLight> {
    let ratio = bounds.size().x / SPONZA_SIZE_X;
    // Loaded in metres the ratio is 1 up to float noise: keep the paper's exact numbers then.
    let scale = if (ratio - 1.0).abs() < 0.05 || !ratio.is_finite() || ratio <= 0.0 { 1.0 } else { ratio };
    const BAY_X: [f32; 5] = [-8.85, -4.4, 0.0, 4.4, 8.85];
    const ARCADE_Z: f32 = 5.2;
    const HEIGHT: f32 = 0.09 + 1.5;
    const RADIUS: f32 = 0.14;
    let mut lights = Vec::with_capacity(80);
    for side in [-1.0f32, 1.0] {
        for x in BAY_X {
            let center = Vec3::new(x, HEIGHT, side * ARCADE_Z) * scale;
            lights.extend(circle(
                center,
                RADIUS * scale,
                8,
                SPONZA_PAPER_RANGE * scale,
                SPONZA_PAPER_INTENSITY,
                warm_white(),
            ));
        }
    }
    lights
}

/// A light intensity for lights of range `range` that lights a surface of albedo [`REFERENCE_ALBEDO`] to about
/// [`TARGET_RADIANCE`] when the surface faces one light at half its range.
pub fn default_intensity_for_range(range: f32) -> f32 {
    layout_intensity(range, 1, 0.0)
}

/// The intensity of a generated layout, from two estimates of the radiance a lit surface gets per unit
/// intensity, whichever is larger:
/// - *sparse*: the surface faces one group of `cluster` lights (1, or a circle) at half the range:
///   `albedo / pi * cluster * attenuation(range / 2)`;
/// - *dense*: lights fill the half-space in front of the surface with `density` lights per unit volume. Summing
///   `albedo / pi * attenuation(d) * cos` over that half-space gives `albedo * density * G(range)` with
///   `G(r) = integral_0^r attenuation(d) d^2 dd` (the cosine integrates to pi over the hemisphere).
///
/// The intensity then brings that radiance to [`TARGET_RADIANCE`]. Shadows make real images darker, and the
/// tone mapping compresses the brighter spots near lights.
pub fn layout_intensity(range: f32, cluster: usize, density: f32) -> f32 {
    if !(range.is_finite() && range > 0.0) {
        return 0.0;
    }
    let sparse = cluster.max(1) as f32 * attenuation(0.5 * range, range) / std::f32::consts::PI;
    let dense = density.max(0.0) * attenuation_moment(range);
    TARGET_RADIANCE / (REFERENCE_ALBEDO * sparse.max(dense))
}

/// `integral_0^range attenuation(d) d^2 dd`, by Simpson's rule (the integrand is smooth).
fn attenuation_moment(range: f32) -> f32 {
    const STEPS: usize = 64;
    let h = range / STEPS as f32;
    let f = |d: f32| attenuation(d, range) * d * d;
    let inner: f32 = (1..STEPS).map(|i| f(i as f32 * h) * if i % 2 == 1 { 4.0 } else { 2.0 }).sum();
    (f(0.0) + inner + f(range)) * h / 3.0
}

/// The colour of structured layouts (circles, grids, Sponza): a warm white, like the papers' yellowish lights.
fn warm_white() -> Vec3 {
    Vec3::new(1.0, 0.9, 0.75)
}
