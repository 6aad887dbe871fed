//! Copies of a scene's geometry for paraboloid shadow maps: its long edges cut, and optionally simplified.
//!
//! **Long edges** (always): a paraboloid map (Brabec et al. 2002; the per-VPL maps and the VAL maps) projects a
//! triangle's corners exactly but draws its edges straight and its depth linearly between them, while the true
//! image of an edge is curved. A triangle that spans a large angle from the map's centre (a wall of two
//! triangles, seen from a VPL on the floor beside it) is drawn in the wrong place or clipped away: the conference
//! room's per-VPL maps against ray-traced VPL visibility were at FLIP 0.106 / RMSE 0.031 (160x90, 1,024 VPLs)
//! with its own triangles and 0.072 / 0.019 with every edge cut to a twentieth of the scene's diagonal. Every
//! edge longer than `max_edge` is cut at its midpoint until none is; the cut depends on the edge alone, so both
//! triangles of an edge cut it at the same point (no crack), and the midpoint's attributes are the mean of the
//! ends' (a cut-out's UVs stay right).
//!
//! **Simplified** (`keep` below 1): Dong et al. 2009 close with "we will investigate if geometric
//! simplifications can be included on top of the visibility approximations"; lavapipe draws a shadow map at the
//! cost of its triangles, so fewer triangles are what a cheaper VAL map needs. Then, before the cut:
//!
//! 1. the vertices are welded by position (a UV or normal seam is not an edge of the surface for a depth map);
//!    triangles with a non-finite or repeated corner are dropped;
//! 2. the opaque materials' triangles are simplified together with meshoptimizer's quadric edge collapse
//!    ([`meshopt::simplify`]) toward `keep` of their count, the surface never moved by more than `max_error`
//!    (world units; the collapse stops there) and open borders locked (with each material simplified apart an
//!    unlocked border collapsed into wedges across the room; apart, every border between two materials was
//!    kept too, and each material's chunks spread over the whole scene: together, Sponza's copy at 2 cm keeps
//!    19,013 triangles instead of 22,586 and its cluster maps draw half as many);
//! 3. cut-out (alpha-tested) materials are kept as they are, so leaves still cast leaf-shaped shadows.
//!
//! Both cut into chunks like the scene's ([`super::chunks::push_chunks`]) for the same culling.

use glam::{Vec2, Vec3};

use super::chunks::{push_chunks, ChunkedGeometry, Vertex, CHUNK_TRIANGLES};

/// The fewest triangles a simplified copy's chunk holds (smaller chunks would make draw calls the cost).
const MIN_CHUNK_TRIANGLES: usize = 32;

/// The default longest edge of the paraboloid maps' triangles, as a share of the scene's diagonal (measured in
/// docs/techniques/vpl-gather.md: the Cornell box's per-VPL maps against ray-traced visibility FLIP 0.139 with its
/// own triangles, 0.039 at 0.05, 0.019 at 0.02).
pub const DEFAULT_MAX_EDGE: f32 = 0.05;

/// How much of the geometry a proxy keeps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProxyParams {
    /// The share of each material's triangles to aim for, in (0, 1] (1: not simplified, only cut).
    pub keep: f32,
    /// The largest distance the simplified surface may move, world units.
    pub max_error: f32,
    /// The longest edge a triangle may have, world units (longer ones are cut; 0: none is).
    pub max_edge: f32,
}

impl ProxyParams {
    /// Whether it simplifies (`keep` below 1; not a number: no).
    fn simplifies(&self) -> bool {
        self.keep < 1.0
    }

    /// The copy would be the scene's own triangles: nothing simplified, no edge cut (a `max_edge` that is not a
    /// positive number cuts nothing).
    pub fn is_identity(&self) -> bool {
        let cuts = self.max_edge > 0.0 && self.max_edge.is_finite();
        !self.simplifies() && !cuts
    }

    /// The same copy, named one way: not simplified, the error bound means nothing and is dropped, so every
    /// technique that only cuts edges asks for (and shares) one copy.
    pub fn normalized(self) -> ProxyParams {
        if self.simplifies() {
            self
        } else {
            ProxyParams { keep: 1.0, max_error: 0.0, ..self }
        }
    }
}

/// The copy of `geometry` that `params` asks for (see the module). `masked[m]`: material `m` is cut out.
pub fn build(geometry: &ChunkedGeometry, masked: &[bool], params: ProxyParams) -> ChunkedGeometry {
    let keep = if params.keep.is_finite() { params.keep.clamp(1e-4, 1.0) } else { 1.0 };
    let max_error = if params.max_error.is_finite() { params.max_error.max(0.0) } else { 0.0 };
    let simplify = keep < 1.0;
    let mut out = ChunkedGeometry::default();
    // The source's vertices as they are (cut only) or, to simplify, welded by exact position; remap[i] is vertex
    // i's index in `out.vertices`.
    let mut remap = Vec::with_capacity(geometry.vertices.len());
    if simplify {
        let mut welded = std::collections::HashMap::<[u32; 3], u32>::new();
        for v in &geometry.vertices {
            let next = out.vertices.len() as u32;
            let id = *welded.entry(v.position.map(f32::to_bits)).or_insert_with(|| {
                out.vertices.push(Vertex { position: v.position, normal: [0.0, 1.0, 0.0], uv: [0.0, 0.0] });
                next
            });
            remap.push(id);
        }
    } else {
        out.vertices.extend_from_slice(&geometry.vertices);
        remap.extend(0..geometry.vertices.len() as u32);
    }
    let finite = |i: u32| Vec3::from(geometry.vertices[i as usize].position).is_finite();

    let mut midpoints = std::collections::HashMap::new();
    let (mut opaque, mut opaque_source, mut opaque_material) = (Vec::<[u32; 3]>::new(), 0usize, None::<u32>);
    // Chunks of one material are adjacent (ChunkedGeometry::build sorts meshes by material).
    let mut start = 0;
    while start < geometry.chunks.len() {
        let material = geometry.chunks[start].material;
        let end = start + geometry.chunks[start..].iter().take_while(|c| c.material == material).count();
        let source_count: usize = geometry.chunks[start..end].iter().map(|c| c.triangle_count() as usize).sum();
        let source = geometry.chunks[start..end].iter().flat_map(|c| {
            let first = c.first_index as usize;
            geometry.indices[first..first + c.index_count as usize].chunks_exact(3)
        });
        let mut tris: Vec<[u32; 3]> = Vec::new();
        if simplify && masked.get(material as usize).copied().unwrap_or(false) {
            // 3. Cut-outs as they are, with their own vertices (their UVs drive the alpha test).
            for t in source.filter(|t| t.iter().all(|&i| finite(i))) {
                let first = out.vertices.len() as u32;
                out.vertices.extend(t.iter().map(|&i| geometry.vertices[i as usize]));
                tris.push([first, first + 1, first + 2]);
            }
        } else {
            for t in source.filter(|t| t.iter().all(|&i| finite(i))) {
                let w = [remap[t[0] as usize], remap[t[1] as usize], remap[t[2] as usize]];
                if w[0] != w[1] && w[1] != w[2] && w[0] != w[2] {
                    tris.push(w);
                }
            }
            if simplify {
                // 2. Gathered across materials and simplified together below.
                opaque_material.get_or_insert(material);
                opaque_source += source_count;
                opaque.append(&mut tris);
                start = end;
                continue;
            }
        }
        let tris = split_long_edges(&mut out.vertices, tris, params.max_edge, &mut midpoints);
        push_chunks(
            &mut out.indices,
            &mut out.chunks,
            |i| out_position(&out.vertices, i),
            tris,
            material,
            CHUNK_TRIANGLES,
        );
        start = end;
    }
    // 2. The opaque materials together (a depth map does not see materials, and simplified apart they would keep
    // every border between two of them), by quadric edge collapse toward `keep` of the triangles within
    // `max_error`. Their chunks carry the first opaque material's index (only cut-outs need theirs).
    if let Some(material) = opaque_material.filter(|_| !opaque.is_empty()) {
        let indices: Vec<u32> = opaque.iter().flatten().copied().collect();
        let target = ((opaque.len() as f32 * keep).ceil() as usize).max(1) * 3;
        let bytes: &[u8] = bytemuck::cast_slice(&out.vertices);
        let mut tris = opaque;
        if let Ok(adapter) = meshopt::VertexDataAdapter::new(bytes, std::mem::size_of::<Vertex>(), 0) {
            let options = meshopt::SimplifyOptions::ErrorAbsolute | meshopt::SimplifyOptions::LockBorder;
            let simplified = meshopt::simplify(&indices, &adapter, target, max_error, options, None);
            tris = simplified.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        }
        let tris = split_long_edges(&mut out.vertices, tris, params.max_edge, &mut midpoints);
        // Chunks that cover about as much surface as the scene's: the simplified triangles are larger, and 256 of
        // them would span so much that the per-face culling kept most of them (Sponza's cluster maps drew 2.3
        // times the copy's triangles per map, the scene's own 1.2 times).
        let per_chunk =
            (CHUNK_TRIANGLES * tris.len()).div_ceil(opaque_source.max(1)).clamp(MIN_CHUNK_TRIANGLES, CHUNK_TRIANGLES);
        push_chunks(&mut out.indices, &mut out.chunks, |i| out_position(&out.vertices, i), tris, material, per_chunk);
    }
    out.uv1 = vec![Vec2::ZERO.to_array(); out.vertices.len()];
    out
}

/// The most triangles [`split_long_edges`] makes per triangle it is given (plus 4,096 per material).
pub const SPLIT_BUDGET: usize = 16;

/// `tris` with every edge longer than `max_edge` cut at its midpoint, again until none is (new vertices appended
/// to `vertices`). Whether an edge is cut depends on the edge alone and its midpoint is shared through
/// `midpoints` (across materials too), so both triangles of an edge cut it at the same vertex: no T-junction, no
/// crack for light to leak through. A triangle with one, two or three long edges becomes two, three or four.
fn split_long_edges(
    vertices: &mut Vec<Vertex>,
    tris: Vec<[u32; 3]>,
    max_edge: f32,
    midpoints: &mut std::collections::HashMap<(u32, u32), u32>,
) -> Vec<[u32; 3]> {
    if !(max_edge.is_finite() && max_edge > 0.0) {
        return tris;
    }
    let limit = max_edge * max_edge;
    // At most sixteen times the triangles (and a few thousand): a bound against an absurdly short `max_edge`,
    // past which the rest are kept as they are.
    let budget = SPLIT_BUDGET * tris.len() + 4096;
    let mut out = Vec::with_capacity(tris.len());
    let mut stack = tris;
    while let Some(t) = stack.pop() {
        let p = t.map(|i| out_position(vertices, i));
        let long = [0, 1, 2].map(|k| (p[(k + 1) % 3] - p[k]).length_squared() > limit);
        let count = long.iter().filter(|&&l| l).count();
        if count == 0 || out.len() + stack.len() > budget {
            out.push(t);
            continue;
        }
        let mut mid = |a: u32, b: u32| {
            *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
                let (va, vb) = (vertices[a as usize], vertices[b as usize]);
                let half = |x: [f32; 3], y: [f32; 3]| ((Vec3::from(x) + Vec3::from(y)) * 0.5).to_array();
                let normal = Vec3::from(half(va.normal, vb.normal)).normalize_or(Vec3::Y).to_array();
                let uv = ((Vec2::from(va.uv) + Vec2::from(vb.uv)) * 0.5).to_array();
                vertices.push(Vertex { position: half(va.position, vb.position), normal, uv });
                (vertices.len() - 1) as u32
            })
        };
        match count {
            1 => {
                // The long edge from a to b, c opposite.
                let k = long.iter().position(|&l| l).unwrap_or(0);
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let m = mid(a, b);
                stack.extend([[a, m, c], [m, b, c]]);
            }
            2 => {
                // Edges a-b and b-c long, c-a short.
                let k = long.iter().position(|&l| !l).map_or(0, |short| (short + 1) % 3);
                let (a, b, c) = (t[k], t[(k + 1) % 3], t[(k + 2) % 3]);
                let (mab, mbc) = (mid(a, b), mid(b, c));
                stack.extend([[mab, b, mbc], [a, mab, mbc], [a, mbc, c]]);
            }
            _ => {
                let (a, b, c) = (t[0], t[1], t[2]);
                let (mab, mbc, mca) = (mid(a, b), mid(b, c), mid(c, a));
                stack.extend([[a, mab, mca], [mab, b, mbc], [mca, mbc, c], [mab, mbc, mca]]);
            }
        }
    }
    out
}

fn out_position(vertices: &[Vertex], i: u32) -> Vec3 {
    Vec3::from(vertices[i as usize].position)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::chunks::Chunk;
    use std::collections::HashMap;

    /// An `n` x `n` grid of unit quads on y = 0 (material 0) and a tall thin box beside it (material 1), as one
    /// chunked geometry with the vertices of each quad separate (seams everywhere, as loaded meshes have).
    fn grid_and_box(n: usize) -> ChunkedGeometry {
        let mut g = ChunkedGeometry::default();
        let quad = |g: &mut ChunkedGeometry, c: [Vec3; 4], material: u32| {
            let first = g.vertices.len() as u32;
            g.vertices.extend(c.iter().map(|p| Vertex {
                position: p.to_array(),
                normal: [0.0, 1.0, 0.0],
                uv: [0.5; 2],
            }));
            let tris = vec![[first, first + 1, first + 2], [first, first + 2, first + 3]];
            let vertices = g.vertices.clone();
            push_chunks(&mut g.indices, &mut g.chunks, |i| out_position(&vertices, i), tris, material, CHUNK_TRIANGLES);
        };
        for i in 0..n {
            for j in 0..n {
                let (x, z) = (i as f32, j as f32);
                let c = [
                    Vec3::new(x, 0.0, z),
                    Vec3::new(x, 0.0, z + 1.0),
                    Vec3::new(x + 1.0, 0.0, z + 1.0),
                    Vec3::new(x + 1.0, 0.0, z),
                ];
                quad(&mut g, c, 0);
            }
        }
        let h = n as f32;
        quad(
            &mut g,
            [Vec3::new(-1.0, 0.0, 0.0), Vec3::new(-1.0, h, 0.0), Vec3::new(-1.0, h, h), Vec3::new(-1.0, 0.0, h)],
            1,
        );
        g.uv1 = vec![[0.0; 2]; g.vertices.len()];
        g
    }

    fn triangles(g: &ChunkedGeometry) -> Vec<[Vec3; 3]> {
        g.indices.chunks_exact(3).map(|t| [0, 1, 2].map(|k| Vec3::from(g.vertices[t[k] as usize].position))).collect()
    }

    fn area(g: &ChunkedGeometry) -> f32 {
        triangles(g).iter().map(|t| (t[1] - t[0]).cross(t[2] - t[0]).length() * 0.5).sum()
    }

    fn chunks_cover_the_indices(g: &ChunkedGeometry) {
        let covered: u32 = g.chunks.iter().map(|c: &Chunk| c.index_count).sum();
        assert_eq!(covered as usize, g.indices.len());
        for c in &g.chunks {
            for &i in &g.indices[c.first_index as usize..(c.first_index + c.index_count) as usize] {
                let p = Vec3::from(g.vertices[i as usize].position);
                assert!(c.bounds.min.cmple(p).all() && p.cmple(c.bounds.max).all(), "{p} outside its chunk");
            }
        }
    }

    #[test]
    fn cut_edges_are_short_the_surface_is_the_same_and_no_crack_opens() {
        let g = grid_and_box(4);
        let cut = build(&g, &[false, false], ProxyParams { keep: 1.0, max_error: 0.0, max_edge: 0.3 });
        chunks_cover_the_indices(&cut);
        assert!(cut.triangle_count() > 8 * g.triangle_count(), "{} triangles", cut.triangle_count());
        for t in triangles(&cut) {
            for k in 0..3 {
                assert!((t[(k + 1) % 3] - t[k]).length() <= 0.3 + 1e-5, "an edge of {t:?} is longer than 0.3");
            }
        }
        assert!((area(&cut) - area(&g)).abs() < 1e-3 * area(&g), "area {} -> {}", area(&g), area(&cut));
        // Conforming: in the grid (welded by position) every interior edge is used by exactly two triangles, so no
        // vertex sits inside another triangle's edge.
        let key = |p: Vec3| p.to_array().map(|c| (c * 1e4).round() as i64);
        let mut uses: HashMap<([i64; 3], [i64; 3]), u32> = HashMap::new();
        for t in triangles(&cut).iter().filter(|t| t.iter().all(|p| p.y == 0.0)) {
            for k in 0..3 {
                let (a, b) = (key(t[k]), key(t[(k + 1) % 3]));
                *uses.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        let on_border = |e: &([i64; 3], [i64; 3])| {
            let (a, b) = (e.0, e.1);
            (a[0] == b[0] && (a[0] == 0 || a[0] == 40_000)) || (a[2] == b[2] && (a[2] == 0 || a[2] == 40_000))
        };
        for (e, n) in &uses {
            assert_eq!(*n, if on_border(e) { 1 } else { 2 }, "edge {e:?} used {n} times: a T-junction");
        }
        // Attributes at the new vertices are the ends' means.
        assert!(cut.vertices.iter().all(|v| v.uv == [0.5, 0.5]));
        // Nothing asked: the same triangles.
        let same = build(&g, &[false, false], ProxyParams { keep: 1.0, max_error: 0.0, max_edge: 0.0 });
        assert_eq!(same.triangle_count(), g.triangle_count());
    }

    #[test]
    fn simplifying_a_flat_grid_keeps_its_plane_and_a_cut_out_whole() {
        let g = grid_and_box(8);
        let p = ProxyParams { keep: 0.1, max_error: 0.01, max_edge: 0.0 };
        let s = build(&g, &[false, true], p);
        chunks_cover_the_indices(&s);
        let ground =
            |g: &ChunkedGeometry| g.chunks.iter().filter(|c| c.material == 0).map(|c| c.index_count / 3).sum::<u32>();
        let wall =
            |g: &ChunkedGeometry| g.chunks.iter().filter(|c| c.material == 1).map(|c| c.index_count / 3).sum::<u32>();
        // Its 32 border vertices are locked (an open border collapsed makes wedges across a room).
        assert!(ground(&s) <= 40, "the flat grid of 128 triangles kept {}", ground(&s));
        assert_eq!(wall(&s), wall(&g), "the cut-out material is kept whole");
        assert!((area(&s) - area(&g)).abs() < 1e-3 * area(&g), "area {} -> {}", area(&g), area(&s));
        assert!(triangles(&s).iter().flatten().all(|p| p.y == 0.0 || p.x == -1.0), "a vertex left the surface");
        // The cut-out's UVs survive; the welded ground's are not kept.
        let first = s.chunks.iter().find(|c| c.material == 1).unwrap().first_index as usize;
        assert_eq!(s.vertices[s.indices[first] as usize].uv, [0.5, 0.5]);
    }

    #[test]
    fn a_simplified_copy_cuts_smaller_chunks_so_they_cull_as_well_as_the_scenes() {
        let g = grid_and_box(32);
        let s = build(&g, &[false, false], ProxyParams { keep: 0.05, max_error: 0.01, max_edge: 0.0 });
        chunks_cover_the_indices(&s);
        let ground: Vec<&Chunk> = s.chunks.iter().filter(|c| c.material == 0).collect();
        let kept: u32 = ground.iter().map(|c| c.triangle_count()).sum();
        // 2,048 triangles kept as `kept`: a chunk holds 256 * kept / 2,048 of them (at least 32), not 256.
        let per_chunk = (256 * kept).div_ceil(2048).clamp(MIN_CHUNK_TRIANGLES as u32, 256);
        assert!(kept < 2048 / 4, "the flat grid kept {kept} triangles");
        assert!(ground.iter().all(|c| c.triangle_count() <= per_chunk), "a chunk holds more than {per_chunk}");
        assert!(ground.len() as u32 >= kept.div_ceil(per_chunk), "{} chunks for {kept} triangles", ground.len());
        assert!(ground.len() > 1);
        // Copies that are only cut keep the scene's chunk size.
        let cut = build(&g, &[false, false], ProxyParams { keep: 1.0, max_error: 0.0, max_edge: 0.5 });
        assert!(cut.chunks.iter().any(|c| c.triangle_count() as usize == CHUNK_TRIANGLES));
    }

    #[test]
    fn opaque_materials_are_simplified_together_across_their_borders() {
        // The 16 x 16 ground in two opaque materials (x < 8: 0, else 2) beside the cut-out wall (1).
        let n = 16;
        let mut g = grid_and_box(n);
        for (k, c) in g.chunks.iter_mut().enumerate().take(n * n) {
            c.material = if k < n * n / 2 { 0 } else { 2 };
        }
        let p = ProxyParams { keep: 0.01, max_error: 0.01, max_edge: 0.0 };
        let s = build(&g, &[false, true, false], p);
        chunks_cover_the_indices(&s);
        let ground = s.chunks.iter().filter(|c| c.material != 1).map(|c| c.triangle_count()).sum::<u32>();
        let one = build(&grid_and_box(n), &[false, true], p);
        let alone = one.chunks.iter().filter(|c| c.material == 0).map(|c| c.triangle_count()).sum::<u32>();
        // As few as with one material: the seam between the two is not a border that stays.
        assert!(ground <= alone + 2, "two materials kept {ground} triangles, one {alone}");
        assert!(s.chunks.iter().all(|c| c.material != 2), "the opaque triangles carry the first opaque material");
        assert!((area(&s) - area(&g)).abs() < 1e-3 * area(&g));
    }

    #[test]
    fn a_copy_of_nothing_is_asked_for_as_nothing_and_cut_only_copies_are_one() {
        let p = |keep, max_error, max_edge| ProxyParams { keep, max_error, max_edge };
        assert!(p(1.0, 0.3, 0.0).is_identity() && p(f32::NAN, 0.0, f32::NAN).is_identity());
        assert!(!p(1.0, 0.0, 0.1).is_identity() && !p(0.5, 0.0, 0.0).is_identity());
        // Cut only: the error bound is dropped, so two techniques asking with different bounds share one copy.
        assert_eq!(p(1.0, 0.3, 0.1).normalized(), p(1.0, 0.0, 0.1).normalized());
        assert_eq!(p(0.5, 0.3, 0.1).normalized(), p(0.5, 0.3, 0.1));
    }

    #[test]
    fn broken_input_gives_a_defined_proxy() {
        let mut g = grid_and_box(2);
        g.vertices[0].position = [f32::NAN, 0.0, 0.0];
        for p in [
            ProxyParams { keep: 0.5, max_error: 0.01, max_edge: 0.5 },
            ProxyParams { keep: f32::NAN, max_error: f32::INFINITY, max_edge: f32::NAN },
            ProxyParams { keep: -1.0, max_error: -1.0, max_edge: -1.0 },
            ProxyParams { keep: 1.0, max_error: 0.0, max_edge: 1e-9 },
        ] {
            let s = build(&g, &[], p);
            chunks_cover_the_indices(&s);
            assert!(triangles(&s).iter().flatten().all(|p| p.is_finite()), "{p:?}");
            assert!(s.triangle_count() <= SPLIT_BUDGET * g.triangle_count() + 2 * 4100, "{p:?}");
        }
        let empty = build(&ChunkedGeometry::default(), &[], ProxyParams { keep: 0.5, max_error: 0.1, max_edge: 0.1 });
        assert_eq!(empty.triangle_count(), 0);
    }
}
