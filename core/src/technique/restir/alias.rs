//! The source pdf `p` of ReSTIR's candidates, sampled in O(1) per candidate whatever the light count: uniform
//! over the visible lights, or in proportion to their power through an alias table (Walker 1977, built with
//! Vose's 1991 method in O(N)). Pure CPU; the GPU form is one [`SourceEntry`] per light.

/// One slot of the source table as the shaders read it. Mirrors `SourceEntry` in `restir/reservoir.wgsl`.
///
/// Sampling (both forms): pick slot `i` uniformly, keep it when a second uniform number is below `threshold`,
/// else take `alias_slot`; the light drawn has the probability `pdf` of its own slot.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct SourceEntry {
    pub threshold: f32,
    pub alias_slot: u32,
    /// The probability `p(x)` of drawing this slot's light.
    pub pdf: f32,
    /// The light of the slot: an index into the frame's lights.
    pub light: u32,
}
const _: () = assert!(std::mem::size_of::<SourceEntry>() == 16);

/// A uniform source over `lights` (indices into the frame's lights): every slot keeps itself, `p = 1/N`.
pub fn uniform_table(lights: &[usize]) -> Vec<SourceEntry> {
    let pdf = 1.0 / lights.len().max(1) as f32;
    lights
        .iter()
        .enumerate()
        .map(|(i, &l)| SourceEntry { threshold: 1.0, alias_slot: i as u32, pdf, light: l as u32 })
        .collect()
}

/// An alias table drawing `lights[i]` with probability `weights[i] / sum(weights)` (Vose's method). None when
/// the weights are empty, do not sum to a positive finite number, or one is negative or not finite: the caller
/// then has nothing to sample by power.
pub fn alias_table(lights: &[usize], weights: &[f64]) -> Option<Vec<SourceEntry>> {
    assert_eq!(lights.len(), weights.len(), "a weight per light");
    let n = weights.len();
    if n == 0 || weights.iter().any(|w| !w.is_finite() || *w < 0.0) {
        return None;
    }
    let total: f64 = weights.iter().sum();
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    // Scaled probabilities: mean 1. Slots below 1 are topped up by one slot above 1 (their alias).
    let mut scaled: Vec<f64> = weights.iter().map(|w| w * n as f64 / total).collect();
    let mut threshold = vec![1.0f64; n];
    let mut alias: Vec<u32> = (0..n as u32).collect();
    let (mut small, mut large): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| scaled[i] < 1.0);
    while let (Some(&s), Some(&l)) = (small.last(), large.last()) {
        small.pop();
        threshold[s] = scaled[s];
        alias[s] = l as u32;
        scaled[l] -= 1.0 - scaled[s];
        if scaled[l] < 1.0 {
            large.pop();
            small.push(l);
        }
    }
    // What is left is 1 up to rounding: those slots keep themselves.
    for i in small.into_iter().chain(large) {
        threshold[i] = 1.0;
        alias[i] = i as u32;
    }
    Some(
        (0..n)
            .map(|i| SourceEntry {
                threshold: threshold[i] as f32,
                alias_slot: alias[i],
                pdf: (weights[i] / total) as f32,
                light: lights[i] as u32,
            })
            .collect(),
    )
}

/// The probability with which the table draws each slot (uniform slot, then the threshold test): what the
/// tests hold against each slot's `pdf`.
pub fn drawn_probabilities(table: &[SourceEntry]) -> Vec<f64> {
    let n = table.len() as f64;
    let mut p = vec![0.0f64; table.len()];
    for (i, e) in table.iter().enumerate() {
        let keep = (e.threshold as f64).clamp(0.0, 1.0);
        p[i] += keep / n;
        p[e.alias_slot as usize] += (1.0 - keep) / n;
    }
    p
}

#[cfg(test)]
mod tests {
    use super::*;

    /// SplitMix64, for test weights.
    fn weights(seed: u64, n: usize) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|i| {
                s = s.wrapping_add(0x9E37_79B9_7F4A_7C15);
                let mut z = s;
                z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
                z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
                let u = ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64;
                // Some zero weights, some tiny, a few huge: the cases that break naive tables.
                match i % 7 {
                    0 => 0.0,
                    1 => u * 1e-6,
                    2 => u * 1e4,
                    _ => u,
                }
            })
            .collect()
    }

    #[test]
    fn the_alias_table_draws_every_light_with_its_share_of_the_power() {
        for (seed, n) in [(1, 1), (2, 2), (3, 7), (4, 100), (5, 100_000)] {
            let w = weights(seed, n);
            let lights: Vec<usize> = (0..n).map(|i| i * 3 + 1).collect();
            let Some(table) = alias_table(&lights, &w) else {
                assert!(w.iter().sum::<f64>() == 0.0, "n = {n}: no table for positive weights");
                continue;
            };
            let total: f64 = w.iter().sum();
            let drawn = drawn_probabilities(&table);
            for i in 0..n {
                let want = w[i] / total;
                assert!((drawn[i] - want).abs() <= 1e-6 * want.max(1.0 / n as f64), "n = {n}, slot {i}");
                assert!((table[i].pdf as f64 - want).abs() <= 1e-6 * want + 1e-12, "n = {n}, slot {i}: pdf");
                assert_eq!(table[i].light, lights[i] as u32);
                if w[i] == 0.0 {
                    assert!(table[i].threshold == 0.0 && table[table[i].alias_slot as usize].pdf > 0.0);
                }
            }
        }
    }

    #[test]
    fn the_uniform_table_keeps_every_slot() {
        let table = uniform_table(&[4, 9, 2]);
        assert_eq!(drawn_probabilities(&table), vec![1.0 / 3.0; 3]);
        assert!(table.iter().all(|e| (e.pdf - 1.0 / 3.0).abs() < 1e-7));
        assert!(uniform_table(&[]).is_empty());
    }

    #[test]
    fn weights_without_power_give_no_table() {
        assert!(alias_table(&[], &[]).is_none());
        assert!(alias_table(&[0, 1], &[0.0, 0.0]).is_none());
        assert!(alias_table(&[0, 1], &[1.0, f64::NAN]).is_none());
        assert!(alias_table(&[0, 1], &[1.0, -1.0]).is_none());
    }
}
