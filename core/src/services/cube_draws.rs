//! The culled draw lists of a depth pass into the shadow atlas: per tile (a cube face, a paraboloid, a
//! perspective view) the chunks kept, opaque ones merged into index ranges, cut-outs one by one. Built by
//! `cube_shadows.rs`'s `CubeShadowRenderer` and recorded by it.

use super::cube_atlas::CubeStats;
use super::cube_geometry::CubeGeometry;
use crate::scene::chunks::{merge_draw_ranges, Chunk};

/// One tile's draws: its opaque ranges `all_ranges[first..first + count]` and its cut-out chunks
/// `all_masked[first_masked..first_masked + masked]`.
#[derive(Clone, Copy)]
pub(super) struct TileDraw {
    pub(super) tile: u32,
    pub(super) first: usize,
    pub(super) count: usize,
    pub(super) first_masked: usize,
    pub(super) masked: usize,
}

/// Splits `ids` into `opaque` (merged into draw ranges by the caller) and `masked` chunks.
fn split_cutouts(geometry: &CubeGeometry<'_>, ids: &[u32], opaque: &mut Vec<u32>, masked: &mut Vec<u32>) {
    opaque.clear();
    for &id in ids {
        if geometry.masked(id as usize) {
            masked.push(id);
        } else {
            opaque.push(id);
        }
    }
}

/// The draw lists of one depth pass: per tile its merged opaque index ranges and its cut-out chunks.
#[derive(Default)]
pub(super) struct DrawLists {
    pub(super) draws: Vec<TileDraw>,
    pub(super) ranges: Vec<(u32, u32)>,
    pub(super) masked: Vec<u32>,
}

/// Reused per-tile scratch of the culled draw loop.
#[derive(Default)]
pub(super) struct TileScratch {
    selected: Vec<u32>,
    opaque: Vec<u32>,
    ranges: Vec<(u32, u32)>,
}

/// The culled draw loop of every view (cube face, paraboloid, perspective): of the chunks `candidates`, those
/// `keep` accepts are drawn into `tile`, opaque ones merged into ranges, cut-outs one by one; the triangles
/// submitted and culled are added to `stats`.
pub(super) fn push_tile(
    lists: &mut DrawLists,
    scratch: &mut TileScratch,
    geometry: &CubeGeometry<'_>,
    tile: usize,
    candidates: impl Iterator<Item = u32>,
    keep: impl Fn(&Chunk) -> bool,
    stats: &mut CubeStats,
) {
    scratch.selected.clear();
    let mut tris = 0u64;
    for id in candidates {
        let chunk = &geometry.chunks[id as usize];
        if keep(chunk) {
            scratch.selected.push(id);
            tris += chunk.triangle_count() as u64;
        }
    }
    stats.triangles_submitted += tris;
    stats.triangles_culled += geometry.triangle_count - tris;
    let first_masked = lists.masked.len();
    split_cutouts(geometry, &scratch.selected, &mut scratch.opaque, &mut lists.masked);
    merge_draw_ranges(geometry.chunks, scratch.opaque.iter().copied(), &mut scratch.ranges);
    lists.draws.push(TileDraw {
        tile: tile as u32,
        first: lists.ranges.len(),
        count: scratch.ranges.len(),
        first_masked,
        masked: lists.masked.len() - first_masked,
    });
    lists.ranges.extend_from_slice(&scratch.ranges);
}
