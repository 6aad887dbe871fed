//! What INSM shows and teaches: its overlay layers (the reference viewpoints, their frusta and sample points,
//! the reconstructed meshes), their legends, and the Explain steps of the paper.

use super::*;

impl Insm {
    pub(super) fn explain_steps(&self) -> Vec<crate::technique::ExplainStep> {
        use crate::technique::ExplainStep;
        vec![
            ExplainStep {
                title: "1. Viewpoints",
                text: "k reference viewpoints around (box) or inside (inside) the scene, or your own (custom); auto \
                       (the default) takes inside for an enclosed interior and box for an object.",
                layers: &["INSM viewpoints"],
                shows_shadow_maps: false,
                ..Default::default()
            },
            ExplainStep {
                title: "2. Intermediate depth images",
                text: "One depth image of the scene per viewpoint (insm_res²); each sample is a point on a surface. \
                       The Shadow maps panel shows the images.",
                layers: &["INSM viewpoints", "INSM samples"],
                shows_shadow_maps: true,
                maps: 1,
                ..Default::default()
            },
            ExplainStep {
                title: "3. Their meshes",
                text: "Each image is triangulated (Algorithm 2): two triangles per 2x2 neighbourhood, an edge dropped \
                       only where the second differences of depth show a step across it (ε; a tighter one where \
                       the surface is seen nearly edge-on). Red: dropped edges. Beyond the paper, \
                       planar blocks of 2x2 to 8x8 neighbourhoods become fans of a few triangles (adaptive, \
                       merge_block) and a map leaves out what another map reconstructs more finely (drop_covered). The Shadow maps panel shows the meshes seen from the viewpoints \
                       (mesh_views): against step 2's images, what the meshes kept, bridged or lost.",
                layers: &["INSM mesh (wireframe)", "INSM dropped edges"],
                // The meshes seen from the viewpoints (depth image set 2), to hold against step 2's images.
                shows_shadow_maps: true,
                maps: 2,
                params: &[("mesh_views", "on")],
            },
            ExplainStep {
                title: "4. Cube maps from the meshes",
                text: if self.params.simplify < 1.0 {
                    "Every light's cube shadow map is rendered from the meshes instead of the scene, here simplified \
                     first ('Mesh kept', beyond the paper: the green wireframe), culled per light and face in \
                     chunks (the Shadow maps panel shows the last batch's). The mesh stands for its surface only to \
                     about a sample, so beyond the paper each vertex is drawn push_samples widths of its own sample \
                     further from the light, and the lookup's bias is bias_samples mean widths: a mesh does not \
                     shadow the surface it stands for."
                } else {
                    "Every light's cube shadow map is rendered from the meshes instead of the scene, culled per \
                     light and face in tiles (the Shadow maps panel shows the last batch's). The mesh stands for \
                     its surface only to about a sample, so beyond the paper each vertex is drawn push_samples \
                     widths of its own sample further from the light, and the lookup's bias is bias_samples \
                     mean widths: a mesh does not shadow the surface it stands for."
                },
                layers: if self.params.simplify < 1.0 {
                    &["lights", "INSM simplified mesh (wireframe)"]
                } else {
                    &["lights"]
                },
                shows_shadow_maps: true,
                ..Default::default()
            },
            ExplainStep {
                title: "5. Final image",
                text: "Shaded as the reference; the only difference is the geometry in the cube maps (light leaks \
                       where thin geometry eroded).",
                layers: &[],
                shows_shadow_maps: false,
                ..Default::default()
            },
        ]
    }

    pub(super) fn legend_of(&self, layer: &OverlayLayer) -> Vec<crate::technique::LegendEntry> {
        use crate::technique::{Glyph, LegendEntry};
        let palette = crate::technique::index_color(0);
        let mut legend = match layer.name {
            "INSM viewpoints" => vec![
                LegendEntry::new(Glyph::Dot, [1.0, 0.85, 0.2, 1.0], "a viewpoint of an intermediate depth image"),
                LegendEntry::new(Glyph::Frustum, palette, "its frustum, one colour per viewpoint"),
            ],
            "INSM samples" => {
                vec![LegendEntry::new(Glyph::Palette, palette, "a depth sample, in its viewpoint's colour")]
            }
            "INSM mesh (wireframe)" => vec![LegendEntry::new(
                Glyph::Palette,
                palette,
                "edges of the mesh triangulated from the samples (Algorithm 2; planar blocks as fans)",
            )],
            "INSM merged blocks" => {
                let summary = "merged planar blocks: green 8x8, yellow 4x4, orange 2x2";
                let mut entries = vec![LegendEntry::new(Glyph::Line, block_color(8), summary)];
                entries.extend(
                    [
                        (8, "a whole 8x8 tile: 2 to 32 triangles instead of 128"),
                        (4, "a 4x4 quadrant: 2 to 16 instead of 32"),
                        (2, "a 2x2 block: 2 to 8 instead of 8"),
                    ]
                    .map(|(size, text)| LegendEntry::new(Glyph::Line, block_color(size), text)),
                );
                entries
            }
            "INSM simplified mesh (wireframe)" => vec![LegendEntry::new(
                Glyph::Line,
                [0.2, 1.0, 0.6, 0.9],
                "edges of the simplified meshes the per-light maps draw ('Mesh kept', beyond the paper)",
            )],
            "INSM dropped edges" => vec![LegendEntry::new(
                Glyph::Line,
                [1.0, 0.2, 0.2, 1.0],
                "edges dropped by the ε test: depth discontinuities",
            )],
            _ => crate::technique::light_layer_legend(layer).unwrap_or_default(),
        };
        legend.extend(layer.summary());
        legend
    }

    pub(super) fn overlay_layers(
        &self,
        lights: &[PointLight],
        shown: &dyn Fn(&str, bool) -> bool,
    ) -> Vec<OverlayLayer> {
        let mut layers = crate::technique::light_overlays(lights);
        let frustum_color = [1.0, 0.85, 0.2, 1.0];
        layers.push(OverlayLayer {
            name: "INSM viewpoints",
            visible_by_default: true,
            primitives: self
                .views
                .iter()
                .enumerate()
                .flat_map(|(i, v)| {
                    let color = crate::technique::index_color(i);
                    [
                        Overlay::Point { position: v.position, color: frustum_color, radius_px: 5.0 },
                        Overlay::Line { from: v.position, to: v.target, color: [color[0], color[1], color[2], 0.6] },
                    ]
                })
                .chain(self.views.iter().enumerate().map(|(i, v)| {
                    // Frusta drawn to an eighth of the scene's size: their far planes enclose the whole scene.
                    let (near, _) = v.depth_range(&self.bounds);
                    let depth = (self.bounds.size().length() * 0.125).max(near * 2.0);
                    Overlay::Frustum {
                        clip_from_world: v.clip_from_world_range(near, depth),
                        color: crate::technique::index_color(i),
                    }
                }))
                .collect(),
        });
        if let Some(layer) = &self.snapshot.simplified {
            // Named always, its lines copied only when shown (the app asks every UI frame).
            layers.push(if shown(layer.name, false) {
                layer.clone()
            } else {
                OverlayLayer { name: layer.name, visible_by_default: false, primitives: Vec::new() }
            });
        }
        if MESH_LAYERS.iter().any(|name| shown(name, false)) {
            layers.extend(self.snapshot.layers.get_or_init(|| self.snapshot.build_layers()).iter().cloned());
        } else if self.snapshot.source.is_some() {
            // Named for the layer list, not built: nothing is read back.
            layers.extend(MESH_LAYERS.iter().map(|&name| OverlayLayer {
                name,
                visible_by_default: false,
                primitives: Vec::new(),
            }));
        }
        for layer in &mut layers {
            if !shown(layer.name, layer.visible_by_default) {
                layer.primitives.clear();
            }
        }
        layers
    }
}

impl MeshSnapshot {
    /// Overlay layers of the reconstructed meshes: samples, wireframe and dropped edges, each capped.
    /// The samples, read back the first time they are asked for (empty when they cannot be).
    pub(super) fn samples(&self) -> &[Vec4] {
        self.samples.get_or_init(|| {
            let Some(s) = &self.source else { return Arc::default() };
            let read = || -> Result<Vec<Vec4>, GpuError> {
                s.gpu.check_lost()?;
                let mut encoder = s.gpu.device.create_command_encoder(&Default::default());
                encoder.copy_buffer_to_buffer(&s.vertices, 0, &s.readback, 0, s.bytes);
                s.gpu.queue.submit([encoder.finish()]);
                Ok(bytemuck::cast_slice(&map_read(&s.gpu, &s.readback, s.bytes)?).to_vec())
            };
            match read() {
                Ok(samples) => Arc::new(samples),
                Err(e) => {
                    log::warn!("INSM overlays: the samples could not be read back: {e}");
                    Arc::default()
                }
            }
        })
    }

    pub(super) fn build_layers(&self) -> Vec<OverlayLayer> {
        let snap = self;
        let mut layers = Vec::new();
        let samples = snap.samples();
        if samples.is_empty() || snap.resolution == 0 {
            return layers;
        }
        let r = snap.resolution as usize;
        let images: Vec<SampledImage> =
            samples.chunks(r * r).map(|s| SampledImage { resolution: snap.resolution, samples: s }).collect();

        // Point cloud of the valid samples, every `stride`-th.
        let valid: usize = images.iter().map(|i| i.valid_samples()).sum();
        let stride = valid.div_ceil(MAX_OVERLAY_POINTS).max(1);
        let points = samples
            .iter()
            .enumerate()
            .filter(|(_, s)| s.w > 0.0)
            .step_by(stride)
            .map(|(i, s)| Overlay::Point {
                position: s.truncate(),
                color: crate::technique::index_color(i / (r * r)),
                radius_px: 1.5,
            })
            .collect();
        layers.push(OverlayLayer { name: MESH_LAYERS[0], visible_by_default: false, primitives: points });

        // Wireframe of the reconstructed triangles (the CPU twin's mesh): every `stride`-th when large.
        let mut wire = Vec::new();
        let (meshes, blocks): (Vec<_>, Vec<_>) =
            triangulate::meshes_with_blocks(&images, &snap.views, &snap.settings).into_iter().unzip();
        let total: usize = meshes.iter().map(Vec::len).sum();
        let stride = total.div_ceil(MAX_WIREFRAME_TRIANGLES).max(1);
        for (j, (img, mesh)) in images.iter().zip(&meshes).enumerate() {
            let [cr, cg, cb, _] = crate::technique::index_color(j);
            let color = [cr, cg, cb, 0.8];
            for t in mesh.iter().step_by(stride) {
                let p = t.map(|i| img.samples[i as usize].truncate());
                wire.push(Overlay::Line { from: p[0], to: p[1], color });
                wire.push(Overlay::Line { from: p[1], to: p[2], color });
                wire.push(Overlay::Line { from: p[2], to: p[0], color });
            }
        }
        layers.push(OverlayLayer { name: MESH_LAYERS[1], visible_by_default: false, primitives: wire });

        // Dropped edges: the depth discontinuities, in red.
        let mut dropped: Vec<Overlay> = Vec::new();
        for img in &images {
            for e in img.dropped_edges(snap.settings.connectivity()) {
                if dropped.len() >= MAX_DROPPED_EDGES {
                    break;
                }
                dropped.push(Overlay::Line { from: e.from, to: e.to, color: [1.0, 0.1, 0.1, 1.0] });
            }
        }
        layers.push(OverlayLayer { name: MESH_LAYERS[2], visible_by_default: false, primitives: dropped });

        // The adaptive mesh's merged blocks, outlined by their size: what became fans of a few triangles.
        let total: usize = blocks.iter().map(Vec::len).sum();
        let stride = total.div_ceil(MAX_WIREFRAME_TRIANGLES).max(1);
        let mut outlines = Vec::new();
        for (img, leaves) in images.iter().zip(&blocks) {
            for &(u0, v0, size) in leaves.iter().step_by(stride) {
                let color = block_color(size);
                let p = |i: u32, j: u32| img.samples[((v0 + j) * snap.resolution + u0 + i) as usize].truncate();
                let corners = [p(0, 0), p(size, 0), p(size, size), p(0, size)];
                for k in 0..4 {
                    outlines.push(Overlay::Line { from: corners[k], to: corners[(k + 1) % 4], color });
                }
            }
        }
        layers.push(OverlayLayer { name: MESH_LAYERS[3], visible_by_default: false, primitives: outlines });
        layers
    }
}

/// The outline colour of a merged block of `size` neighbourhoods a side.
fn block_color(size: u32) -> [f32; 4] {
    match size {
        8.. => [0.2, 0.9, 0.4, 0.9],
        4 => [1.0, 0.85, 0.2, 0.9],
        _ => [1.0, 0.45, 0.1, 0.9],
    }
}
