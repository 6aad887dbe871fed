//! INSM's reconstructed meshes on the GPU: the buffers Algorithm 2 writes (samples as vertices, triangles by
//! tile, the tiles' counts), the triangulation's bind group, the geometry the per-light maps (and the
//! viewpoints' views) draw from them, and reading them back for tests and tools.

use super::*;

/// Vertex of a reconstructed mesh: world position and inverse depth (0 = background sample).
pub(super) const MESH_VERTEX_BYTES: u64 = 16;

/// The reconstructed meshes of `k` maps of `resolution²`, and their readback buffers.
pub(super) struct MeshBuffers {
    pub k: u32,
    pub resolution: u32,
    pub vertices: wgpu::Buffer,
    pub indices: wgpu::Buffer,
    pub tiles: wgpu::Buffer,
    pub tiles_readback: wgpu::Buffer,
    pub vertices_readback: Option<wgpu::Buffer>,
    pub bind_group: wgpu::BindGroup,
}

impl MeshBuffers {
    /// The reconstructed meshes as the per-light maps draw them: in tiles (`chunks`, non-empty ones of this
    /// frame), through `simplified`'s indices when the meshes were simplified, each vertex pushed away from the
    /// map's centre by `push_per_depth` of its view depth (0: where it is). Receivers are set by `encode_batch`.
    pub fn geometry<'a>(
        &'a self,
        simplified: Option<&'a wgpu::Buffer>,
        chunks: &'a [Chunk],
        triangle_count: u64,
        push_per_depth: f32,
    ) -> CubeGeometry<'a> {
        CubeGeometry {
            vertex_buffer: &self.vertices,
            index_buffer: simplified.unwrap_or(&self.indices),
            chunks,
            triangle_count,
            cull: true,
            cutouts: None,
            receivers: None,
            push_per_depth,
        }
    }
}

impl Insm {
    /// The mesh buffers for `k` maps of `resolution²` (kept while they fit).
    pub(super) fn ensure_mesh(&mut self, gpu: &GpuContext, k: u32, resolution: u32) {
        if self.mesh.as_ref().is_some_and(|m| m.k == k && m.resolution == resolution) {
            return;
        }
        let device = &gpu.device;
        let samples = k as u64 * resolution as u64 * resolution as u64;
        let tps = triangulate::tiles_per_side(resolution) as u64;
        let tiles = k as u64 * tps * tps;
        let vertex_bytes = samples * MESH_VERTEX_BYTES;
        let buffer = |label, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(16),
                usage,
                mapped_at_creation: false,
            })
        };
        let vertices = buffer(
            "insm vertices",
            vertex_bytes,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_SRC,
        );
        let indices = buffer(
            "insm indices",
            tiles * MAX_TRIANGLES_PER_TILE as u64 * 12,
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_SRC,
        );
        let tile_bytes = tiles * std::mem::size_of::<GpuTile>() as u64;
        let tiles_buffer = buffer("insm tiles", tile_bytes, wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC);
        let readback = wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ;
        let tiles_readback = buffer("insm tiles readback", tile_bytes, readback);
        let vertices_readback =
            (vertex_bytes <= OVERLAY_READBACK_LIMIT).then(|| buffer("insm vertices readback", vertex_bytes, readback));
        // `prepare` ensured the depth atlas first, and rebuilds this bind group when the atlas changes.
        self.mesh = Some(MeshBuffers {
            k,
            resolution,
            bind_group: self.bind_group_for(gpu, &vertices, &indices, &tiles_buffer),
            vertices,
            indices,
            tiles: tiles_buffer,
            tiles_readback,
            vertices_readback,
        });
    }

    pub(super) fn bind_group_for(
        &self,
        gpu: &GpuContext,
        vertices: &wgpu::Buffer,
        indices: &wgpu::Buffer,
        tiles: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        let atlas = self.images.atlas().expect("the depth atlas is ensured before the mesh");
        gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("insm triangulate"),
            layout: &self.triangulate_layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: self.uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: self.views_buffer.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&atlas.view) },
                wgpu::BindGroupEntry { binding: 3, resource: vertices.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 4, resource: indices.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 5, resource: tiles.as_entire_binding() },
            ],
        })
    }

    /// Read back the samples and the triangles of each reconstructed mesh, as the GPU wrote them (for tests and
    /// tools): `(samples, triangles as sample indices)`. Call after a frame.
    pub fn read_meshes(&self, gpu: &GpuContext) -> Result<(Vec<Vec4>, Vec<[u32; 3]>), GpuError> {
        let mesh = self.mesh.as_ref().ok_or_else(|| GpuError::Readback("INSM has not rendered a frame".into()))?;
        let tiles: Vec<GpuTile> = bytemuck::cast_slice(&read_buffer(gpu, &mesh.tiles)?).to_vec();
        self.read_mesh_triangles(gpu, &tiles)
    }

    /// The samples and the triangles of `tiles` (this frame's, already read back), from the GPU's buffers.
    pub(super) fn read_mesh_triangles(
        &self,
        gpu: &GpuContext,
        tiles: &[GpuTile],
    ) -> Result<(Vec<Vec4>, Vec<[u32; 3]>), GpuError> {
        let mesh = self.mesh.as_ref().ok_or_else(|| GpuError::Readback("INSM has not rendered a frame".into()))?;
        let samples: Vec<Vec4> = bytemuck::cast_slice(&read_buffer(gpu, &mesh.vertices)?).to_vec();
        let indices: Vec<u32> = bytemuck::cast_slice(&read_buffer(gpu, &mesh.indices)?).to_vec();
        let mut triangles = Vec::new();
        for (t, tile) in tiles.iter().enumerate() {
            let base = t * MAX_TRIANGLES_PER_TILE as usize * 3;
            for i in 0..tile.count.min(MAX_TRIANGLES_PER_TILE) as usize {
                let o = base + i * 3;
                if let Some(tri) = indices.get(o..o + 3) {
                    triangles.push([tri[0], tri[1], tri[2]]);
                }
            }
        }
        Ok((samples, triangles))
    }
}
