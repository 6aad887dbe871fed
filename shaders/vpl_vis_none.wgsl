// VPL visibility: none (every VPL sees every receiver): the unshadowed denominator of indirect shadow factors.

fn vpl_visibility(s: Surface, v: Vpl, k: u32) -> f32 {
    return 1.0;
}

// No visibility, no work to count.
fn count_visibility_work(pixel: vec2<i32>) {}
