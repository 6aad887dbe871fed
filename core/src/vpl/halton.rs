//! The Halton sequence: dimension `d` of point `i` is the radical inverse of `i` in the `d`-th prime base.
//! Low discrepancy, deterministic, and prefix-stable (the first `N` points of `N + 1` are those of `N`).

/// The first 32 primes: the bases of dimensions 0..32.
pub const PRIMES: [u32; 32] = [
    2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83, 89, 97, 101, 103, 107, 109,
    113, 127, 131,
];

/// Dimension `dim` (< 32, wrapped otherwise) of Halton point `index`, in [0, 1).
pub fn radical_inverse(dim: u32, mut index: u64) -> f32 {
    let base = PRIMES[dim as usize % PRIMES.len()] as u64;
    let inv_base = 1.0 / base as f64;
    let mut inv = inv_base;
    let mut result = 0.0f64;
    while index > 0 {
        result += (index % base) as f64 * inv;
        index /= base;
        inv *= inv_base;
    }
    (result as f32).min(1.0 - f32::EPSILON)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base_two_is_the_van_der_corput_sequence() {
        let v: Vec<f32> = (1..=4).map(|i| radical_inverse(0, i)).collect();
        assert_eq!(v, vec![0.5, 0.25, 0.75, 0.125]);
        assert!((radical_inverse(1, 1) - 1.0 / 3.0).abs() < 1e-7);
    }

    #[test]
    fn points_fill_the_unit_square_evenly() {
        // 4096 points of dimensions (1, 2) in an 8x8 grid: every cell gets 64 +- a few.
        let mut cells = [0u32; 64];
        for i in 1..=4096u64 {
            let (u, v) = (radical_inverse(1, i), radical_inverse(2, i));
            cells[(u * 8.0) as usize * 8 + (v * 8.0) as usize] += 1;
        }
        assert!(cells.iter().all(|&c| (58..=70).contains(&c)), "{cells:?}");
    }
}
