//! The scene's BVH as a renderer service: built once per scene on the CPU (binned SAH,
//! [`crate::technique::raytraced::bvh`]), uploaded once, and shared by everything that traces rays: the
//! ray-traced shadows, the VPL generator (closest hits on the CPU), the VPL ray-traced gather and the path
//! tracer (closest hits on the GPU). It lives in [`GpuScene`] behind a `OnceLock`, so a scene that never
//! traces a ray never pays for it.
//!
//! Besides the traversal layout (`raytrace_bvh.wgsl`) it keeps, per BVH triangle, what a hit needs to shade:
//! the geometric normal and the material's mean albedo ([`BvhSurface`] on the CPU; on the GPU the albedo rides
//! in the unused `w` components of the triangle and the normal is `cross(e1, e2)`). Hits use
//! the material's *mean* albedo (its factor times the mean of its texture) rather than the texel under the hit:
//! a GPU hit shader cannot sample an arbitrary material's texture without bindless textures, and the CPU VPL
//! generator and the path tracer must agree. Receivers (the G-buffer) keep their textured albedo.

use std::sync::Arc;

use glam::Vec3;
use wgpu::util::DeviceExt;

use super::gpu_scene::GpuScene;
use crate::gpu::GpuContext;
use crate::scene::chunks::ChunkedGeometry;
use crate::technique::raytraced::bvh::{self, Bvh, Hit};

/// Per BVH triangle: geometric normal (xyz) and the material's mean albedo (rgb).
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct BvhSurface {
    pub normal: [f32; 4],
    pub albedo: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<BvhSurface>() == 32);

/// The BVH of a scene, on the CPU and on the GPU.
pub struct SceneBvh {
    pub cpu: Bvh,
    /// Per entry of `cpu.triangles`.
    pub surfaces: Vec<BvhSurface>,
    pub nodes: wgpu::Buffer,
    /// `BvhTriangle`s with the albedo in the `w` of `v0`, `e1`, `e2` (r, g, b).
    pub triangles: wgpu::Buffer,
}

/// What a closest hit found, in world space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceHit {
    pub t: f32,
    pub position: Vec3,
    /// Geometric normal, facing the ray's origin.
    pub normal: Vec3,
    pub albedo: Vec3,
}

impl SceneBvh {
    pub fn build(gpu: &GpuContext, geometry: &ChunkedGeometry, material_albedo: &[Vec3]) -> SceneBvh {
        let cpu = Bvh::from_geometry(geometry);
        // Material of each input triangle: chunks are index ranges with one material each.
        let mut triangle_material = vec![0u32; geometry.triangle_count()];
        for c in &geometry.chunks {
            let first = (c.first_index / 3) as usize;
            for m in &mut triangle_material[first..first + c.triangle_count() as usize] {
                *m = c.material;
            }
        }
        let surfaces: Vec<BvhSurface> = cpu
            .triangles
            .iter()
            .zip(&cpu.triangle_ids)
            .map(|(t, &id)| {
                let [a, b, c] = t.vertices();
                let n = (b - a).cross(c - a).normalize_or(Vec3::Y);
                let albedo =
                    material_albedo.get(triangle_material[id as usize] as usize).copied().unwrap_or(Vec3::ZERO);
                BvhSurface { normal: n.extend(0.0).to_array(), albedo: albedo.extend(1.0).to_array() }
            })
            .collect();
        log::info!(
            "scene BVH: {} triangles, {} nodes, depth {}, built in {:.1} ms",
            cpu.stats.triangles,
            cpu.stats.nodes,
            cpu.stats.max_depth,
            cpu.stats.build_ms
        );
        let storage = |label, contents: &[u8]| {
            gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                // An empty scene still binds a valid (one-element) buffer.
                contents: if contents.is_empty() { &[0u8; 64] } else { contents },
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let (nodes, mut triangles) = cpu.gpu_buffers();
        // The unused w of v0, e1, e2 carry the albedo, so a hit shader reads it without another storage buffer
        // (downlevel devices allow four per stage).
        for (t, s) in triangles.iter_mut().zip(&surfaces) {
            t.v0[3] = s.albedo[0];
            t.e1[3] = s.albedo[1];
            t.e2[3] = s.albedo[2];
        }
        SceneBvh {
            nodes: storage("bvh nodes", bytemuck::cast_slice(&nodes)),
            triangles: storage("bvh triangles", bytemuck::cast_slice(&triangles)),
            surfaces,
            cpu,
        }
    }

    /// Nearest surface on `origin + t * dir` (`dir` normalised) for `0 < t < t_max`.
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<SurfaceHit> {
        let Hit { t, triangle, .. } = bvh::closest_hit_cpu(&self.cpu, origin, dir, t_max)?;
        let s = &self.surfaces[triangle as usize];
        let n = Vec3::from_slice(&s.normal[..3]);
        Some(SurfaceHit {
            t,
            position: origin + dir * t,
            normal: if n.dot(dir) > 0.0 { -n } else { n },
            albedo: Vec3::from_slice(&s.albedo[..3]),
        })
    }
}

impl GpuScene {
    /// The scene's BVH, built the first time it is asked for; the second value is its build time when this
    /// call built it.
    pub fn bvh(&self, gpu: &GpuContext) -> (Arc<SceneBvh>, Option<f64>) {
        let mut built = None;
        let bvh = self.bvh_cell.get_or_init(|| {
            let b = Arc::new(SceneBvh::build(gpu, &self.geometry, &self.material_albedo));
            built = Some(b.cpu.stats.build_ms);
            b
        });
        (bvh.clone(), built)
    }
}
