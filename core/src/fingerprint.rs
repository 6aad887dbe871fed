//! Fingerprints: telling configurations apart within one build (the frame report's view, the app's cached
//! timings, ReSTIR's reservoirs), not for storing.

use crate::scene::PointLight;

/// A fingerprint of `value`'s `Debug` form (which writes every `f32` exactly), without building the text:
/// stable within one build, for telling configurations apart, not for storing.
pub fn fingerprint(value: &impl std::fmt::Debug) -> u64 {
    use std::fmt::Write;
    use std::hash::Hasher;
    struct Sink(std::collections::hash_map::DefaultHasher);
    impl Write for Sink {
        fn write_str(&mut self, s: &str) -> std::fmt::Result {
            self.0.write(s.as_bytes());
            Ok(())
        }
    }
    let mut sink = Sink(std::collections::hash_map::DefaultHasher::new());
    let _ = write!(sink, "{value:?}");
    sink.0.finish()
}

/// A fingerprint of a light set from the bits of its numbers (no text: the app asks it every complete frame,
/// and a set may hold 100k lights).
pub fn lights_fingerprint(lights: &[PointLight]) -> u64 {
    use std::hash::Hasher;
    let mut h = std::collections::hash_map::DefaultHasher::new();
    h.write_usize(lights.len());
    for l in lights {
        let spot =
            l.spot.map_or([0.0; 5], |s| [s.direction.x, s.direction.y, s.direction.z, s.inner_angle, s.outer_angle]);
        let numbers = l.position.to_array().into_iter().chain(l.color.to_array()).chain([l.intensity, l.range]);
        for v in numbers.chain(spot) {
            h.write_u32(v.to_bits());
        }
        h.write_u8(l.spot.is_some() as u8);
    }
    h.finish()
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn a_light_set_fingerprint_changes_with_any_light() {
        let a = vec![PointLight::new(Vec3::ONE, Vec3::ONE, 1.0, 5.0); 3];
        let mut b = a.clone();
        assert_eq!(lights_fingerprint(&a), lights_fingerprint(&b));
        b[2].position.x += 1e-3;
        assert_ne!(lights_fingerprint(&a), lights_fingerprint(&b));
        let mut c = a.clone();
        c[0].range = 6.0;
        assert_ne!(lights_fingerprint(&a), lights_fingerprint(&c));
        assert_ne!(lights_fingerprint(&a), lights_fingerprint(&a[..2]));
    }
}
