//! The GPU's work counters: what only the GPU knows of a frame's work (per pixel, the lights and VPLs
//! evaluated, shadow lookups, filter taps, rays), counted by the shading shaders themselves with `count_work`
//! (shaders/common.wgsl) into one buffer of the screen bind group, cleared at the start of a frame and read
//! once it is done (after its timings, so the readback is in no step's time).
//!
//! Each counter is 64 bits (a low and a high word) in one of [`BUCKETS`] buckets chosen by the pixel's 16x16
//! tile, so the atomics of a pass spread over many addresses; the readback sums the buckets. The cost in the
//! timed passes: one atomic add per counter a pixel touches per pass.

use crate::contract::work::WorkCounts;
use crate::error::GpuError;
use crate::gpu::GpuContext;

/// Keep in sync with the `WORK_*` constants in shaders/common.wgsl (a test checks).
pub mod slot {
    pub const SHADED_PIXELS: u32 = 0;
    pub const LIGHT_EVALUATIONS: u32 = 1;
    pub const SHADOW_LOOKUPS: u32 = 2;
    pub const FILTER_TAPS: u32 = 3;
    pub const SHADOW_RAYS: u32 = 4;
    pub const CLOSEST_HIT_RAYS: u32 = 5;
    pub const VPL_EVALUATIONS: u32 = 6;
    pub const INDIRECT_SHADOW_LOOKUPS: u32 = 7;
    pub const INDIRECT_FILTER_TAPS: u32 = 8;
    pub const INDIRECT_SHADOW_RAYS: u32 = 9;
    pub const INDIRECT_CLOSEST_HIT_RAYS: u32 = 10;
    pub const INDIRECT_LIGHT_EVALUATIONS: u32 = 11;
    /// Slots per bucket.
    pub const COUNT: u32 = 12;
}

/// Buckets of counters (see the module doc).
pub const BUCKETS: u32 = 1024;

/// What the GPU counted in one frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct GpuWork {
    pub shaded_pixels: u64,
    /// The direct technique's counts.
    pub direct: WorkCounts,
    /// The indirect technique's counts.
    pub indirect: WorkCounts,
}

pub struct WorkCounters {
    pub buffer: wgpu::Buffer,
}

impl WorkCounters {
    pub fn new(device: &wgpu::Device) -> WorkCounters {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("work counters"),
            size: (BUCKETS * slot::COUNT * 2 * 4) as u64,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        WorkCounters { buffer }
    }

    /// Zero every counter (the first step of a frame).
    pub fn clear(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.clear_buffer(&self.buffer, 0, None);
    }

    /// Read the counters of the frame (blocking).
    pub fn read(&self, gpu: &GpuContext) -> Result<GpuWork, GpuError> {
        let bytes = crate::gpu::readback::read_buffer(gpu, &self.buffer)?;
        let words: &[u32] = bytemuck::cast_slice(&bytes);
        Ok(sum_buckets(words))
    }
}

/// The totals of the buckets' 64-bit counters (`words`: BUCKETS x COUNT x (low, high)).
pub fn sum_buckets(words: &[u32]) -> GpuWork {
    let mut totals = [0u64; slot::COUNT as usize];
    for bucket in words.chunks_exact(slot::COUNT as usize * 2) {
        for (s, pair) in bucket.chunks_exact(2).enumerate() {
            totals[s] += pair[0] as u64 | ((pair[1] as u64) << 32);
        }
    }
    let t = |s: u32| totals[s as usize];
    GpuWork {
        shaded_pixels: t(slot::SHADED_PIXELS),
        direct: WorkCounts {
            light_pixel_evaluations: t(slot::LIGHT_EVALUATIONS),
            shadow_lookups: t(slot::SHADOW_LOOKUPS),
            filter_taps: t(slot::FILTER_TAPS),
            shadow_rays: t(slot::SHADOW_RAYS),
            closest_hit_rays: t(slot::CLOSEST_HIT_RAYS),
            ..Default::default()
        },
        indirect: WorkCounts {
            light_pixel_evaluations: t(slot::INDIRECT_LIGHT_EVALUATIONS),
            vpl_pixel_evaluations: t(slot::VPL_EVALUATIONS),
            shadow_lookups: t(slot::INDIRECT_SHADOW_LOOKUPS),
            filter_taps: t(slot::INDIRECT_FILTER_TAPS),
            shadow_rays: t(slot::INDIRECT_SHADOW_RAYS),
            closest_hit_rays: t(slot::INDIRECT_CLOSEST_HIT_RAYS),
            ..Default::default()
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn buckets_add_up_with_their_high_words() {
        let mut words = vec![0u32; (BUCKETS * slot::COUNT * 2) as usize];
        let at = |bucket: u32, s: u32| ((bucket * slot::COUNT + s) * 2) as usize;
        words[at(0, slot::SHADOW_LOOKUPS)] = 5;
        words[at(7, slot::SHADOW_LOOKUPS)] = u32::MAX;
        words[at(7, slot::SHADOW_LOOKUPS) + 1] = 2;
        words[at(3, slot::VPL_EVALUATIONS)] = 9;
        let w = sum_buckets(&words);
        assert_eq!(w.direct.shadow_lookups, 5 + u32::MAX as u64 + (2u64 << 32));
        assert_eq!(w.indirect.vpl_pixel_evaluations, 9);
        assert_eq!(w.shaded_pixels, 0);
    }

    #[test]
    fn the_slots_match_the_shaders() {
        let common = include_str!("../../../shaders/common.wgsl");
        let value = |name: &str| -> u32 {
            let line = common
                .lines()
                .find(|l| l.starts_with(&format!("const {name}: u32 = ")))
                .unwrap_or_else(|| panic!("common.wgsl has no const {name}"));
            line.split('=').nth(1).unwrap().trim().trim_end_matches(';').trim_end_matches('u').parse().unwrap()
        };
        assert_eq!(value("WORK_SHADED_PIXELS"), slot::SHADED_PIXELS);
        assert_eq!(value("WORK_LIGHT_EVALUATIONS"), slot::LIGHT_EVALUATIONS);
        assert_eq!(value("WORK_SHADOW_LOOKUPS"), slot::SHADOW_LOOKUPS);
        assert_eq!(value("WORK_FILTER_TAPS"), slot::FILTER_TAPS);
        assert_eq!(value("WORK_SHADOW_RAYS"), slot::SHADOW_RAYS);
        assert_eq!(value("WORK_CLOSEST_HIT_RAYS"), slot::CLOSEST_HIT_RAYS);
        assert_eq!(value("WORK_VPL_EVALUATIONS"), slot::VPL_EVALUATIONS);
        assert_eq!(value("WORK_INDIRECT_SHADOW_LOOKUPS"), slot::INDIRECT_SHADOW_LOOKUPS);
        assert_eq!(value("WORK_INDIRECT_FILTER_TAPS"), slot::INDIRECT_FILTER_TAPS);
        assert_eq!(value("WORK_INDIRECT_SHADOW_RAYS"), slot::INDIRECT_SHADOW_RAYS);
        assert_eq!(value("WORK_INDIRECT_CLOSEST_HIT_RAYS"), slot::INDIRECT_CLOSEST_HIT_RAYS);
        assert_eq!(value("WORK_INDIRECT_LIGHT_EVALUATIONS"), slot::INDIRECT_LIGHT_EVALUATIONS);
        assert_eq!(value("WORK_SLOTS"), slot::COUNT);
        assert_eq!(value("WORK_BUCKETS"), BUCKETS);
    }
}
