//! `shadowlab info`: a scene's statistics and the GPU adapter.

use anyhow::Result;
use shadowlab_core::GpuContext;

use super::args::SceneArgs;
use super::setup::load_scene;

pub fn run(args: SceneArgs) -> Result<()> {
    let (scene, lights) = load_scene(&args)?;
    let b = scene.bounds;
    println!("scene      {}", scene.name);
    println!("triangles  {}", scene.triangle_count());
    println!("meshes     {}", scene.meshes.len());
    println!("materials  {}", scene.materials.len());
    println!("textures   {}", scene.textures.len());
    println!("lights     {}", lights.len());
    println!(
        "bounds     [{:.2}, {:.2}, {:.2}] .. [{:.2}, {:.2}, {:.2}]",
        b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
    );
    match GpuContext::headless() {
        Ok(gpu) => println!("adapter    {}", gpu.adapter_description()),
        Err(e) => println!("adapter    none ({e})"),
    }
    Ok(())
}
