//! The depth pipelines of [`CubeShadowRenderer`]: the per-face matrices' layout and buffer, the cube-map and
//! paraboloid depth pipelines (plain, pushed for INSM's meshes, alpha-tested for cut-out materials).

use super::{CubeGeometry, CubeShadowRenderer, TileScratch, MAX_CUBES_PER_BATCH, SHADOW_FORMAT};
use crate::gpu::GpuContext;
use crate::services::gpu_data::MatrixUniform;
use crate::shaders;

impl CubeShadowRenderer {
    pub(super) fn with_layout(gpu: &GpuContext, vertex_stride: u64, pushed: bool) -> CubeShadowRenderer {
        let device = &gpu.device;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cube face"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: true,
                    min_binding_size: wgpu::BufferSize::new(80),
                },
                count: None,
            }],
        });
        let faces = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("cube face matrices"),
            size: (MAX_CUBES_PER_BATCH * 6 * std::mem::size_of::<MatrixUniform>()) as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let faces_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("cube face matrices"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &faces,
                    offset: 0,
                    size: wgpu::BufferSize::new(80),
                }),
            }],
        });
        let module = crate::gpu::pipeline::create_module(device, "shadow_depth", shaders::SHADOW_DEPTH.source);
        let pipeline = if pushed {
            Self::depth_pipeline_with(
                device,
                &layout,
                None,
                &module,
                vertex_stride,
                "shadow depth (pushed)",
                false,
                true,
            )
        } else {
            Self::depth_pipeline(device, &layout, &module, vertex_stride, "shadow depth", false)
        };
        CubeShadowRenderer {
            pipeline,
            paraboloid_pipeline: None,
            masked_pipeline: None,
            paraboloid_masked_pipeline: None,
            faces_layout: layout,
            vertex_stride,
            faces,
            faces_bind_group,
            atlas: None,
            visible: Vec::new(),
            scratch: TileScratch::default(),
        }
    }

    pub(super) fn depth_pipeline(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        module: &wgpu::ShaderModule,
        vertex_stride: u64,
        label: &str,
        with_fragment: bool,
    ) -> wgpu::RenderPipeline {
        Self::depth_pipeline_with(device, layout, None, module, vertex_stride, label, with_fragment, false)
    }

    /// The depth pipeline; with `material` the alpha-tested variant (`vs_masked`/`fs_masked`, group 1 the
    /// material, the UVs at location 2); `pushed`: `vs_pushed` (the inverse depth at location 1, offset 12).
    #[allow(clippy::too_many_arguments)]
    fn depth_pipeline_with(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        material: Option<&wgpu::BindGroupLayout>,
        module: &wgpu::ShaderModule,
        vertex_stride: u64,
        label: &str,
        with_fragment: bool,
        pushed: bool,
    ) -> wgpu::RenderPipeline {
        let mut groups = vec![Some(layout)];
        groups.extend(material.map(Some));
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &groups,
            immediate_size: 0,
        });
        let masked = material.is_some();
        let attributes: &[wgpu::VertexAttribute] = if masked {
            &wgpu::vertex_attr_array![0 => Float32x3, 2 => Float32x2]
        } else if pushed {
            &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32]
        } else {
            &wgpu::vertex_attr_array![0 => Float32x3]
        };
        let offset = |location| match location {
            1 => 12,
            2 => 24,
            _ => 0,
        };
        let attributes: Vec<wgpu::VertexAttribute> =
            attributes.iter().map(|a| wgpu::VertexAttribute { offset: offset(a.shader_location), ..*a }).collect();
        let entry = if masked {
            "vs_masked"
        } else if pushed {
            "vs_pushed"
        } else {
            "vs_main"
        };
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&pipeline_layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: vertex_stride,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &attributes,
                })],
            },
            // No back-face culling: real scenes have single-sided walls that must still cast shadows.
            primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: SHADOW_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: Default::default(),
            // Depth-only; a fragment stage only where it must discard (paraboloids), as it costs early depth tests.
            fragment: (with_fragment || masked).then_some(wgpu::FragmentState {
                module,
                entry_point: Some(if masked { "fs_masked" } else { "fs_main" }),
                compilation_options: Default::default(),
                targets: &[],
            }),
            multiview_mask: None,
            cache: None,
        })
    }

    /// Create the alpha-tested pipelines when `geometry` has cut-out materials.
    pub(super) fn ensure_masked(&mut self, gpu: &GpuContext, geometry: &CubeGeometry<'_>, paraboloid: bool) {
        if !geometry.cutouts.is_some_and(|c| c.masked.iter().any(|&m| m)) {
            return;
        }
        let slot_empty =
            if paraboloid { self.paraboloid_masked_pipeline.is_none() } else { self.masked_pipeline.is_none() };
        if !slot_empty {
            return;
        }
        let material_layout = crate::accel::gpu_scene::GpuScene::material_layout(&gpu.device);
        let (label, source) = if paraboloid {
            ("paraboloid depth (alpha-tested)", shaders::PARABOLOID_DEPTH.source)
        } else {
            ("shadow depth (alpha-tested)", shaders::SHADOW_DEPTH.source)
        };
        let module = crate::gpu::pipeline::create_module(&gpu.device, label, source);
        let pipeline = Self::depth_pipeline_with(
            &gpu.device,
            &self.faces_layout,
            Some(&material_layout),
            &module,
            self.vertex_stride,
            label,
            true,
            false,
        );
        if paraboloid {
            self.paraboloid_masked_pipeline = Some(pipeline);
        } else {
            self.masked_pipeline = Some(pipeline);
        }
    }
}
