//! CPU stages other than clustering: chunking a scene for culling, building the ray tracer's BVH, and the
//! comparison metrics on a 640x360 image. `cargo bench -p shadowlab-core --bench cpu_stages` prints a table
//! (Dabrovic Sponza is added when `../shared/scenes` is present). Under `cargo test` only a quick smoke run.

use std::hint::black_box;
use std::time::Instant;

use shadowlab_core::accel::bvh::Bvh;
use shadowlab_core::compare::{self, CompareOptions, Image};
use shadowlab_core::scene::chunks::ChunkedGeometry;
use shadowlab_core::scene::Scene;

fn median_ms(runs: usize, mut f: impl FnMut()) -> f64 {
    let mut times: Vec<f64> = (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1000.0
        })
        .collect();
    times.sort_by(f64::total_cmp);
    times[times.len() / 2]
}

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    let runs = if full { 7 } else { 1 };
    let mut scenes = vec![Scene::builtin("cornell").unwrap()];
    if full {
        scenes.push(Scene::builtin("arcade").unwrap());
        let sponza =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes/dabrovic-sponza/sponza.obj");
        if sponza.is_file() {
            scenes.push(Scene::load(&sponza, 1.0).unwrap());
        }
    }
    println!("| stage | input | median ms |");
    println!("|---|---|---:|");
    for scene in &scenes {
        let label = format!("{} ({} triangles)", scene.name, scene.triangle_count());
        let ms = median_ms(runs, || {
            black_box(ChunkedGeometry::build(black_box(scene)));
        });
        println!("| chunking | {label} | {ms:.2} |");
        let geometry = ChunkedGeometry::build(scene);
        let ms = median_ms(runs, || {
            black_box(Bvh::from_geometry(black_box(&geometry)));
        });
        println!("| BVH build | {label} | {ms:.2} |");
    }
    // Metrics on two synthetic 640x360 images that differ smoothly.
    let (w, h) = if full { (640u32, 360u32) } else { (64, 36) };
    let pixels = |phase: f32| -> Vec<[f32; 4]> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 / w as f32, (i / w) as f32 / h as f32);
                let v = 0.5 + 0.4 * (x * 9.0 + phase).sin() * (y * 5.0).cos();
                [v, v * 0.8, v * 0.6, 1.0]
            })
            .collect()
    };
    let a = Image::new(w, h, pixels(0.0)).unwrap();
    let b = Image::new(w, h, pixels(0.05)).unwrap();
    let mask = vec![true; (w * h) as usize];
    let size = format!("{w}x{h}");
    let no_flip = CompareOptions { flip: false, ..Default::default() };
    let ms = median_ms(runs, || {
        black_box(compare::compare(&a, &b, Some(&mask), &no_flip).unwrap());
    });
    println!("| metrics without FLIP | {size} | {ms:.2} |");
    let ms = median_ms(runs, || {
        black_box(compare::compare(&a, &b, Some(&mask), &CompareOptions::default()).unwrap());
    });
    println!("| metrics with FLIP | {size} | {ms:.2} |");
    let ms = median_ms(runs, || {
        black_box(compare::difference_image(&a, &b, Some(&mask), compare::DiffMode::Absolute, 5.0).unwrap());
    });
    println!("| difference image | {size} | {ms:.2} |");
}
