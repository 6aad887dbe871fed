//! Splitting meshes into small spatially coherent chunks for culling.
//!
//! lavapipe is vertex-bound (a full Sponza cube map costs ~21 ms whatever its resolution), so a shadow map must
//! draw as few triangles as possible. Whole meshes are far too coarse for that (Sponza's 38 meshes: 74% still
//! pass per cube face). At load, every mesh is cut into chunks of at most [`CHUNK_TRIANGLES`] triangles, ordered
//! along a Morton curve of their centroids so each chunk is compact, and each chunk keeps its bounds. A light's
//! cube map then draws only chunks inside its range sphere, and each face only those inside the face frustum.

use glam::{Vec2, Vec3};

use super::{Aabb, Scene};

/// Triangles per chunk: small enough to cull well, large enough that draw calls stay cheap.
pub const CHUNK_TRIANGLES: usize = 256;

/// The vertex layout of every mesh on the GPU. Keep in sync with `gbuffer.wgsl` and `shadow_depth.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
pub struct Vertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub uv: [f32; 2],
}
const _: () = assert!(std::mem::size_of::<Vertex>() == 32);

/// A run of triangles in [`ChunkedGeometry::indices`] with one material and its bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Chunk {
    pub first_index: u32,
    pub index_count: u32,
    pub material: u32,
    pub bounds: Aabb,
}

impl Chunk {
    pub fn triangle_count(&self) -> u32 {
        self.index_count / 3
    }
}

/// All meshes of a scene merged into one vertex and one index buffer, cut into chunks.
/// Chunks of the same material are adjacent, so consecutive visible chunks merge into one draw.
#[derive(Clone, Debug, Default)]
pub struct ChunkedGeometry {
    pub vertices: Vec<Vertex>,
    /// Per vertex, the second UV channel ([`crate::scene::Mesh::uvs1`], zeros when a mesh has none): a
    /// vertex stream of its own, read by the G-buffer pass only.
    pub uv1: Vec<[f32; 2]>,
    pub indices: Vec<u32>,
    pub chunks: Vec<Chunk>,
}

impl ChunkedGeometry {
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    pub fn build(scene: &Scene) -> ChunkedGeometry {
        let mut out = ChunkedGeometry::default();
        // Meshes sorted by material keep same-material chunks adjacent (fewer bind-group switches).
        let mut order: Vec<usize> = (0..scene.meshes.len()).collect();
        order.sort_by_key(|&i| scene.meshes[i].material);
        for mi in order {
            let mesh = &scene.meshes[mi];
            let base = out.vertices.len() as u32;
            out.vertices.extend(mesh.positions.iter().enumerate().map(|(i, p)| Vertex {
                position: p.to_array(),
                normal: mesh.normals.get(i).copied().unwrap_or(Vec3::Y).to_array(),
                uv: mesh.uvs.get(i).copied().unwrap_or(Vec2::ZERO).to_array(),
            }));
            out.uv1
                .extend((0..mesh.positions.len()).map(|i| mesh.uvs1.get(i).copied().unwrap_or(Vec2::ZERO).to_array()));
            let tris: Vec<[u32; 3]> =
                mesh.indices.chunks_exact(3).map(|t| [base + t[0], base + t[1], base + t[2]]).collect();
            let positions = &mesh.positions;
            let position = |i: u32| positions[(i - base) as usize];
            push_chunks(&mut out.indices, &mut out.chunks, position, tris, mesh.material as u32, CHUNK_TRIANGLES);
        }
        out
    }
}

/// Cuts `tris` (indices into the vertices `position` reads) into chunks of at most `per_chunk` triangles (at
/// least one) of `material`, ordered along a Morton curve of their centroids, and appends them to `indices` and
/// `chunks`. The scene's own chunks hold [`CHUNK_TRIANGLES`]; a simplified copy's hold fewer, so that a chunk
/// covers about as much surface as the scene's and culls as well.
pub(crate) fn push_chunks(
    indices: &mut Vec<u32>,
    chunks: &mut Vec<Chunk>,
    position: impl Fn(u32) -> Vec3,
    tris: Vec<[u32; 3]>,
    material: u32,
    per_chunk: usize,
) {
    if tris.is_empty() {
        return;
    }
    let centroid = |t: &[u32; 3]| (position(t[0]) + position(t[1]) + position(t[2])) / 3.0;
    let bounds = Aabb::from_points(tris.iter().map(centroid));
    let extent = bounds.size().max(Vec3::splat(1e-12));
    let mut keyed: Vec<(u64, [u32; 3])> = tris
        .into_iter()
        .map(|t| {
            let q = ((centroid(&t) - bounds.min) / extent * 1023.0).clamp(Vec3::ZERO, Vec3::splat(1023.0));
            (morton3(q.x as u32, q.y as u32, q.z as u32), t)
        })
        .collect();
    keyed.sort_by_key(|k| k.0);
    for group in keyed.chunks(per_chunk.max(1)) {
        let first_index = indices.len() as u32;
        let mut bounds = Aabb::EMPTY;
        for (_, t) in group {
            for &i in t {
                indices.push(i);
                bounds.extend(position(i));
            }
        }
        chunks.push(Chunk { first_index, index_count: (group.len() * 3) as u32, material, bounds });
    }
}

/// Spread the low 10 bits of `v` to every third bit (standard 30-bit Morton code).
fn spread_bits(v: u32) -> u64 {
    let mut x = v & 0x3ff;
    x = (x | (x << 16)) & 0x0300_00ff;
    x = (x | (x << 8)) & 0x0300_f00f;
    x = (x | (x << 4)) & 0x030c_30c3;
    x = (x | (x << 2)) & 0x0924_9249;
    x as u64
}

fn morton3(x: u32, y: u32, z: u32) -> u64 {
    spread_bits(x) | (spread_bits(y) << 1) | (spread_bits(z) << 2)
}

/// Draw ranges (first index, index count) for a sorted list of chunk ids, merging adjacent chunks into one draw.
pub fn merge_draw_ranges(chunks: &[Chunk], visible: impl IntoIterator<Item = u32>, out: &mut Vec<(u32, u32)>) {
    out.clear();
    for id in visible {
        let c = &chunks[id as usize];
        match out.last_mut() {
            Some((first, count)) if *first + *count == c.first_index => *count += c.index_count,
            _ => out.push((c.first_index, c.index_count)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Material, Mesh, SceneSource};

    fn grid_scene(n: usize) -> Scene {
        let mut positions = Vec::new();
        let mut indices = Vec::new();
        for y in 0..=n {
            for x in 0..=n {
                positions.push(Vec3::new(x as f32, 0.0, y as f32));
            }
        }
        for y in 0..n {
            for x in 0..n {
                let i = (y * (n + 1) + x) as u32;
                let w = (n + 1) as u32;
                indices.extend_from_slice(&[i, i + w, i + 1, i + 1, i + w, i + w + 1]);
            }
        }
        let mut scene = Scene {
            name: "grid".into(),
            source: SceneSource::Builtin("grid".into()),
            meshes: vec![Mesh { name: "g".into(), positions, indices, ..Default::default() }],
            materials: vec![Material::default()],
            textures: vec![],
            lights: vec![],
            directional: vec![],
            camera: crate::scene::Camera::look_at(Vec3::ONE, Vec3::ZERO, 1.0, 0.1, 100.0),
            bounds: Aabb::EMPTY,
            warnings: vec![],
        };
        scene.finalize(std::path::Path::new("grid")).unwrap();
        scene
    }

    #[test]
    fn morton_interleaves() {
        assert_eq!(morton3(1, 0, 0), 1);
        assert_eq!(morton3(0, 1, 0), 2);
        assert_eq!(morton3(0, 0, 1), 4);
        assert_eq!(morton3(3, 0, 0), 0b1001);
        assert_eq!(morton3(1023, 1023, 1023), (1u64 << 30) - 1);
    }

    #[test]
    fn chunks_cover_every_triangle_once_and_are_compact() {
        let scene = grid_scene(64); // 8192 triangles
        let geo = ChunkedGeometry::build(&scene);
        assert_eq!(geo.triangle_count(), 8192);
        assert_eq!(geo.chunks.len(), 8192 / CHUNK_TRIANGLES);
        let total: u32 = geo.chunks.iter().map(|c| c.triangle_count()).sum();
        assert_eq!(total, 8192);
        // Every triangle appears exactly once.
        let mut seen: Vec<[u32; 3]> = geo.indices.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
        seen.sort();
        seen.dedup();
        assert_eq!(seen.len(), 8192);
        // Morton order makes chunks compact: each covers a small part of the 64x64 grid.
        for c in &geo.chunks {
            let s = c.bounds.size();
            assert!(s.x * s.z <= 16.0 * 16.0 * 1.01, "chunk too spread: {s}");
        }
    }

    #[test]
    fn adjacent_chunks_merge_into_one_draw() {
        let scene = grid_scene(32);
        let geo = ChunkedGeometry::build(&scene);
        let mut ranges = Vec::new();
        merge_draw_ranges(&geo.chunks, [0, 1, 2, 5], &mut ranges);
        assert_eq!(ranges.len(), 2);
        assert_eq!(ranges[0], (0, geo.chunks[0].index_count * 3));
    }
}
