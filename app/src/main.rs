//! `shadowlab`: with no arguments (or a scene path) the interactive app; with a subcommand the command line.

use std::process::ExitCode;

use clap::Parser;
use shadowlab::{cli, gui};

/// `1280x800` -> (1280.0, 800.0).
fn parse_size(text: &str) -> Result<(f32, f32), String> {
    let bad = || format!("--window-size '{text}': expected WIDTHxHEIGHT, e.g. 1280x800");
    let (w, h) = text.split_once('x').ok_or_else(bad)?;
    let (w, h): (f32, f32) = (w.trim().parse().map_err(|_| bad())?, h.trim().parse().map_err(|_| bad())?);
    if !(320.0..=16384.0).contains(&w) || !(240.0..=16384.0).contains(&h) {
        return Err(format!("--window-size '{text}': the window is at least 320x240 and at most 16384x16384"));
    }
    Ok((w, h))
}

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn,wgpu_hal::gles::egl=off")).init();
    let args = cli::Cli::parse();
    let window_size = match args.window_size.as_deref().map(parse_size) {
        Some(Err(e)) => {
            eprintln!("error: {e}");
            return ExitCode::FAILURE;
        }
        Some(Ok(s)) => Some(s),
        None => None,
    };
    // A NaN or negative time would never (or at once) quit: refused, like a bad window size.
    for (name, secs) in [("--quit-after", args.quit_after), ("--soak-secs", args.soak_secs)] {
        if let Some(v) = secs.filter(|v| !(v.is_finite() && *v >= 0.0)) {
            eprintln!("error: {name} {v}: give a number of seconds of 0 or more");
            return ExitCode::FAILURE;
        }
    }
    let result = match args.command {
        Some(command) => cli::run(command),
        None => gui::run(gui::Startup {
            window_size,
            path: args.path,
            data_dir: None,
            screenshot: args.screenshot,
            quit_after_secs: args.quit_after,
            synchronous: false,
            orbit_demo: args.orbit_demo,
            builtin: args.app_scene,
            start: gui::StartState {
                technique: args.app_technique,
                params: args.app_params,
                indirect: args.app_indirect,
                indirect_params: args.app_indirect_params,
                view: args.app_view,
                against: args.app_against,
                against_params: args.app_against_params,
                against_indirect: args.app_against_indirect,
                component: args.app_component,
                explain: args.app_explain,
                overlays: args.app_overlays,
            },
            relaunch_on_device_loss: true,
            no_file_dialogs: false,
            soak_secs: args.soak_secs,
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

#[cfg(test)]
mod tests {
    use super::parse_size;

    #[test]
    fn a_window_size_is_parsed_and_one_out_of_range_says_the_range() {
        assert_eq!(parse_size("1280x800"), Ok((1280.0, 800.0)));
        assert!(parse_size("1280*800").unwrap_err().contains("expected WIDTHxHEIGHT"));
        assert!(parse_size("wide x 800").unwrap_err().contains("expected WIDTHxHEIGHT"));
        for small_or_large in ["300x200", "100x80", "20000x800", "NaNx800"] {
            let e = parse_size(small_or_large).unwrap_err();
            assert!(e.contains("at least 320x240") || e.contains("expected"), "{small_or_large}: {e}");
        }
        assert!(parse_size("300x200").unwrap_err().contains("at least 320x240"));
    }
}
