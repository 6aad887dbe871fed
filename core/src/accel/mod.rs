//! The scene on the GPU and its acceleration structure: mesh, material and texture buffers ([`gpu_scene`]), the
//! BVH built on the CPU with its CPU traversals ([`bvh`]), its GPU upload with the cut-out masks
//! ([`scene_bvh`]), a GPU traversal of given rays for tests ([`gpu_trace`]), and the first view of a model without a camera
//! ([`first_view`]: inside an interior). Every tracer (the ray tracer,
//! the path tracer, the VPL gather, fuzzy clustering's visibility) and the CPU VPL generation use it; it sits
//! above the scene and the GPU utilities and below the technique interface.

pub mod bvh;
pub mod first_view;
pub mod gpu_scene;
pub mod gpu_trace;
pub mod scene_bvh;
