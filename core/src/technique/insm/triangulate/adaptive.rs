//! The adaptive mesh of the CPU twin (beyond the paper, `adaptive`): a quadtree of planar blocks in each tile
//! (the whole tile, its 4x4 quadrants, its 2x2 blocks), each neighbourhood in the largest planar block around it,
//! merged leaves written as two triangles or a fan over the vertices of their boundary. The twin of `classify`,
//! `leaf_of`, `is_vertex` and `emit_leaf` in `insm/triangulate_adaptive.wgsl`.

use super::{tiles_per_side, Connectivity, SampledImage, TILE};

/// Bit of a tile's planar mask: the whole tile (`TILE`² neighbourhoods) is planar.
pub const TILE_BIT: u32 = 1;
/// Bits `1 + qy * 2 + qx`: quadrant `(qx, qy)` (4x4 neighbourhoods) is planar.
const QUADRANT_BITS: u32 = 1;
/// Bits `5 + by * 4 + bx`: block `(bx, by)` (2x2 neighbourhoods) is planar.
const BLOCK_BITS: u32 = 5;

/// The block that bit `bit` of a planar mask stands for: its origin in the tile and its side, in neighbourhoods.
fn mask_block(bit: u32) -> (u32, u32, u32) {
    match bit {
        0 => (0, 0, TILE),
        b if b < BLOCK_BITS => ((b - QUADRANT_BITS) % 2 * 4, (b - QUADRANT_BITS) / 2 * 4, 4),
        b => ((b - BLOCK_BITS) % 4 * 2, (b - BLOCK_BITS) / 4 * 2, 2),
    }
}

/// Boundary point `k` (0..=`size`) of side `side` of a block, in fan order: top right to left, left down,
/// bottom left to right, right up (block coordinates). The twin of `side_point` in the shader.
fn side_point(side: u32, k: u32, size: u32) -> (u32, u32) {
    match side {
        0 => (size - k, 0),
        1 => (0, k),
        2 => (k, size),
        _ => (size, size - k),
    }
}

impl SampledImage<'_> {
    /// True when the block of `size`² neighbourhoods at neighbourhood `(u0, v0)` is planar, so that the
    /// adaptive mesh may merge it into a few large triangles: it is whole (its `(size + 1)²` samples lie in the
    /// image), every one of its neighbourhoods keeps both triangles (by `epsilon`), and every sample's inverse
    /// depth is within `merge_epsilon` (relative) of the affine function through the block's corners `z(0,0)`,
    /// `z(size,0)`, `z(0,size)`: on a plane inverse depth is affine in image coordinates, so this is the
    /// second-difference test taken across the whole block, with a tolerance that planes pass to rounding and
    /// that bounds how far a merged block strays from its samples.
    pub fn block_planar(
        &self,
        u0: u32,
        v0: u32,
        size: u32,
        epsilon: impl Into<Connectivity>,
        merge_epsilon: f32,
    ) -> bool {
        let epsilon: Connectivity = epsilon.into();
        if u0 + size >= self.resolution || v0 + size >= self.resolution {
            return false;
        }
        let z = |i: u32, j: u32| self.z((u0 + i) as i64, (v0 + j) as i64);
        let (z00, z10, z01) = (z(0, 0), z(size, 0), z(0, size));
        for j in 0..=size {
            for i in 0..=size {
                let fit = z00 + (z10 - z00) * (i as f32 / size as f32) + (z01 - z00) * (j as f32 / size as f32);
                let zs = z(i, j);
                // Written so that NaN fails.
                let on_plane = (zs - fit).abs() < merge_epsilon * zs;
                if !on_plane {
                    return false;
                }
            }
        }
        (0..size).all(|j| (0..size).all(|i| self.neighbourhood(u0 + i, v0 + j, epsilon).iter().all(Option::is_some)))
    }

    /// The planar mask of tile `(tx, ty)`: bit [`TILE_BIT`] when the whole tile is planar
    /// ([`SampledImage::block_planar`]), bits 1-4 its 4x4 quadrants, bits 5-20 its 2x2 blocks; blocks smaller
    /// than `min_block` are not asked. The mesh merges the largest planar block around each neighbourhood.
    pub fn planar_mask(
        &self,
        tx: u32,
        ty: u32,
        epsilon: impl Into<Connectivity>,
        merge_epsilon: f32,
        min_block: u32,
    ) -> u32 {
        let epsilon: Connectivity = epsilon.into();
        (0..BLOCK_BITS + 16)
            .filter(|&bit| {
                let (x, y, size) = mask_block(bit);
                size >= min_block && self.block_planar(tx * TILE + x, ty * TILE + y, size, epsilon, merge_epsilon)
            })
            .fold(0, |mask, bit| mask | 1 << bit)
    }

    /// The planar mask of every tile, row-major (`tiles_per_side(resolution)²`).
    pub fn planar_masks(&self, epsilon: impl Into<Connectivity>, merge_epsilon: f32, min_block: u32) -> Vec<u32> {
        let epsilon: Connectivity = epsilon.into();
        let tps = tiles_per_side(self.resolution);
        (0..tps * tps).map(|t| self.planar_mask(t % tps, t / tps, epsilon, merge_epsilon, min_block)).collect()
    }

    /// The leaf of the adaptive mesh's quadtree that holds neighbourhood `(x, y)`: the largest planar block of
    /// its tile's mask around it (the whole tile, its quadrant, its 2x2 block) or the neighbourhood alone, as
    /// (origin x, origin y, side) in neighbourhoods; `None` outside the image's neighbourhoods.
    fn leaf(&self, masks: &[u32], x: i64, y: i64) -> Option<(u32, u32, u32)> {
        let n = self.resolution as i64 - 1;
        if x < 0 || y < 0 || x >= n || y >= n {
            return None;
        }
        let (x, y) = (x as u32, y as u32);
        let (tx, ty) = (x / TILE, y / TILE);
        let mask = masks[(ty * tiles_per_side(self.resolution) + tx) as usize];
        let (lx, ly) = (x % TILE, y % TILE);
        let bits = [0, QUADRANT_BITS + ly / 4 * 2 + lx / 4, BLOCK_BITS + ly / 2 * 4 + lx / 2];
        Some(match bits.iter().find(|&&b| mask & 1 << b != 0) {
            Some(&b) => {
                let (bx, by, size) = mask_block(b);
                (tx * TILE + bx, ty * TILE + by, size)
            }
            None => (x, y, 1),
        })
    }

    /// Sample `(x, y)` is a vertex of the adaptive mesh: a corner of the leaf of one of the (up to four)
    /// neighbourhoods around it. A merged block's side keeps every sample that is one, so neighbouring leaves
    /// share every vertex of their common sides: no T-junctions, no cracks.
    fn is_vertex(&self, masks: &[u32], x: u32, y: u32) -> bool {
        [(0, 0), (-1, 0), (0, -1), (-1, -1)].iter().any(|&(dx, dy)| {
            self.leaf(masks, x as i64 + dx, y as i64 + dy).is_some_and(|(ox, oy, size)| {
                let (lx, ly) = (x - ox, y - oy);
                (lx == 0 || lx == size) && (ly == 0 || ly == size)
            })
        })
    }

    /// The triangles of tile `(tx, ty)` in the adaptive mesh (a deviation beyond the paper, see `insm/mod.rs`):
    /// each planar leaf ([`SampledImage::planar_mask`], the largest planar block around a neighbourhood) is two
    /// triangles when its sides hold no vertex but its corners, else a fan from its centre sample over every
    /// vertex of its boundary ([`SampledImage::is_vertex`]: the corners of the leaves around); the other
    /// neighbourhoods keep Algorithm 2's triangles. `masks` is every tile's planar mask, row-major (all 0:
    /// Algorithm 2). With `covered` (per sample, [`covered_samples`]) a triangle whose three corners are
    /// covered is dropped, and a merged block whose samples are all covered.
    pub fn tile_triangles(
        &self,
        tx: u32,
        ty: u32,
        epsilon: impl Into<Connectivity>,
        masks: &[u32],
        covered: Option<&[bool]>,
    ) -> Vec<[u32; 3]> {
        let epsilon: Connectivity = epsilon.into();
        let r = self.resolution;
        let is_covered = |i: u32| covered.is_some_and(|c| c[i as usize]);
        let mut out = Vec::new();
        for v in ty * TILE..((ty + 1) * TILE).min(r.saturating_sub(1)) {
            for u in tx * TILE..((tx + 1) * TILE).min(r.saturating_sub(1)) {
                let Some((u0, v0, size)) = self.leaf(masks, u as i64, v as i64) else { continue };
                if size == 1 {
                    let kept = self.neighbourhood(u, v, epsilon).into_iter().flatten();
                    out.extend(kept.filter(|t| !t.iter().all(|&i| is_covered(i))));
                } else if (u, v) == (u0, v0) {
                    self.leaf_triangles(masks, (u0, v0, size), &is_covered, &mut out);
                }
            }
        }
        out
    }

    /// The merged leaves of the adaptive mesh (origin x, origin y, side, in neighbourhoods), but those whose samples
    /// are all `covered` (their triangles are dropped): what the overlay "INSM merged blocks" outlines.
    pub fn merged_leaves(&self, masks: &[u32], covered: Option<&[bool]>) -> Vec<(u32, u32, u32)> {
        let r = self.resolution;
        let n = r.saturating_sub(1);
        let is_covered = |x: u32, y: u32| covered.is_some_and(|c| c[(y * r + x) as usize]);
        let mut out = Vec::new();
        for v in 0..n {
            for u in 0..n {
                let Some((u0, v0, size)) = self.leaf(masks, u as i64, v as i64) else { continue };
                if size == 1 || (u, v) != (u0, v0) {
                    continue;
                }
                if !(0..=size).all(|j| (0..=size).all(|i| is_covered(u0 + i, v0 + j))) {
                    out.push((u0, v0, size));
                }
            }
        }
        out
    }

    /// A merged leaf's triangles (see [`SampledImage::tile_triangles`]).
    fn leaf_triangles(
        &self,
        masks: &[u32],
        (u0, v0, size): (u32, u32, u32),
        is_covered: &dyn Fn(u32) -> bool,
        out: &mut Vec<[u32; 3]>,
    ) {
        let r = self.resolution;
        let index = |i: u32, j: u32| (v0 + j) * r + u0 + i;
        if (0..=size).all(|j| (0..=size).all(|i| is_covered(index(i, j)))) {
            return;
        }
        // The boundary in fan order (top right to left, left down, bottom left to right, right up), each side's
        // points k = 0..size (its last is the next side's first), the vertices among them.
        let boundary: Vec<u32> = (0..4)
            .flat_map(|side| (0..size).map(move |k| side_point(side, k, size)))
            .filter(|&(i, j)| self.is_vertex(masks, u0 + i, v0 + j))
            .map(|(i, j)| index(i, j))
            .collect();
        if boundary.len() == 4 {
            out.push([index(0, 0), index(0, size), index(size, size)]);
            out.push([index(size, size), index(size, 0), index(0, 0)]);
            return;
        }
        let centre = index(size / 2, size / 2);
        for (i, &a) in boundary.iter().enumerate() {
            out.push([centre, a, boundary[(i + 1) % boundary.len()]]);
        }
    }
}
