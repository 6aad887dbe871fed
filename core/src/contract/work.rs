//! Work counts of a frame, independent of the hardware: what a technique did, not how long it took.
//!
//! Counted where the work is decided: on the CPU for what the CPU decides (triangles submitted to depth passes,
//! shadow-map texels written, k-means distance evaluations), on the GPU for what only the GPU knows (per pixel,
//! how many lights or VPLs it evaluated, shadow lookups, filter taps and rays; `services::work_counters`).
//! The per-pixel means divide by the pixels that hold geometry (`shaded_pixels`).

use std::collections::BTreeMap;

use serde::Serialize;

/// The counts of one technique in one frame (0 where the technique does no such work).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct WorkCounts {
    /// Triangles submitted to depth-only passes (shadow maps, INSM's intermediate maps and meshes, VPL maps).
    pub depth_triangles: u64,
    /// Shadow-map texels the frame's depth passes cover (every face of every map rendered).
    pub shadow_texels_written: u64,
    /// Shadow-map lookups in shading (one per light, cluster, VAL or VPL a pixel looks up).
    pub shadow_lookups: u64,
    /// Texels those lookups read (PCF and PCSS samples, blocker search included).
    pub filter_taps: u64,
    /// Shadow rays traced (any-hit queries).
    pub shadow_rays: u64,
    /// Closest-hit rays traced (path tracing).
    pub closest_hit_rays: u64,
    /// Light-times-pixel evaluations in shading (a light's unshadowed term at a pixel).
    pub light_pixel_evaluations: u64,
    /// VPL-times-pixel evaluations (a VPL, VAL or VPL cluster's term at a pixel).
    pub vpl_pixel_evaluations: u64,
    /// k-means distance evaluations (a point against a centre), CPU or GPU.
    pub kmeans_distance_evaluations: u64,
}

impl WorkCounts {
    /// The counts as named figures, with the per-pixel means of lookups and taps over `shaded_pixels`.
    pub fn to_map(&self, shaded_pixels: u64) -> BTreeMap<String, f64> {
        let per_pixel = |n: u64| if shaded_pixels == 0 { 0.0 } else { n as f64 / shaded_pixels as f64 };
        let mut m = BTreeMap::new();
        let mut put = |k: &str, v: f64| {
            m.insert(k.to_string(), v);
        };
        put("shaded_pixels", shaded_pixels as f64);
        put("depth_triangles", self.depth_triangles as f64);
        put("shadow_texels_written", self.shadow_texels_written as f64);
        put("shadow_lookups", self.shadow_lookups as f64);
        put("shadow_lookups_per_pixel", per_pixel(self.shadow_lookups));
        put("filter_taps", self.filter_taps as f64);
        put("filter_taps_per_pixel", per_pixel(self.filter_taps));
        put("shadow_rays", self.shadow_rays as f64);
        put("closest_hit_rays", self.closest_hit_rays as f64);
        put("light_pixel_evaluations", self.light_pixel_evaluations as f64);
        put("vpl_pixel_evaluations", self.vpl_pixel_evaluations as f64);
        put("kmeans_distance_evaluations", self.kmeans_distance_evaluations as f64);
        m
    }

    /// Field-wise sum.
    pub fn add(&mut self, o: &WorkCounts) {
        self.depth_triangles += o.depth_triangles;
        self.shadow_texels_written += o.shadow_texels_written;
        self.shadow_lookups += o.shadow_lookups;
        self.filter_taps += o.filter_taps;
        self.shadow_rays += o.shadow_rays;
        self.closest_hit_rays += o.closest_hit_rays;
        self.light_pixel_evaluations += o.light_pixel_evaluations;
        self.vpl_pixel_evaluations += o.vpl_pixel_evaluations;
        self.kmeans_distance_evaluations += o.kmeans_distance_evaluations;
    }
}

/// The keys of [`WorkCounts::to_map`], in the order tables show them.
pub const WORK_KEYS: [&str; 12] = [
    "shaded_pixels",
    "depth_triangles",
    "shadow_texels_written",
    "shadow_lookups",
    "shadow_lookups_per_pixel",
    "filter_taps",
    "filter_taps_per_pixel",
    "shadow_rays",
    "closest_hit_rays",
    "light_pixel_evaluations",
    "vpl_pixel_evaluations",
    "kmeans_distance_evaluations",
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_map_has_every_key_and_the_means() {
        let w = WorkCounts { shadow_lookups: 30, filter_taps: 270, ..Default::default() };
        let m = w.to_map(10);
        assert_eq!(m.keys().count(), WORK_KEYS.len());
        assert!(WORK_KEYS.iter().all(|k| m.contains_key(*k)));
        assert_eq!(m["shadow_lookups_per_pixel"], 3.0);
        assert_eq!(m["filter_taps_per_pixel"], 27.0);
        assert_eq!(w.to_map(0)["filter_taps_per_pixel"], 0.0);
    }
}
