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
//!    joins its *nearest* center (smallest squared distance; on an exact tie the center selected first) and
//!    grows that cluster's `C_att = max(C_att, d_C + L_att)`.
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
//! Steps 3 and 4 never compare a light against all centers. Centers go into a uniform grid with a cell size of
//! at least `2 * d_init`: a dense array of cells over the visible lights' bounding box when that has at most
//! `4 * lights + 4096` cells, otherwise a hash grid (open addressing, keyed by the cell coordinates) with the
//! same cell size, so a tiny `d_init` (or a few far-away lights) costs memory proportional to the lights, not
//! to the scene's volume. Each search visits only the cells overlapping the axis-aligned box around the light
//! whose half-width is the search radius (so at most 2 x 2 x 2 cells when the radius is at most `d_init`), and
//! the exact distance test decides. The box is computed in `f64` with a small safety margin, so no light
//! within the radius is ever missed through rounding.
//!
//! - Step 3 searches with the largest `d_min` of the centers selected so far (`<= d_init`): every center that
//!   could cover the light lies within it.
//! - Step 4 is exact: a light reached step 4 because some center `c` covered it at distance
//!   `r = distance(light, c) <= d_min(c) <= d_init`. The nearest center is at most `r` away, so searching the
//!   box of half-width `r` (recorded per light in step 3) finds the nearest center and every tie.
//!
//! The sort is a stable LSD radix sort on the range's bits. [`Clusterer`] keeps every buffer between calls and
//! reuses the output's clusters (and their member vectors) through [`Clusterer::cluster_into`], so a frame
//! allocates nothing once buffers have grown. [`cluster_lights`] is the allocating convenience wrapper.

use glam::Vec3;

use crate::math::Frustum;
use crate::scene::PointLight;

/// "No center / no cluster" in the internal `u32` index arrays.
const NONE: u32 = u32::MAX;
/// Unused slot of the hash grid (cell keys use 63 bits at most).
const EMPTY_KEY: u64 = u64::MAX;
/// Cell coordinates use at most this many bits per axis (the cell size grows to keep them in range).
const AXIS_BITS: u32 = 21;
/// Below this many visible lights the comparison sort beats the radix sort.
const RADIX_MIN: usize = 256;

/// Parameters of the clustering.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClusterParams {
    /// The paper's `d_init`: the largest minimum distance between cluster centers, in world units.
    /// 0 gives one cluster per visible light.
    pub d_init: f32,
    /// The paper's `z_far`: the view distance at which `d_min` reaches 0 (normally [`crate::Camera::z_far`]).
    pub z_far: f32,
    /// Scale `d_min` by the center's distance to the camera (the paper's method). Off: `d_min = d_init` for
    /// every center, which avoids clusters changing while the camera moves.
    pub adaptive: bool,
}

impl Default for ClusterParams {
    /// The paper's settings for its scenes: `d_init = 0.5`, `z_far = 30`, view-adaptive.
    fn default() -> Self {
        ClusterParams { d_init: 0.5, z_far: 30.0, adaptive: true }
    }
}

impl ClusterParams {
    /// Check the parameters for a UI or CLI. Clustering never panics on invalid values (see
    /// [`ClusterParams::effective_d_init`] and [`ClusterParams::scale_at`] for what it does instead).
    pub fn validate(&self) -> Result<(), String> {
        if !(self.d_init.is_finite() && self.d_init >= 0.0) {
            return Err(format!("d_init must be a finite distance >= 0, got {}", self.d_init));
        }
        if !(self.z_far > 0.0) {
            return Err(format!("z_far must be > 0, got {}", self.z_far));
        }
        Ok(())
    }

    /// The `d_init` the clustering uses: NaN, negative and zero give 0 (one cluster per visible light),
    /// infinity gives `f32::MAX`.
    pub fn effective_d_init(&self) -> f32 {
        if self.d_init > 0.0 {
            self.d_init.min(f32::MAX)
        } else {
            0.0
        }
    }

    /// The view-adaptive scale `1 - |C_pos| / z_far` for a center at `distance_to_camera`, clamped to `[0, 1]`
    /// (0 at and beyond `z_far`, and for a NaN distance). 1 when `adaptive` is off, and when `z_far` is NaN
    /// or not positive (invalid: no scaling).
    pub fn scale_at(&self, distance_to_camera: f32) -> f32 {
        if !self.adaptive || !(self.z_far > 0.0) {
            return 1.0;
        }
        let scale = 1.0 - distance_to_camera / self.z_far;
        if scale > 0.0 {
            scale.min(1.0)
        } else {
            0.0
        }
    }

    /// The paper's `d_min = d_init * (1 - |C_pos| / z_far)` of a center at `center` seen from `camera`,
    /// with [`ClusterParams::effective_d_init`] and [`ClusterParams::scale_at`]. Always finite and `>= 0`.
    pub fn d_min_at(&self, center: Vec3, camera: Vec3) -> f32 {
        let d_init = self.effective_d_init();
        if d_init == 0.0 {
            return 0.0;
        }
        d_init * self.scale_at(center.distance(camera))
    }
}

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

/// How the last [`Clusterer`] call indexed its centers (for tests, benchmarks and overlays).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridKind {
    /// No grid was needed (`d_init` is 0, or fewer than two visible lights).
    None,
    /// A dense array of cells over the visible lights' bounding box.
    Dense,
    /// A hash table keyed by cell coordinates.
    Hash,
}

/// Statistics of the last [`Clusterer`] call's grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridInfo {
    pub kind: GridKind,
    /// Cell edge length in world units (0 for [`GridKind::None`]).
    pub cell_size: f64,
    /// Cells per axis of the visible lights' bounding box.
    pub dims: [u32; 3],
    /// Slots allocated: cells for [`GridKind::Dense`], table size for [`GridKind::Hash`].
    pub slots: usize,
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
    /// Step 1/2: per visible light `(!range_bits) << 32 | input index`; sorted ascending = step 2's order.
    keys: Vec<u64>,
    keys_tmp: Vec<u64>,
    /// Per visible light in sorted order: input index, position, range.
    ids: Vec<u32>,
    pos: Vec<Vec3>,
    range: Vec<f32>,
    /// Per visible light in sorted order: its cluster when it is a center, else [`NONE`].
    center_slot: Vec<u32>,
    /// Per visible light in sorted order that is no center: distance to the center that covered it in step 3.
    cover: Vec<f32>,
    /// Per center (cluster index): position, `d_min`, next center in the same grid cell.
    center_pos: Vec<Vec3>,
    center_d_min: Vec<f32>,
    next: Vec<u32>,
    grid: Grid,
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
    /// When `lights` has `u32::MAX` or more entries (cluster indices are `u32`).
    pub fn cluster_into(
        &mut self,
        lights: &[PointLight],
        camera_position: Vec3,
        frustum: &Frustum,
        params: &ClusterParams,
        out: &mut Clustering,
    ) {
        assert!(lights.len() < NONE as usize, "at most {} lights can be clustered", NONE - 1);
        self.cull(lights, frustum);
        sort_by_range(&mut self.keys, &mut self.keys_tmp);
        self.gather(lights);

        let d_init = params.effective_d_init();
        out.visible = self.ids.len();
        out.cluster_of.clear();
        out.cluster_of.resize(lights.len(), None);
        if d_init > 0.0 && self.ids.len() > 1 {
            self.grid.build(&self.pos, d_init);
        } else {
            self.grid.clear();
        }

        let clusters = self.select_centers(params, camera_position, out);
        out.clusters.truncate(clusters);
        if clusters < self.ids.len() {
            self.assign_remaining(out);
        }
    }

    /// Information about the grid of the last call.
    pub fn grid_info(&self) -> GridInfo {
        self.grid.info()
    }

    /// Step 1: keep the lights that are valid and whose bounding sphere of radius `L_att` touches the frustum,
    /// as sort keys (`!range_bits << 32 | index`) in input order.
    fn cull(&mut self, lights: &[PointLight], frustum: &Frustum) {
        self.keys.clear();
        for (i, light) in lights.iter().enumerate() {
            if light.is_valid() && frustum.intersects_sphere(light.position, light.range) {
                // A valid range is positive and finite, so its bits order like its value; `!` makes the
                // ascending key order the descending range order.
                self.keys.push(((!light.range.to_bits()) as u64) << 32 | i as u64);
            }
        }
    }

    /// Lay out the visible lights in sorted order for steps 3 and 4.
    fn gather(&mut self, lights: &[PointLight]) {
        self.ids.clear();
        self.pos.clear();
        self.range.clear();
        for &key in &self.keys {
            let id = key as u32;
            let light = &lights[id as usize];
            self.ids.push(id);
            self.pos.push(light.position);
            self.range.push(light.range);
        }
    }

    /// Step 3: select the cluster centers in sorted order; writes a cluster per center into `out` and returns
    /// how many there are. Non-centers get `center_slot = NONE` and their covering distance in `cover`.
    fn select_centers(&mut self, params: &ClusterParams, camera: Vec3, out: &mut Clustering) -> usize {
        let n = self.ids.len();
        self.center_slot.clear();
        self.center_slot.resize(n, NONE);
        self.cover.clear();
        self.cover.resize(n, 0.0);
        self.center_pos.clear();
        self.center_d_min.clear();
        self.next.clear();
        // Largest d_min of the centers so far: no center can cover a light farther away than this.
        let mut max_d_min = 0.0f32;
        for i in 0..n {
            let p = self.pos[i];
            if max_d_min > 0.0 {
                if let Some(d) = self.covering_distance(p, max_d_min) {
                    self.cover[i] = d;
                    continue;
                }
            }
            let k = self.center_pos.len() as u32;
            let d_min = params.d_min_at(p, camera);
            max_d_min = max_d_min.max(d_min);
            self.center_slot[i] = k;
            self.center_pos.push(p);
            self.center_d_min.push(d_min);
            self.next.push(NONE);
            self.grid.insert(p, k, &mut self.next);

            let id = self.ids[i] as usize;
            let range = self.range[i];
            out.cluster_of[id] = Some(k);
            match out.clusters.get_mut(k as usize) {
                Some(c) => {
                    c.center = id;
                    c.members.clear();
                    c.members.push(id);
                    c.d_min = d_min;
                    c.c_att = range;
                    c.position = p;
                    c.radius = 0.0;
                }
                None => out.clusters.push(Cluster {
                    center: id,
                    members: vec![id],
                    d_min,
                    c_att: range,
                    position: p,
                    radius: 0.0,
                }),
            }
        }
        self.center_pos.len()
    }

    /// Step 3's test: the distance to some center `c` with `distance <= d_min(c)` and `d_min(c) > 0`, or `None`
    /// when `p` is farther than `d_min(c)` from every center (so it becomes a center). Only centers within
    /// `radius` (the largest `d_min`) can cover `p`, and only their cells are visited.
    #[inline]
    fn covering_distance(&self, p: Vec3, radius: f32) -> Option<f32> {
        let (lo, hi) = self.grid.cell_range(p, radius);
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let mut k = self.grid.head([x, y, z]);
                    while k != NONE {
                        let d_min = self.center_d_min[k as usize];
                        if d_min > 0.0 {
                            let d = p.distance(self.center_pos[k as usize]);
                            if d <= d_min {
                                return Some(d);
                            }
                        }
                        k = self.next[k as usize];
                    }
                }
            }
        }
        None
    }

    /// Step 4: assign every light that is no center to its nearest center and grow that cluster's `C_att`.
    fn assign_remaining(&self, out: &mut Clustering) {
        for i in 0..self.ids.len() {
            if self.center_slot[i] != NONE {
                continue;
            }
            let p = self.pos[i];
            let (k, d2) = match self.nearest_center(p, self.cover[i]) {
                Some(found) => found,
                // Unreachable (the covering center is within the searched box); kept exact and panic-free.
                None => self.nearest_center_brute_force(p),
            };
            let d_c = d2.sqrt();
            let id = self.ids[i] as usize;
            let cluster = &mut out.clusters[k as usize];
            cluster.members.push(id);
            cluster.c_att = cluster.c_att.max(d_c + self.range[i]);
            cluster.radius = cluster.radius.max(d_c);
            out.cluster_of[id] = Some(k);
        }
    }

    /// The nearest center to `p` (smallest squared distance, then smallest cluster index) among the centers
    /// within `radius`, with its squared distance.
    #[inline]
    fn nearest_center(&self, p: Vec3, radius: f32) -> Option<(u32, f32)> {
        let (lo, hi) = self.grid.cell_range(p, radius);
        let mut best = NONE;
        let mut best_d2 = f32::INFINITY;
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let mut k = self.grid.head([x, y, z]);
                    while k != NONE {
                        let d2 = p.distance_squared(self.center_pos[k as usize]);
                        if d2 < best_d2 || (d2 == best_d2 && k < best) {
                            best = k;
                            best_d2 = d2;
                        }
                        k = self.next[k as usize];
                    }
                }
            }
        }
        (best != NONE && best_d2.sqrt() <= radius).then_some((best, best_d2))
    }

    fn nearest_center_brute_force(&self, p: Vec3) -> (u32, f32) {
        let mut best = (0, f32::INFINITY);
        for (k, c) in self.center_pos.iter().enumerate() {
            let d2 = p.distance_squared(*c);
            if d2 < best.1 {
                best = (k as u32, d2);
            }
        }
        best
    }
}

/// Step 2: sort the keys made by step 1 ascending, i.e. by `L_att` descending, then by input index. A stable
/// LSD radix sort over the 32 range bits (skipping bytes all keys share); small inputs use `sort_unstable`,
/// which gives the same order because keys are unique.
fn sort_by_range(keys: &mut Vec<u64>, tmp: &mut Vec<u64>) {
    let n = keys.len();
    if n < RADIX_MIN {
        keys.sort_unstable();
        return;
    }
    let mut hist = [[0u32; 256]; 4];
    for &key in keys.iter() {
        let hi = (key >> 32) as u32;
        for (byte, h) in hist.iter_mut().enumerate() {
            h[((hi >> (8 * byte)) & 0xFF) as usize] += 1;
        }
    }
    tmp.clear();
    tmp.resize(n, 0);
    for (byte, h) in hist.iter().enumerate() {
        if h.iter().any(|&c| c as usize == n) {
            continue; // every key has the same byte here
        }
        let mut offsets = [0usize; 256];
        let mut sum = 0usize;
        for (o, &c) in offsets.iter_mut().zip(h.iter()) {
            *o = sum;
            sum += c as usize;
        }
        let shift = 32 + 8 * byte;
        for &key in keys.iter() {
            let b = ((key >> shift) & 0xFF) as usize;
            tmp[offsets[b]] = key;
            offsets[b] += 1;
        }
        std::mem::swap(keys, tmp);
    }
}

/// A uniform grid of cluster centers: per cell the head of a linked list through `Clusterer::next`.
#[derive(Debug)]
struct Grid {
    kind: GridKind,
    /// World position of cell (0, 0, 0)'s minimum corner (the visible lights' bounding box minimum).
    origin: [f64; 3],
    cell: f64,
    inv_cell: f64,
    dims: [u32; 3],
    /// Head center per cell (dense) or per table slot (hash).
    heads: Vec<u32>,
    /// Hash grid: cell key per slot, [`EMPTY_KEY`] when unused.
    keys: Vec<u64>,
    mask: usize,
    shift: u32,
}

impl Default for Grid {
    fn default() -> Self {
        Grid {
            kind: GridKind::None,
            origin: [0.0; 3],
            cell: 0.0,
            inv_cell: 0.0,
            dims: [1; 3],
            heads: Vec::new(),
            keys: Vec::new(),
            mask: 0,
            shift: 64,
        }
    }
}

impl Grid {
    fn clear(&mut self) {
        self.kind = GridKind::None;
        self.cell = 0.0;
        self.dims = [1; 3];
    }

    fn info(&self) -> GridInfo {
        let slots = match self.kind {
            GridKind::None => 0,
            GridKind::Dense => self.heads.len(),
            GridKind::Hash => self.keys.len(),
        };
        GridInfo { kind: self.kind, cell_size: self.cell, dims: self.dims, slots }
    }

    /// Prepare an empty grid over the bounding box of `positions` (finite, at least two) for `d_init > 0`.
    fn build(&mut self, positions: &[Vec3], d_init: f32) {
        let (mut min, mut max) = (positions[0], positions[0]);
        for &p in positions {
            min = min.min(p);
            max = max.max(p);
        }
        let origin = [min.x as f64, min.y as f64, min.z as f64];
        let extent = [max.x as f64 - origin[0], max.y as f64 - origin[1], max.z as f64 - origin[2]];
        let largest = extent[0].max(extent[1]).max(extent[2]);
        // At least 2 * d_init (so a search box of half-width <= d_init spans at most 2 cells per axis) and
        // large enough for cell coordinates to fit AXIS_BITS bits.
        let mut cell = (2.0 * d_init as f64).max(largest / (1u64 << (AXIS_BITS - 1)) as f64);
        if !(cell.is_finite() && cell > 0.0) {
            cell = 1.0;
        }
        let dims = extent.map(|e| ((e / cell).floor() as u32).saturating_add(1).min(1 << AXIS_BITS));
        let cells = dims.iter().map(|&d| d as u64).product::<u64>();
        let n = positions.len() as u64;
        self.origin = origin;
        self.cell = cell;
        self.inv_cell = 1.0 / cell;
        self.dims = dims;
        if cells <= 4 * n + 4096 {
            self.kind = GridKind::Dense;
            self.heads.clear();
            self.heads.resize(cells as usize, NONE);
        } else {
            // At most one occupied cell per center, at most one center per light: load factor <= 1/2.
            self.kind = GridKind::Hash;
            let slots = (2 * positions.len()).next_power_of_two().max(64);
            self.keys.clear();
            self.keys.resize(slots, EMPTY_KEY);
            self.heads.clear();
            self.heads.resize(slots, NONE);
            self.mask = slots - 1;
            self.shift = 64 - slots.trailing_zeros();
        }
    }

    /// Cell coordinates of `p` (inside the bounding box the grid was built over).
    #[inline]
    fn cell_of(&self, p: Vec3) -> [u32; 3] {
        let q = [p.x, p.y, p.z];
        std::array::from_fn(|a| {
            let x = ((q[a] as f64 - self.origin[a]) * self.inv_cell).floor();
            (x.max(0.0) as u32).min(self.dims[a] - 1)
        })
    }

    /// The cells overlapping the box of half-width `radius` around `p`, as inclusive corners. Conservative:
    /// the half-width is widened by a relative 1e-4 (covering `f32` distance rounding) and 1e-6 cells
    /// (covering `f64` rounding of coordinates, which are below 2^21 cells), so every point whose computed
    /// `f32` distance to `p` is at most `radius` lies in one of these cells.
    #[inline]
    fn cell_range(&self, p: Vec3, radius: f32) -> ([u32; 3], [u32; 3]) {
        let q = [p.x, p.y, p.z];
        let r = radius as f64 * 1.0001 * self.inv_cell + 1e-6;
        let mut lo = [0u32; 3];
        let mut hi = [0u32; 3];
        for a in 0..3 {
            let x = (q[a] as f64 - self.origin[a]) * self.inv_cell;
            let top = (self.dims[a] - 1) as f64;
            lo[a] = (x - r).floor().clamp(0.0, top) as u32;
            hi[a] = (x + r).floor().clamp(0.0, top) as u32;
        }
        (lo, hi)
    }

    #[inline]
    fn key(c: [u32; 3]) -> u64 {
        c[0] as u64 | (c[1] as u64) << AXIS_BITS | (c[2] as u64) << (2 * AXIS_BITS)
    }

    #[inline]
    fn slot_of_key(&self, key: u64) -> usize {
        (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> self.shift) as usize
    }

    /// The first center in cell `c`, or [`NONE`].
    #[inline]
    fn head(&self, c: [u32; 3]) -> u32 {
        match self.kind {
            GridKind::Dense => {
                let [nx, ny, _] = self.dims;
                self.heads[c[0] as usize + nx as usize * (c[1] as usize + ny as usize * c[2] as usize)]
            }
            GridKind::Hash => {
                let key = Self::key(c);
                let mut slot = self.slot_of_key(key);
                loop {
                    let k = self.keys[slot];
                    if k == key {
                        return self.heads[slot];
                    }
                    if k == EMPTY_KEY {
                        return NONE;
                    }
                    slot = (slot + 1) & self.mask;
                }
            }
            GridKind::None => NONE,
        }
    }

    /// Add center `k` at `p` to its cell's list.
    #[inline]
    fn insert(&mut self, p: Vec3, k: u32, next: &mut [u32]) {
        let slot = match self.kind {
            GridKind::None => return,
            GridKind::Dense => {
                let c = self.cell_of(p);
                let [nx, ny, _] = self.dims;
                c[0] as usize + nx as usize * (c[1] as usize + ny as usize * c[2] as usize)
            }
            GridKind::Hash => {
                let key = Self::key(self.cell_of(p));
                let mut slot = self.slot_of_key(key);
                loop {
                    let existing = self.keys[slot];
                    if existing == key {
                        break;
                    }
                    if existing == EMPTY_KEY {
                        self.keys[slot] = key;
                        self.heads[slot] = NONE;
                        break;
                    }
                    slot = (slot + 1) & self.mask;
                }
                slot
            }
        };
        next[k as usize] = self.heads[slot];
        self.heads[slot] = k;
    }
}
