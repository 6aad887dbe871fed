//! Light culling and upload, a renderer service: once per frame (`Renderer::begin_frame`) the lights whose
//! range sphere touches the view frustum are found and uploaded as `array<Light>` (`common.wgsl`), in the
//! order of the frame's lights. The reference (and INSM through it), the unshadowed preview and the ray tracer
//! shade from this list; LightCluster clusters it (its step 1) and uploads its lights in cluster order.

use super::gpu_data::GpuLight;
use crate::gpu::buffer::GrowableBuffer;
use crate::gpu::GpuContext;
use crate::math::Frustum;
use crate::scene::PointLight;

pub struct VisibleLights {
    /// Indices into the frame's lights of the visible ones, in order.
    pub indices: Vec<usize>,
    /// Their GPU form, in the same order (what `buffer` holds).
    pub gpu: Vec<GpuLight>,
    /// `array<Light>` of the visible lights.
    pub buffer: GrowableBuffer,
    /// Changes whenever `buffer` is recreated (it grew), so a technique knows to rebuild its bind groups.
    pub generation: u64,
}

impl VisibleLights {
    pub fn new(gpu: &GpuContext) -> VisibleLights {
        VisibleLights {
            indices: Vec::new(),
            gpu: Vec::new(),
            buffer: GrowableBuffer::new(&gpu.device, "visible lights", 64 * 64),
            generation: 0,
        }
    }

    /// Cull `lights` (invalid ones dropped) against `frustum` and upload the visible ones.
    pub fn update(&mut self, gpu: &GpuContext, lights: &[PointLight], frustum: &Frustum) {
        self.indices.clear();
        self.indices.extend(visible_indices(lights, frustum));
        self.gpu.clear();
        self.gpu.extend(self.indices.iter().map(|&i| GpuLight::new(&lights[i])));
        if self.buffer.write(gpu, &self.gpu) {
            self.generation += 1;
        }
    }
}

/// The indices of the valid lights whose range sphere touches `frustum`, in order: a frame's light culling.
pub fn visible_indices<'a>(lights: &'a [PointLight], frustum: &'a Frustum) -> impl Iterator<Item = usize> + 'a {
    lights
        .iter()
        .enumerate()
        .filter(|(_, l)| l.is_valid() && frustum.intersects_sphere(l.position, l.range))
        .map(|(i, _)| i)
}
