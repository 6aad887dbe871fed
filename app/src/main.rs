//! `shadowlab`: with no arguments (or a scene path) the interactive app; with a subcommand the command line.

use std::process::ExitCode;

use clap::Parser;
use shadowlab::{cli, gui};

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn,wgpu_hal::gles::egl=off")).init();
    let args = cli::Cli::parse();
    let result = match args.command {
        Some(command) => cli::run(command),
        None => gui::run(gui::Startup {
            path: args.path,
            data_dir: None,
            screenshot: args.screenshot,
            quit_after_secs: args.quit_after,
            synchronous: false,
            orbit_demo: args.orbit_demo,
            technique: args.app_technique,
            view: args.app_view,
            builtin: args.app_scene,
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // One line: the error and its causes.
            let chain: Vec<String> = e.chain().map(|c| c.to_string()).collect();
            eprintln!("error: {}", chain.join(": "));
            ExitCode::FAILURE
        }
    }
}
