//! Steps 1 and 2 of LightCluster's clustering ([`super::clustering`], section 3.1.2): the branch-free frustum
//! test of a light's sphere, four planes at a time, and the sort of the visible lights by `L_att`, largest first
//! (a stable LSD radix sort for many lights).

use glam::Vec4;

use crate::math::Frustum;
use crate::scene::PointLight;

/// Below this many visible lights the comparison sort beats the radix sort.
const RADIX_MIN: usize = 4096;
/// The radix sort's digit: 11 bits, so three passes cover the 32 bits of a range.
const RADIX_BITS: usize = 11;
pub(super) const RADIX_BUCKETS: usize = 1 << RADIX_BITS;

/// The six frustum planes as two groups of four lanes (normal x, y, z and distance per lane; the second group
/// repeats its last plane), so that step 1 tests a sphere against four planes at once.
pub(super) struct FrustumLanes {
    x: [Vec4; 2],
    y: [Vec4; 2],
    z: [Vec4; 2],
    w: [Vec4; 2],
}

impl FrustumLanes {
    pub(super) fn new(frustum: &Frustum) -> Self {
        let p = &frustum.planes;
        let lanes = |f: fn(&Vec4) -> f32| {
            [Vec4::new(f(&p[0]), f(&p[1]), f(&p[2]), f(&p[3])), Vec4::new(f(&p[4]), f(&p[5]), f(&p[5]), f(&p[5]))]
        };
        FrustumLanes { x: lanes(|v| v.x), y: lanes(|v| v.y), z: lanes(|v| v.z), w: lanes(|v| v.w) }
    }
}

/// Step 1's test, `light.is_valid() && frustum.intersects_sphere(light.position, light.range)` with the same
/// arithmetic per plane (`normal.dot(center) + distance >= -range`, evaluated in the same order, lane by lane),
/// but without branches, so the compiler keeps it in registers.
#[inline(always)]
pub(super) fn is_visible(light: &PointLight, planes: &FrustumLanes) -> bool {
    let (p, c, r) = (light.position, light.color, light.range);
    let finite = p.is_finite() & c.is_finite() & light.intensity.is_finite() & r.is_finite();
    let usable = (r > 0.0) & (light.intensity >= 0.0) & (c.x >= 0.0) & (c.y >= 0.0) & (c.z >= 0.0);
    let (x, y, z, neg_r) = (Vec4::splat(p.x), Vec4::splat(p.y), Vec4::splat(p.z), Vec4::splat(-r));
    let mut inside = true;
    for g in 0..2 {
        let d = planes.x[g] * x + planes.y[g] * y + planes.z[g] * z + planes.w[g];
        inside &= d.cmpge(neg_r).all();
    }
    finite & usable & inside & light.spot.is_none_or(|s| s.is_valid())
}

/// Step 2: sort the keys made by step 1 ascending, i.e. by `L_att` descending, then by input index. Large inputs
/// use a stable LSD radix sort over the 32 range bits in three 11-bit digits (skipping digits all keys share),
/// small ones `sort_unstable`, which gives the same order because keys are unique.
pub(super) fn sort_by_range(keys: &mut Vec<u64>, tmp: &mut Vec<u64>, hist: &mut Vec<[u32; RADIX_BUCKETS]>) {
    let n = keys.len();
    if n < RADIX_MIN {
        keys.sort_unstable();
        return;
    }
    hist.clear();
    hist.resize(3, [0; RADIX_BUCKETS]);
    for &key in keys.iter() {
        let hi = (key >> 32) as usize;
        for (digit, h) in hist.iter_mut().enumerate() {
            h[(hi >> (RADIX_BITS * digit)) & (RADIX_BUCKETS - 1)] += 1;
        }
    }
    tmp.clear();
    tmp.resize(n, 0);
    for (digit, h) in hist.iter_mut().enumerate() {
        if h.iter().any(|&c| c as usize == n) {
            continue; // every key has the same digit here
        }
        let mut sum = 0u32;
        for c in h.iter_mut() {
            let count = *c;
            *c = sum;
            sum += count;
        }
        let shift = 32 + RADIX_BITS * digit;
        for &key in keys.iter() {
            let b = &mut h[(key >> shift) as usize & (RADIX_BUCKETS - 1)];
            tmp[*b as usize] = key;
            *b += 1;
        }
        std::mem::swap(keys, tmp);
    }
}
