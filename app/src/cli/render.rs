//! `shadowlab render`: one technique's image (and its shadow maps) as PNGs, with a JSON frame report.

use std::path::PathBuf;

use anyhow::{bail, Result};
use clap::Args;
use serde::Serialize;
use shadowlab_core::scene::Camera;
use shadowlab_core::FrameReport;

use super::args::{check_technique, FrameArgs, SceneArgs, TechniqueChoice};
use super::progress::Progress;
use super::setup::{draw_overlays, setup};
use crate::files::{check_output_path, encode_png, write_atomic};
use crate::rsm_picture::{mark_drawn, picture, RsmShow};

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    #[command(flatten)]
    pub choice: TechniqueChoice,
    /// Output PNG.
    #[arg(long)]
    pub out: PathBuf,
    /// Frame report as JSON.
    #[arg(long)]
    pub report: Option<PathBuf>,
    /// Draw the overlay layers the techniques show by default (lights, clusters, VPLs, ...) over the image;
    /// `--overlay-layer NAME` picks layers by name instead (repeatable).
    #[arg(long)]
    pub overlays: bool,
    #[arg(long = "overlay-layer", value_name = "NAME")]
    pub overlay_layers: Vec<String>,
    /// Save the technique's shadow-map atlas (near white, far black) as this PNG, the indirect
    /// technique's as `<name>-indirect.png` (the last batch when a frame had several), and other depth
    /// images the technique renders (INSM's intermediate images) as `<name>-images.png`.
    #[arg(long)]
    pub maps_out: Option<PathBuf>,
    /// Save a light's reflective shadow map (what the `rsm` VPL source draws its VPLs from; cast on the CPU) as
    /// this PNG: a cube unfolded as a cross, a spot's face or a sun's square; with an indirect technique, the
    /// texels the frame's first-bounce VPLs of that light came from in magenta.
    #[arg(long)]
    pub rsm_out: Option<PathBuf>,
    /// Whose RSM: a point light's index, or the number of point lights + k for sun k.
    #[arg(long, default_value_t = 0)]
    pub rsm_light: usize,
    /// The RSM's texels a face side (1 to 512).
    #[arg(long, default_value_t = 128)]
    pub rsm_res: u32,
    /// What the RSM's texels show.
    #[arg(long, value_enum, default_value_t = RsmShow::Flux)]
    pub rsm_show: RsmShow,
}

#[derive(Serialize)]
struct RenderReport<'a> {
    adapter: String,
    scene: &'a str,
    scene_triangles: usize,
    scale: f32,
    lights: &'a str,
    technique: &'a str,
    parameters: std::collections::BTreeMap<String, String>,
    width: u32,
    height: u32,
    camera: Camera,
    frame: &'a FrameReport,
    timing: &'a crate::measure::TimingSummary,
}

pub fn run(args: RenderArgs) -> Result<()> {
    check_output_path(&args.out, "png")?;
    if let Some(m) = &args.maps_out {
        check_output_path(m, "png")?;
    }
    if let Some(m) = &args.rsm_out {
        check_output_path(m, "png")?;
    }
    if let Some(r) = &args.report {
        check_output_path(r, "json")?;
    }
    check_technique(&args.choice.technique)?;
    let (gpu, mut renderer, scene, lights, camera) = setup(&args.scene, &args.frame)?;
    let frame = &args.frame;
    let mut technique = args.choice.create(&renderer, frame.shadow_res)?;
    crate::measure::apply_indirect(&mut renderer, &frame.indirect_choice())?;

    let mut reports = Vec::new();
    let total = frame.warmup + frame.repeat.max(1);
    for i in 0..total {
        let label = if i < frame.warmup {
            format!("warm-up {}/{}", i + 1, frame.warmup)
        } else {
            format!("{} / {} {}/{}", scene.name, technique.key(), i + 1 - frame.warmup, frame.repeat.max(1))
        };
        let mut progress = Progress::new(&label, frame.quiet);
        let r = renderer.render_frame(technique.as_mut(), &camera, &lights, &mut |d, t| progress.update(d, t))?;
        if i >= frame.warmup {
            reports.push(r);
        }
    }
    let timing = crate::measure::summarize(&reports);
    let report = reports.pop().expect("at least one measured frame");
    if let Some(path) = &args.maps_out {
        let mut wrote = 0;
        if let Some((atlas, what)) = technique.shadow_atlas() {
            let img = shadowlab_core::gpu::readback::depth_atlas_image(renderer.gpu(), &atlas.texture)?;
            write_atomic(path, &encode_png(&img)?)?;
            wrote += 1;
            if !frame.quiet {
                eprintln!("wrote {} ({what}, {} tiles of {}²)", path.display(), atlas.tiles, atlas.resolution);
            }
        }
        if let Some((atlas, what)) = renderer.indirect().and_then(|t| t.shadow_atlas()) {
            let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("maps");
            let indirect_path = path.with_file_name(format!("{stem}-indirect.png"));
            let img = shadowlab_core::gpu::readback::depth_atlas_image(renderer.gpu(), &atlas.texture)?;
            write_atomic(&indirect_path, &encode_png(&img)?)?;
            wrote += 1;
            if !frame.quiet {
                eprintln!("wrote {} ({what}, {} tiles of {}²)", indirect_path.display(), atlas.tiles, atlas.resolution);
            }
        }
        // Other depth images the technique rendered (INSM's intermediate images): `<name>-images.png`.
        let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("maps").to_string();
        let images = technique.depth_images();
        for (i, (atlas, what)) in images.iter().enumerate() {
            let suffix = if images.len() == 1 { String::new() } else { format!("-{i}") };
            let images_path = path.with_file_name(format!("{stem}-images{suffix}.png"));
            let img = shadowlab_core::gpu::readback::depth_atlas_image(renderer.gpu(), &atlas.texture)?;
            write_atomic(&images_path, &encode_png(&img)?)?;
            wrote += 1;
            if !frame.quiet {
                eprintln!("wrote {} ({what}, {} tiles of {}²)", images_path.display(), atlas.tiles, atlas.resolution);
            }
        }
        if wrote == 0 {
            bail!("--maps-out: neither '{}' nor the indirect technique renders shadow maps", args.choice.technique);
        }
    }
    if let Some(path) = &args.rsm_out {
        write_rsm(&renderer, &lights, &args, path)?;
    }
    if args.overlays || !args.overlay_layers.is_empty() {
        draw_overlays(&mut renderer, technique.as_ref(), &camera, &lights, &args.overlay_layers)?;
    }
    write_atomic(&args.out, &encode_png(&renderer.read_output()?)?)?;

    if !frame.quiet {
        eprintln!(
            "{}x{} on {}: {:.1} ms ({}), {:.0} ms wall; {} of {} lights visible, {} shadow maps in {} batches; \
             {} shadow triangles drawn, {} culled",
            report.width,
            report.height,
            gpu.adapter_description(),
            report.frame_ms(),
            report.timing.source.name(),
            report.wall_ms,
            report.counts.technique.lights_visible,
            report.counts.lights_total,
            report.counts.technique.shadow_maps,
            report.counts.technique.batches,
            report.counts.technique.shadow_triangles_submitted,
            report.counts.technique.shadow_triangles_culled,
        );
        if let Some(reason) = &report.timing.reason {
            eprintln!("  timing: {reason}");
        }
        let work = report.total_work();
        let shown: Vec<String> = shadowlab_core::technique::work::WORK_KEYS
            .iter()
            .filter_map(|k| {
                work.get(*k).filter(|v| **v != 0.0).map(|v| format!("{k} {}", crate::measure::count_text(*v)))
            })
            .collect();
        eprintln!("  work: {}", shown.join(", "));
        if let Some(c) = report.counts.technique.clusters {
            eprintln!(
                "  {c} clusters{}",
                if report.counts.technique.fell_back_to_reference { " (= visible lights: reference path)" } else { "" }
            );
        }
        for p in &report.passes {
            eprintln!("  {:<14} {:>10.2} ms  ({} passes)", p.name, p.ms, p.count);
        }
        for p in &report.cpu_stages {
            eprintln!("  {:<14} {:>10.3} ms  (CPU)", p.name, p.ms);
        }
        if let Some((scale, average)) = renderer.auto_exposure()? {
            eprintln!(
                "  auto exposure: log-average luminance {average:.4}, scale x{scale:.3} (times --exposure {})",
                frame.exposure
            );
        }
        if timing.frames > 1 {
            eprintln!(
                "  {} frames: median {:.2} ms, min {:.2} ms, mean of 3 best {:.2} ms ({})",
                timing.frames,
                timing.median_ms,
                timing.min_ms,
                timing.best3_mean_ms,
                timing.clock.name()
            );
        }
        eprintln!("wrote {}", args.out.display());
    }
    if let Some(path) = &args.report {
        let parameters = technique.params().into_iter().map(|p| (p.key.to_string(), p.value.to_string())).collect();
        let r = RenderReport {
            adapter: gpu.adapter_description(),
            scene: &args.scene.scene,
            scene_triangles: scene.triangle_count(),
            scale: args.scene.scale,
            lights: &args.scene.lights,
            technique: technique.key(),
            parameters,
            width: report.width,
            height: report.height,
            camera,
            frame: &report,
            timing: &timing,
        };
        write_atomic(path, serde_json::to_string_pretty(&r)?.as_bytes())?;
        if !frame.quiet {
            eprintln!("wrote {}", path.display());
        }
    }
    Ok(())
}

/// `--rsm-out`: the chosen light's reflective shadow map, with the texels its VPLs of this frame came from.
fn write_rsm(
    renderer: &shadowlab_core::Renderer,
    lights: &[shadowlab_core::scene::PointLight],
    args: &RenderArgs,
    path: &std::path::Path,
) -> Result<()> {
    use shadowlab_core::vpl::rsm::{rsm_image, RsmEmitter};
    let suns = renderer.directional_lights();
    let i = args.rsm_light;
    let emitter = match i.checked_sub(lights.len()) {
        None => RsmEmitter::Point(&lights[i]),
        Some(k) if k < suns.len() => RsmEmitter::Sun(&suns[k]),
        Some(_) => {
            let points = match lights.len() {
                0 => "no point lights".to_string(),
                n => format!("{n} point lights (0 to {})", n - 1),
            };
            bail!("--rsm-light {i}: the scene has {points} and {} suns (numbered after them)", suns.len())
        }
    };
    let bvh = renderer.scene().bvh(renderer.gpu()).0;
    let image = rsm_image(&bvh, emitter, args.rsm_res).map_err(|e| anyhow::anyhow!("--rsm-out: {e}"))?;
    let mut png = picture(&image, args.rsm_show);
    let drawn = image.drawn_texels(renderer.vpls(), i as u32);
    mark_drawn(&mut png, &image, &drawn);
    write_atomic(path, &encode_png(&png)?)?;
    if !args.frame.quiet {
        let total = image.total_flux();
        eprintln!(
            "wrote {} (the RSM of {}: {} of {}², reflected flux ({:.4}, {:.4}, {:.4}); {} of the frame's {} VPLs came \
             from it, first bounce)",
            path.display(),
            shadowlab_core::vpl::emitter_name(i, lights.len()),
            if image.faces == 1 { "one face".to_string() } else { format!("{} faces", image.faces) },
            image.resolution,
            total.x,
            total.y,
            total.z,
            drawn.values().sum::<u32>(),
            renderer.vpls().vpls.len()
        );
    }
    Ok(())
}
