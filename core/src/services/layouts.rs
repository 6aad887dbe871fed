//! The bind-group layouts and formats every technique shares (the screen group of `common.wgsl`, materials,
//! camera, tile lists), and the full-screen and compute pipelines built over them.

use crate::accel::gpu_scene::GpuScene;
use crate::gpu::pipeline::create_module;
use crate::gpu::GpuContext;
use crate::services::light_tiles;

/// Bind group layouts and formats every technique uses.
pub struct SharedLayouts {
    /// Group 0 of full-screen passes: frame uniform + G-buffer (`common.wgsl`).
    pub screen: wgpu::BindGroupLayout,
    pub material: wgpu::BindGroupLayout,
    pub camera: wgpu::BindGroupLayout,
    /// Group 2 of shading passes that read tile lists (`light_tiles.wgsl`).
    pub light_tiles: wgpu::BindGroupLayout,
}

impl SharedLayouts {
    /// The HDR radiance target's format on `device`: `Rgba32Float` where the device can blend it
    /// (`FLOAT32_BLENDABLE`, requested whenever the adapter has it), else `Rgba16Float`. Every shading pass adds
    /// its batch of lights into this target, and an f16 target rounds each sum to 11 bits, so its image would
    /// depend on how the lights are batched (docs/techniques/reference.md); f32 keeps that below 1e-6.
    pub fn hdr_format(device: &wgpu::Device) -> wgpu::TextureFormat {
        if device.features().contains(wgpu::Features::FLOAT32_BLENDABLE) {
            wgpu::TextureFormat::Rgba32Float
        } else {
            wgpu::TextureFormat::Rgba16Float
        }
    }
    pub const OUTPUT_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
    pub const ALBEDO_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;
    pub const NORMAL_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
    pub const EMISSIVE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;
    pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

    pub(crate) fn new(device: &wgpu::Device) -> SharedLayouts {
        let tex = |binding, sample_type| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type,
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let uniform = |binding, visibility| wgpu::BindGroupLayoutEntry {
            binding,
            visibility,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let unfilterable = wgpu::TextureSampleType::Float { filterable: false };
        let screen = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("screen"),
            entries: &[
                uniform(0, wgpu::ShaderStages::VERTEX_FRAGMENT | wgpu::ShaderStages::COMPUTE),
                tex(1, unfilterable),
                tex(2, unfilterable),
                tex(3, unfilterable),
                // Depth bound as an unfilterable float texture: textureLoad on depth textures has no GLSL form.
                tex(4, unfilterable),
                // The work counters (services/work_counters.rs), written by shading passes.
                wgpu::BindGroupLayoutEntry {
                    binding: 5,
                    visibility: wgpu::ShaderStages::FRAGMENT | wgpu::ShaderStages::COMPUTE,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { read_only: false },
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let camera = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("camera"),
            entries: &[uniform(0, wgpu::ShaderStages::VERTEX)],
        });
        SharedLayouts {
            screen,
            material: GpuScene::material_layout(device),
            camera,
            light_tiles: light_tiles::read_layout(device),
        }
    }

    /// A full-screen pipeline: `common.wgsl`'s triangle, `fs_main` of `module`, groups `[screen, extra...]`,
    /// writing one `format` target, additive when `additive`.
    pub fn fullscreen_pipeline(
        &self,
        device: &wgpu::Device,
        label: &str,
        module: &wgpu::ShaderModule,
        extra_groups: &[&wgpu::BindGroupLayout],
        format: wgpu::TextureFormat,
        additive: bool,
    ) -> wgpu::RenderPipeline {
        let mut groups: Vec<Option<&wgpu::BindGroupLayout>> = vec![Some(&self.screen)];
        groups.extend(extra_groups.iter().map(|g| Some(*g)));
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(label),
            bind_group_layouts: &groups,
            immediate_size: 0,
        });
        let blend = additive.then_some(wgpu::BlendState {
            color: wgpu::BlendComponent {
                src_factor: wgpu::BlendFactor::One,
                dst_factor: wgpu::BlendFactor::One,
                operation: wgpu::BlendOperation::Add,
            },
            alpha: wgpu::BlendComponent::OVER,
        });
        device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(label),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module,
                entry_point: Some("fullscreen_vs"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: Default::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState { format, blend, write_mask: wgpu::ColorWrites::ALL })],
            }),
            multiview_mask: None,
            cache: None,
        })
    }
}

/// A compute pipeline over `[screen, extra...]` groups with entry point `entry`.
pub fn compute_pipeline(
    gpu: &GpuContext,
    layouts: &SharedLayouts,
    label: &str,
    source: &str,
    entry: &str,
    extra_groups: &[&wgpu::BindGroupLayout],
) -> wgpu::ComputePipeline {
    let device = &gpu.device;
    let module = create_module(device, label, source);
    let mut groups: Vec<Option<&wgpu::BindGroupLayout>> = vec![Some(&layouts.screen)];
    groups.extend(extra_groups.iter().map(|g| Some(*g)));
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &groups,
        immediate_size: 0,
    });
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(label),
        layout: Some(&layout),
        module: &module,
        entry_point: Some(entry),
        compilation_options: Default::default(),
        cache: None,
    })
}
