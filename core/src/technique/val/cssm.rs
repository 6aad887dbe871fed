//! Convolution soft shadow maps (Annen et al. 2008) as Dong et al. 2009 use them (section 4.1, 6): from the
//! VALs' paraboloid depth atlas, the Fourier basis textures of the depth test (4 terms, 8 bit) and the basis-z
//! textures (16-bit float), then a mip chain of each (`val/cssm.wgsl`); `val/gather.wgsl` filters them with
//! one trilinear lookup per texture for the blocker search and one for the penumbra kernel.
//!
//! Textures are the atlas's size; the chain stops where a tile's side is no longer even (a power-of-two tile
//! of 256 has 9 levels), so a mip texel never mixes two VALs' maps.

use crate::error::GpuError;
use crate::gpu::GpuContext;
use crate::services::cube_shadows::CubeAtlas;
use crate::timing::PassTimer;

/// Its WGSL module (listed by the technique's `SHADERS`).
pub const CSSM: crate::shaders::WgslModule = crate::shaders::wgsl!("val_cssm", ["core/src/technique/val/cssm.wgsl"]);

const FORMATS: [wgpu::TextureFormat; 4] = [
    wgpu::TextureFormat::Rgba8Unorm,
    wgpu::TextureFormat::Rgba8Unorm,
    wgpu::TextureFormat::Rgba16Float,
    wgpu::TextureFormat::Rgba16Float,
];

/// A filterable float texture binding for compute and fragment stages.
pub fn filterable_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

fn storage_entry(binding: u32, format: wgpu::TextureFormat) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::StorageTexture {
            access: wgpu::StorageTextureAccess::WriteOnly,
            format,
            view_dimension: wgpu::TextureViewDimension::D2,
        },
        count: None,
    }
}

struct Textures {
    size: (u32, u32),
    levels: u32,
    textures: Vec<wgpu::Texture>,
    /// All levels, for sampling.
    full: Vec<wgpu::TextureView>,
}

pub struct Cssm {
    basis_layout: wgpu::BindGroupLayout,
    mip_layout: wgpu::BindGroupLayout,
    basis: wgpu::ComputePipeline,
    mip: wgpu::ComputePipeline,
    pub sampler: wgpu::Sampler,
    textures: Option<Textures>,
    /// 1x1 stand-ins bound when CSSM is off.
    dummy: Vec<wgpu::TextureView>,
}

impl Cssm {
    pub fn new(gpu: &GpuContext) -> Cssm {
        let device = &gpu.device;
        let storage: Vec<wgpu::BindGroupLayoutEntry> =
            FORMATS.iter().enumerate().map(|(i, f)| storage_entry(1 + i as u32, *f)).collect();
        let mut basis_entries = vec![crate::gpu::bind::depth_texture_entry(0)];
        basis_entries.extend(storage.iter().cloned());
        let basis_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cssm basis"),
            entries: &basis_entries,
        });
        let mut mip_entries = storage.clone();
        mip_entries.extend((0..4).map(|i| wgpu::BindGroupLayoutEntry {
            binding: 5 + i,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: false },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        }));
        let mip_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cssm mip"),
            entries: &mip_entries,
        });
        let module = crate::gpu::pipeline::create_module(device, "val_cssm", CSSM.source);
        let pipeline = |layout: &wgpu::BindGroupLayout, entry: &str| {
            let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(entry),
                bind_group_layouts: &[Some(layout)],
                immediate_size: 0,
            });
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(entry),
                layout: Some(&pl),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        let basis = pipeline(&basis_layout, "cssm_basis");
        let mip = pipeline(&mip_layout, "cssm_mip");
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("cssm"),
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            ..Default::default()
        });
        let dummy = FORMATS
            .iter()
            .map(|f| {
                device
                    .create_texture(&wgpu::TextureDescriptor {
                        label: Some("cssm off"),
                        size: wgpu::Extent3d { width: 1, height: 1, depth_or_array_layers: 1 },
                        mip_level_count: 1,
                        sample_count: 1,
                        dimension: wgpu::TextureDimension::D2,
                        format: *f,
                        usage: wgpu::TextureUsages::TEXTURE_BINDING,
                        view_formats: &[],
                    })
                    .create_view(&Default::default())
            })
            .collect();
        Cssm { basis_layout, mip_layout, basis, mip, sampler, textures: None, dummy }
    }

    /// Mip levels of the basis textures (1 when none).
    pub fn levels(&self) -> u32 {
        self.textures.as_ref().map_or(1, |t| t.levels)
    }

    /// The four basis views to bind: the real ones when `on` and built, else 1x1 stand-ins.
    pub fn views(&self, on: bool) -> &[wgpu::TextureView] {
        match (&self.textures, on) {
            (Some(t), true) => &t.full,
            _ => &self.dummy,
        }
    }

    fn ensure(&mut self, gpu: &GpuContext, atlas: &CubeAtlas) -> Result<(), GpuError> {
        let size = (atlas.texture.width(), atlas.texture.height());
        // Levels while the tile side stays even (down to one texel for power-of-two tiles).
        let levels = atlas.resolution.trailing_zeros() + 1;
        if self.textures.as_ref().is_some_and(|t| t.size == size && t.levels == levels) {
            return Ok(());
        }
        let bytes: u64 = FORMATS.iter().map(|f| f.block_copy_size(None).unwrap_or(8) as u64).sum::<u64>()
            * size.0 as u64
            * size.1 as u64
            * 4
            / 3;
        if bytes > 2 << 30 {
            return Err(GpuError::InvalidSettings(format!(
                "val: CSSM basis textures for a {}x{} atlas need {} MiB (lower vals or shadow_res)",
                size.0,
                size.1,
                bytes >> 20
            )));
        }
        let textures: Vec<wgpu::Texture> = FORMATS
            .iter()
            .map(|f| {
                gpu.device.create_texture(&wgpu::TextureDescriptor {
                    label: Some("cssm basis"),
                    size: wgpu::Extent3d { width: size.0, height: size.1, depth_or_array_layers: 1 },
                    mip_level_count: levels,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format: *f,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::STORAGE_BINDING,
                    view_formats: &[],
                })
            })
            .collect();
        let full = textures.iter().map(|t| t.create_view(&Default::default())).collect();
        self.textures = Some(Textures { size, levels, textures, full });
        Ok(())
    }
}

/// The storage bindings 1-4 of both CSSM passes.
fn storage_entries(views: &[wgpu::TextureView]) -> Vec<wgpu::BindGroupEntry<'_>> {
    views
        .iter()
        .enumerate()
        .map(|(i, v)| wgpu::BindGroupEntry { binding: 1 + i as u32, resource: wgpu::BindingResource::TextureView(v) })
        .collect()
}

impl Cssm {
    /// Encode the basis textures of `atlas` and their mip chain.
    pub fn encode(
        &mut self,
        gpu: &GpuContext,
        timer: &PassTimer,
        encoder: &mut wgpu::CommandEncoder,
        atlas: &CubeAtlas,
    ) -> Result<(), GpuError> {
        self.ensure(gpu, atlas)?;
        let t = self.textures.as_ref().expect("ensured");
        let level = |i: usize, l: u32| {
            t.textures[i].create_view(&wgpu::TextureViewDescriptor {
                base_mip_level: l,
                mip_level_count: Some(1),
                ..Default::default()
            })
        };
        let base: Vec<wgpu::TextureView> = (0..4).map(|i| level(i, 0)).collect();
        let mut entries =
            vec![wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(&atlas.view) }];
        entries.extend(storage_entries(&base));
        let basis_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("cssm basis"),
            layout: &self.basis_layout,
            entries: &entries,
        });
        let mut mip_groups = Vec::new();
        for l in 1..t.levels {
            let dst: Vec<wgpu::TextureView> = (0..4).map(|i| level(i, l)).collect();
            let src: Vec<wgpu::TextureView> = (0..4).map(|i| level(i, l - 1)).collect();
            let mut entries = storage_entries(&dst);
            entries.extend((0..4).map(|i| wgpu::BindGroupEntry {
                binding: 5 + i as u32,
                resource: wgpu::BindingResource::TextureView(&src[i]),
            }));
            let group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("cssm mip"),
                layout: &self.mip_layout,
                entries: &entries,
            });
            mip_groups.push((group, (t.size.0 >> l).max(1), (t.size.1 >> l).max(1)));
        }
        timer.compute_pass(encoder, "val cssm basis", |pass| {
            pass.set_pipeline(&self.basis);
            pass.set_bind_group(0, &basis_group, &[]);
            pass.dispatch_workgroups(t.size.0.div_ceil(8), t.size.1.div_ceil(8), 1);
            pass.set_pipeline(&self.mip);
            for (group, w, h) in &mip_groups {
                pass.set_bind_group(0, group, &[]);
                pass.dispatch_workgroups(w.div_ceil(8), h.div_ceil(8), 1);
            }
        });
        Ok(())
    }
}
