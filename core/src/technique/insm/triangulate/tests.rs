//! The CPU twin's tests: Algorithm 2 on planes, steps and creases, the adaptive mesh, covered triangles,
//! dilation and the steep-edge tolerance (the GPU is tested equal to this twin in `core/tests/insm_render.rs`).

use super::*;

fn adaptive_mesh(epsilon: f32) -> MeshSettings {
    MeshSettings { epsilon, step_epsilon: epsilon, adaptive: true, ..MeshSettings::default() }
}

/// A `r x r` image of inverse depths from `f(x, y)` (positions on a fake grid).
fn image(r: u32, f: impl Fn(u32, u32) -> f32) -> Vec<Vec4> {
    (0..r * r).map(|i| Vec4::new((i % r) as f32, (i / r) as f32, 0.0, f(i % r, i / r))).collect()
}

#[test]
fn a_steep_edge_is_held_to_the_tighter_tolerance_and_only_a_steep_one() {
    // Rows of inverse depth bending by about 3 % a sample: between the step tolerance (2 %) and ε (4 %).
    let tolerances = |steep: f32| Connectivity { epsilon: 0.04, step: 0.02, steep };
    let steep_row = [0.100, 0.103, 0.109, 0.118];
    let s = image(4, |x, _| steep_row[x as usize]);
    let img = SampledImage { resolution: 4, samples: &s };
    // Edge (1, 2) changes inverse depth by 5.5 % (relative): steep above a slope of 0.03, not below 0.1.
    assert!(img.edge_connected((1, 0), (2, 0), tolerances(0.0)), "no edge is steep: ε holds");
    assert!(img.edge_connected((1, 0), (2, 0), tolerances(0.1)), "not steep for this map: ε holds");
    assert!(!img.edge_connected((1, 0), (2, 0), tolerances(0.03)), "steep: the 2 % tolerance cuts it");
    // A diagonal edge's change is over √2 samples: steep only above √2 times the slope.
    let d = image(4, |x, y| steep_row[x.max(y) as usize]);
    let diag = SampledImage { resolution: 4, samples: &d };
    assert!(diag.edge_connected((1, 1), (2, 2), tolerances(0.05)), "5.5 % over √2 samples is under 0.05");
    assert!(!diag.edge_connected((1, 1), (2, 2), tolerances(0.03)));
    // A row that bends as much but changes little (1.5 % a sample) is not steep: ε keeps it.
    let zigzag = [0.100, 0.1015, 0.100, 0.1015];
    let z = image(4, |x, _| zigzag[x as usize]);
    let flat = SampledImage { resolution: 4, samples: &z };
    assert!(flat.edge_connected((1, 0), (2, 0), tolerances(0.03)));
    assert!(!flat.edge_connected((1, 0), (2, 0), Connectivity::from(0.02)), "the step tolerance alone cuts it");
    // The steepness of a map: tan(angle) sample widths; none at 90° or for a bad angle.
    let slope = steep_slope(75.0, 100.0, 128);
    assert!((slope - 75f32.to_radians().tan() * 2.0 * 50f32.to_radians().tan() / 128.0).abs() < 1e-6);
    assert!((steep_slope(75.0, 100.0, 256) - 0.5 * slope).abs() < 1e-6, "finer maps, finer samples");
    for bad in [90.0, 120.0, -5.0, f32::NAN] {
        assert_eq!(steep_slope(bad, 100.0, 128), 0.0, "{bad}");
    }
    // At 0° every edge whose depth changes is steep (the tighter tolerance everywhere but on flat rows).
    assert!(steep_slope(0.0, 100.0, 128) > 0.0);
    assert!(!img.edge_connected((1, 0), (2, 0), tolerances(steep_slope(0.0, 100.0, 128))));
}

#[test]
fn a_plane_is_fully_connected_whatever_its_slope() {
    for (a, b, c) in [(0.5, 0.0, 0.0), (0.5, 0.01, 0.02), (0.9, -0.03, 0.005)] {
        let s = image(9, |x, y| a + b * x as f32 + c * y as f32);
        let img = SampledImage { resolution: 9, samples: &s };
        assert_eq!(img.triangles(1e-4).len(), 2 * 8 * 8, "plane {a} {b} {c}");
        assert!(img.dropped_edges(1e-4).is_empty());
    }
}

#[test]
fn a_depth_step_is_not_bridged() {
    // Left half near (z=1), right half far (z=0.25): a discontinuity between x=3 and x=4.
    let s = image(8, |x, _| if x < 4 { 1.0 } else { 0.25 });
    let img = SampledImage { resolution: 8, samples: &s };
    let tris = img.triangles(0.05);
    for t in &tris {
        let xs: Vec<u32> = t.iter().map(|&i| i % 8).collect();
        assert!(xs.iter().all(|&x| x < 4) || xs.iter().all(|&x| x >= 4), "triangle {t:?} spans the step");
    }
    // Only the edges across the step go (both second differences fail, with opposite signs): in the inner
    // rows the neighbourhoods of column 3 lose their triangles, every other column keeps them, so each side
    // keeps its last sample (the paper's half-sample erosion). The paper's "both below ε" also dropped
    // columns 2 and 4. (In the first and last rows a diagonal next to the step has one outer sample outside
    // the image and the other across the step: it is dropped, the ambiguous case.)
    let inner = |t: &&[u32; 3]| t.iter().all(|&i| (1..7).contains(&(i / 8)));
    assert_eq!(tris.iter().filter(inner).count(), 2 * 5 * 6);
    let dropped = img.dropped_edges(0.05);
    let across = |e: &DroppedEdge| e.from.x == 3.0 && e.to.x == 4.0;
    assert!(dropped.iter().all(|e| across(e) || e.from.y == 0.0 || e.to.y == 7.0), "{dropped:?}");
    assert_eq!(dropped.iter().filter(|e| across(e)).count(), 8 + 7, "the step's horizontal and diagonal edges");
}

#[test]
fn a_crease_cuts_one_edge_and_a_spike_is_not_bridged() {
    // A crease (a roof: inverse depth rising then falling, the kink between x = 3 and x = 4): only the edges
    // across the kink go (the paper's "both below ε" also dropped the columns either side).
    let roof = image(8, |x, _| if x < 4 { 0.5 + 0.05 * x as f32 } else { 0.5 + 0.05 * (7 - x) as f32 });
    let img = SampledImage { resolution: 8, samples: &roof };
    let inner = |t: &&[u32; 3]| t.iter().all(|&i| (1..7).contains(&(i / 8)));
    assert_eq!(img.triangles(0.01).iter().filter(inner).count(), 2 * 6 * 5);
    // A one-sample spike in front of the ground is not bridged to it.
    let spike = image(8, |x, _| if x == 3 { 1.0 } else { 0.25 });
    let img = SampledImage { resolution: 8, samples: &spike };
    assert!(img.triangles(0.01).iter().all(|t| t.iter().all(|&i| i % 8 != 3)));
}

#[test]
fn dilation_moves_the_samples_at_a_cut_edge_half_a_sample_across_it_and_no_other() {
    // A step between x = 3 (near, z = 1) and x = 4 (far, z = 0.25) on a grid of unit spacing: both sides
    // end at their last sample, so the union of the meshes misses the strip 3..4 (the half-sample erosion
    // on each side). Dilated, the near side reaches 3.5 and the far side starts there.
    let s = image(8, |x, _| if x < 4 { 1.0 } else { 0.25 });
    let img = SampledImage { resolution: 8, samples: &s };
    let d = img.dilated(0.05);
    for (i, (before, after)) in s.iter().zip(&d).enumerate() {
        let (x, y) = (i % 8, i / 8);
        assert_eq!(after.w, before.w, "inverse depth is kept");
        let expected_x = match x {
            3 | 4 => 3.5,
            _ => x as f32,
        };
        // (In the first and last rows the diagonal next to the step is ambiguous, but dilation only looks
        // along the axes.)
        assert_eq!((after.x, after.y), (expected_x, y as f32), "sample ({x}, {y})");
    }
    // A bar three samples wide in front of the ground grows to three samples' width (2.5 to 5.5); a bar one
    // sample wide has no triangle and does not move; the ground's samples next to a bar move under it.
    let bar = image(14, |x, _| if (3..=5).contains(&x) || x == 9 { 1.0 } else { 0.25 });
    let img = SampledImage { resolution: 14, samples: &bar };
    let d = img.dilated(0.05);
    let x_at = |x: usize| d[5 * 14 + x].x;
    assert_eq!([x_at(3), x_at(4), x_at(5)], [2.5, 4.0, 5.5]);
    assert_eq!(x_at(9), 9.0, "a one-sample bar has no kept edge behind it");
    assert_eq!([x_at(2), x_at(6), x_at(8), x_at(10)], [2.5, 5.5, 8.5, 9.5]);
    // Nothing moves on a plane, nor at the image's border (the surface goes on outside it).
    let plane = image(9, |x, y| 0.5 + 0.01 * x as f32 + 0.02 * y as f32);
    let img = SampledImage { resolution: 9, samples: &plane };
    assert_eq!(img.dilated(1e-3), plane);
}

#[test]
fn dilation_extrapolates_along_a_slanted_surface() {
    // World positions along a slope (z rises by 0.3 per sample) ending at a step: the last sample moves
    // half a step along the slope, in depth too, not in the image plane alone.
    let r = 8;
    let s: Vec<Vec4> = (0..r * r)
        .map(|i| {
            let (x, y) = (i % r, i / r);
            if x < 5 {
                Vec4::new(x as f32, y as f32, 0.3 * x as f32, 1.0 / (2.0 + 0.1 * x as f32))
            } else {
                Vec4::new(x as f32, y as f32, 5.0, 0.1)
            }
        })
        .collect();
    let img = SampledImage { resolution: r, samples: &s };
    let d = img.dilated(0.01);
    let last = d[(3 * r + 4) as usize];
    assert!((last.x - 4.5).abs() < 1e-6 && (last.z - 1.35).abs() < 1e-6, "{last}");
}

#[test]
fn dilation_leaves_a_surface_seen_at_a_grazing_angle() {
    // A plane (inverse depth affine in the image) ending at a step to a far surface; its view depth grows by
    // 0.2-0.4 per sample. Spaced 1 apart sideways it is seen nearly face-on and its last sample moves; spaced
    // 0.05 apart it is seen almost edge-on (depth changing six times faster than the spacing) and stays.
    let r = 10;
    for (spacing, moves) in [(1.0f32, true), (0.05, false)] {
        let s: Vec<Vec4> = (0..r * r)
            .map(|i| {
                let (x, y) = (i % r, i / r);
                let w = if x < 5 { 0.5 - 0.04 * x as f32 } else { 0.05 };
                Vec4::new(spacing * x as f32, spacing * y as f32, 1.0 / w, w)
            })
            .collect();
        let img = SampledImage { resolution: r, samples: &s };
        let last = img.dilated(0.01)[(4 * r + 4) as usize];
        assert_eq!(last.x != s[(4 * r + 4) as usize].x, moves, "spacing {spacing}: {last}");
    }
}

/// Checks a mesh of an image whose neighbourhoods all keep their triangles: it covers the image's square
/// exactly (the triangles' areas sum to it and every interior edge joins exactly two triangles, so there is
/// no hole, overlap or T-junction crack), and every triangle has Algorithm 2's winding.
fn assert_watertight(r: u32, tris: &[[u32; 3]]) {
    let xy = |i: u32| ((i % r) as i64, (i / r) as i64);
    let mut area2 = 0i64;
    let mut edges: std::collections::HashMap<(u32, u32), u32> = Default::default();
    for t in tris {
        let [a, b, c] = t.map(xy);
        let cross = (b.0 - a.0) * (c.1 - a.1) - (b.1 - a.1) * (c.0 - a.0);
        assert!(cross < 0, "triangle {t:?} is degenerate or wound the other way");
        area2 -= cross;
        for (p, q) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edges.entry((p.min(q), p.max(q))).or_default() += 1;
        }
    }
    let side = (r - 1) as i64;
    assert_eq!(area2, 2 * side * side, "the triangles do not cover the image exactly once");
    for (&(p, q), &n) in &edges {
        let (a, b) = (xy(p), xy(q));
        let on_border = (a.0 == b.0 && (a.0 == 0 || a.0 == side)) || (a.1 == b.1 && (a.1 == 0 || a.1 == side));
        assert!(n == 2 || (n == 1 && on_border), "edge {a:?}-{b:?} is used {n} times (a crack or T-junction)");
    }
}

#[test]
fn a_planar_image_becomes_a_few_triangles_per_tile_and_stays_watertight() {
    let r = 8 * TILE + 1;
    for (a, b, c) in [(0.5, 0.0, 0.0), (0.5, 0.002, 0.003), (0.9, -0.004, 0.001)] {
        let s = image(r, |x, y| a + b * x as f32 + c * y as f32);
        let img = SampledImage { resolution: r, samples: &s };
        let full = img.triangles(1e-3);
        let adaptive = img.mesh(&adaptive_mesh(1e-3));
        assert_eq!(full.len(), 2 * 64 * 64);
        // 8x8 merged tiles of two triangles each (the ninth tile column and row hold no neighbourhood).
        assert_eq!(adaptive.len(), 2 * 64, "plane {a} {b} {c}");
        assert_watertight(r, &adaptive);
    }
}

#[test]
fn a_curved_image_keeps_full_resolution() {
    // Second differences 0.002 pass the edge test at epsilon 0.01, but across a tile the surface bends by
    // far more than 1 % of its depth: no tile merges.
    let r = 4 * TILE + 1;
    let s = image(r, |x, y| 0.5 + 0.001 * (x * x + y * y) as f32);
    let img = SampledImage { resolution: r, samples: &s };
    assert!(img.planar_masks(0.01, MeshSettings::default().merge_epsilon, TILE).iter().all(|&m| m == 0));
    let sorted = |mut t: Vec<[u32; 3]>| {
        t.sort();
        t
    };
    let tiles_only = MeshSettings { min_block: TILE, ..adaptive_mesh(0.01) };
    assert_eq!(sorted(img.mesh(&tiles_only)), sorted(img.triangles(0.01)));
    assert_eq!(img.triangles(0.01).len(), 2 * 32 * 32);
    // 2x2 blocks merge only far from the origin, where the bend is small against the depth; the first
    // ones, where it is not, keep their four triangles each.
    let masks = img.planar_masks(0.01, MeshSettings::default().merge_epsilon, 2);
    assert_eq!(masks[0] & 1 << 5, 0, "the first 2x2 block bends by 0.4 % of its depth");
    let blocks = img.mesh(&adaptive_mesh(0.01));
    assert_watertight(r, &blocks);
}

#[test]
fn merged_and_full_tiles_meet_without_cracks() {
    // A plane with a bump in one tile: that tile and its neighbours' shared sides keep every sample.
    let r = 4 * TILE + 1;
    let bump = |x: u32, y: u32| {
        let (dx, dy) = (x as f32 - 12.0, y as f32 - 12.0);
        0.012 * (-(dx * dx + dy * dy) / 16.0).exp()
    };
    let s = image(r, |x, y| 0.6 + 0.001 * x as f32 + bump(x, y));
    let img = SampledImage { resolution: r, samples: &s };
    // The crack test, at a merge tolerance as loose as epsilon so that the bump's neighbours merge.
    for min_block in [TILE, 4, 2] {
        let settings = MeshSettings { merge_epsilon: 0.01, min_block, ..adaptive_mesh(0.01) };
        let masks = img.planar_masks(0.01, settings.merge_epsilon, min_block);
        let tps = tiles_per_side(r) as usize;
        assert_eq!(masks[tps + 1] & TILE_BIT, 0, "the bump's tile must not merge");
        assert!(masks.iter().filter(|&&m| m & TILE_BIT != 0).count() >= 8, "the flat tiles merge: {masks:?}");
        let mesh = img.mesh(&settings);
        assert!(mesh.len() < img.triangles(0.01).len() / 2);
        assert_watertight(r, &mesh);
    }
}

#[test]
fn the_default_merge_tolerance_keeps_curved_tiles_that_epsilon_would_merge() {
    // A gentle bend: within epsilon (1 %) of each tile's plane, not within the merge tolerance.
    let r = 4 * TILE + 1;
    let s = image(r, |x, y| 0.5 + 0.00004 * (x * x + y * y) as f32);
    let img = SampledImage { resolution: r, samples: &s };
    let whole_tiles =
        |merge_epsilon| img.planar_masks(0.01, merge_epsilon, TILE).iter().filter(|&&m| m & TILE_BIT != 0).count();
    assert!(whole_tiles(0.01) >= 4);
    assert!(whole_tiles(MeshSettings::default().merge_epsilon) < 4);
}

#[test]
fn planar_blocks_beside_a_crease_merge_inside_their_tile_and_stay_watertight() {
    // Two planes meeting along sample column 13 (a roof seen from above): every neighbourhood keeps both
    // triangles, but the tiles and blocks across the crease are not planar. With whole tiles only, tile 1 of
    // each row keeps Algorithm 2's 128 triangles; with 4x4 and 2x2 blocks its quadrant left of the crease and
    // the 2x2 blocks right of it merge.
    let r = 4 * TILE + 1;
    // The crease bends by 0.8 % of the depth: within ε (1 %), not within the merge tolerance (0.2 %).
    let roof = |x: u32| if x <= 13 { 0.002 * x as f32 } else { 0.002 * (26.0 - x as f32) };
    let s = image(r, |x, y| 0.5 + roof(x) + 0.001 * y as f32);
    let img = SampledImage { resolution: r, samples: &s };
    assert_eq!(img.triangles(0.01).len(), 2 * 32 * 32, "the crease is connected");
    let mesh = |min_block| img.mesh(&MeshSettings { min_block, ..adaptive_mesh(0.01) });
    let (tiles, quadrants, blocks) = (mesh(TILE), mesh(4), mesh(2));
    for m in [&tiles, &quadrants, &blocks] {
        assert_watertight(r, m);
    }
    // Tile 1 of a row: 128 triangles whole-tile only; its left quadrants merge at 4, and at 2 also the 2x2
    // blocks of its right quadrants but the column of blocks across the crease (12..14).
    let masks = img.planar_masks(0.01, MeshSettings::default().merge_epsilon, 2);
    let m = masks[1];
    assert_eq!(m & TILE_BIT, 0);
    assert_eq!(m & 0b11110, 0b01010, "quadrants 0 and 2 (left of the crease) are planar: {m:#b}");
    for (bx, by) in [(2, 0), (3, 0), (2, 3), (3, 3)] {
        let planar = m & 1 << (5 + by * 4 + bx) != 0;
        assert_eq!(planar, bx == 3, "block ({bx}, {by}) of tile 1: {m:#b}");
    }
    // The merged leaves (the overlay's outlines): tile 1's left quadrants and its 2x2 blocks right of the crease
    // (x 14..16, four of them), the other tiles whole.
    let leaves = img.merged_leaves(&masks, None);
    assert!(leaves.contains(&(8, 0, 4)) && leaves.contains(&(8, 4, 4)), "{leaves:?}");
    assert_eq!(leaves.iter().filter(|&&(x, _, s)| s == 2 && x == 14).count(), 4 * 4, "{leaves:?}");
    assert!(!leaves.iter().any(|&(x, _, s)| s == 2 && x == 12), "the blocks across the crease stay: {leaves:?}");
    let whole_tiles = masks.iter().filter(|&&m| m & TILE_BIT != 0).count();
    assert_eq!(leaves.iter().filter(|&&(_, _, s)| s == TILE).count(), whole_tiles);
    let counts = (tiles.len(), quadrants.len(), blocks.len());
    assert!(counts.1 < counts.0 && counts.2 < counts.1, "{counts:?}");
    // 608 triangles whole tiles only, 320 with 2x2 blocks.
    assert!(counts.2 * 3 < counts.0 * 2, "{counts:?}");
}

#[test]
fn the_partial_tiles_at_the_image_edge_merge_their_whole_blocks() {
    // 64 samples a side: 63 neighbourhoods, so the last tile of a row or column holds 7 and never merges
    // whole; its first quadrant and its whole 2x2 blocks do.
    let r = 8 * TILE;
    let s = image(r, |x, y| 0.5 + 0.002 * x as f32 + 0.001 * y as f32);
    let img = SampledImage { resolution: r, samples: &s };
    let mesh = |min_block| img.mesh(&MeshSettings { min_block, ..adaptive_mesh(1e-3) });
    let (tiles, blocks) = (mesh(TILE), mesh(2));
    assert_watertight(r, &tiles);
    assert_watertight(r, &blocks);
    let masks = img.planar_masks(1e-3, MeshSettings::default().merge_epsilon, 2);
    let last = masks[7];
    assert_eq!(last & TILE_BIT, 0);
    assert_eq!(last & 0b11110, 0b01010, "only the left quadrants are whole: {last:#b}");
    assert!(blocks.len() * 2 < tiles.len(), "{} against {}", blocks.len(), tiles.len());
}

/// A camera at `eye` looking straight down (up = -z), 60°, with near and far as INSM sets them.
fn looking_down(eye: Vec3) -> MapView {
    let (near, far) = (0.01, 20.0);
    let clip_from_world = crate::math::perspective_rh(60f32.to_radians(), 1.0, near, far)
        * crate::math::look_to_rh(eye, -Vec3::Y, Vec3::NEG_Z);
    MapView { clip_from_world, near, far, steep: 0.0 }
}

/// The `r x r` samples of `view` seeing the plane y = `height` (world position, inverse view depth), as
/// the GPU writes them: a ray through each sample's centre.
fn samples_of_plane(view: &MapView, r: u32, height: f32) -> Vec<Vec4> {
    let world_from_clip = view.clip_from_world.inverse();
    (0..r * r)
        .map(|i| {
            let ndc =
                Vec2::new(((i % r) as f32 + 0.5) / r as f32 * 2.0 - 1.0, 1.0 - ((i / r) as f32 + 0.5) / r as f32 * 2.0);
            let a = world_from_clip.project_point3(ndc.extend(0.0));
            let b = world_from_clip.project_point3(ndc.extend(1.0));
            let p = a + (b - a) * ((height - a.y) / (b.y - a.y));
            let c = view.clip_from_world * p.extend(1.0);
            let z = c.z / c.w;
            p.extend((view.far - z * (view.far - view.near)) / (view.near * view.far))
        })
        .collect()
}

/// Sample `i` of a map of `r²` projected into `view`'s image: inside it with a margin of `margin` samples.
fn inside(view: &MapView, p: Vec3, r: u32, margin: f32) -> bool {
    let c = view.clip_from_world * p.extend(1.0);
    let ndc = c.truncate() / c.w;
    let (fx, fy) = ((ndc.x + 1.0) * 0.5 * r as f32 - 0.5, (1.0 - ndc.y) * 0.5 * r as f32 - 0.5);
    let hi = r as f32 - 1.0 - margin;
    fx >= margin && fy >= margin && fx <= hi && fy <= hi
}

#[test]
fn a_map_drops_what_a_finer_map_reconstructs_and_keeps_the_rest() {
    // A near map (2 m above the ground) and a far one (6 m, three times coarser, seeing three times as
    // much): the far map's triangles over the near map's footprint go, the rest stay, the near map keeps all.
    let r = 33;
    let settings = MeshSettings { drop_covered: true, ..MeshSettings::default() };
    for near_first in [true, false] {
        let (near, far) = (looking_down(Vec3::new(0.0, 2.0, 0.0)), looking_down(Vec3::new(0.3, 6.0, 0.0)));
        let (near_s, far_s) = (samples_of_plane(&near, r, 0.0), samples_of_plane(&far, r, 0.0));
        let (views, samples, n, f) =
            if near_first { ([near, far], [&near_s, &far_s], 0, 1) } else { ([far, near], [&far_s, &near_s], 1, 0) };
        let images: Vec<SampledImage> = samples.iter().map(|s| SampledImage { resolution: r, samples: s }).collect();
        let meshes = meshes(&images, &views, &settings);
        assert_eq!(meshes[n].len(), images[n].triangles(settings.epsilon).len(), "the finest map keeps everything");
        let kept: std::collections::HashSet<[u32; 3]> = meshes[f].iter().copied().collect();
        let (mut dropped, mut outside) = (0, 0);
        for t in images[f].triangles(settings.epsilon) {
            let corners = t.map(|i| images[f].samples[i as usize].truncate());
            if corners.iter().all(|&p| inside(&views[n], p, r, 1.0)) {
                assert!(!kept.contains(&t), "near first {near_first}: {t:?} is over the near map and kept");
                dropped += 1;
            } else if corners.iter().any(|&p| !inside(&views[n], p, r, -0.5)) {
                assert!(kept.contains(&t), "near first {near_first}: {t:?} is outside the near map and dropped");
                outside += 1;
            }
        }
        assert!(dropped > 100 && outside > 1000, "{dropped} dropped, {outside} outside the near map");
        // Without the option nothing is dropped.
        let all = self::meshes(&images, &views, &MeshSettings { drop_covered: false, ..settings });
        assert_eq!(all[f].len(), images[f].triangles(settings.epsilon).len());
    }
}

#[test]
fn the_covered_test_asks_of_the_point_a_sample_saw_not_of_its_moved_vertex() {
    let r = 33;
    let (near, far) = (looking_down(Vec3::new(0.0, 2.0, 0.0)), looking_down(Vec3::new(0.3, 6.0, 0.0)));
    let (near_s, far_s) = (samples_of_plane(&near, r, 0.0), samples_of_plane(&far, r, 0.0));
    // The point a sample saw, from its inverse depth and its map's camera, is where the sample is.
    let world_from_clip = far.clip_from_world.inverse();
    for (i, s) in far_s.iter().enumerate() {
        let seen = far.sample_position(&world_from_clip, i as u32 % r, i as u32 / r, r, s.w);
        assert!(seen.distance(s.truncate()) < 1e-3 * (1.0 + s.truncate().length()), "{seen} vs {s}");
    }
    let views = [near, far];
    let covered = |far_samples: &[Vec4]| {
        let images =
            [SampledImage { resolution: r, samples: &near_s }, SampledImage { resolution: r, samples: far_samples }];
        covered_samples(&images, &views, 1, 0.01)
    };
    let plain = covered(&far_s);
    assert!(plain.iter().filter(|&&c| c).count() > 100, "the near map covers part of the far one");
    // The far map's vertices moved 30 cm off the plane (as dilation moves the ones at a cut edge), their
    // inverse depths kept: the same samples are covered, since the test asks of the points they saw.
    let moved: Vec<Vec4> = far_s.iter().map(|s| (s.truncate() + Vec3::Y * 0.3).extend(s.w)).collect();
    assert_eq!(covered(&moved), plain);
}

#[test]
fn equal_maps_keep_one_copy_and_other_surfaces_are_not_covered() {
    let r = 17;
    let settings = MeshSettings { drop_covered: true, ..MeshSettings::default() };
    let view = looking_down(Vec3::new(0.0, 3.0, 0.0));
    let ground = samples_of_plane(&view, r, 0.0);
    // The same map twice: the lower-numbered one keeps every triangle, the other only those touching its
    // border (a border sample projects onto the first map's border, half a sample from its neighbourhoods'
    // edge, rounded either way).
    let images = [SampledImage { resolution: r, samples: &ground }, SampledImage { resolution: r, samples: &ground }];
    let m = meshes(&images, &[view, view], &settings);
    let full = images[0].triangles(settings.epsilon).len();
    assert_eq!(m[0].len(), full);
    let border = |i: u32| i.is_multiple_of(r) || i / r == 0 || i % r == r - 1 || i / r == r - 1;
    assert!(m[1].iter().all(|t| t.iter().any(|&i| border(i))), "an inner triangle of the copy is kept");
    assert!(m[1].len() <= 2 * 4 * (r as usize - 2), "{} of {full} triangles kept by the copy", m[1].len());
    // A map of a plane 0.5 m above the ground (a table top): the ground map does not reconstruct it, and
    // the table does not cover the ground map.
    let top = samples_of_plane(&view, r, 0.5);
    let images = [SampledImage { resolution: r, samples: &ground }, SampledImage { resolution: r, samples: &top }];
    let m = meshes(&images, &[view, view], &settings);
    assert_eq!(m[0].len(), full);
    assert_eq!(m[1].len(), full);
}

#[test]
fn every_sample_belongs_to_one_tile() {
    assert_eq!(tiles_per_side(16 * TILE), 16);
    assert_eq!(tiles_per_side(16 * TILE + 1), 17);
}
