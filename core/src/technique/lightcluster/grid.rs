//! The multi-level uniform grid of cluster centers behind step 3 of [`super::clustering`] (section 3.1): which
//! center covers a light is a lookup in the cells around it, not a scan of all centers. See the clustering
//! module's docs (Performance) for the layout and why it is exact.

use glam::Vec3;

/// "No center / no cluster" in the internal `u32` index arrays.
pub(super) const NONE: u32 = u32::MAX;
/// Unused slot of the hash grid (cell keys use 63 bits at most).
pub(super) const EMPTY_KEY: u64 = u64::MAX;
/// Cell coordinates use at most this many bits per axis (the cell size grows to keep them in range); the hash
/// key holds three of them and the level.
pub(super) const AXIS_BITS: u32 = 19;
/// Levels of the grid at most (level 0 has cells of `d_init`, each level halves them).
pub(super) const MAX_LEVELS: usize = 24;

/// How the last [`Clusterer`] call indexed its centers (for tests, benchmarks and overlays).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GridKind {
    /// No grid was needed (`d_init` is 0, or fewer than two visible lights).
    None,
    /// Every level that received centers was a dense array of cells.
    Dense,
    /// Every level that received centers lived in the hash table.
    Hash,
    /// Some levels of each kind.
    Mixed,
}

/// Statistics of the last [`Clusterer`] call's grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridInfo {
    pub kind: GridKind,
    /// Levels prepared (cells from `d_init` down to the floor cell size).
    pub levels: usize,
    /// Levels that received centers, dense and hashed.
    pub dense_levels: usize,
    pub hash_levels: usize,
    /// Cell size of the coarsest and the finest (floor) level, in world units (0 without a grid).
    pub coarsest_cell: f64,
    pub finest_cell: f64,
}

/// The cell of cell coordinate `x`, `floor(x)` clamped to `0..=top` (NaN gives 0). `as i32` truncates towards
/// zero and saturates, which differs from `floor` only below 0, where the clamp gives 0 either way; integer
/// clamping is cheaper than `f64::clamp`.
#[inline(always)]
pub(super) fn cell_index(x: f64, top: i32) -> u32 {
    (x as i32).clamp(0, top) as u32
}

/// The largest squared distance `d2` with `d2.sqrt() <= d_min`, or -1 when `d_min` is not positive (a center
/// with `d_min = 0` covers nothing). `f32::sqrt` is correctly rounded, so for every `d2`,
/// `d2 <= cover_limit(d_min)` exactly when `d2.sqrt() <= d_min`: step 3's `distance(p, c) <= d_min(c)` (glam's
/// `distance` is `distance_squared(..).sqrt()`) without a square root per candidate.
///
/// `d2.sqrt()` rounds to at most `d_min` exactly when the exact root is below the midpoint `m` of `d_min` and the
/// next `f32` (never equal: `m` has 25 significant bits, so `m^2` has 49 or 50 and is no `f32`). `m` and `m^2` are
/// exact in `f64`, so the limit is the largest `f32` below `m^2`.
pub(super) fn cover_limit(d_min: f32) -> f32 {
    if d_min.is_nan() || d_min <= 0.0 {
        return -1.0;
    }
    let m = (d_min as f64 + d_min.next_up() as f64) * 0.5;
    if !m.is_finite() {
        return f32::MAX; // d_min is f32::MAX: every finite d2 is covered
    }
    let m2 = m * m;
    let below = m2 as f32;
    if below as f64 > m2 {
        below.next_down()
    } else {
        below
    }
}

/// One level of the grid: cells of one size, holding the centers of one `d_min` band.
#[derive(Clone, Copy, Debug)]
pub(super) struct Level {
    pub(super) cell: f64,
    pub(super) inv_cell: f64,
    /// `dims - 1` per axis (below 2^19), for clamping cell coordinates.
    pub(super) top: [i32; 3],
    pub(super) dims: [u32; 3],
    pub(super) dense: bool,
    /// Whether any light belongs to the level (then a dense level has its slots from `offset` on).
    pub(super) used: bool,
    pub(super) offset: u32,
    /// Centers so far, the largest `d_min` among them (no center of the level covers a light farther away),
    /// and the smallest and largest distance to the camera among them (for pruning; view-adaptive only).
    pub(super) count: u32,
    pub(super) max_d_min: f32,
    pub(super) near: f32,
    pub(super) far: f32,
}

/// Cells to visit: inclusive corners and the cell of the light itself.
#[derive(Clone, Copy, Debug)]
pub(super) struct CellBox {
    pub(super) lo: [u32; 3],
    pub(super) hi: [u32; 3],
    pub(super) own: [u32; 3],
}

/// A multi-level uniform grid of cluster centers; see the module docs (Performance).
///
/// Every visible light knows in advance the level and cell ("slot") it would occupy as a center, because its
/// `d_min` depends only on its distance to the camera. So the slots are laid out up front by a counting sort,
/// each with room for all its lights, and a center is appended to its slot's contiguous run of entries: no
/// linked lists, and a cell's centers are read sequentially (in selection order).
#[derive(Debug, Default)]
pub(super) struct Grid {
    /// World position of every level's cell (0, 0, 0) minimum corner (the visible lights' bounding box min).
    pub(super) origin: [f64; 3],
    pub(super) d_init: f64,
    pub(super) inv_d_init: f64,
    /// Prune levels by distance to the camera (view-adaptive only).
    pub(super) prune: bool,
    pub(super) levels: Vec<Level>,
    /// Per slot: the first entry and one past the last center so far. Slots are the cells of the dense levels
    /// in use, then the hash table's slots.
    pub(super) runs: Vec<[u32; 2]>,
    /// Per visible light (sorted order): its level and slot.
    pub(super) light_level: Vec<u8>,
    pub(super) light_slot: Vec<u32>,
    /// Center entries `[x, y, z, cover_limit(d_min)]` and cluster indices, grouped by slot.
    pub(super) entries: Vec<[f32; 4]>,
    pub(super) entry_k: Vec<u32>,
    pub(super) dense_budget: u64,
    pub(super) hash_keys: Vec<u64>,
    pub(super) hash_base: u32,
    pub(super) hash_slots: usize,
    pub(super) hash_ready: bool,
    pub(super) mask: usize,
    pub(super) shift: u32,
    /// Scratch: occupancy bitmap for the spacing estimate.
    pub(super) occupied: Vec<u64>,
}

/// Level `l` has cells of `CELL_PER_D_MIN * d_init / 2^l`: at least this many times the largest `d_min` it
/// holds (except the floor level, whose cells may be larger).
const CELL_PER_D_MIN: f64 = 1.0;
/// Lights sampled for the spacing estimate at most.
const SPACING_SAMPLES: usize = 512;
/// The floor level's cells, in estimated light spacings.
const FLOOR_PER_SPACING: f64 = 2.0;

impl Grid {
    pub(super) fn clear(&mut self) {
        self.levels.clear();
    }

    pub(super) fn info(&self) -> GridInfo {
        let used = || self.levels.iter().filter(|l| l.count > 0);
        let dense_levels = used().filter(|l| l.dense).count();
        let hash_levels = used().filter(|l| !l.dense).count();
        let kind = match (dense_levels, hash_levels) {
            (0, 0) => GridKind::None,
            (_, 0) => GridKind::Dense,
            (0, _) => GridKind::Hash,
            _ => GridKind::Mixed,
        };
        GridInfo {
            kind,
            levels: self.levels.len(),
            dense_levels,
            hash_levels,
            coarsest_cell: self.levels.first().map_or(0.0, |l| l.cell),
            finest_cell: self.levels.last().map_or(0.0, |l| l.cell),
        }
    }

    /// Prepare the levels over the bounding box `min..max` of `positions` (finite, at least two) for
    /// `d_init > 0`, and lay out every light's slot.
    pub(super) fn build(
        &mut self,
        positions: &[Vec3],
        d_min: &[f32],
        min: Vec3,
        max: Vec3,
        d_init: f32,
        adaptive: bool,
    ) {
        let n = positions.len();
        let origin = [min.x as f64, min.y as f64, min.z as f64];
        let extent = [max.x as f64 - origin[0], max.y as f64 - origin[1], max.z as f64 - origin[2]];
        let largest = extent[0].max(extent[1]).max(extent[2]);
        // Cells at least this large keep cell coordinates within AXIS_BITS bits.
        let smallest_cell = largest / (1u64 << (AXIS_BITS - 1)) as f64;
        let floor = self.spacing(positions, origin, extent) * FLOOR_PER_SPACING;
        // Slightly more than d_init, so level 0 holds every d_min <= d_init.
        self.d_init = d_init as f64 * (1.0 + 1e-6);
        self.inv_d_init = 1.0 / self.d_init;
        self.origin = origin;
        self.prune = adaptive;
        self.dense_budget = 4 * n as u64 + 4096;
        self.hash_ready = false;
        self.hash_slots = (2 * n).next_power_of_two().max(64);
        self.levels.clear();
        let mut cell = CELL_PER_D_MIN * self.d_init;
        loop {
            // Without view-adaptive scaling every d_min is d_init: one level.
            // Finer cells than `smallest_cell` (or than a point) are pointless.
            let last = !adaptive
                || cell <= floor
                || cell <= smallest_cell
                || largest == 0.0
                || self.levels.len() + 1 == MAX_LEVELS;
            let mut size = if last { cell.max(floor) } else { cell };
            size = size.max(smallest_cell);
            if !(size.is_finite() && size > 0.0) {
                size = if largest > 0.0 { largest } else { 1.0 };
            }
            let dims = extent.map(|e| ((e / size) as u32).saturating_add(1).min(1 << AXIS_BITS));
            let cells = dims.iter().map(|&d| d as u64).product::<u64>();
            self.levels.push(Level {
                cell: size,
                inv_cell: 1.0 / size,
                top: dims.map(|d| (d - 1) as i32),
                dims,
                dense: cells <= self.dense_budget,
                used: false,
                offset: 0,
                count: 0,
                max_d_min: 0.0,
                near: f32::INFINITY,
                far: f32::NEG_INFINITY,
            });
            if last {
                break;
            }
            cell /= 2.0;
        }

        // Every light's level, then the slots of the levels in use, then every light's slot (as if it were a
        // center), counted per slot.
        self.runs.clear();
        let mut light_level = std::mem::take(&mut self.light_level);
        light_level.clear();
        light_level.extend(d_min.iter().map(|&d| self.level_of(d) as u8));
        self.light_level = light_level;
        for &level in &self.light_level {
            self.levels[level as usize].used = true;
        }
        for level in 0..self.levels.len() {
            self.prepare_level(level);
        }
        self.light_slot.resize(n, 0);
        for (i, &p) in positions.iter().enumerate() {
            let level = self.light_level[i] as usize;
            let l = &self.levels[level];
            let c = self.cell_of(l, p);
            let slot = if l.dense { Self::dense_slot(l, c) } else { self.insert_hash_key(level, c) };
            self.light_slot[i] = slot;
            self.runs[slot as usize][1] += 1;
        }
        // Runs start where the previous slot's lights end; empty for now.
        let mut start = 0u32;
        for run in self.runs.iter_mut() {
            let count = run[1];
            *run = [start, start];
            start += count;
        }
        // Unused entries are NaN, so scanning a row of cells across their gaps finds only centers.
        self.entries.clear();
        self.entries.resize(n, [f32::NAN; 4]);
        self.entry_k.resize(n, 0);
    }

    /// Estimated spacing of the lights: the cell size at which the bounding box has about one cell per light
    /// along its non-degenerate axes, refined by the share of those cells the lights occupy (so clumps and
    /// flat or linear layouts get their own spacing, not the bounding box's).
    pub(super) fn spacing(&mut self, positions: &[Vec3], origin: [f64; 3], extent: [f64; 3]) -> f64 {
        let n = positions.len() as f64;
        let mut used = extent.map(|e| e > 0.0);
        let mut cell = 0.0;
        for _ in 0..3 {
            let axes = used.iter().filter(|&&u| u).count();
            if axes == 0 {
                return 0.0;
            }
            let volume: f64 = (0..3).filter(|&a| used[a]).map(|a| extent[a]).product();
            cell = (volume / n).powf(1.0 / axes as f64);
            if (0..3).all(|a| !used[a] || extent[a] >= cell) {
                break;
            }
            for a in 0..3 {
                used[a] &= extent[a] >= cell;
            }
        }
        let axes = used.iter().filter(|&&u| u).count().max(1);
        if !(cell.is_finite() && cell > 0.0) {
            return 0.0;
        }
        // Occupancy is counted for a strided sample of at most SPACING_SAMPLES lights (sorted by range, so
        // spread over space), in cells that hold one sampled light each on average: the spacing of the sample,
        // times (sample / lights)^(1 / axes), estimates the lights' (the same for all of them).
        let stride = positions.len().div_ceil(SPACING_SAMPLES).max(1);
        let sampled = positions.len().div_ceil(stride);
        let sample_cell = cell * (n / sampled as f64).powf(1.0 / axes as f64);
        let dims = extent.map(|e| ((e / sample_cell) as u64).saturating_add(1));
        let cells = dims.iter().product::<u64>();
        if cells > 64 * sampled as u64 {
            return cell;
        }
        self.occupied.clear();
        self.occupied.resize(cells.div_ceil(64) as usize, 0);
        // Only an estimate: f32 is precise enough.
        let inv = (1.0 / sample_cell) as f32;
        let origin = Vec3::new(origin[0] as f32, origin[1] as f32, origin[2] as f32);
        let top = dims.map(|d| (d - 1) as f32);
        let mut count = 0u64;
        for &p in positions.iter().step_by(stride) {
            let q = (p - origin) * inv;
            let c = [q.x.clamp(0.0, top[0]) as u64, q.y.clamp(0.0, top[1]) as u64, q.z.clamp(0.0, top[2]) as u64];
            let index = c[0] + dims[0] * (c[1] + dims[1] * c[2]);
            let (word, bit) = ((index / 64) as usize, 1u64 << (index % 64));
            count += (self.occupied[word] & bit == 0) as u64;
            self.occupied[word] |= bit;
        }
        cell * (count as f64 / sampled as f64).powf(1.0 / axes as f64)
    }

    /// The level for a center with `d_min`: the finest `l` with `d_init / 2^l >= d_min` (the last for 0).
    #[inline]
    pub(super) fn level_of(&self, d_min: f32) -> usize {
        let last = self.levels.len() - 1;
        // x = d_min / d_init in (0, 1): with x = m 2^e (1 <= m < 2), floor(log2(1 / x)) is -e - 1, or -e when
        // m = 1. Every positive f32 is a normal f64.
        let x = d_min as f64 * self.inv_d_init;
        if x.is_nan() || x <= 0.0 {
            return last;
        }
        let bits = x.to_bits();
        let exponent = ((bits >> 52) & 0x7FF) as i64 - 1023;
        let level = -exponent - (bits & ((1 << 52) - 1) != 0) as i64;
        (level.max(0) as usize).min(last)
    }

    #[inline(always)]
    pub(super) fn cell_of(&self, l: &Level, p: Vec3) -> [u32; 3] {
        let q = [p.x, p.y, p.z];
        std::array::from_fn(|a| cell_index((q[a] as f64 - self.origin[a]) * l.inv_cell, l.top[a]))
    }

    /// Give a level in use its slots: a dense level its cells (unless slot indices would grow too large, then
    /// it is hashed), a hashed level the hash table (shared by all hashed levels).
    pub(super) fn prepare_level(&mut self, level: usize) {
        let l = &mut self.levels[level];
        if !l.used {
            return;
        }
        if l.dense {
            let cells = l.dims.iter().map(|&d| d as usize).product::<usize>();
            if self.runs.len() + cells < (NONE / 4) as usize {
                l.offset = self.runs.len() as u32;
                self.runs.resize(self.runs.len() + cells, [0, 0]);
                return;
            }
            l.dense = false; // slot indices must stay far below u32::MAX
        }
        if !self.hash_ready {
            self.hash_ready = true;
            self.hash_base = self.runs.len() as u32;
            self.runs.resize(self.runs.len() + self.hash_slots, [0, 0]);
            self.hash_keys.clear();
            self.hash_keys.resize(self.hash_slots, EMPTY_KEY);
            self.mask = self.hash_slots - 1;
            self.shift = 64 - self.hash_slots.trailing_zeros();
        }
    }

    #[inline(always)]
    pub(super) fn dense_slot(l: &Level, c: [u32; 3]) -> u32 {
        l.offset + c[0] + l.dims[0] * (c[1] + l.dims[1] * c[2])
    }

    /// The slot of cell `c` of a hashed `level`, adding the cell to the table when new.
    pub(super) fn insert_hash_key(&mut self, level: usize, c: [u32; 3]) -> u32 {
        let key = Self::key(level, c);
        let mut slot = self.hash_start(key);
        while self.hash_keys[slot] != key {
            if self.hash_keys[slot] == EMPTY_KEY {
                self.hash_keys[slot] = key;
                break;
            }
            slot = (slot + 1) & self.mask;
        }
        self.hash_base + slot as u32
    }

    /// The cells of `level` overlapping the box of half-width `radius` around `p`, or `None` when the level has
    /// no center that can be within `radius` of `p` (none yet, or its centers' distances to the camera are all
    /// farther than `radius` from `to_camera`).
    ///
    /// Conservative: the half-width is widened by a relative 1e-4 (covering `f32` distance rounding) and 1e-6
    /// cells (covering `f64` rounding of coordinates, which are below 2^19 cells), and the distance band by a
    /// relative 1e-4, so every center whose computed `f32` distance to `p` is at most `radius` is visited.
    #[inline(always)]
    pub(super) fn search_box(&self, level: usize, p: Vec3, to_camera: f32, radius: f32) -> Option<CellBox> {
        let l = &self.levels[level];
        if l.count == 0 || radius.is_nan() || radius < 0.0 {
            return None;
        }
        if self.prune && to_camera.is_finite() && l.far.is_finite() {
            let slack = (to_camera + radius) * 1e-4;
            if to_camera + radius + slack < l.near || to_camera - radius - slack > l.far {
                return None;
            }
        }
        let q = [p.x, p.y, p.z];
        let r = radius as f64 * 1.0001 * l.inv_cell + 1e-6;
        let mut b = CellBox { lo: [0; 3], hi: [0; 3], own: [0; 3] };
        for (a, &v) in q.iter().enumerate() {
            let x = (v as f64 - self.origin[a]) * l.inv_cell;
            b.lo[a] = cell_index(x - r, l.top[a]);
            b.hi[a] = cell_index(x + r, l.top[a]);
            b.own[a] = cell_index(x, l.top[a]);
        }
        Some(b)
    }

    #[inline]
    pub(super) fn key(level: usize, c: [u32; 3]) -> u64 {
        c[0] as u64 | (c[1] as u64) << AXIS_BITS | (c[2] as u64) << (2 * AXIS_BITS) | (level as u64) << (3 * AXIS_BITS)
    }

    #[inline]
    pub(super) fn hash_start(&self, key: u64) -> usize {
        (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> self.shift) as usize
    }

    /// The slot of cell `c` of `level` (which has centers), or [`NONE`] for a hashed cell no light maps to.
    #[inline(always)]
    pub(super) fn slot(&self, level: usize, c: [u32; 3]) -> u32 {
        let l = &self.levels[level];
        if l.dense {
            return Self::dense_slot(l, c);
        }
        let key = Self::key(level, c);
        let mut slot = self.hash_start(key);
        loop {
            let k = self.hash_keys[slot];
            if k == key {
                return self.hash_base + slot as u32;
            }
            if k == EMPTY_KEY {
                return NONE;
            }
            slot = (slot + 1) & self.mask;
        }
    }

    /// The centers in `slot` so far (entries `[x, y, z, cover_limit(d_min)]`) and the index of the first.
    #[inline(always)]
    pub(super) fn centers_in_cell(&self, slot: u32) -> (&[[f32; 4]], usize) {
        match self.runs.get(slot as usize) {
            Some(&[first, end]) => (&self.entries[first as usize..end as usize], first as usize),
            None => (&[], 0),
        }
    }

    /// Entries `first..end` of the cells `x0..=x1` of row `(y, z)` of dense `level`: their runs are adjacent,
    /// and the entries between one cell's centers and the next cell's first are unused (NaN).
    #[inline(always)]
    pub(super) fn dense_row_range(&self, level: usize, x0: u32, x1: u32, y: u32, z: u32) -> (usize, usize) {
        let l = &self.levels[level];
        let s0 = Self::dense_slot(l, [x0, y, z]) as usize;
        let s1 = s0 + (x1 - x0) as usize;
        (self.runs[s0][0] as usize, self.runs[s1][1] as usize)
    }

    #[inline(always)]
    pub(super) fn dense_row(&self, level: usize, x0: u32, x1: u32, y: u32, z: u32) -> &[[f32; 4]] {
        let (first, end) = self.dense_row_range(level, x0, x1, y, z);
        &self.entries[first..end]
    }

    /// Step 4's test over `entries` (from index `first`): keep in `best` the nearest center to `p` (smallest
    /// squared distance, then smallest cluster index) and its squared distance. Unused entries are NaN: never
    /// nearer.
    #[inline(always)]
    pub(super) fn nearest_in(&self, p: Vec3, entries: &[[f32; 4]], first: usize, best: &mut (u32, f32)) {
        for (e, entry) in entries.iter().enumerate() {
            let d2 = p.distance_squared(Vec3::new(entry[0], entry[1], entry[2]));
            if d2 <= best.1 {
                let k = self.entry_k[first + e];
                if d2 < best.1 || k < best.0 {
                    *best = (k, d2);
                }
            }
        }
    }

    /// Step 3's test over some entries: the distance to a center among them that covers `p`.
    ///
    /// `distance(p, c) <= d_min(c)` is tested as `distance_squared(p, c) <= cover_limit(d_min(c))` (stored in
    /// the entry), which is the same test without a square root per center; unused entries are NaN and fail it.
    #[inline(always)]
    pub(super) fn cover_in(&self, entries: &[[f32; 4]], p: Vec3) -> Option<f32> {
        for e in entries {
            let d2 = p.distance_squared(Vec3::new(e[0], e[1], e[2]));
            if d2 <= e[3] {
                return Some(d2.sqrt());
            }
        }
        None
    }

    /// Make visible light `i` (sorted order) at `p` center `k`, with `d_min`, `to_camera` from the camera.
    pub(super) fn insert(&mut self, i: usize, p: Vec3, to_camera: f32, d_min: f32, k: u32) {
        if self.levels.is_empty() {
            return;
        }
        let l = &mut self.levels[self.light_level[i] as usize];
        l.count += 1;
        l.max_d_min = l.max_d_min.max(d_min);
        l.near = l.near.min(to_camera);
        l.far = l.far.max(to_camera);
        let run = &mut self.runs[self.light_slot[i] as usize];
        let e = run[1] as usize;
        run[1] += 1;
        self.entries[e] = [p.x, p.y, p.z, cover_limit(d_min)];
        self.entry_k[e] = k;
    }
}

#[cfg(test)]
mod tests {
    use super::cover_limit;

    /// `cover_limit(d)` is the largest `d2` with `d2.sqrt() <= d`, over every binade (subnormals included).
    #[test]
    fn cover_limit_is_the_largest_square_covered() {
        let mut state = 0x2545_F491_4F6C_DD1Du64;
        let mut values = vec![f32::from_bits(1), f32::MIN_POSITIVE, 1e-20, 0.5, 1.0, 1.6, 3.0, 1e19, 1e30, f32::MAX];
        for _ in 0..200_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let d = f32::from_bits((state >> 33) as u32 % 0x7F80_0000); // every positive finite f32 but 0
            if d > 0.0 {
                values.push(d);
            }
        }
        for d in values {
            let t = cover_limit(d);
            assert!(t >= 0.0 && t.sqrt() <= d, "d {d:e}: limit {t:e} has root {:e}", t.sqrt());
            if t < f32::MAX {
                let above = t.next_up();
                assert!(above.sqrt() > d, "d {d:e}: {above:e} above the limit {t:e} is still covered");
            }
        }
        assert_eq!(cover_limit(0.0), -1.0);
        assert_eq!(cover_limit(-1.0), -1.0);
        assert_eq!(cover_limit(f32::NAN), -1.0);
    }
}
