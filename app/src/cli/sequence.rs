//! `shadowlab sequence`: an image sequence (an orbit, or the lights moving), every frame complete, as PNGs
//! and a GIF.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{anyhow, bail, Context, Result};
use clap::Args;
use shadowlab_core::scene::PointLight;

use super::args::{check_technique, parse_step, FrameArgs, SceneArgs, TechniqueChoice};
use super::progress::Progress;
use super::setup::{draw_overlays, parse_vec3s, setup};
use crate::files::{check_output_path, encode_png, write_atomic};

#[derive(Args, Debug)]
pub struct SequenceArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub frame: FrameArgs,
    #[command(flatten)]
    pub choice: TechniqueChoice,
    /// Frames of the sequence.
    #[arg(long, default_value_t = 36)]
    pub frames: u32,
    #[arg(long, value_enum, default_value = "orbit")]
    pub motion: crate::sequence::Motion,
    /// With `--motion lights`: the move of every light per frame, `DX,DY,DZ` in world units.
    #[arg(long, value_name = "DX,DY,DZ", default_value = "0.02,0,0")]
    pub step: String,
    /// Folder for `frame-0000.png`, `frame-0001.png`, ... (created when missing).
    #[arg(long)]
    pub out_dir: PathBuf,
    /// Also write the frames as one looping animated GIF.
    #[arg(long)]
    pub gif: Option<PathBuf>,
    /// How long the GIF shows each frame, in milliseconds (GIF counts hundredths of a second).
    #[arg(long, default_value_t = 80)]
    pub frame_ms: u32,
    /// Draw the overlay layers the techniques show by default over every frame; `--overlay-layer NAME` picks
    /// layers by name instead (repeatable).
    #[arg(long)]
    pub overlays: bool,
    #[arg(long = "overlay-layer", value_name = "NAME")]
    pub overlay_layers: Vec<String>,
}

pub fn run(args: SequenceArgs) -> Result<()> {
    let frames = args.frames as usize;
    crate::sequence::check_frames(frames).map_err(|e| anyhow!("--frames {frames}: {e}"))?;
    if let Some(g) = &args.gif {
        check_output_path(g, "gif")?;
    }
    check_technique(&args.choice.technique)?;
    let step = parse_step(&args.step)?;
    if args.out_dir.exists() && !args.out_dir.is_dir() {
        bail!("--out-dir {}: not a folder", args.out_dir.display());
    }
    let (_gpu, mut renderer, scene, lights, camera) = setup(&args.scene, &args.frame)?;
    let f = &args.frame;
    let mut technique = args.choice.create(&renderer, f.shadow_res)?;
    crate::measure::apply_indirect(&mut renderer, &f.indirect_choice())?;
    std::fs::create_dir_all(&args.out_dir).with_context(|| format!("cannot create {}", args.out_dir.display()))?;
    let target = match &f.camera {
        Some(text) => parse_vec3s(text)?.1,
        None => crate::sequence::orbit_target(&camera, &scene.bounds),
    };
    let mut gif = args.gif.as_deref().map(|g| crate::sequence::GifWriter::new(g, args.frame_ms)).transpose()?;
    let mut gif_secs = 0.0;
    let mut progress = Progress::new(&format!("sequence {}", args.choice.technique), f.quiet).with_unit("frame");
    for i in 0..frames {
        let (camera, moved) = match args.motion {
            crate::sequence::Motion::Orbit => {
                let angle = std::f32::consts::TAU * i as f32 / frames as f32;
                (crate::sequence::orbit_camera(&camera, target, angle), lights.clone())
            }
            crate::sequence::Motion::Lights => {
                let moved = lights.iter().map(|l| PointLight { position: l.position + step * i as f32, ..*l });
                (camera, moved.collect())
            }
        };
        renderer.render_frame(technique.as_mut(), &camera, &moved, &mut |_, _| {})?;
        if args.overlays || !args.overlay_layers.is_empty() {
            draw_overlays(&mut renderer, technique.as_ref(), &camera, &moved, &args.overlay_layers)?;
        }
        let image = renderer.read_output()?;
        write_atomic(&crate::sequence::frame_path(&args.out_dir, i), &encode_png(&image)?)?;
        if let Some(gif) = &mut gif {
            let start = Instant::now();
            gif.add(&image)?;
            gif_secs += start.elapsed().as_secs_f32();
        }
        progress.update(i + 1, frames);
    }
    if let Some(gif) = gif {
        gif.finish()?;
    }
    if !f.quiet {
        eprintln!("wrote {frames} frames in {}", args.out_dir.display());
        if let Some(g) = &args.gif {
            let kib = std::fs::metadata(g).map(|m| m.len() / 1024).unwrap_or(0);
            eprintln!("wrote {} ({frames} frames, {kib} KiB, encoded in {gif_secs:.2} s)", g.display());
        }
    }
    Ok(())
}
