//! What a ReSTIR frame keeps: the reservoirs as the shaders store them, their buffers and bind groups, the last
//! frame's camera for the temporal reuse, and what the final reservoirs were (the per-pixel maps, with their
//! layer names). The struct (`mod.rs`) holds them; the passes (`passes.rs`) and the overlays (`overlays.rs`)
//! act on them.

use std::sync::Arc;

use glam::{Mat4, Vec3};

use crate::compare::colormap;

/// The per-pixel ID map of the light in each pixel's final reservoir (the app's `pixel_ids` layer).
pub const LIGHT_MAP: &str = "light per pixel (reservoir sample y)";
/// The heat map of each final reservoir's weight `W`.
pub const WEIGHT_MAP: &str = "reservoir weight W (log heat map)";
/// The heat map of each final reservoir's length `M`.
pub const LENGTH_MAP: &str = "reservoir length M (heat map)";

/// The maps of read-back final reservoirs of a `size` image; `candidates` is the `M` of one frame.
pub(super) fn inspect(reservoirs: &[GpuReservoir], size: (u32, u32), candidates: u32) -> Inspection {
    let pixels = size.0 as usize * size.1 as usize;
    if reservoirs.len() < pixels {
        return Inspection::default();
    }
    let reservoirs = &reservoirs[..pixels];
    let lights: Vec<u32> =
        reservoirs.iter().map(|r| if r.is_geometry() && r.light != u32::MAX { r.light } else { u32::MAX }).collect();
    // W spans orders of magnitude (it is 1/p̂ times a mean weight): a log scale between its 1st and 99th
    // percentiles; M a linear one from one frame's candidates to the largest.
    let mut weights: Vec<f32> =
        reservoirs.iter().filter(|r| r.is_geometry() && r.w > 0.0 && r.w.is_finite()).map(|r| r.w).collect();
    weights.sort_by(f32::total_cmp);
    let at = |q: f64| weights.get(((weights.len().max(1) - 1) as f64 * q) as usize).copied().unwrap_or(1.0);
    let (w_lo, w_hi) = (at(0.01), at(0.99).max(at(0.01) * 1.0001));
    let m_lo = candidates as f32;
    let m_hi = reservoirs.iter().filter(|r| r.is_geometry()).map(|r| r.m).fold(m_lo, f32::max);
    let heat = |t: f32| {
        let [r, g, b] = colormap(t);
        [r, g, b, 200]
    };
    let weight_map = reservoirs
        .iter()
        .map(|r| {
            if !r.is_geometry() {
                [0, 0, 0, 0]
            } else if r.w <= 0.0 || !r.w.is_finite() {
                [0, 0, 0, 200]
            } else {
                heat((r.w / w_lo).ln() / (w_hi / w_lo).ln())
            }
        })
        .collect();
    let length_map = reservoirs
        .iter()
        .map(|r| if r.is_geometry() { heat((r.m - m_lo) / (m_hi - m_lo).max(1e-6)) } else { [0, 0, 0, 0] })
        .collect();
    Inspection {
        size,
        lights: Arc::new(lights),
        weight_map: Some(Arc::new(weight_map)),
        length_map: Some(Arc::new(length_map)),
        weight_range: (w_lo, w_hi),
        length_range: (m_lo, m_hi),
    }
}

/// A reservoir as the shaders store it. Mirrors `Reservoir` in `restir/reservoir.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
pub struct GpuReservoir {
    /// `y`: an index into the frame's lights, `u32::MAX` when none.
    pub light: u32,
    pub w_sum: f32,
    pub m: f32,
    pub w: f32,
    pub position: [f32; 3],
    /// Octahedral normal (2 x 15 bits), bit 30 geometry, bit 31 a non-black BRDF.
    pub surface: u32,
}
const _: () = assert!(std::mem::size_of::<GpuReservoir>() == 32);

impl GpuReservoir {
    pub fn is_geometry(&self) -> bool {
        self.surface & (1 << 30) != 0
    }
}

/// The camera of the last ReSTIR frame: the next one reprojects onto its reservoirs.
#[derive(Clone, Copy, Debug)]
pub(super) struct History {
    pub(super) clip_from_world: Mat4,
    pub(super) camera_position: Vec3,
}

/// What the last frame's final reservoirs were, read back when `inspect` is on (for the per-pixel maps).
#[derive(Default)]
pub(super) struct Inspection {
    pub(super) size: (u32, u32),
    /// Per pixel, the light of its final reservoir (`u32::MAX`: none, or background).
    pub(super) lights: Arc<Vec<u32>>,
    pub(super) weight_map: Option<Arc<Vec<[u8; 4]>>>,
    pub(super) length_map: Option<Arc<Vec<[u8; 4]>>>,
    /// The W (positive ones) and M spans the heat maps stretch over.
    pub(super) weight_range: (f32, f32),
    pub(super) length_range: (f32, f32),
}

/// The two reservoir buffers of a size: this frame's per pixel (steps 1-3) and the final ones (step 4), which
/// the shading reads and the next frame's temporal reuse reprojects onto.
pub(super) struct Reservoirs {
    pub(super) size: (u32, u32),
    pub(super) working: wgpu::Buffer,
    pub(super) last: wgpu::Buffer,
    /// The mean of the rendered frame's ReSTIR frames, linear RGBA f32 per pixel.
    pub(super) mean: wgpu::Buffer,
    /// What the HDR target holds of the mean so far (the running mean of the ReSTIR frames done), and what this
    /// step's output adds to it.
    pub(super) shown: wgpu::Buffer,
    pub(super) delta: wgpu::Buffer,
}

/// The bind groups of a frame: into `working` (candidates, temporal: reads `last`), into `last` (spatial: reads
/// `working`), the shading's (reads `last`, into `mean`) and the output's (reads `mean`).
pub(super) struct Groups {
    pub(super) to_working: wgpu::BindGroup,
    pub(super) to_last: wgpu::BindGroup,
    pub(super) shade: wgpu::BindGroup,
    pub(super) output: wgpu::BindGroup,
}
