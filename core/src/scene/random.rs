//! The deterministic randomness of generated light sets: a small generator and a warm light palette, shared
//! by the built-in scenes and the light layouts.

use glam::Vec3;

/// A random colour from a warm palette (candle, tungsten, warm and neutral white), slightly jittered. Red stays
/// 1 and the largest channel (jitter only lowers green and blue), so the colour keeps the light's brightness.
pub(crate) fn warm_color(rng: &mut SplitMix64) -> Vec3 {
    const PALETTE: [Vec3; 5] = [
        Vec3::new(1.0, 0.62, 0.32),
        Vec3::new(1.0, 0.75, 0.5),
        Vec3::new(1.0, 0.85, 0.68),
        Vec3::new(1.0, 0.93, 0.84),
        Vec3::new(1.0, 0.98, 0.95),
    ];
    let base = PALETTE[(rng.next_u64() % PALETTE.len() as u64) as usize];
    base * Vec3::new(1.0, rng.range(0.92, 1.0), rng.range(0.92, 1.0))
}

/// SplitMix64 (Steele, Lea & Flood 2014): a tiny, fast, well-mixed deterministic generator. Good enough to
/// scatter lights; not for anything cryptographic.
#[derive(Clone, Debug)]
pub(crate) struct SplitMix64 {
    state: u64,
}

impl SplitMix64 {
    pub(crate) fn new(seed: u64) -> Self {
        SplitMix64 { state: seed }
    }

    pub(crate) fn next_u64(&mut self) -> u64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1): the top 24 bits, which an `f32` represents exactly.
    pub(crate) fn next_f32(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// Uniform in [lo, hi).
    pub(crate) fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }
}
