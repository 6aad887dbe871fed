//! LightCluster's min-distance light clustering (Wiesenhütter, Klein, Nischwitz 2013, section 3.1), on the CPU.
//!
//! A pure, deterministic function of the lights, the camera position, the view frustum and [`ClusterParams`]:
//! the same input always gives the same [`Clustering`], bit for bit.
//!
//! # Symbols (as in the paper)
//!
//! - `L_att`: a light's attenuation range, [`PointLight::range`]; the radius of its bounding sphere.
//! - `C_pos`: the position of a cluster center, which is always a real light ([`Cluster::position`]);
//!   `|C_pos|` is its distance to the camera position.
//! - `d_init`: the initial (largest) minimum distance between clusters, [`ClusterParams::d_init`].
//! - `z_far`: the maximum view distance, [`ClusterParams::z_far`] (normally the camera's far plane).
//! - `d_min = d_init * (1 - |C_pos| / z_far)`: the minimum distance of one center, [`Cluster::d_min`],
//!   computed by [`ClusterParams::d_min_at`]; smaller near the far plane, so clusters are smaller (more shadow
//!   maps) near the camera.
//! - `d_C`: the distance of a light to the center of its cluster.
//! - `C_att = max(C_att, d_C + L_att)`: the attenuation range of a cluster, [`Cluster::c_att`]; it starts as
//!   the center light's own `L_att`.
//!
//! # Steps (one function each, all run by [`Clusterer::cluster_into`])
//!
//! 1. **Cull** (`Clusterer::cull`, section 3.1.2): a light is visible when [`PointLight::is_valid`] and its
//!    bounding sphere (center = position, radius = `L_att`) passes [`Frustum::intersects_sphere`]. All other
//!    lights (including NaN positions) are culled: `cluster_of` is `None` for them.
//! 2. **Sort** (`sort_by_range`, section 3.1.2): the visible lights by `L_att`, largest first; equal ranges keep
//!    input order (a stable sort), so the result is deterministic.
//! 3. **Select cluster centers** (`Clusterer::select_centers`, section 3.1.2): in sorted order, the first light
//!    is a center; a later light becomes a new center when it is farther than `d_min(c)` from *every* existing
//!    center `c` (`d_min` is per center: `distance(light, c) > d_min(c)` for all `c`). Otherwise it is marked
//!    unclustered for step 4 (it does *not* join the center that covered it).
//! 4. **Assign the remaining lights** (`Clusterer::assign_remaining`, section 3.1.3): every unclustered light
//!    joins its *nearest* center (smallest squared distance; on an exact tie the center selected first);
//!    `Clusterer::write_output` then lists the members and grows each cluster's `C_att = max(C_att, d_C + L_att)`.
//!
//! # Conventions beyond the paper
//!
//! - The scale `1 - |C_pos| / z_far` is clamped to `[0, 1]`: a center at or beyond `z_far` from the camera (it
//!   can still be visible through its range) gets `d_min = 0`.
//! - A center with `d_min = 0` covers no other light, not even one at exactly the same position. So
//!   `d_init = 0` gives exactly one cluster per visible light (the reference technique's shadow count).
//! - `adaptive: false` switches the view-adaptive scaling off: `d_min = d_init` for every center. The paper
//!   suggests this against flickering when the camera moves.
//! - Invalid parameters never panic: a NaN or negative `d_init` is treated as 0 (one cluster per light), an
//!   infinite one as `f32::MAX`; a NaN or non-positive `z_far` disables the scaling (scale 1), as does
//!   `z_far = inf`. [`ClusterParams::validate`] reports these for a UI.
//! - Clusters are numbered in the order their centers were selected, so `clusters[0]` holds the visible light
//!   with the largest range. [`Cluster::members`] lists the center first, then the other members in sorted
//!   (step 2) order.
//!
//! # Performance
//!
//! Steps 3 and 4 never compare a light against all centers: centers go into a multi-level uniform grid, and
//! every search visits only the cells overlapping the axis-aligned box whose half-width is the search radius,
//! then applies the exact distance test.
//!
//! - **Levels.** View-adaptive `d_min` shrinks from `d_init` at the camera to 0 at `z_far`, so the spacing of
//!   centers varies a lot across the frustum and no single cell size fits. Level `l` has cells of
//!   `d_init / 2^l` and holds the centers with `d_min` in `(d_init / 2^(l+1), d_init / 2^l]`, so a search of
//!   radius `<= d_min` spans at most 3 cells per axis of its level, and a cell holds few centers (they are more
//!   than `d_min` apart). Levels stop at a floor cell size, twice the estimated spacing of the visible lights
//!   (from the share of cells of their bounding box that a strided sample of at most 512 of them occupies, so
//!   flat, linear and clumped layouts are estimated well); all smaller `d_min` (and 0) share the floor level,
//!   whose cells hold a few lights. Without view-adaptive scaling there is one level.
//! - **Slots laid out up front.** A light's `d_min`, so its level and cell (its "slot"), are known before step
//!   3, from its distance to the camera alone. A counting sort gives every slot a contiguous run with room for
//!   all its lights; a new center is appended to its slot's run. So a cell's centers are read sequentially, in
//!   selection order, without linked lists. In a dense level the runs of a row of cells along x are adjacent
//!   and the entries not (yet) used by a center are NaN, which no distance test accepts, so a search reads a
//!   row of cells as one slice.
//! - **Dense or hash.** A level is a dense array of slots over the visible lights' bounding box when that has
//!   at most `4 * lights + 4096` cells; otherwise its cells live in a hash table (open addressing, keyed by
//!   level and cell coordinates), so a tiny `d_init` or a few far-away lights cost memory proportional to the
//!   lights, never to the scene's volume.
//! - **Pruning levels.** A level records the range of its centers' distances to the camera; a light at distance
//!   `D` from the camera searches a level with radius `h` only when that range meets `[D - h, D + h]` (a center
//!   within `h` of the light is within `h` of `D`, by the triangle inequality), so most searches visit one level.
//! - **Step 3** searches each level with the smaller of the largest `d_min` of its centers and a bound from the
//!   light's own distance to the camera (`CoverBound`). A center's entry holds `cover_limit(d_min)`, the largest
//!   squared distance whose square root is at most `d_min`, so `distance <= d_min` is tested without a square
//!   root.
//! - **Step 4 is exact**: a light reached step 4 because some center `c` covered it at distance
//!   `r = distance(light, c) <= d_min(c) <= d_init` (recorded per light in step 3). The nearest center is at
//!   most `r` away, so searching every level with radius `r` finds it and every tie; the nearest center in the
//!   light's own cell is searched first and shrinks `r` further. With many such lights
//!   they are visited slot by slot, so neighbours share cached cells; the results do not depend on the order.
//! - **Rounding.** Boxes are computed in `f64` and widened by a relative `1e-4` plus `1e-6` cells, and level
//!   pruning by a relative `1e-4`, far more than `f32` distance rounding, so no candidate is ever missed: the
//!   result is exactly that of the brute-force `O(lights * centers)` algorithm (the tests compare the two).
//!
//! Step 1 is branch-free (four frustum planes per SIMD lane group; it and step 2's sort live in `cull_sort.rs`) and copies each visible light's position and
//! range into a compact array, which steps 2 and 3 read in sorted order instead of the whole lights. The sort is
//! a stable LSD radix sort on the range's bits for many lights. [`Clusterer`] keeps every buffer
//! between calls and reuses the output's clusters (and their member vectors) through
//! [`Clusterer::cluster_into`], so a frame allocates nothing once buffers have grown. [`cluster_lights`] is the
//! allocating convenience wrapper.

use glam::Vec3;

pub use super::cluster_params::ClusterParams;
use super::cull_sort::{is_visible, sort_by_range, FrustumLanes, RADIX_BUCKETS};
use super::grid::{Grid, NONE};
pub use super::grid::{GridInfo, GridKind};
use crate::math::Frustum;
use crate::scene::PointLight;

/// Inputs must be shorter (a hash grid has up to `2 * lights` slots, all `u32` indices).
const MAX_LIGHTS: usize = 1 << 30;
/// From this many lights left for step 4 on, they are visited in grid order (better cache use).
const SPATIAL_ORDER_MIN: usize = 2048;

/// One cluster: a center light and the lights assigned to it.
#[derive(Clone, Debug, PartialEq)]
pub struct Cluster {
    /// Index of the center light in the input slice.
    pub center: usize,
    /// Input indices of the member lights: the center first, then the others in sorted order (largest
    /// `L_att` first, then by index).
    pub members: Vec<usize>,
    /// The center's minimum distance `d_min`; the paper uses it as the radius of the cluster's area light.
    pub d_min: f32,
    /// The cluster's attenuation range `C_att`: `max(L_att(center), max over members of d_C + L_att)`.
    pub c_att: f32,
    /// The center light's position `C_pos`.
    pub position: Vec3,
    /// The largest distance `d_C` of a member to the center (0 for a lone light).
    pub radius: f32,
}

/// The result of [`cluster_lights`] / [`Clusterer::cluster_into`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Clustering {
    /// In the order the centers were selected.
    pub clusters: Vec<Cluster>,
    /// Per input light, its index in `clusters`; `None` when the light was culled (step 1).
    pub cluster_of: Vec<Option<u32>>,
    /// How many lights passed step 1 (the sum of all clusters' member counts).
    pub visible: usize,
}

/// Cluster lights with fresh buffers: steps 1 to 4 of section 3.1 (see the [module docs](self)).
///
/// For every frame, prefer a long-lived [`Clusterer`] and [`Clusterer::cluster_into`], which reuse all
/// buffers and the output's vectors.
pub fn cluster_lights(
    lights: &[PointLight],
    camera_position: Vec3,
    frustum: &Frustum,
    params: &ClusterParams,
) -> Clustering {
    let mut out = Clustering::default();
    Clusterer::default().cluster_into(lights, camera_position, frustum, params, &mut out);
    out
}

/// The clustering with its scratch buffers, kept between frames so that clustering does not allocate.
#[derive(Debug, Default)]
pub struct Clusterer {
    /// Step 1/2: per visible light `(!range_bits) << 32 | visible index`; sorted ascending = step 2's order
    /// (visible lights are numbered in input order, so ties keep input order).
    keys: Vec<u64>,
    /// Step 1: per visible light in input order, its input index and `[x, y, z, L_att]`: step 2's gather reads
    /// these (compact, 16 bytes a light) instead of the whole lights.
    visible_ids: Vec<u32>,
    visible_lights: Vec<[f32; 4]>,
    /// Scratch for an unsorted `visible` list handed to `cluster_visible_into`.
    visible_sorted: Vec<usize>,
    keys_tmp: Vec<u64>,
    radix_counts: Vec<[u32; RADIX_BUCKETS]>,
    /// Per visible light in sorted order: input index, position, range, distance to the camera.
    ids: Vec<u32>,
    pos: Vec<Vec3>,
    range: Vec<f32>,
    to_camera: Vec<f32>,
    /// Per visible light in sorted order: its cluster ([`NONE`] until assigned).
    cluster: Vec<u32>,
    /// Per visible light in sorted order that is no center: the distance to the center that covered it in
    /// step 3, then the distance `d_C` to its cluster's center after step 4.
    cover: Vec<f32>,
    /// Per visible light in sorted order: its `d_min` were it a center.
    d_min: Vec<f32>,
    /// Per center (cluster index), in selection order: its visible light (sorted order) and position.
    center_light: Vec<u32>,
    centers: Vec<Vec3>,
    /// Step 4 scratch: per grid slot the end of its non-centers in `by_slot`, and the non-centers by slot.
    cursor: Vec<u32>,
    by_slot: Vec<u32>,
    /// Member vectors of clusters dropped from an output, for reuse.
    spare_members: Vec<Vec<usize>>,
    grid: Grid,
}

/// Bound on the distance of any center that can cover a light (view-adaptive only): with
/// `k = d_init / z_far < 1`, a center `c` covering `p` satisfies
/// `|p - c| <= d_min(c) <= d_init (1 - (|p| - |p - c|) / z_far)`, so `|p - c| <= d_init (1 - |p| / z_far) / (1 - k)`
/// (distances to the camera). Widened by a relative 1e-4 plus `d_init * 1e-5` for rounding.
#[derive(Clone, Copy, Debug)]
struct CoverBound {
    enabled: bool,
    scale: f32,
    inv_z_far: f32,
    slack: f32,
}

impl CoverBound {
    fn new(params: &ClusterParams) -> Self {
        let d_init = params.effective_d_init();
        let k = d_init as f64 / params.z_far as f64;
        let enabled = params.is_view_adaptive() && params.z_far.is_finite() && k <= 0.5;
        CoverBound {
            enabled,
            scale: if enabled { (d_init as f64 / (1.0 - k) * 1.0001) as f32 } else { 0.0 },
            inv_z_far: if enabled { 1.0 / params.z_far } else { 0.0 },
            slack: d_init * 1e-5,
        }
    }

    /// Largest distance of a center that can cover a light `to_camera` from the camera (may be negative: none).
    #[inline(always)]
    fn radius(&self, to_camera: f32) -> f32 {
        if self.enabled && to_camera.is_finite() {
            self.scale * (1.0 - to_camera * self.inv_z_far) + self.slack
        } else {
            f32::INFINITY
        }
    }
}

impl Clusterer {
    pub fn new() -> Self {
        Self::default()
    }

    /// Cluster `lights` into a new [`Clustering`] (allocates the output; buffers are reused).
    pub fn cluster(
        &mut self,
        lights: &[PointLight],
        camera_position: Vec3,
        frustum: &Frustum,
        params: &ClusterParams,
    ) -> Clustering {
        let mut out = Clustering::default();
        self.cluster_into(lights, camera_position, frustum, params, &mut out);
        out
    }

    /// Cluster `lights` into `out`, overwriting it and reusing its vectors (steps 1 to 4).
    ///
    /// # Panics
    /// When `lights` has 2^30 or more entries (indices are `u32`, grid slots need headroom).
    pub fn cluster_into(
        &mut self,
        lights: &[PointLight],
        camera_position: Vec3,
        frustum: &Frustum,
        params: &ClusterParams,
        out: &mut Clustering,
    ) {
        assert!(lights.len() < MAX_LIGHTS, "at most {} lights can be clustered", MAX_LIGHTS - 1);
        self.cull(lights, frustum);
        self.cluster_culled(camera_position, params, lights.len(), out);
    }

    /// [`Clusterer::cluster_into`] with step 1 already done: `visible` are the indices (ascending) of the valid
    /// lights whose range touches the frustum, as the renderer's light list (`VisibleLights`) holds them. The
    /// result is the same as `cluster_into`'s with that frustum.
    pub fn cluster_visible_into(
        &mut self,
        lights: &[PointLight],
        visible: &[usize],
        camera_position: Vec3,
        params: &ClusterParams,
        out: &mut Clustering,
    ) {
        assert!(lights.len() < MAX_LIGHTS, "at most {} lights can be clustered", MAX_LIGHTS - 1);
        // Visible lights are numbered in input order, so that equal ranges keep it (step 2).
        let mut sorted = std::mem::take(&mut self.visible_sorted);
        let visible = if visible.is_sorted() {
            visible
        } else {
            sorted.clear();
            sorted.extend_from_slice(visible);
            sorted.sort_unstable();
            &sorted[..]
        };
        self.keys.clear();
        self.visible_ids.clear();
        self.visible_lights.clear();
        for &i in visible.iter().filter(|&&i| i < lights.len()) {
            let light = &lights[i];
            self.keys.push(((!light.range.to_bits()) as u64) << 32 | self.visible_ids.len() as u64);
            self.visible_ids.push(i as u32);
            let p = light.position;
            self.visible_lights.push([p.x, p.y, p.z, light.range]);
        }
        self.visible_sorted = sorted;
        self.cluster_culled(camera_position, params, lights.len(), out);
    }

    /// Steps 2 onwards, from the culled keys.
    fn cluster_culled(&mut self, camera_position: Vec3, params: &ClusterParams, lights: usize, out: &mut Clustering) {
        sort_by_range(&mut self.keys, &mut self.keys_tmp, &mut self.radix_counts);
        let (min, max) = self.gather(camera_position, params);

        let d_init = params.effective_d_init();
        out.cluster_of.clear();
        out.cluster_of.resize(lights, None);
        if d_init > 0.0 && self.ids.len() > 1 {
            self.grid.build(&self.pos, &self.d_min, min, max, d_init, params.is_view_adaptive());
        } else {
            self.grid.clear();
        }

        self.select_centers(params);
        if self.centers.len() < self.ids.len() {
            self.assign_remaining();
        }
        self.write_output(out);
    }

    /// Information about the grid of the last call.
    pub fn grid_info(&self) -> GridInfo {
        self.grid.info()
    }

    /// Step 1: keep the lights that are valid and whose bounding sphere of radius `L_att` touches the frustum,
    /// as sort keys (`!range_bits << 32 | index`) in input order.
    fn cull(&mut self, lights: &[PointLight], frustum: &Frustum) {
        // Branch-free compaction: write every key, keep it by advancing only past visible ones.
        self.keys.resize(lights.len(), 0);
        self.visible_ids.resize(lights.len(), 0);
        self.visible_lights.resize(lights.len(), [0.0; 4]);
        let planes = FrustumLanes::new(frustum);
        let mut visible = 0;
        for (i, light) in lights.iter().enumerate() {
            // A valid range is positive and finite, so its bits order like its value; `!` makes the ascending
            // key order the descending range order.
            self.keys[visible] = ((!light.range.to_bits()) as u64) << 32 | visible as u64;
            self.visible_ids[visible] = i as u32;
            let p = light.position;
            self.visible_lights[visible] = [p.x, p.y, p.z, light.range];
            visible += is_visible(light, &planes) as usize;
        }
        self.keys.truncate(visible);
        self.visible_ids.truncate(visible);
        self.visible_lights.truncate(visible);
    }

    /// Lay out the visible lights in sorted order for steps 3 and 4, with their distance to the camera and
    /// `d_min`; returns their bounding box.
    fn gather(&mut self, camera: Vec3, params: &ClusterParams) -> (Vec3, Vec3) {
        let n = self.keys.len();
        for v in [&mut self.range, &mut self.to_camera, &mut self.d_min] {
            v.resize(n, 0.0);
        }
        self.ids.resize(n, 0);
        self.pos.resize(n, Vec3::ZERO);
        let adaptive = params.is_view_adaptive();
        let (mut min, mut max) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for (i, &key) in self.keys.iter().enumerate() {
            let v = key as u32 as usize;
            self.ids[i] = self.visible_ids[v];
            let [x, y, z, range] = self.visible_lights[v];
            let position = Vec3::new(x, y, z);
            self.pos[i] = position;
            self.range[i] = range;
            min = min.min(position);
            max = max.max(position);
            // The same expression as `ClusterParams::d_min_at(position, camera)`.
            let to_camera = if adaptive { position.distance(camera) } else { 0.0 };
            self.to_camera[i] = to_camera;
            self.d_min[i] = params.d_min_at_distance(to_camera);
        }
        (min, max)
    }

    /// Step 3: select the cluster centers in sorted order. Centers get their cluster index in `cluster`;
    /// the others keep [`NONE`] and get their covering distance in `cover`.
    fn select_centers(&mut self, params: &ClusterParams) {
        let n = self.ids.len();
        self.cluster.clear();
        self.cluster.resize(n, NONE);
        self.cover.clear();
        self.cover.resize(n, 0.0);
        self.centers.clear();
        self.center_light.clear();
        let bound = CoverBound::new(params);
        for i in 0..n {
            let p = self.pos[i];
            let to_camera = self.to_camera[i];
            if let Some(d) = self.covering_distance(p, to_camera, bound.radius(to_camera)) {
                self.cover[i] = d;
                continue;
            }
            let k = self.centers.len() as u32;
            self.cluster[i] = k;
            self.centers.push(p);
            self.center_light.push(i as u32);
            self.grid.insert(i, p, to_camera, self.d_min[i], k);
        }
    }

    /// Step 3's test: the distance to some center `c` with `distance <= d_min(c)` and `d_min(c) > 0`, or `None`
    /// when `p` is farther than `d_min(c)` from every center (so it becomes a center). Each level is searched
    /// with the smaller of the largest `d_min` of its centers and `bound` (see [`CoverBound`]); the light's own
    /// cell first, where a covering center is most likely.
    #[inline]
    fn covering_distance(&self, p: Vec3, to_camera: f32, bound: f32) -> Option<f32> {
        if bound.is_nan() || bound < 0.0 {
            return None;
        }
        let grid = &self.grid;
        for level in 0..grid.levels.len() {
            // A level whose centers all have d_min 0 covers nothing.
            let radius = grid.levels[level].max_d_min.min(bound);
            if radius.is_nan() || radius <= 0.0 {
                continue;
            }
            let Some(b) = grid.search_box(level, p, to_camera, radius) else {
                continue;
            };
            if grid.levels[level].dense {
                // Each row of cells along x is one contiguous run of entries (unused ones never cover).
                for z in b.lo[2]..=b.hi[2] {
                    for y in b.lo[1]..=b.hi[1] {
                        if let Some(d) = grid.cover_in(grid.dense_row(level, b.lo[0], b.hi[0], y, z), p) {
                            return Some(d);
                        }
                    }
                }
                continue;
            }
            if let Some(d) = grid.cover_in(grid.centers_in_cell(grid.slot(level, b.own)).0, p) {
                return Some(d);
            }
            for z in b.lo[2]..=b.hi[2] {
                for y in b.lo[1]..=b.hi[1] {
                    for x in b.lo[0]..=b.hi[0] {
                        if [x, y, z] != b.own {
                            if let Some(d) = grid.cover_in(grid.centers_in_cell(grid.slot(level, [x, y, z])).0, p) {
                                return Some(d);
                            }
                        }
                    }
                }
            }
        }
        None
    }

    /// Step 4: assign every light that is no center to its nearest center (`cluster`, and `d_C` in `cover`).
    /// Many lights are visited grid slot by grid slot, so that neighbours share cached cells.
    fn assign_remaining(&mut self) {
        let n = self.ids.len();
        let remaining = n - self.centers.len();
        if remaining < SPATIAL_ORDER_MIN || self.grid.levels.is_empty() {
            for i in 0..n {
                if self.cluster[i] == NONE {
                    self.assign(i);
                }
            }
            return;
        }
        let runs = &self.grid.runs;
        self.cursor.clear();
        self.cursor.extend(runs.iter().map(|r| r[0]));
        self.by_slot.resize(n, 0);
        for i in 0..n {
            if self.cluster[i] == NONE {
                let c = &mut self.cursor[self.grid.light_slot[i] as usize];
                self.by_slot[*c as usize] = i as u32;
                *c += 1;
            }
        }
        for s in 0..self.cursor.len() {
            for j in self.grid.runs[s][0]..self.cursor[s] {
                self.assign(self.by_slot[j as usize] as usize);
            }
        }
    }

    /// Step 4 for visible light `i`.
    #[inline]
    fn assign(&mut self, i: usize) {
        let p = self.pos[i];
        let (k, d2) = match self.nearest_center(p, self.to_camera[i], self.cover[i], self.grid.light_slot[i]) {
            Some(found) => found,
            // Unreachable (the covering center is within the searched boxes); kept exact and panic-free.
            None => self.nearest_center_brute_force(p),
        };
        self.cluster[i] = k;
        self.cover[i] = d2.sqrt();
    }

    /// Write the clusters: centers first (in selection order), then every other light in sorted order, growing
    /// its cluster's `C_att = max(C_att, d_C + L_att)`.
    fn write_output(&mut self, out: &mut Clustering) {
        out.visible = self.ids.len();
        // Keep the member vectors of clusters no longer needed for later frames with more clusters.
        let keep = self.centers.len().min(out.clusters.len());
        // Reversed, so that popping hands each vector back to the same cluster index next time.
        self.spare_members.extend(out.clusters.drain(keep..).rev().map(|c| c.members));
        for (k, &i) in self.center_light.iter().enumerate() {
            let i = i as usize;
            let (id, d_min, range, position) = (self.ids[i] as usize, self.d_min[i], self.range[i], self.pos[i]);
            match out.clusters.get_mut(k) {
                Some(c) => {
                    c.center = id;
                    c.members.clear();
                    c.members.push(id);
                    c.d_min = d_min;
                    c.c_att = range;
                    c.position = position;
                    c.radius = 0.0;
                }
                None => out.clusters.push(Cluster {
                    center: id,
                    members: {
                        let mut members = self.spare_members.pop().unwrap_or_default();
                        members.clear();
                        members.push(id);
                        members
                    },
                    d_min,
                    c_att: range,
                    position,
                    radius: 0.0,
                }),
            }
        }
        for (i, &k) in self.cluster.iter().enumerate() {
            let id = self.ids[i] as usize;
            out.cluster_of[id] = Some(k);
            if self.center_light[k as usize] as usize != i {
                let d_c = self.cover[i];
                let cluster = &mut out.clusters[k as usize];
                cluster.members.push(id);
                cluster.c_att = cluster.c_att.max(d_c + self.range[i]);
                cluster.radius = cluster.radius.max(d_c);
            }
        }
    }

    /// The nearest center to `p` (smallest squared distance, then smallest cluster index) among the centers
    /// within `radius`, with its squared distance.
    #[inline]
    fn nearest_center(&self, p: Vec3, to_camera: f32, radius: f32, own_slot: u32) -> Option<(u32, f32)> {
        let grid = &self.grid;
        let mut best = (NONE, f32::INFINITY);
        // The centers of the light's own cell first: the nearest of them bounds the search (the nearest center
        // overall is no farther), which usually shrinks the boxes to a few cells. Visiting them twice is harmless.
        let (entries, first) = grid.centers_in_cell(own_slot);
        grid.nearest_in(p, entries, first, &mut best);
        let search = radius.min(best.1.sqrt());
        for level in 0..grid.levels.len() {
            let Some(b) = grid.search_box(level, p, to_camera, search) else {
                continue;
            };
            let dense = grid.levels[level].dense;
            for z in b.lo[2]..=b.hi[2] {
                for y in b.lo[1]..=b.hi[1] {
                    if dense {
                        let (first, end) = grid.dense_row_range(level, b.lo[0], b.hi[0], y, z);
                        grid.nearest_in(p, &grid.entries[first..end], first, &mut best);
                    } else {
                        for x in b.lo[0]..=b.hi[0] {
                            let (entries, first) = grid.centers_in_cell(grid.slot(level, [x, y, z]));
                            grid.nearest_in(p, entries, first, &mut best);
                        }
                    }
                }
            }
        }
        let (best, best_d2) = best;
        (best != NONE && best_d2.sqrt() <= radius).then_some((best, best_d2))
    }

    fn nearest_center_brute_force(&self, p: Vec3) -> (u32, f32) {
        let mut best = (0, f32::INFINITY);
        for (k, &c) in self.centers.iter().enumerate() {
            let d2 = p.distance_squared(c);
            if d2 < best.1 {
                best = (k as u32, d2);
            }
        }
        best
    }
}
