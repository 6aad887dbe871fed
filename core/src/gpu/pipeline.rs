//! Shader modules and pipelines.

/// Create a shader module from WGSL source (one of the composed modules of `crate::shaders` or a technique's).
pub fn create_module(device: &wgpu::Device, label: &str, source: &str) -> wgpu::ShaderModule {
    device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    })
}
