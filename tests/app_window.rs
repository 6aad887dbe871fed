//! A real window under Xvfb: start the binary, let it render its first frames, and check that the window
//! screenshot it saves is not blank. CI installs `xvfb` (scripts/setup).

use std::path::PathBuf;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

#[test]
fn the_app_opens_a_window_and_draws_the_scene() {
    let xvfb = which("Xvfb").expect("Xvfb is missing: install it with scripts/setup (Debian package xvfb)");
    let display = format!(":{}", 90 + std::process::id() % 9);
    let mut server = Command::new(xvfb)
        .args([display.as_str(), "-screen", "0", "1280x800x24", "-nolisten", "tcp"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start Xvfb");
    std::thread::sleep(Duration::from_millis(800));
    let out_dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/test-output/window");
    std::fs::create_dir_all(&out_dir).unwrap();
    let shot = out_dir.join("window.png");
    let _ = std::fs::remove_file(&shot);
    let started = Instant::now();
    let output = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(["--quit-after", "12", "--screenshot", shot.to_str().unwrap()])
        .env("DISPLAY", &display)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .env("XDG_DATA_HOME", &out_dir)
        .output()
        .expect("run shadowlab");
    let _ = server.kill();
    let _ = server.wait();
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "the app failed after {:?}:\n{stderr}", started.elapsed());
    let img = image::open(&shot).unwrap_or_else(|e| panic!("no screenshot ({e}):\n{stderr}")).to_rgba8();
    assert!(img.width() >= 640 && img.height() >= 400);
    // Not blank: many distinct colours, and the 3D view (centre) is not the UI's flat background.
    let mut colours = std::collections::HashSet::new();
    for p in img.pixels().step_by(7) {
        colours.insert(p.0);
    }
    assert!(colours.len() > 200, "the window looks blank ({} colours)", colours.len());
    let c = img.get_pixel(img.width() / 2, img.height() / 3).0;
    let bright = img
        .enumerate_pixels()
        .filter(|(x, y, _)| *x > img.width() / 4 && *x < img.width() * 3 / 4 && *y < img.height() * 3 / 4)
        .filter(|(_, _, p)| p.0[0] as u32 + p.0[1] as u32 + p.0[2] as u32 > 300)
        .count();
    assert!(bright > 1000, "the 3D view shows no lit surface (centre pixel {c:?})");
}

fn which(name: &str) -> Option<PathBuf> {
    std::env::var_os("PATH")?.to_str()?.split(':').map(|d| PathBuf::from(d).join(name)).find(|p| p.is_file())
}
