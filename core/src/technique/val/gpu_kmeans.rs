//! The clustering of [`super::kmeans`] on the GPU (`val/kmeans.wgsl`), as the paper does it (section 6): one
//! dispatch per step over the frame's VPL buffer, fixed-point atomic sums instead of additive blending (WGSL
//! has no float atomics), the VPL-to-VAL map `C` left on the GPU for the gather, and the VALs read back (M x 48
//! bytes, plus `C` for the overlays) because their maps are rendered with per-VAL culling on the CPU.

use glam::Vec3;

use super::kmeans::{Clustering, KMeansParams, Val};

/// Its WGSL module (listed by the technique's `SHADERS`).
pub const KMEANS: crate::shaders::WgslModule =
    crate::shaders::wgsl!("val_kmeans", ["shaders/vpl_basis.wgsl", "core/src/technique/val/kmeans.wgsl"]);
use crate::error::GpuError;
use crate::gpu::kernels::Kernels;
use crate::gpu::readback;
use crate::gpu::GpuContext;
use crate::timing::PassTimer;
use crate::vpl::Vpl;

/// Mirrors `KmParams` in `val/kmeans.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct KmParamsUniform {
    vpl_count: u32,
    val_count: u32,
    scale: f32,
    w_x: f32,
    w_a: f32,
    scene_length: f32,
    _pad: [u32; 2],
    bounds_min: [f32; 4],
    bounds_extent: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<KmParamsUniform>() == 64);

/// Mirrors `ValState` in `val/kmeans.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct ValState {
    position: [f32; 4],
    normal: [f32; 4],
    rect: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<ValState>() == 48);

/// Words of the accumulator per VAL (`ACC` in the shader).
const ACC: u64 = 12;

pub struct GpuKMeans {
    kernels: Kernels,
    vals: Option<wgpu::Buffer>,
    acc: Option<wgpu::Buffer>,
    /// `C`, one u32 per VPL (bound by the gather).
    pub assignment: Option<wgpu::Buffer>,
}

fn storage(gpu: &GpuContext, label: &str, size: u64, copy_src: bool) -> wgpu::Buffer {
    let mut usage = wgpu::BufferUsages::STORAGE;
    if copy_src {
        usage |= wgpu::BufferUsages::COPY_SRC;
    }
    gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: size.max(16),
        usage,
        mapped_at_creation: false,
    })
}

impl GpuKMeans {
    pub fn new(gpu: &GpuContext) -> GpuKMeans {
        let entries = ["km_init", "km_clear", "km_assign", "km_update", "km_final", "km_finish"];
        let uniform_bytes = std::mem::size_of::<KmParamsUniform>() as u64;
        // Binding 1: the VPLs (read); 2-4: the VALs, the fixed-point sums, the assignment.
        let kernels =
            Kernels::new(gpu, "val kmeans", KMEANS.source, &entries, uniform_bytes, &[true, false, false, false], &[]);
        GpuKMeans { kernels, vals: None, acc: None, assignment: None }
    }

    /// Cluster the `vpls` held in `vpl_buffer` (`GpuVpl`s) on the GPU and read the result back.
    #[allow(clippy::too_many_arguments)]
    pub fn run(
        &mut self,
        gpu: &GpuContext,
        timer: &PassTimer,
        vpl_buffer: &wgpu::Buffer,
        vpls: &[Vpl],
        params: &KMeansParams,
        bounds_min: Vec3,
        bounds_extent: Vec3,
    ) -> Result<Clustering, GpuError> {
        let n = vpls.len();
        let m = params.vals.min(n);
        if m == 0 {
            return Ok(Clustering { assignment: vec![0; n], ..Default::default() });
        }
        let grow = |slot: &mut Option<wgpu::Buffer>, label: &str, size: u64, copy_src: bool| {
            if slot.as_ref().is_none_or(|b| b.size() < size) {
                *slot = Some(storage(gpu, label, size.next_power_of_two(), copy_src));
            }
        };
        grow(&mut self.vals, "val states", (m * 48) as u64, true);
        grow(&mut self.acc, "val accumulators", m as u64 * ACC * 4, false);
        grow(&mut self.assignment, "vpl to val", (n * 4) as u64, true);
        let scale = ((u32::MAX as u64 / n as u64) as f32).min((1u32 << 24) as f32);
        let uniform = KmParamsUniform {
            vpl_count: n as u32,
            val_count: m as u32,
            scale,
            w_x: params.w_x,
            w_a: params.w_a,
            scene_length: params.scene_length,
            _pad: [0; 2],
            bounds_min: bounds_min.extend(0.0).to_array(),
            bounds_extent: bounds_extent.max(Vec3::splat(1e-12)).extend(0.0).to_array(),
        };
        self.kernels.write_uniform(gpu, &uniform);
        let (vals, acc, assignment) = (
            self.vals.as_ref().expect("grown"),
            self.acc.as_ref().expect("grown"),
            self.assignment.as_ref().expect("grown"),
        );
        let group = self.kernels.bind_group(gpu, &[vpl_buffer, vals, acc, assignment]);
        let over_vals = (m as u32).div_ceil(64);
        let over_vpls = (n as u32).div_ceil(64);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        timer.compute_pass(&mut encoder, "val clustering", |pass| {
            pass.set_bind_group(0, &group, &[]);
            pass.set_pipeline(self.kernels.pipeline("km_init"));
            pass.dispatch_workgroups(over_vals, 1, 1);
            for _ in 0..params.iterations {
                pass.set_pipeline(self.kernels.pipeline("km_clear"));
                pass.dispatch_workgroups(over_vals, 1, 1);
                pass.set_pipeline(self.kernels.pipeline("km_assign"));
                pass.dispatch_workgroups(over_vpls, 1, 1);
                pass.set_pipeline(self.kernels.pipeline("km_update"));
                pass.dispatch_workgroups(over_vals, 1, 1);
            }
            pass.set_pipeline(self.kernels.pipeline("km_clear"));
            pass.dispatch_workgroups(over_vals, 1, 1);
            pass.set_pipeline(self.kernels.pipeline("km_final"));
            pass.dispatch_workgroups(over_vpls, 1, 1);
            pass.set_pipeline(self.kernels.pipeline("km_finish"));
            pass.dispatch_workgroups(over_vals, 1, 1);
        });
        gpu.queue.submit([encoder.finish()]);
        let states_bytes = readback::read_buffer(gpu, vals)?;
        let states: &[ValState] = bytemuck::cast_slice(&states_bytes[..m * 48]);
        let c_bytes = readback::read_buffer(gpu, assignment)?;
        let c: Vec<u32> = bytemuck::cast_slice::<u8, u32>(&c_bytes[..n * 4]).to_vec();
        let mut out: Vec<Val> = states
            .iter()
            .map(|s| {
                let position = Vec3::from_slice(&s.position[..3]);
                let normal = Vec3::from_slice(&s.normal[..3]).normalize_or(Vec3::Y);
                let (axis_u, axis_v) = normal.any_orthonormal_pair();
                let [s0, s1, t0, t1] = s.rect;
                Val {
                    position,
                    normal,
                    axis_u,
                    axis_v,
                    half_u: 0.5 * (s1 - s0).max(0.0),
                    half_v: 0.5 * (t1 - t0).max(0.0),
                    offset_u: 0.5 * (s1 + s0),
                    offset_v: 0.5 * (t1 + t0),
                    count: s.position[3] as u32,
                    flux: Vec3::ZERO,
                }
            })
            .collect();
        for (&k, v) in c.iter().zip(vpls) {
            if let Some(val) = out.get_mut(k as usize) {
                val.flux += v.flux;
            }
        }
        let non_empty = out.iter().filter(|v| v.count > 0).count();
        Ok(Clustering { vals: out, assignment: c, non_empty })
    }
}
