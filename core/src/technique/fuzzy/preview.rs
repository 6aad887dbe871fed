//! The shading-point clusters of a moving camera, for the overlays (the app's preview while the camera moves).
//!
//! A frame clusters the shading points of its G-buffer on the GPU; the preview renders none. So while the
//! camera moves, [`FuzzyClustering::follow_view`] runs Algorithms 1 and 2 again on the CPU twin
//! ([`kmeans::cluster`]) over a coarse grid of the moved camera's pixels (at most [`PREVIEW_POINTS`]): each grid
//! pixel's shading point is the first surface its central ray meets in the scene's BVH (the surface the
//! G-buffer holds there, with the triangle's geometric normal for the interpolated one), `K_sp` the frame's,
//! `gamma` scaled down with the grid. The per-pixel maps are the grid's, stretched over the view; the
//! centroids and clusters are the CPU run's, and the probe (Alt+click) shows its pixel's clusters there with their
//! rays to the lights. The frame's own assignment is left alone.

use glam::{Vec2, Vec3};

use super::gpu::GpuPoint;
use super::{kmeans, ClusterMode, FuzzyClustering, MAX_F};
use crate::scene::Camera;

/// Most shading points the preview clusters on the CPU in a UI frame.
pub(super) const PREVIEW_POINTS: u32 = 4096;

/// The grid the preview clusters for a frame of `w x h` pixels: the frame's aspect, at most [`PREVIEW_POINTS`]
/// points, and the factor it is coarser by.
pub(super) fn preview_grid(w: u32, h: u32) -> (u32, u32, u32) {
    let s = ((w as f64 * h as f64 / PREVIEW_POINTS as f64).sqrt().ceil() as u32).max(1);
    (w.div_ceil(s), h.div_ceil(s), s)
}

/// The first surface through the centre of pixel `(x, y)` of a `w x h` image seen by `camera`.
fn shading_point(
    bvh: &crate::accel::scene_bvh::SceneBvh,
    camera: &Camera,
    w: u32,
    h: u32,
    x: u32,
    y: u32,
) -> kmeans::Point {
    let world_from_clip = camera.clip_from_world(w as f32 / h as f32).inverse();
    let ndc = Vec2::new((x as f32 + 0.5) / w as f32 * 2.0 - 1.0, 1.0 - (y as f32 + 0.5) / h as f32 * 2.0);
    // Two points of the pixel's ray, whatever the depth convention.
    let (a, b) = (world_from_clip.project_point3(ndc.extend(0.25)), world_from_clip.project_point3(ndc.extend(0.75)));
    let miss = kmeans::Point { position: Vec3::ZERO, normal: Vec3::Z, valid: false };
    let Some(dir) = (b - a).try_normalize().map(|d| if d.dot(camera.forward()) < 0.0 { -d } else { d }) else {
        return miss;
    };
    match bvh.closest_hit(camera.position, dir, camera.z_far) {
        Some(hit) => kmeans::Point { position: hit.position, normal: hit.normal, valid: true },
        None => miss,
    }
}

impl FuzzyClustering {
    /// The shading-point clusters of `ctx`'s camera on the CPU (see the module's text), into the inspection's
    /// centroids, clusters and per-pixel maps; the legend's note, or None where there is nothing to follow (no
    /// frame yet, the shading points not clustered, inspection off).
    pub(super) fn follow_view(&mut self, ctx: &crate::technique::OverlayContext) -> Option<String> {
        let (w, h) = self.inspection.size;
        let bvh = self.bvh.clone()?;
        if !self.params.inspect || self.params.cluster_mode() == ClusterMode::Vpls || w == 0 || h == 0 {
            return None;
        }
        let (pw, ph, s) = preview_grid(w, h);
        let note = format!("shading points from a {pw}x{ph} grid of rays on the CPU (the frame's: {w}x{h})");
        let followed = |(camera, vpls): &(Camera, std::sync::Arc<crate::vpl::VplSet>)| {
            camera == ctx.camera && std::sync::Arc::ptr_eq(vpls, &self.vpls)
        };
        if self.followed_view.as_ref().is_some_and(followed) {
            return Some(note);
        }
        let points: Vec<kmeans::Point> = (0..ph)
            .flat_map(|y| (0..pw).map(move |x| (x, y)))
            .map(|(x, y)| shading_point(&bvh, ctx.camera, pw, ph, x, y))
            .collect();
        let f = (self.params.fuzziness as usize).clamp(1, MAX_F);
        let gamma = (self.params.gamma as f32 / s as f32).round().max(1.0) as u32;
        let kp =
            self.kmeans_params(ctx.scene_bounds, self.params.sp_clusters(w as usize * h as usize), pw, ph, gamma, f);
        let c = kmeans::cluster(&points, &kp);
        let ins = &mut self.inspection;
        ins.sp_centroids = c
            .centroids
            .iter()
            .zip(&c.members)
            .map(|(centroid, &members)| GpuPoint {
                position: centroid.position.extend(if members > 0 { 1.0 } else { 0.0 }).to_array(),
                normal: centroid.normal.extend(members as f32).to_array(),
                flux: [0.0; 4],
            })
            .collect();
        // As a frame's clusters: the representative's position, the members' mean normal and count.
        ins.sp_clusters = (0..c.centroids.len())
            .map(|k| match c.representative[k] {
                Some(r) if c.members[k] > 0 => GpuPoint {
                    position: points[r as usize].position.extend(1.0).to_array(),
                    normal: c.member_normal[k].extend(c.members[k] as f32).to_array(),
                    flux: [0.0; 4],
                },
                _ => GpuPoint { normal: [0.0, 0.0, 1.0, 0.0], ..Default::default() },
            })
            .collect();
        let mode = self.params.shade_mode();
        let (hard, blend) = super::overlays::pixel_maps(mode, c.fuzziness, &c.assignment, &c.inverse_distance);
        ins.map_size = (pw, ph);
        ins.hard_map = Some(std::sync::Arc::new(hard));
        ins.blend_map = Some(std::sync::Arc::new(blend));
        // The probe: the frame's pixel in the grid, its F clusters, rays to the lights the frame would trace to.
        let (x, y) = (self.params.probe_x, self.params.probe_y);
        if x >= 0 && y >= 0 && (x as u32) < w && (y as u32) < h {
            let m = (y as u32 / s).min(ph - 1) as usize * pw as usize + (x as u32 / s).min(pw - 1) as usize;
            let entries = c.assignment[m * c.fuzziness..(m + 1) * c.fuzziness].to_vec();
            let lights: Vec<GpuPoint> = match self.params.cluster_mode() {
                ClusterMode::ShadingPoints => self.vpls.vpls.iter().map(GpuPoint::of_vpl).collect(),
                _ => self.inspection.vpl_clusters.clone(),
            };
            let probe = self.probe_rays(ctx.camera.position, &entries, &self.inspection.sp_clusters, &lights);
            self.inspection.probe = probe;
        }
        self.followed_view = Some((*ctx.camera, self.vpls.clone()));
        Some(note)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_preview_grid_keeps_the_aspect_within_its_budget() {
        assert_eq!(preview_grid(64, 48), (64, 48, 1), "small frames: every pixel");
        let (pw, ph, s) = preview_grid(1024, 720);
        assert!(pw * ph <= PREVIEW_POINTS && pw * ph > PREVIEW_POINTS / 2, "{pw}x{ph}");
        assert_eq!((s, pw, ph), (14, 74, 52));
        assert_eq!(preview_grid(1, 10_000).0, 1);
    }
}
