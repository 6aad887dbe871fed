//! Building a renderer: its targets, the G-buffer, ambient and tone-mapping pipelines, and the bind groups over
//! the frame targets.

use super::*;

impl Renderer {
    pub(super) fn with_scene(
        gpu: &GpuContext,
        gpu_scene: std::sync::Arc<GpuScene>,
        layouts: std::sync::Arc<SharedLayouts>,
        settings: RenderSettings,
    ) -> Result<Renderer, GpuError> {
        let device = &gpu.device;
        let targets = FrameTargets::new(gpu, settings.width, settings.height);
        let frame_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame"),
            size: std::mem::size_of::<FrameUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let camera_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("camera"),
            size: std::mem::size_of::<MatrixUniform>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let camera_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("camera"),
            layout: &layouts.camera,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: camera_uniform.as_entire_binding() }],
        });

        let gbuffer_module = crate::gpu::pipeline::create_module(device, "gbuffer", shaders::GBUFFER.source);
        let gbuffer_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("gbuffer"),
            bind_group_layouts: &[Some(&layouts.camera), Some(&layouts.material)],
            immediate_size: 0,
        });
        // Cut-out materials run `fs_main` (its alpha test discards); opaque ones `fs_opaque`, whose fragments a
        // rasterizer can reject by depth before shading them.
        let gbuffer_pipeline_with = |fragment_entry: &str| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("gbuffer"),
                layout: Some(&gbuffer_layout),
                vertex: wgpu::VertexState {
                    module: &gbuffer_module,
                    entry_point: Some("vs_main"),
                    compilation_options: Default::default(),
                    buffers: &[
                        Some(wgpu::VertexBufferLayout {
                            array_stride: std::mem::size_of::<crate::scene::chunks::Vertex>() as u64,
                            step_mode: wgpu::VertexStepMode::Vertex,
                            attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x2],
                        }),
                        // The second UV channel, a stream of its own (the depth passes never read it).
                        Some(wgpu::VertexBufferLayout {
                            array_stride: 8,
                            step_mode: wgpu::VertexStepMode::Vertex,
                            attributes: &wgpu::vertex_attr_array![3 => Float32x2],
                        }),
                    ],
                },
                primitive: wgpu::PrimitiveState { cull_mode: None, ..Default::default() },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: SharedLayouts::DEPTH_FORMAT,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &gbuffer_module,
                    entry_point: Some(fragment_entry),
                    compilation_options: Default::default(),
                    targets: &[
                        Some(SharedLayouts::ALBEDO_FORMAT.into()),
                        Some(SharedLayouts::NORMAL_FORMAT.into()),
                        Some(SharedLayouts::EMISSIVE_FORMAT.into()),
                    ],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let gbuffer_pipeline = gbuffer_pipeline_with("fs_main");
        let gbuffer_opaque_pipeline = gbuffer_pipeline_with("fs_opaque");
        let ambient_module = crate::gpu::pipeline::create_module(device, "ambient", shaders::AMBIENT.source);
        let ambient_pipeline = layouts.fullscreen_pipeline(
            device,
            "ambient",
            &ambient_module,
            &[],
            SharedLayouts::hdr_format(device),
            false,
        );
        let tonemap_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("tonemap"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Texture {
                        sample_type: wgpu::TextureSampleType::Float { filterable: false },
                        view_dimension: wgpu::TextureViewDimension::D2,
                        multisampled: false,
                    },
                    count: None,
                },
                crate::gpu::bind::storage_entry(1),
                crate::gpu::bind::storage_entry(2),
            ],
        });
        let tonemap_module = crate::gpu::pipeline::create_module(device, "tonemap", shaders::TONEMAP.source);
        let tonemap_pipeline = layouts.fullscreen_pipeline(
            device,
            "tonemap",
            &tonemap_module,
            &[&tonemap_layout],
            SharedLayouts::OUTPUT_FORMAT,
            false,
        );
        let work_counters = work_counters::WorkCounters::new(device);
        let directional = directional::DirectionalLights::new(gpu, &layouts, &gpu_scene.directional);
        let screen_bind_group = Self::screen_bind_group(device, &layouts, &frame_uniform, &targets, &work_counters);
        let indirect_buffer = create_indirect_buffer(gpu, settings.width, settings.height, false)?;
        let exposure = exposure::ExposureMeter::new(gpu, &layouts, &targets, &indirect_buffer);
        let tonemap_bind_group =
            Self::tonemap_bind_group(device, &tonemap_layout, &targets, &indirect_buffer, &exposure.result);
        let timer = PassTimer::new(gpu)?;
        let light_tiles = light_tiles::TileLists::new(gpu, &layouts.screen, &layouts.light_tiles);
        Ok(Renderer {
            gpu: gpu.clone(),
            layouts,
            settings,
            scene: gpu_scene,
            targets,
            frame_uniform,
            camera_uniform,
            camera_bind_group,
            screen_bind_group,
            gbuffer_pipeline,
            gbuffer_opaque_pipeline,
            ambient_pipeline,
            tonemap_pipeline,
            tonemap_layout,
            tonemap_bind_group,
            exposure,
            timer,
            draw_ranges: Vec::new(),
            overlay: None,
            overlay_style: Default::default(),
            indirect: None,
            indirect_buffer,
            vpls: VplFrame {
                set: Default::default(),
                buffer: crate::gpu::buffer::GrowableBuffer::new(device, "vpls", 48 * 64),
                key: None,
            },
            fixed_vpls: false,
            visible_lights: lights::VisibleLights::new(gpu),
            light_tiles,
            light_spheres: Vec::new(),
            work_counters,
            directional,
        })
    }

    pub(super) fn screen_bind_group(
        device: &wgpu::Device,
        layouts: &SharedLayouts,
        frame_uniform: &wgpu::Buffer,
        t: &FrameTargets,
        work: &work_counters::WorkCounters,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("screen"),
            layout: &layouts.screen,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: frame_uniform.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::TextureView(&t.albedo) },
                wgpu::BindGroupEntry { binding: 2, resource: wgpu::BindingResource::TextureView(&t.normal) },
                wgpu::BindGroupEntry { binding: 3, resource: wgpu::BindingResource::TextureView(&t.emissive) },
                wgpu::BindGroupEntry { binding: 4, resource: wgpu::BindingResource::TextureView(&t.depth) },
                wgpu::BindGroupEntry { binding: 5, resource: work.buffer.as_entire_binding() },
            ],
        })
    }

    pub(super) fn tonemap_bind_group(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        t: &FrameTargets,
        indirect: &wgpu::Buffer,
        exposure: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("tonemap"),
            layout,
            entries: &[
                wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&t.hdr) },
                wgpu::BindGroupEntry { binding: 1, resource: indirect.as_entire_binding() },
                wgpu::BindGroupEntry { binding: 2, resource: exposure.as_entire_binding() },
            ],
        })
    }
}
