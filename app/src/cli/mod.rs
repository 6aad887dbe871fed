//! The headless command line: `shadowlab render`, `compare`, `sweep`, `bench`, `info`, `animate`, `sequence`,
//! `tradeoff`:
//! the clap types here, one file per subcommand, the argument groups they share in [`args`].

use std::path::PathBuf;

use anyhow::Result;
use clap::{Parser, Subcommand};
use shadowlab_core::technique;

pub mod animate;
pub mod args;
pub mod bench;
pub mod compare;
pub mod info;
pub mod progress;
pub mod render;
pub mod sequence;
pub mod setup;
pub mod sweep;
pub mod tradeoff;

pub use animate::AnimateArgs;
pub use args::{check_indirect, FrameArgs, SceneArgs, TargetArgs};
pub use bench::BenchArgs;
pub use compare::CompareArgs;
pub use progress::Progress;
pub use render::RenderArgs;
pub use sequence::SequenceArgs;
pub use setup::load_scene;
pub use sweep::SweepArgs;
pub use tradeoff::TradeoffArgs;

#[derive(Parser, Debug)]
#[command(
    name = "shadowlab",
    version,
    about = "See and measure how many-light shadow techniques trade quality for speed"
)]
#[command(args_conflicts_with_subcommands = true)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
    /// Open this scene file (.ron) or model (.obj, .gltf, .glb) in the app.
    pub path: Option<PathBuf>,
    #[arg(long = "app-technique", value_name = "KEY", help = args::registry_help("App: start with this technique", false))]
    pub app_technique: Option<String>,
    /// App: a parameter of the start technique, `key=value`; repeatable.
    #[arg(long = "app-param", value_name = "KEY=VALUE")]
    pub app_params: Vec<String>,
    /// App: start in this view: single, side, split or difference.
    #[arg(long = "app-view", value_name = "VIEW")]
    pub app_view: Option<String>,
    /// App: start on this built-in scene (cornell, arcade, restaurant).
    #[arg(long = "app-scene", value_name = "NAME")]
    pub app_scene: Option<String>,
    #[arg(long = "app-indirect", value_name = "KEY", help = args::registry_help("App: start with this indirect technique", true))]
    pub app_indirect: Option<String>,
    /// App: a parameter of the start indirect technique, `key=value`; repeatable.
    #[arg(long = "app-indirect-param", value_name = "KEY=VALUE")]
    pub app_indirect_params: Vec<String>,
    #[arg(long = "app-against", value_name = "KEY", help = target_help())]
    pub app_against: Option<String>,
    /// App: a parameter of the comparison target, `key=value`; repeatable.
    #[arg(long = "app-against-param", value_name = "KEY=VALUE")]
    pub app_against_params: Vec<String>,
    #[arg(
        long = "app-against-indirect",
        value_name = "KEY",
        help = args::registry_help("App: the comparison target's indirect technique, none or one of", true)
    )]
    pub app_against_indirect: Option<String>,
    /// App: the component of the light the views show: total, direct or indirect (with an indirect technique,
    /// `indirect` compares it with its own target, e.g. VALs with one shadow map per VPL).
    #[arg(long = "app-component", value_name = "COMPONENT")]
    pub app_component: Option<String>,
    /// App: open on an Explain step: `N` (1-based) of the technique's steps, or `KEY:N` of the technique or the
    /// indirect technique `KEY` (its layers, maps and parameters, as choosing it in the Explain panel).
    #[arg(long = "app-explain", value_name = "[KEY:]N")]
    pub app_explain: Option<String>,
    /// App: show an overlay layer of the technique or the indirect technique by its name as the Overlays panel
    /// lists it (`LAYER`, or `LAYER=off` to hide one shown by default); repeatable.
    #[arg(long = "app-overlay", value_name = "LAYER[=on|off]")]
    pub app_overlays: Vec<String>,
    /// App: save a screenshot of the window to this PNG when quitting (with --quit-after).
    #[arg(long, hide = true)]
    pub screenshot: Option<PathBuf>,
    /// App: quit after this many seconds (smoke tests, README pictures).
    #[arg(long, hide = true)]
    pub quit_after: Option<f32>,
    /// App: window size in points, `WIDTHxHEIGHT` (default 1400x860; 1024x640 on a software rasterizer).
    #[arg(long = "window-size", value_name = "WxH")]
    pub window_size: Option<String>,
    /// App: a long run of this many seconds (lights animated, every technique in turn, memory printed).
    #[arg(long, hide = true)]
    pub soak_secs: Option<f32>,
    /// App: orbit the camera continuously (UI frame-rate measurement).
    #[arg(long, hide = true)]
    pub orbit_demo: bool,
}

/// `--app-against`: the registry's comparison targets.
fn target_help() -> String {
    let keys: Vec<&str> = technique::registry::targets().map(|e| e.key).collect();
    format!("App: compare against this reference or ground truth: {}", keys.join(", "))
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render a scene with a technique to a PNG, with a JSON frame report.
    Render(RenderArgs),
    /// Render a technique and a comparison target; write the difference image and the error metrics.
    Compare(CompareArgs),
    /// Render a technique for every combination of parameter values, compared with the reference; CSV rows.
    Sweep(SweepArgs),
    /// The standard suite: every technique of the registries, direct and indirect, at its defaults against its
    /// own comparison target on the built-in scenes (and the shared real scenes when present); a Markdown table.
    Bench(BenchArgs),
    /// Print a scene's statistics (triangles, materials, lights, bounds) and the GPU adapter.
    Info(SceneArgs),
    /// Move the lights in small steps (and turn the camera, `--orbit`) over a number of frames and measure the
    /// flicker: the mean frame-to-frame change of the chosen component, each frame's time and figures and, with
    /// `--against-indirect`, its error against a target; CSV rows.
    Animate(AnimateArgs),
    /// Render an image sequence, every frame complete: the camera orbiting its target once, or the lights
    /// moving by a step a frame; numbered PNGs in a folder and, with `--gif`, one looping animated GIF.
    Sequence(SequenceArgs),
    /// Several techniques with ranges of their parameters against one target: error against time per frame
    /// (and work), the Pareto front; with `--budget-ms` or `--max-error`, the pick that fits; CSV rows.
    Tradeoff(TradeoffArgs),
}

pub fn run(command: Command) -> Result<()> {
    match command {
        Command::Render(args) => render::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Sweep(args) => sweep::run(args),
        Command::Bench(args) => bench::run(args),
        Command::Info(args) => info::run(args),
        Command::Animate(args) => animate::run(args),
        Command::Sequence(args) => sequence::run(args),
        Command::Tradeoff(args) => tradeoff::run(args),
    }
}
