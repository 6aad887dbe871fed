//! Buffers that grow with a frame's needs.

use super::GpuContext;

/// A storage buffer of `T` that grows (to the next power of two) when a frame needs more.
pub struct GrowableBuffer {
    pub buffer: wgpu::Buffer,
    capacity_bytes: u64,
    label: &'static str,
}

impl GrowableBuffer {
    pub fn new(device: &wgpu::Device, label: &'static str, capacity_bytes: u64) -> Self {
        let capacity_bytes = capacity_bytes.max(256);
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: capacity_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        GrowableBuffer { buffer, capacity_bytes, label }
    }

    /// Upload `data`; returns true when the buffer was recreated (bind groups must be rebuilt).
    pub fn write<T: bytemuck::Pod>(&mut self, gpu: &GpuContext, data: &[T]) -> bool {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let mut grown = false;
        if bytes.len() as u64 > self.capacity_bytes {
            *self = GrowableBuffer::new(&gpu.device, self.label, (bytes.len() as u64).next_power_of_two());
            grown = true;
        }
        if !bytes.is_empty() {
            gpu.queue.write_buffer(&self.buffer, 0, bytes);
        }
        grown
    }
}
