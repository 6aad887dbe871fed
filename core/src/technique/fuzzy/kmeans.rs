//! Colom, Marques, Santos 2022, section 3.2-3.3: K-means of surface points (VPLs or shading points) with the
//! distance of equation 7, a regular grid over the centroids, and the fuzzy final assignment (Algorithm 2).
//! The CPU twin of `fuzzy/kmeans.wgsl` (same initial centroids, search, fixed-point means, tie rule), pure and
//! deterministic; the property tests below run on it and a GPU test compares the two.
//!
//! Algorithm 1 (symbols of the paper):
//! 1. `D'` = downsample(`D`, `gamma`): the points at every `gamma`-th column and row (a 1-row dataset, the VPLs,
//!    keeps every `gamma`-th point); `S` = |`D'`|.
//! 2. initialCentroids(`K`, `D'`): centroid `k` is the first valid point of `D'` at or after index `k S / K`
//!    (the paper picks "often random, but it can also leverage some structure in the data"; a stride through
//!    the image spreads them over the view and is deterministic). `K` is clamped to `S`; a centroid whose
//!    share holds no valid point (sky) stays inactive.
//! 3. Per iteration: `G` = grid(`C`) (a regular grid over the scene's bounds, centroids binned into cells),
//!    then each `d_s` in `D'` joins its nearest centroid by `dist` (equation 7: `|p1 - p2|` when
//!    `n1 . n2 > n_t`, else infinity), searched in the 27 cells around `d_s`'s cell, and the centroids become
//!    the mean position and (renormalised) mean normal of their members.
//! 4. clusterAssign(`C`, `D`, `F`) (Algorithm 2): every point of the full dataset gets its `F` nearest
//!    centroids `I_m` and inverse distances `W_m = 1 / R_m`.
//!
//! Deviations, and why:
//! - The neighbourhood grows past the paper's 27 cells until it provably holds the nearest centroids: after
//!   the shell of Chebyshev radius `r` around the point's cell every unvisited centroid lies beyond the
//!   visited block's faces, so the search stops once the `F`-th distance found is within the distance to the
//!   nearest face that has cells beyond it (or the grid is exhausted).
//!   The paper's fixed 27 cells can miss the nearest centroid where clusters are sparse; the result here
//!   equals a brute-force search (tested), at the cost of larger searches there.
//!   `max_ring = 1` keeps the paper's 27 cells (the search still grows while no compatible centroid is found).
//! - A point whose normal matches no centroid (`dist` infinite for all: a lone surface orientation, or a zero
//!   normal) would join the last centroid tested in Algorithm 1 (`dist <= minDist` with both infinite): here
//!   it joins the nearest centroid by position, with inverse distance 0 (the shading then uses it alone).
//! - Ties go to the lower centroid index (the paper's `<=` keeps the last one visited, which depends on the
//!   grid's order).
//! - With `neighbour_lists` (the technique's default, `assign=neighbours`), Algorithm 2 searches the grid only
//!   for the samples of `D'`; a point between samples takes its `F` nearest from the union of the `F`-lists of
//!   the (up to) four samples around it, and searches the grid when fewer than `F` of those are compatible with
//!   its normal (a thin object between samples, a crease). The grid search over every pixel was most of the
//!   clustering's time on a CPU rasterizer; neighbouring pixels share almost all of their nearest clusters.
//!   Not exact: a cluster none of the four samples lists is missed (measured in the tests and the docs).
//! - `W` uses `1 / max(R, r_min)` so a point on a centroid gets a finite weight.
//! - Means are fixed point, as on the GPU (WGSL has no float atomics): each member adds its position as a
//!   fraction of the scene's bounds and its normal as `(n + 1) / 2`, times 2^24, into 64-bit sums (two u32
//!   atomics with carry on the GPU), so a mean keeps 2^-24 of the bounds (6e-8) whatever the member count.

use glam::Vec3;

/// Most clusters a point may belong to (`F`).
pub const MAX_F: usize = 8;
/// Cells per axis of the centroid grid at most (32^3 cells).
pub const MAX_GRID: u32 = 32;
/// Fixed-point scale of the sums (2^24).
pub const FIXED: f32 = 16_777_216.0;

/// A surface point: a VPL or a shading point. Invalid points (sky pixels) take no part.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Point {
    pub position: Vec3,
    pub normal: Vec3,
    pub valid: bool,
}

/// The clustering's inputs besides the points.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KMeansParams {
    /// `K` asked for (clamped to the number of samples).
    pub clusters: usize,
    pub iterations: u32,
    /// `gamma`: every `gamma`-th column and row of the dataset takes part in the iterations.
    pub gamma: u32,
    /// `F`, 1 to [`MAX_F`].
    pub fuzziness: usize,
    /// `n_t` of equation 7.
    pub n_t: f32,
    /// Smallest distance in `W = 1 / R` (world units).
    pub min_distance: f32,
    /// 0: search until the result is exact; `n`: stop after the shells up to Chebyshev radius `n` once a
    /// compatible centroid is found (1: the paper's 27 cells).
    pub max_ring: u32,
    /// Algorithm 2 for the points off the sample grid (`gamma` > 1) from their neighbouring samples' lists:
    /// the `F` nearest among the clusters of the (up to) four samples around the point, by equation 7; a grid
    /// search where fewer than `F` of them are compatible. False: every point searches the grid.
    pub neighbour_lists: bool,
    /// The dataset's layout: `width x height` points (shading points: the image; VPLs: N x 1).
    pub width: u32,
    pub height: u32,
    /// Bounds of the grid and of the fixed-point sums (the scene's).
    pub bounds_min: Vec3,
    pub bounds_extent: Vec3,
}

/// A centroid of `C`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Centroid {
    pub position: Vec3,
    pub normal: Vec3,
    /// False when its initial share had no valid point: it never takes part.
    pub active: bool,
}

/// The result of Algorithm 1 with Algorithm 2's final assignment.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Clustering {
    pub centroids: Vec<Centroid>,
    /// `A`: for point `m`, entries `m F .. m F + F`, nearest first; `u32::MAX` where fewer than `F` clusters
    /// are compatible (or the point is invalid).
    pub assignment: Vec<u32>,
    /// `W`: the inverse distances of `assignment`'s entries (0 for the by-position fallback and empty entries).
    pub inverse_distance: Vec<f32>,
    /// Points whose nearest cluster (entry 0) is this one.
    pub members: Vec<u32>,
    /// Per cluster: the member nearest its centroid (lowest index on ties), `None` when it has no member.
    pub representative: Vec<Option<u32>>,
    /// The mean normal of the final members (renormalised; the centroid's when none).
    pub member_normal: Vec<Vec3>,
    /// `F` used (the parameter clamped to 1..=MAX_F).
    pub fuzziness: usize,
}

impl Clustering {
    /// Clusters with at least one member.
    pub fn non_empty(&self) -> usize {
        self.members.iter().filter(|&&m| m > 0).count()
    }
}

/// Equation 7, with infinity as `None`.
pub fn dist(n_t: f32, position: Vec3, normal: Vec3, c: &Centroid) -> Option<f32> {
    (normal.dot(c.normal) > n_t).then(|| (position - c.position).length())
}

/// A centroid found by a search: (distance, index).
pub type Candidate = (f32, u32);

/// The regular grid over the centroids (rebuilt every iteration).
#[derive(Clone, Debug)]
pub struct Grid {
    pub origin: Vec3,
    pub cell: f32,
    pub dims: [u32; 3],
    /// Cell `c`'s centroids are `items[start[c] .. start[c + 1]]`.
    pub start: Vec<u32>,
    pub items: Vec<u32>,
}

/// Cell size and cells per axis for `k` centroids in `extent`: cubic cells of 1.5 times the centroids'
/// expected spacing on surfaces, `sqrt(A / k)` with `A` the surface of the bounding box (centroids lie on
/// surfaces, not in a volume), so the 27 cells around a point usually hold its `F = 6` nearest; at most
/// [`MAX_GRID`] per axis. The exact search returns the same clusters whatever the cells; they only change
/// how many centroids a search visits.
pub fn grid_shape(extent: Vec3, k: usize) -> (f32, [u32; 3]) {
    let e = extent.max(Vec3::ZERO);
    let area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
    let longest = e.max_element();
    let mut cell = 1.5 * (area / k.max(1) as f32).sqrt();
    if !(cell > 0.0 && cell.is_finite()) {
        cell = if longest > 0.0 && longest.is_finite() { longest } else { 1.0 };
    }
    // No more than MAX_GRID cells along any axis: the grid must still cover the bounds.
    cell = cell.max(longest / MAX_GRID as f32);
    let axis = |v: f32| ((v / cell).ceil() as u32).clamp(1, MAX_GRID);
    (cell, [axis(e.x), axis(e.y), axis(e.z)])
}

impl Grid {
    pub fn cell_of(&self, p: Vec3) -> [i32; 3] {
        let c = ((p - self.origin) / self.cell).floor();
        let clamp = |v: f32, d: u32| (if v.is_finite() { v } else { 0.0 }).clamp(0.0, d as f32 - 1.0) as i32;
        [clamp(c.x, self.dims[0]), clamp(c.y, self.dims[1]), clamp(c.z, self.dims[2])]
    }

    fn index(&self, c: [i32; 3]) -> usize {
        (c[0] as u32 + self.dims[0] * (c[1] as u32 + self.dims[1] * c[2] as u32)) as usize
    }

    pub fn build(params: &KMeansParams, centroids: &[Centroid]) -> Grid {
        let (cell, dims) = grid_shape(params.bounds_extent, centroids.len());
        let mut grid = Grid { origin: params.bounds_min, cell, dims, start: Vec::new(), items: Vec::new() };
        let cells = (dims[0] * dims[1] * dims[2]) as usize;
        let mut count = vec![0u32; cells + 1];
        let keys: Vec<Option<usize>> =
            centroids.iter().map(|c| c.active.then(|| grid.index(grid.cell_of(c.position)))).collect();
        for &k in keys.iter().flatten() {
            count[k] += 1;
        }
        let mut start = vec![0u32; cells + 1];
        for c in 0..cells {
            start[c + 1] = start[c] + count[c];
        }
        let mut cursor = start.clone();
        let mut items = vec![0u32; start[cells] as usize];
        for (k, key) in keys.iter().enumerate() {
            if let Some(c) = key {
                items[cursor[*c] as usize] = k as u32;
                cursor[*c] += 1;
            }
        }
        grid.start = start;
        grid.items = items;
        grid
    }

    /// The `f_max` nearest compatible centroids of `(position, normal)` by equation 7, nearest first (ties: lower
    /// index), searched shell by shell from the 27 cells around the point until provably complete. Also the
    /// nearest active centroid by position alone: the fallback when none is compatible (only then is it the
    /// nearest: it is kept only while no compatible one is found, as on the GPU).
    ///
    /// Once `f_max` are found, a cell whose box lies farther than the `f_max`-th is skipped, and a farther
    /// candidate is rejected with one comparison; neither changes the result (tested against brute force). A
    /// border cell's box reaches to infinity outwards, since centroids beyond the bounds are binned into it.
    pub fn nearest(
        &self,
        centroids: &[Centroid],
        n_t: f32,
        position: Vec3,
        normal: Vec3,
        f_max: usize,
        max_ring: u32,
    ) -> (Vec<Candidate>, Option<Candidate>) {
        let mut best: Vec<(f32, u32)> = Vec::with_capacity(f_max + 1);
        let mut any: Option<(f32, u32)> = None;
        let consider = |k: u32, best: &mut Vec<(f32, u32)>, any: &mut Option<(f32, u32)>| {
            let centroid = &centroids[k as usize];
            let d = (position - centroid.position).length();
            if best.is_empty() && any.is_none_or(|a| (d, k) < a) {
                *any = Some((d, k));
            }
            if normal.dot(centroid.normal) > n_t {
                insert(best, f_max, (d, k));
            }
        };
        let c = self.cell_of(position);
        let dims = self.dims.map(|d| d as i32);
        let reach = (0..3).map(|a| c[a].max(dims[a] - 1 - c[a])).max().unwrap_or(0);
        let mut r = 0;
        loop {
            self.visit_shell(c, r, |cell| {
                if best.len() == f_max && self.cell_distance(position, cell) > best[f_max - 1].0 {
                    return;
                }
                let (s, e) = (self.start[cell] as usize, self.start[cell + 1] as usize);
                for &k in &self.items[s..e] {
                    consider(k, &mut best, &mut any);
                }
            });
            let complete = best.len() == f_max && best[f_max - 1].0 <= self.guarantee(position, c, r);
            let ring_done = max_ring > 0 && r >= max_ring as i32 && !best.is_empty();
            if (r >= 1 && (complete || ring_done)) || r >= reach {
                break;
            }
            r += 1;
        }
        (best, any)
    }

    /// The distance from `p` to the box of cell `index`, a border cell's box reaching to infinity outwards.
    fn cell_distance(&self, p: Vec3, index: usize) -> f32 {
        let (nx, ny) = (self.dims[0] as usize, self.dims[1] as usize);
        let c = [index % nx, (index / nx) % ny, index / (nx * ny)];
        let mut d2 = 0.0f32;
        for a in 0..3 {
            let lo = if c[a] == 0 { f32::NEG_INFINITY } else { self.origin[a] + c[a] as f32 * self.cell };
            let hi = if c[a] + 1 == self.dims[a] as usize {
                f32::INFINITY
            } else {
                self.origin[a] + (c[a] + 1) as f32 * self.cell
            };
            let e = (lo - p[a]).max(p[a] - hi).max(0.0);
            d2 += e * e;
        }
        d2.sqrt()
    }

    /// How far every centroid outside the block of Chebyshev radius `r` around cell `c` is from `p` at least:
    /// the distance from `p` to the block's nearest face, where a face on the grid's border counts as infinitely
    /// far (no cell lies beyond it). Centroids outside the bounds are binned into border cells on their own
    /// side, so the bound holds for them too.
    pub fn guarantee(&self, p: Vec3, c: [i32; 3], r: i32) -> f32 {
        let mut g = f32::INFINITY;
        for a in 0..3 {
            if c[a] - r > 0 {
                g = g.min(p[a] - (self.origin[a] + (c[a] - r) as f32 * self.cell));
            }
            if c[a] + r < self.dims[a] as i32 - 1 {
                g = g.min(self.origin[a] + (c[a] + r + 1) as f32 * self.cell - p[a]);
            }
        }
        g
    }

    /// Calls `f` with the index of every grid cell at Chebyshev distance exactly `r` from `c`.
    fn visit_shell(&self, c: [i32; 3], r: i32, mut f: impl FnMut(usize)) {
        let dims = self.dims.map(|d| d as i32);
        let lo = |a: usize| (c[a] - r).max(0);
        let hi = |a: usize| (c[a] + r).min(dims[a] - 1);
        for z in lo(2)..=hi(2) {
            for y in lo(1)..=hi(1) {
                let edge = (z - c[2]).abs() == r || (y - c[1]).abs() == r;
                if edge {
                    for x in lo(0)..=hi(0) {
                        f(self.index([x, y, z]));
                    }
                } else {
                    for x in [c[0] - r, c[0] + r] {
                        if x >= 0 && x < dims[0] {
                            f(self.index([x, y, z]));
                        }
                    }
                }
            }
        }
    }
}

/// Insert `item` into the ascending list `best`, keeping at most `f_max`.
fn insert(best: &mut Vec<(f32, u32)>, f_max: usize, item: (f32, u32)) {
    let at = best.iter().position(|b| item < *b).unwrap_or(best.len());
    if at < f_max {
        best.insert(at, item);
        best.truncate(f_max);
    }
}

/// The indices of `D'` in the full dataset (step 1).
pub fn samples(params: &KMeansParams) -> Vec<u32> {
    let g = params.gamma.max(1);
    let mut out = Vec::new();
    for y in (0..params.height).step_by(g as usize) {
        for x in (0..params.width).step_by(g as usize) {
            out.push(y * params.width + x);
        }
    }
    out
}

/// Whether point `m` of the `width x height` dataset is a sample of `D'` (every `gamma`-th column and row).
pub fn is_sample(params: &KMeansParams, m: usize) -> bool {
    let (w, g) = (params.width.max(1) as usize, params.gamma.max(1) as usize);
    (m % w).is_multiple_of(g) && (m / w).is_multiple_of(g)
}

/// The samples of `D'` at the corners of the sample-grid cell holding point `m` (the last sample column or
/// row stands for the one beyond the dataset's edge; corners repeat there).
pub fn sample_corners(params: &KMeansParams, m: usize) -> [usize; 4] {
    let (w, h, g) = (params.width.max(1) as usize, params.height.max(1) as usize, params.gamma.max(1) as usize);
    let (x, y) = (m % w, m / w);
    let (x0, y0) = (x / g * g, y / g * g);
    let (x1, y1) = ((x0 + g).min((w - 1) / g * g), (y0 + g).min((h - 1) / g * g));
    [y0 * w + x0, y0 * w + x1, y1 * w + x0, y1 * w + x1]
}

/// 64-bit fixed-point sums of positions (fractions of the bounds) and normals ((n + 1) / 2), as the GPU does.
#[derive(Clone, Copy, Default)]
struct Sums {
    p: [u64; 3],
    n: [u64; 3],
    count: u32,
}

fn quantize(v: f32) -> u64 {
    // `u32(clamp(v, 0, 1) * 2^24)` on the GPU.
    (v.clamp(0.0, 1.0) * FIXED) as u64
}

impl Sums {
    fn add(&mut self, params: &KMeansParams, p: &Point) {
        let f = (p.position - params.bounds_min) / params.bounds_extent.max(Vec3::splat(1e-12));
        let n = p.normal * 0.5 + Vec3::splat(0.5);
        for a in 0..3 {
            self.p[a] += quantize(f[a]);
            self.n[a] += quantize(n[a]);
        }
        self.count += 1;
    }

    /// The mean, in f32 exactly as the shader computes it: `(f32(hi) * 2^32 + f32(lo)) / (count * 2^24)`.
    fn mean(v: u64, count: u32) -> f32 {
        let (hi, lo) = ((v >> 32) as u32, v as u32);
        (hi as f32 * 4_294_967_296.0 + lo as f32) / (count as f32 * FIXED)
    }

    fn position(&self, params: &KMeansParams) -> Vec3 {
        let f = Vec3::new(
            Self::mean(self.p[0], self.count),
            Self::mean(self.p[1], self.count),
            Self::mean(self.p[2], self.count),
        );
        params.bounds_min + f * params.bounds_extent.max(Vec3::splat(1e-12))
    }

    /// The renormalised mean normal, or None when it vanishes (opposite normals).
    fn normal(&self) -> Option<Vec3> {
        let n = Vec3::new(
            Self::mean(self.n[0], self.count),
            Self::mean(self.n[1], self.count),
            Self::mean(self.n[2], self.count),
        ) * 2.0
            - Vec3::ONE;
        (n.length_squared() > 1e-12).then(|| n.normalize())
    }
}

/// Algorithm 1 (with Algorithm 2 as its last line) over `points` (`width x height`, row-major).
pub fn cluster(points: &[Point], params: &KMeansParams) -> Clustering {
    cluster_from(points, params, None)
}

/// [`cluster`], started from `start` instead of step 2's initial centroids when it holds `K` of them (a warm
/// start: the last view's centroids, the paper's section 6 proposal); each iteration then moves a centroid
/// left without members (or inactive) back to its step-2 sample of this dataset, since its surface left the
/// view. With `start` None or of another length it is [`cluster`].
pub fn cluster_from(points: &[Point], params: &KMeansParams, start: Option<&[Centroid]>) -> Clustering {
    let f_max = params.fuzziness.clamp(1, MAX_F);
    let valid = |p: &Point| p.valid && p.position.is_finite() && p.normal.is_finite();
    // Step 1.
    let samples: Vec<u32> = samples(params).into_iter().filter(|&m| (m as usize) < points.len()).collect();
    let s = samples.len();
    let k_count = params.clusters.min(s);
    // Step 2.
    let seed = |k: usize| {
        let (a, b) = (k * s / k_count, (k + 1) * s / k_count);
        match samples[a..b].iter().map(|&m| &points[m as usize]).find(|p| valid(p)) {
            Some(p) => Centroid { position: p.position, normal: p.normal, active: true },
            None => Centroid { position: Vec3::ZERO, normal: Vec3::Z, active: false },
        }
    };
    let warm = start.filter(|c| c.len() == k_count);
    let mut centroids: Vec<Centroid> = match warm {
        Some(c) => c.to_vec(),
        None => (0..k_count).map(seed).collect(),
    };
    let nearest_one = |grid: &Grid, centroids: &[Centroid], p: &Point| -> Option<(f32, u32, bool)> {
        let (best, any) = grid.nearest(centroids, params.n_t, p.position, p.normal, 1, params.max_ring);
        match best.first() {
            Some(&(d, k)) => Some((d, k, true)),
            None => any.map(|(d, k)| (d, k, false)),
        }
    };
    // Step 3.
    for _ in 0..params.iterations {
        let grid = Grid::build(params, &centroids);
        let mut sums = vec![Sums::default(); k_count];
        for &m in &samples {
            let p = &points[m as usize];
            if !valid(p) {
                continue;
            }
            if let Some((_, k, _)) = nearest_one(&grid, &centroids, p) {
                sums[k as usize].add(params, p);
            }
        }
        for (k, (c, s)) in centroids.iter_mut().zip(&sums).enumerate() {
            if c.active && s.count > 0 {
                c.position = s.position(params);
                if let Some(n) = s.normal() {
                    c.normal = n;
                }
            } else if warm.is_some() {
                *c = seed(k);
            }
        }
    }
    // Step 4: Algorithm 2 over the full dataset: the samples first (with `neighbour_lists`, the others then
    // choose among their neighbouring samples' lists).
    let grid = Grid::build(params, &centroids);
    let mut assignment = vec![u32::MAX; points.len() * f_max];
    let mut inverse_distance = vec![0.0f32; points.len() * f_max];
    let mut members = vec![0u32; k_count];
    let mut rep: Vec<Option<(f32, u32)>> = vec![None; k_count];
    let mut normals = vec![Sums::default(); k_count];
    let neighbours = params.neighbour_lists && params.gamma > 1;
    let (order_first, order_then): (Vec<usize>, Vec<usize>) = if neighbours {
        (0..points.len()).partition(|&m| is_sample(params, m))
    } else {
        ((0..points.len()).collect(), Vec::new())
    };
    for (m, from_neighbours) in
        order_first.into_iter().map(|m| (m, false)).chain(order_then.into_iter().map(|m| (m, true)))
    {
        let p = &points[m];
        if !valid(p) {
            continue;
        }
        let mut best = Vec::new();
        let mut any = None;
        if from_neighbours {
            for c in sample_corners(params, m).into_iter().filter(|&c| c < points.len()) {
                for &k in assignment[c * f_max..c * f_max + f_max].iter().take_while(|&&k| k != u32::MAX) {
                    if best.iter().any(|b: &Candidate| b.1 == k) {
                        continue;
                    }
                    if let Some(d) = dist(params.n_t, p.position, p.normal, &centroids[k as usize]) {
                        insert(&mut best, f_max, (d, k));
                    }
                }
            }
        }
        if best.len() < f_max {
            (best, any) = grid.nearest(&centroids, params.n_t, p.position, p.normal, f_max, params.max_ring);
        }
        let entries: Vec<(f32, u32, f32)> = if best.is_empty() {
            any.map(|(d, k)| (d, k, 0.0)).into_iter().collect()
        } else {
            best.iter().map(|&(d, k)| (d, k, 1.0 / d.max(params.min_distance))).collect()
        };
        for (f, &(_, k, w)) in entries.iter().enumerate() {
            assignment[m * f_max + f] = k;
            inverse_distance[m * f_max + f] = w;
        }
        if let Some(&(d, k, _)) = entries.first() {
            let k = k as usize;
            members[k] += 1;
            normals[k].add(params, p);
            if rep[k].is_none_or(|r| (d, m as u32) < r) {
                rep[k] = Some((d, m as u32));
            }
        }
    }
    let member_normal =
        normals.iter().zip(&centroids).map(|(s, c)| if s.count > 0 { s.normal() } else { None }.unwrap_or(c.normal));
    Clustering {
        member_normal: member_normal.collect(),
        centroids,
        assignment,
        inverse_distance,
        members,
        representative: rep.iter().map(|r| r.map(|(_, m)| m)).collect(),
        fuzziness: f_max,
    }
}

/// Visibility weights of one point's entries for a shading mode (equations 8-10): `hard` (F = 1: entry 0 only),
/// `fuzzy` (the mean over its entries), `weighted` (inverse-distance weights). The by-position fallback (all
/// inverse distances 0) gets weight 1 on entry 0. Empty entries weigh 0; the weights sum to 1 (or all 0 for an
/// invalid point).
pub fn weights(mode: ShadeMode, entries: &[u32], inverse_distance: &[f32]) -> Vec<f32> {
    let used = entries.iter().take_while(|&&k| k != u32::MAX).count();
    let mut w = vec![0.0; entries.len()];
    if used == 0 {
        return w;
    }
    let total: f32 = inverse_distance[..used].iter().sum();
    match mode {
        _ if total <= 0.0 => w[0] = 1.0,
        ShadeMode::Hard => w[0] = 1.0,
        ShadeMode::Fuzzy => w[..used].fill(1.0 / used as f32),
        ShadeMode::Weighted => {
            for f in 0..used {
                w[f] = inverse_distance[f] / total;
            }
        }
    }
    w
}

/// How a shading point's visibility combines its clusters' (section 3.2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShadeMode {
    Hard,
    Fuzzy,
    Weighted,
}

impl ShadeMode {
    pub fn index(self) -> u32 {
        match self {
            ShadeMode::Hard => 0,
            ShadeMode::Fuzzy => 1,
            ShadeMode::Weighted => 2,
        }
    }
}

#[cfg(test)]
#[path = "kmeans_tests.rs"]
mod tests;
