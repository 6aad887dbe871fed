//! Drawing a technique's overlay primitives ([`crate::contract::overlay::Overlay`]) over the tone-mapped output:
//! lines for segments, wireframe spheres (three great circles) and camera frusta, each segment a screen-space
//! quad of [`OverlayStyle::line_width_px`]; screen-sized round dots for points. Depth-tested against the G-buffer
//! depth with the occluded parts drawn faded ([`OverlayStyle::occluded_alpha`]), or drawn on top in x-ray mode.

use glam::{Mat4, Vec3, Vec4};
use wgpu::util::DeviceExt;

use super::layouts::SharedLayouts;
use crate::contract::overlay::{index_color, Overlay, MAX_FULL_SPHERES, MAX_SPHERES};
use crate::gpu::GpuContext;
use crate::shaders;

/// Mirrors `View` in `overlay.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct OverlayUniform {
    clip_from_world: [[f32; 4]; 4],
    viewport: [f32; 4],
    /// line width in pixels, alpha factor of occluded parts, unused, unused
    style: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<OverlayUniform>() == 96);

/// How overlays look, in the render target's pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OverlayStyle {
    /// Width of lines (segments, sphere circles, frusta) in pixels of the render target.
    pub line_width_px: f32,
    /// Alpha factor of the parts hidden behind the scene's surfaces (depth-tested mode; 0 hides them).
    pub occluded_alpha: f32,
}

impl Default for OverlayStyle {
    fn default() -> Self {
        OverlayStyle { line_width_px: 1.5, occluded_alpha: 0.25 }
    }
}

/// One line segment, drawn as an instanced quad of six vertices. Mirrors `SegmentIn` in `overlay.wgsl`.
#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct LineVertex {
    a: [f32; 3],
    b: [f32; 3],
    color: [f32; 4],
}
const _: () = assert!(std::mem::size_of::<LineVertex>() == 40);

#[repr(C)]
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
struct DotVertex {
    center: [f32; 3],
    corner_px: [f32; 2],
    color: [f32; 4],
}

/// Segments per circle of a wireframe sphere.
const CIRCLE_SEGMENTS: usize = 48;
/// Segments of the one horizontal circle a sphere is drawn as above [`MAX_FULL_SPHERES`].
const CHEAP_SEGMENTS: usize = 6;

pub struct OverlayRenderer {
    uniform: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
    /// [depth tested, x-ray, occluded parts faded]
    line_pipelines: [wgpu::RenderPipeline; 3],
    dot_pipelines: [wgpu::RenderPipeline; 3],
    idmap_pipeline: wgpu::RenderPipeline,
    idmap_layout: wgpu::BindGroupLayout,
    /// The last primitives and what they became on the GPU: the app draws the same overlays every UI frame, and
    /// they are tessellated and uploaded again only when they change.
    cache: Option<Uploaded>,
    /// How many times primitives were tessellated and uploaded (for tests and the timings panel).
    pub uploads: u64,
}

/// Primitives tessellated and uploaded: vertex buffers of lines and dots, ID-map textures.
struct Uploaded {
    primitives: Vec<Overlay>,
    lines: Option<(wgpu::Buffer, u32)>,
    dots: Option<(wgpu::Buffer, u32)>,
    id_maps: Vec<wgpu::BindGroup>,
}

/// Colour an ID map on the CPU: a distinct colour per ID at `alpha`, transparent where there is no ID.
fn colorize_ids(ids: &[u32], alpha: f32) -> Vec<u8> {
    ids.iter()
        .flat_map(|&id| {
            if id == u32::MAX {
                [0, 0, 0, 0]
            } else {
                let c = index_color(id as usize);
                [
                    (c[0] * 255.0) as u8,
                    (c[1] * 255.0) as u8,
                    (c[2] * 255.0) as u8,
                    (alpha.clamp(0.0, 1.0) * 255.0) as u8,
                ]
            }
        })
        .collect()
}

/// Segments (one per line) and dot triangles for a set of primitives.
fn tessellate(primitives: &[Overlay], lines: &mut Vec<LineVertex>, dots: &mut Vec<DotVertex>) {
    let spheres = primitives.iter().filter(|p| matches!(p, Overlay::Sphere { .. })).count();
    let cheap = spheres > MAX_FULL_SPHERES;
    let mut spheres_drawn = 0usize;
    let mut seg = |a: Vec3, b: Vec3, color: [f32; 4]| {
        if a.is_finite() && b.is_finite() {
            lines.push(LineVertex { a: a.to_array(), b: b.to_array(), color });
        }
    };
    for p in primitives {
        match p {
            Overlay::Line { from, to, color } => seg(*from, *to, *color),
            Overlay::Sphere { center, radius, color } => {
                spheres_drawn += 1;
                if spheres_drawn > MAX_SPHERES {
                    continue;
                }
                let (axes, segments) = if cheap { (1, CHEAP_SEGMENTS) } else { (3, CIRCLE_SEGMENTS) };
                for axis in 0..axes {
                    let point = |i: usize| {
                        let a = i as f32 / segments as f32 * std::f32::consts::TAU;
                        let (s, c) = a.sin_cos();
                        // The cheap form keeps the horizontal circle (axis 1): a range seen from above reads best.
                        let v = match if cheap { 1 } else { axis } {
                            0 => Vec3::new(c, s, 0.0),
                            1 => Vec3::new(c, 0.0, s),
                            _ => Vec3::new(0.0, c, s),
                        };
                        *center + v * *radius
                    };
                    for i in 0..segments {
                        seg(point(i), point(i + 1), *color);
                    }
                }
            }
            Overlay::Frustum { clip_from_world, color } => {
                let world_from_clip = clip_from_world.inverse();
                let corner = |x: f32, y: f32, z: f32| {
                    let p = world_from_clip * Vec4::new(x, y, z, 1.0);
                    p.truncate() / p.w
                };
                let c: Vec<Vec3> = [(-1., -1.), (1., -1.), (1., 1.), (-1., 1.)]
                    .iter()
                    .flat_map(|&(x, y)| [corner(x, y, 0.0), corner(x, y, 1.0)])
                    .collect();
                for i in 0..4 {
                    let j = (i + 1) % 4;
                    seg(c[2 * i], c[2 * j], *color);
                    seg(c[2 * i + 1], c[2 * j + 1], *color);
                    seg(c[2 * i], c[2 * i + 1], *color);
                }
            }
            Overlay::Rect { center, half_u, half_v, color } => {
                let c = [
                    *center - *half_u - *half_v,
                    *center + *half_u - *half_v,
                    *center + *half_u + *half_v,
                    *center - *half_u + *half_v,
                ];
                for i in 0..4 {
                    seg(c[i], c[(i + 1) % 4], *color);
                }
            }
            // Drawn as a texture, not as lines or dots.
            Overlay::IdMap { .. } | Overlay::ColorMap { .. } => {}
            Overlay::Point { position, color, radius_px } => {
                if !position.is_finite() {
                    continue;
                }
                let r = radius_px.clamp(0.5, 64.0);
                for (x, y) in [(-r, -r), (r, -r), (r, r), (-r, -r), (r, r), (-r, r)] {
                    dots.push(DotVertex { center: position.to_array(), corner_px: [x, y], color: *color });
                }
            }
        }
    }
}

impl OverlayRenderer {
    pub fn new(gpu: &GpuContext) -> OverlayRenderer {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("overlay"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("overlay view"),
            contents: bytemuck::bytes_of(&<OverlayUniform as bytemuck::Zeroable>::zeroed()),
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("overlay"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: uniform.as_entire_binding() }],
        });
        let module = crate::gpu::pipeline::create_module(device, "overlay", shaders::OVERLAY.source);
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("overlay"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let idmap_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("overlay id map"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let idmap_pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("overlay id map"),
            bind_group_layouts: &[Some(&layout), Some(&idmap_layout)],
            immediate_size: 0,
        });
        let idmap_pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("overlay id map"),
            layout: Some(&idmap_pipeline_layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("idmap_vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: Some(wgpu::DepthStencilState {
                format: SharedLayouts::DEPTH_FORMAT,
                depth_write_enabled: Some(false),
                depth_compare: Some(wgpu::CompareFunction::Always),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("idmap_fs"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: SharedLayouts::OUTPUT_FORMAT,
                    blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        let make = |vs: &str, fs: &str, topology, buffer: wgpu::VertexBufferLayout, depth_compare| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("overlay"),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers: &[Some(buffer)],
                },
                primitive: wgpu::PrimitiveState { topology, ..Default::default() },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: SharedLayouts::DEPTH_FORMAT,
                    depth_write_enabled: Some(false),
                    depth_compare: Some(depth_compare),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: SharedLayouts::OUTPUT_FORMAT,
                        blend: Some(wgpu::BlendState::ALPHA_BLENDING),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        const LINE_ATTRIBUTES: [wgpu::VertexAttribute; 3] =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x4];
        const DOT_ATTRIBUTES: [wgpu::VertexAttribute; 3] =
            wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x2, 2 => Float32x4];
        let line_layout = || wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<LineVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Instance,
            attributes: &LINE_ATTRIBUTES,
        };
        let dot_layout = || wgpu::VertexBufferLayout {
            array_stride: std::mem::size_of::<DotVertex>() as u64,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &DOT_ATTRIBUTES,
        };
        let tris = wgpu::PrimitiveTopology::TriangleList;
        use wgpu::CompareFunction::{Always, Greater, LessEqual};
        OverlayRenderer {
            uniform,
            bind_group,
            line_pipelines: [
                make("line_vs", "line_fs", tris, line_layout(), LessEqual),
                make("line_vs", "line_fs", tris, line_layout(), Always),
                make("line_vs", "line_faded_fs", tris, line_layout(), Greater),
            ],
            dot_pipelines: [
                make("dot_vs", "dot_fs", tris, dot_layout(), LessEqual),
                make("dot_vs", "dot_fs", tris, dot_layout(), Always),
                make("dot_vs", "dot_faded_fs", tris, dot_layout(), Greater),
            ],
            idmap_pipeline,
            idmap_layout,
            cache: None,
            uploads: 0,
        }
    }

    /// Tessellate `primitives` and upload them: line and dot vertex buffers, a texture per ID or colour map.
    fn upload(&self, gpu: &GpuContext, primitives: &[Overlay]) -> Uploaded {
        let mut lines = Vec::new();
        let mut dots = Vec::new();
        tessellate(primitives, &mut lines, &mut dots);
        // ID maps become textures, drawn first (under the lines and dots).
        let id_maps: Vec<wgpu::BindGroup> = primitives
            .iter()
            .filter_map(|p| {
                let (width, height, pixels) = match p {
                    Overlay::IdMap { width, height, ids, alpha }
                        if *width > 0 && *height > 0 && ids.len() == (*width as usize) * (*height as usize) =>
                    {
                        (width, height, colorize_ids(ids, *alpha))
                    }
                    Overlay::ColorMap { width, height, rgba }
                        if *width > 0 && *height > 0 && rgba.len() == (*width as usize) * (*height as usize) =>
                    {
                        (width, height, bytemuck::cast_slice(rgba.as_slice()).to_vec())
                    }
                    _ => return None,
                };
                let texture = gpu.device.create_texture_with_data(
                    &gpu.queue,
                    &wgpu::TextureDescriptor {
                        label: Some("id map"),
                        size: wgpu::Extent3d { width: *width, height: *height, depth_or_array_layers: 1 },
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format: wgpu::TextureFormat::Rgba8Unorm,
                        usage: wgpu::TextureUsages::TEXTURE_BINDING,
                        view_formats: &[],
                    },
                    wgpu::util::TextureDataOrder::LayerMajor,
                    &pixels,
                );
                let view = texture.create_view(&Default::default());
                Some(gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("id map"),
                    layout: &self.idmap_layout,
                    entries: &[wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&view),
                    }],
                }))
            })
            .collect();
        let buffer = |data: &[u8]| {
            gpu.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("overlay vertices"),
                contents: data,
                usage: wgpu::BufferUsages::VERTEX,
            })
        };
        Uploaded {
            primitives: primitives.to_vec(),
            lines: (!lines.is_empty()).then(|| (buffer(bytemuck::cast_slice(&lines)), lines.len() as u32)),
            dots: (!dots.is_empty()).then(|| (buffer(bytemuck::cast_slice(&dots)), dots.len() as u32)),
            id_maps,
        }
    }

    /// Draw `primitives` over `output` (the tone-mapped target) using `depth` (the G-buffer depth).
    #[allow(clippy::too_many_arguments)]
    pub fn draw(
        &mut self,
        gpu: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        output: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        clip_from_world: Mat4,
        size: (u32, u32),
        primitives: &[Overlay],
        x_ray: bool,
        style: OverlayStyle,
    ) {
        // Equal primitives (ID maps compare by pointer first) reuse last time's buffers and textures.
        if self.cache.as_ref().is_none_or(|c| c.primitives.as_slice() != primitives) {
            self.cache = Some(self.upload(gpu, primitives));
            self.uploads += 1;
        }
        let Some(cache) = &self.cache else { return };
        if cache.lines.is_none() && cache.dots.is_none() && cache.id_maps.is_empty() {
            return;
        }
        let (w, h) = (size.0 as f32, size.1 as f32);
        let uniform = OverlayUniform {
            clip_from_world: clip_from_world.to_cols_array_2d(),
            viewport: [w, h, 1.0 / w, 1.0 / h],
            style: [style.line_width_px.clamp(0.5, 16.0), style.occluded_alpha.clamp(0.0, 1.0), 0.0, 0.0],
        };
        gpu.queue.write_buffer(&self.uniform, 0, bytemuck::bytes_of(&uniform));
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("overlays"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: output,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations { load: wgpu::LoadOp::Load, store: wgpu::StoreOp::Store }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        // X-ray: everything on top. Otherwise the occluded parts faded first, then the visible ones.
        let passes: &[usize] = if x_ray {
            &[1]
        } else if style.occluded_alpha > 0.0 {
            &[2, 0]
        } else {
            &[0]
        };
        pass.set_bind_group(0, &self.bind_group, &[]);
        for group in &cache.id_maps {
            pass.set_pipeline(&self.idmap_pipeline);
            pass.set_bind_group(1, group, &[]);
            pass.draw(0..3, 0..1);
        }
        for &i in passes {
            if let Some((b, n)) = &cache.lines {
                pass.set_pipeline(&self.line_pipelines[i]);
                pass.set_vertex_buffer(0, b.slice(..));
                pass.draw(0..6, 0..*n);
            }
            if let Some((b, n)) = &cache.dots {
                pass.set_pipeline(&self.dot_pipelines[i]);
                pass.set_vertex_buffer(0, b.slice(..));
                pass.draw(0..*n, 0..1);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn primitives_tessellate_to_the_expected_vertex_counts() {
        let (mut lines, mut dots) = (Vec::new(), Vec::new());
        let c = [1.0; 4];
        tessellate(
            &[
                Overlay::Line { from: Vec3::ZERO, to: Vec3::X, color: c },
                Overlay::Sphere { center: Vec3::ZERO, radius: 1.0, color: c },
                Overlay::Frustum { clip_from_world: Mat4::IDENTITY, color: c },
                Overlay::Point { position: Vec3::Y, color: c, radius_px: 3.0 },
                Overlay::Point { position: Vec3::NAN, color: c, radius_px: 3.0 },
                Overlay::Rect { center: Vec3::ZERO, half_u: Vec3::X, half_v: Vec3::Y, color: c },
                Overlay::IdMap { width: 2, height: 1, ids: std::sync::Arc::new(vec![0, u32::MAX]), alpha: 0.5 },
            ],
            &mut lines,
            &mut dots,
        );
        assert_eq!(lines.len(), 1 + 3 * CIRCLE_SEGMENTS + 12 + 4, "one instance per segment");
        assert_eq!(dots.len(), 6, "a NaN point is skipped");
        let colored = colorize_ids(&[0, u32::MAX, 1], 0.5);
        assert_eq!(colored.len(), 12);
        assert_eq!(colored[7], 0, "no ID is transparent");
        assert_eq!(colored[3], 127);
        assert_ne!(colored[0..3], colored[8..11], "two IDs, two colours");
        // Sphere points lie on the sphere.
        for v in &lines[1..1 + 3 * CIRCLE_SEGMENTS] {
            assert!((Vec3::from_array(v.a).length() - 1.0).abs() < 1e-5);
            assert!((Vec3::from_array(v.b).length() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn a_hundred_thousand_range_spheres_stay_within_a_vertex_budget() {
        let c = [1.0; 4];
        let spheres: Vec<Overlay> =
            (0..100_000).map(|i| Overlay::Sphere { center: Vec3::splat(i as f32), radius: 1.0, color: c }).collect();
        let (mut lines, mut dots) = (Vec::new(), Vec::new());
        tessellate(&spheres, &mut lines, &mut dots);
        assert_eq!(lines.len(), MAX_SPHERES * CHEAP_SEGMENTS);
        // About 8 MB of segments instead of ~600 MB.
        assert!(lines.len() * std::mem::size_of::<LineVertex>() < 16 << 20);
        // Few spheres keep their full form.
        let (mut few, mut d) = (Vec::new(), Vec::new());
        tessellate(&spheres[..10], &mut few, &mut d);
        assert_eq!(few.len(), 10 * 3 * CIRCLE_SEGMENTS);
    }
}
