//! Step 3, pull-push hole filling (Ritschel et al. 2008, section 3.3, after Grossman and Dally 1998 and
//! Marroquim et al. 2007): the CPU twin of `ism/pull_push.wgsl`, which follows it operation for operation, so
//! the two agree to f32 rounding (tested in `core/tests/ism.rs`).
//!
//! A map holds normalised depths `z = (d - near) / (far - near)`; [`EMPTY`] (1.0, the far plane) marks a texel
//! no point landed in. Levels halve the resolution (rounding up), `levels` of them at most:
//! - pull, level `l` to `l + 1`: a coarse texel is the mean of its (up to four) children that are not empty and
//!   lie within the depth threshold `τ` of the nearest of them (`z <= z_min (1 + τ)`), so a point of the
//!   background seen through a gap is not averaged with the surface in front of it;
//! - push, level `l + 1` back to `l`, coarsest first: an empty fine texel takes the bilinear interpolation of the
//!   four coarse texels around it, over those that are not empty and within `τ` of the nearest (weights
//!   renormalised); texels that hold a point keep it. A hole wider than `2^levels` texels stays empty (lit).

/// The depth of an empty texel (nothing between the map's centre and its far plane).
pub const EMPTY: f32 = 1.0;

/// The most pull-push levels: a 4096-texel map is a single texel after 12.
pub const MAX_LEVELS: u32 = 12;

/// The side of level `level` of a `resolution`-texel map.
pub fn level_resolution(resolution: u32, level: u32) -> u32 {
    (0..level).fold(resolution, |r, _| r.div_ceil(2))
}

/// The levels a `resolution`-texel map can have before its coarsest level is one texel, at most `levels`.
pub fn usable_levels(resolution: u32, levels: u32) -> u32 {
    let mut n = 0;
    while n < levels.min(MAX_LEVELS) && level_resolution(resolution, n) > 1 {
        n += 1;
    }
    n
}

fn is_empty(z: f32) -> bool {
    z >= EMPTY || z.is_nan()
}

/// The mean of the non-empty `values` within `threshold` of their nearest, weighted by `weights`; EMPTY when all
/// are empty. The same sums in the same order as `pp_near_mean` in `ism/pull_push.wgsl`.
fn near_mean(values: [f32; 4], weights: [f32; 4], threshold: f32) -> f32 {
    let mut z_min = EMPTY;
    for (z, w) in values.iter().zip(weights) {
        if !is_empty(*z) && w > 0.0 {
            z_min = z_min.min(*z);
        }
    }
    if is_empty(z_min) {
        return EMPTY;
    }
    let limit = z_min * (1.0 + threshold);
    let (mut sum, mut weight) = (0f32, 0f32);
    for (z, w) in values.iter().zip(weights) {
        if !is_empty(*z) && w > 0.0 && *z <= limit {
            sum += *z * w;
            weight += w;
        }
    }
    if weight > 0.0 {
        sum / weight
    } else {
        EMPTY
    }
}

/// One pull step: the `coarse` level (side `level_resolution(fine_res, 1)`) from the `fine` one.
pub fn pull(fine: &[f32], fine_res: u32, threshold: f32) -> Vec<f32> {
    let coarse_res = fine_res.div_ceil(2);
    let mut coarse = vec![EMPTY; (coarse_res * coarse_res) as usize];
    for y in 0..coarse_res {
        for x in 0..coarse_res {
            let mut values = [EMPTY; 4];
            let mut weights = [0.0; 4];
            for (k, (dx, dy)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
                let (fx, fy) = (2 * x + dx, 2 * y + dy);
                if fx < fine_res && fy < fine_res {
                    values[k] = fine[(fy * fine_res + fx) as usize];
                    weights[k] = 1.0;
                }
            }
            coarse[(y * coarse_res + x) as usize] = near_mean(values, weights, threshold);
        }
    }
    coarse
}

/// One push step: the empty texels of `fine` (side `fine_res`) filled from `coarse` (its next level).
pub fn push(fine: &mut [f32], fine_res: u32, coarse: &[f32], threshold: f32) {
    let coarse_res = fine_res.div_ceil(2) as i32;
    for y in 0..fine_res {
        for x in 0..fine_res {
            let at = (y * fine_res + x) as usize;
            if !is_empty(fine[at]) {
                continue;
            }
            fine[at] = interpolate(coarse, coarse_res, x, y, threshold);
        }
    }
}

/// The coarse level's value at fine texel (x, y): bilinear over the four coarse texels around its centre.
fn interpolate(coarse: &[f32], coarse_res: i32, x: u32, y: u32, threshold: f32) -> f32 {
    // The fine texel's centre in coarse texel units.
    let cx = (x as f32 + 0.5) * 0.5 - 0.5;
    let cy = (y as f32 + 0.5) * 0.5 - 0.5;
    let (x0, y0) = (cx.floor(), cy.floor());
    let (fx, fy) = (cx - x0, cy - y0);
    let (x0, y0) = (x0 as i32, y0 as i32);
    let mut values = [EMPTY; 4];
    let weights = [(1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy];
    for (k, (dx, dy)) in [(0, 0), (1, 0), (0, 1), (1, 1)].into_iter().enumerate() {
        let (sx, sy) = ((x0 + dx).clamp(0, coarse_res - 1), (y0 + dy).clamp(0, coarse_res - 1));
        values[k] = coarse[(sy * coarse_res + sx) as usize];
    }
    near_mean(values, weights, threshold)
}

/// Pull-push of one `resolution`² map in place, with at most `levels` levels and depth threshold `threshold`.
pub fn pull_push(map: &mut [f32], resolution: u32, levels: u32, threshold: f32) {
    assert_eq!(map.len(), (resolution * resolution) as usize, "a map is resolution² texels");
    let levels = usable_levels(resolution, levels);
    let mut pyramid = vec![map.to_vec()];
    for l in 0..levels {
        let next = pull(&pyramid[l as usize], level_resolution(resolution, l), threshold);
        pyramid.push(next);
    }
    for l in (0..levels).rev() {
        let (fine, coarse) = pyramid.split_at_mut(l as usize + 1);
        push(&mut fine[l as usize], level_resolution(resolution, l), &coarse[0], threshold);
    }
    map.copy_from_slice(&pyramid[0]);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_plane_with_holes_is_filled_and_a_hole_too_wide_stays() {
        // A constant 0.4 plane in a 16² map, every other texel of every other row set (3/4 are holes).
        let res = 16;
        let mut map = vec![EMPTY; 256];
        for y in (0..res).step_by(2) {
            for x in (0..res).step_by(2) {
                map[(y * res + x) as usize] = 0.4;
            }
        }
        let mut filled = map.clone();
        pull_push(&mut filled, res, 1, 0.1);
        assert!(filled.iter().all(|&z| (z - 0.4).abs() < 1e-6), "{filled:?}");
        // No levels: nothing changes.
        let mut same = map.clone();
        pull_push(&mut same, res, 0, 0.1);
        assert_eq!(same, map);
        // One point in an empty map: one level fills its 2x2 block's neighbourhood, not the whole map.
        let mut one = vec![EMPTY; 256];
        one[0] = 0.3;
        pull_push(&mut one, res, 1, 0.1);
        assert!(one[1] < EMPTY && one[res as usize] < EMPTY && is_empty(one[255]));
        let mut all = vec![EMPTY; 256];
        all[0] = 0.3;
        pull_push(&mut all, res, 4, 0.1);
        assert!(all.iter().all(|&z| (z - 0.3).abs() < 1e-6), "four levels reach the whole 16² map");
    }

    #[test]
    fn the_background_is_not_averaged_with_the_surface_in_front() {
        // A near surface (0.2) with a hole in which a background point (0.8) landed, and empty texels around it.
        let res = 8;
        let mut map = vec![EMPTY; 64];
        for y in 0..res {
            for x in 0..res {
                if (x + y) % 2 == 0 {
                    map[(y * res + x) as usize] = 0.2;
                }
            }
        }
        map[(3 * res + 5) as usize] = 0.8;
        map[(3 * res + 4) as usize] = EMPTY;
        pull_push(&mut map, res, 3, 0.1);
        // The hole next to the background point is filled with the near surface only.
        assert!((map[(3 * res + 4) as usize] - 0.2).abs() < 1e-6, "{}", map[(3 * res + 4) as usize]);
        // The background point itself is kept (holes only are filled).
        assert_eq!(map[(3 * res + 5) as usize], 0.8);
        assert!(map.iter().all(|&z| z < EMPTY));
    }

    #[test]
    fn odd_sizes_and_levels() {
        assert_eq!(level_resolution(128, 3), 16);
        assert_eq!(level_resolution(5, 1), 3);
        assert_eq!(usable_levels(128, 100), 7);
        assert_eq!(usable_levels(1, 4), 0);
        assert_eq!(usable_levels(5, 4), 3);
        let mut map = vec![EMPTY; 25];
        map[12] = 0.5;
        pull_push(&mut map, 5, 3, 0.05);
        assert!(map.iter().all(|&z| (z - 0.5).abs() < 1e-6));
        let mut tiny = vec![EMPTY];
        pull_push(&mut tiny, 1, 4, 0.1);
        assert_eq!(tiny, vec![EMPTY]);
    }
}
