//! When the GPU device is lost: the state saved to a recovery scene file, the window saying so, and (in the
//! binary) a new ShadowLab started on that file.

use std::path::PathBuf;

use eframe::egui;

use super::state::Recovery;
use super::ShadowLabApp;

/// Set by a recovered process, so a device lost again is not relaunched in a loop.
const RECOVERED_ENV: &str = "SHADOWLAB_RECOVERED";

impl ShadowLabApp {
    /// The GPU device is gone (a driver reset, a shader that ran too long, an unplugged GPU): eframe's device
    /// is the one egui paints with, so neither the renderers nor the window can be recreated in this process.
    /// Save everything to a recovery scene file, stop rendering, say so, and (in the binary) start a new
    /// ShadowLab on that file and close this window. A process that was itself started this way does not
    /// relaunch again; it only saves and says so.
    pub fn handle_device_lost(&mut self, ctx: &egui::Context, reason: String) {
        if self.recovery.is_some() {
            return;
        }
        log::error!("GPU device lost: {reason}");
        self.views.gpu = None;
        self.views.sweep = None;
        let file = self.lifecycle.data_dir.join("recovery.ron");
        let saved = std::fs::create_dir_all(&self.lifecycle.data_dir)
            .map_err(anyhow::Error::from)
            .and_then(|_| self.session.scene_file_data().save(&file));
        let relaunch_allowed = self.lifecycle.relaunch_on_device_loss && std::env::var_os(RECOVERED_ENV).is_none();
        let mut recovery = Recovery { reason: reason.clone(), file: None, relaunch: None, message: String::new() };
        recovery.message = match saved {
            Err(e) => format!(
                "The GPU device was lost ({reason}). ShadowLab could not save a recovery file ({e:#}); save your \
                 scene with File → Save scene file if the menu still responds, then restart ShadowLab."
            ),
            Ok(()) => {
                recovery.file = Some(file.clone());
                let program = std::env::current_exe().unwrap_or_else(|_| PathBuf::from("shadowlab"));
                let args = vec![file.display().to_string()];
                if relaunch_allowed {
                    let spawned = std::process::Command::new(&program).args(&args).env(RECOVERED_ENV, "1").spawn();
                    match spawned {
                        Ok(_) => {
                            recovery.relaunch = Some((program, args));
                            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                            format!(
                                "The GPU device was lost ({reason}). Your scene, lights, camera and settings were \
                                 saved to {}; a new ShadowLab window opens on them.",
                                file.display()
                            )
                        }
                        Err(e) => format!(
                            "The GPU device was lost ({reason}). Your scene was saved to {}, but a new ShadowLab \
                             could not be started ({e}); start it with that file.",
                            file.display()
                        ),
                    }
                } else {
                    // Tests record the command the binary would run; a recovered process runs none.
                    if !self.lifecycle.relaunch_on_device_loss {
                        recovery.relaunch = Some((program, args));
                    }
                    format!(
                        "The GPU device was lost ({reason}). Your scene, lights, camera and settings were saved to {}; \
                         restart ShadowLab with that file (`shadowlab {}`) to go on.",
                        file.display(),
                        file.display()
                    )
                }
            }
        };
        self.error(recovery.message.clone());
        self.chrome.status = recovery.message.clone();
        self.recovery = Some(recovery);
    }
}
