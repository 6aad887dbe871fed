//! What a [`GpuKMeans`] run leaves on the GPU, read back: the clusters, the working centroids, the blocks'
//! lists, the assignment, the search queue's length and the searches' work counts (for the counts, the overlays
//! and the tests).

use super::{fine_table, grid_shape, GpuKMeans, GpuPoint, KMeansParams, RunShape, ACC, NB};
use crate::error::GpuError;
use crate::gpu::readback;
use crate::gpu::GpuContext;

/// The kinds of search whose work [`GpuKMeans::read_search_counts`] reports, in the shader's order
/// (kmeans.wgsl `COUNT_ASSIGN` ...).
pub const SEARCH_KINDS: [&str; 5] = ["km_assign", "km_assign_wide", "km_final", "km_fill", "km_search"];

/// One kind of search's work in a run (with [`GpuKMeans::set_count_searches`]). 32-bit sums on the GPU: past
/// 2^32 (billions of centroids, far beyond 1024x720) they wrap.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SearchCounts {
    /// Points searched (summed over the iterations for `km_assign`).
    pub points: u32,
    /// Grid cells visited and centroids considered, by all invocations.
    pub cells: u32,
    pub centroids: u32,
    /// Points queued for a search of their own.
    pub queued: u32,
    /// The most cells and centroids one invocation visited.
    pub most: u32,
}

impl GpuKMeans {
    /// The searches' work in the last run, per kind ([`SEARCH_KINDS`]); None unless counting.
    pub fn read_search_counts(&self, gpu: &GpuContext) -> Result<Option<[SearchCounts; 5]>, GpuError> {
        if !self.count_searches {
            return Ok(None);
        }
        let bytes = readback::read_buffer(gpu, &self.search_counts)?;
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes);
        let mut counts = [SearchCounts::default(); 5];
        for (c, w) in counts.iter_mut().zip(words.chunks_exact(5)) {
            *c = SearchCounts { points: w[0], cells: w[1], centroids: w[2], queued: w[3], most: w[4] };
        }
        Ok(Some(counts))
    }

    /// The clusters of the last run (submitted) as lights / endpoints: `K` entries.
    pub fn read_clusters(&self, gpu: &GpuContext) -> Result<Vec<GpuPoint>, GpuError> {
        let Some(buffer) = &self.clusters else { return Ok(Vec::new()) };
        let bytes = readback::read_buffer(gpu, buffer)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes[..self.shape.clusters * 48]))
    }

    /// The working centroids of the last run (`K` entries: position w = 1 when active; normal).
    pub fn read_centroids(&self, gpu: &GpuContext) -> Result<Vec<GpuPoint>, GpuError> {
        let Some(buffer) = &self.clusters else { return Ok(Vec::new()) };
        let bytes = readback::read_buffer(gpu, buffer)?;
        let k = self.shape.clusters;
        Ok(bytemuck::pod_collect_to_vec(&bytes[k * 48..2 * k * 48]))
    }

    /// The blocks' merged lists of the last run with neighbour lists (`km_blocks`): per sample, the clusters of
    /// the four samples at the corners of the block of pixels it is the top left corner of, each once, in the
    /// order `km_fill` considers them; empty without neighbour lists. For tests and inspection.
    pub fn read_block_lists(&self, gpu: &GpuContext, params: &KMeansParams) -> Result<Vec<Vec<u32>>, GpuError> {
        let Some(buffer) = &self.assignment else { return Ok(Vec::new()) };
        let RunShape { points: m, fuzziness: f, .. } = self.shape;
        let g = params.gamma.max(1) as usize;
        let samples = (params.width as usize).div_ceil(g) * (params.height as usize).div_ceil(g);
        let stride = 1 + 4 * f;
        if m == 0 || !params.neighbour_lists || g == 1 || buffer.size() < ((m * f * 2 + samples * stride) * 4) as u64 {
            return Ok(Vec::new());
        }
        let bytes = readback::read_buffer(gpu, buffer)?;
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes[m * f * 8..(m * f * 2 + samples * stride) * 4]);
        Ok(words.chunks_exact(stride).map(|block| block[1..1 + (block[0] as usize).min(4 * f)].to_vec()).collect())
    }

    /// The length of the last run's search queue: the points `km_fill` left to `km_search` (a CPU rasterizer's
    /// schedule) or to `km_search_wide` (a real GPU's). For tests that a path is taken.
    pub fn read_queue_len(&self, gpu: &GpuContext, params: &KMeansParams) -> Result<u32, GpuError> {
        let Some(buffer) = &self.work else { return Ok(0) };
        let (_, dims) = grid_shape(params.bounds_extent, self.shape.clusters);
        let cells = (dims[0] * dims[1] * dims[2]) as usize;
        let fine_levels = if self.gpu_schedule { self.fine_levels } else { 0 };
        let fine = fine_levels as usize * fine_table(self.shape.clusters) as usize;
        let word = self.shape.clusters * ACC as usize + cells + fine + 2 * NB as usize;
        let bytes = readback::read_buffer(gpu, buffer)?;
        Ok(bytemuck::pod_read_unaligned(&bytes[word * 4..word * 4 + 4]))
    }

    /// The assignment of the last run: per point, `F` (cluster or `u32::MAX`, inverse distance).
    pub fn read_assignment(&self, gpu: &GpuContext) -> Result<(Vec<u32>, Vec<f32>), GpuError> {
        let Some(buffer) = &self.assignment else { return Ok((Vec::new(), Vec::new())) };
        let n = self.shape.points * self.shape.fuzziness;
        if n == 0 {
            return Ok((Vec::new(), Vec::new()));
        }
        let bytes = readback::read_buffer(gpu, buffer)?;
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&bytes[..n * 8]);
        let clusters = words[..2 * n].iter().step_by(2).copied().collect();
        let inverse = words[1..2 * n].iter().step_by(2).map(|&w| f32::from_bits(w)).collect();
        Ok((clusters, inverse))
    }
}
