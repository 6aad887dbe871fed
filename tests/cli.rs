//! End-to-end tests of `shadowlab` as a user runs it: real renders with a report, and bad input that must give
//! a non-zero exit and a one-line error, never a panic.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn shadowlab(args: &[&str]) -> Output {
    let runtime = std::env::temp_dir().join("shadowlab-xdg");
    std::fs::create_dir_all(&runtime).unwrap();
    Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(args)
        // Quiets Mesa's "XDG_RUNTIME_DIR is invalid" noise.
        .env("XDG_RUNTIME_DIR", &runtime)
        .output()
        .expect("run shadowlab")
}

fn out_dir(name: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../target/test-output/cli").join(name);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn fixtures() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../tests/fixtures")
}

/// The shared real scenes (`../shared/scenes`, or `SHADOWLAB_SCENES`). In CI (`CI` set, not `false`) a missing
/// folder fails the test with instructions; elsewhere the test says clearly that it did not run and passes, so
/// a fresh clone without the data passes the README's test command.
fn shared_scenes(test: &str) -> Option<PathBuf> {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes");
    if dir.is_dir() {
        return Some(dir);
    }
    let message = format!("the shared scenes are missing: {test} expected them at {}", dir.display());
    if std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false") {
        panic!("{message}");
    }
    eprintln!("NOT RUN: {message}");
    None
}

/// Bad input: exit code 1, no panic, and the last stderr line is one `error: ...` line containing `expect`.
fn assert_fails_with(args: &[&str], expect: &str) {
    let out = shadowlab(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{args:?} should fail; stderr:\n{stderr}");
    assert!(!stderr.contains("panicked"), "{args:?} panicked:\n{stderr}");
    let last = stderr.lines().last().unwrap_or_default();
    assert!(last.starts_with("error: "), "{args:?}: last line is not an error line: {last:?}");
    assert!(last.contains(expect), "{args:?}: expected '{expect}' in {last:?}");
}

fn render_ok(name: &str, extra: &[&str]) -> (image::RgbaImage, serde_json::Value) {
    let dir = out_dir(name);
    let png = dir.join("out.png");
    let json = dir.join("report.json");
    let mut args = vec!["render", "--quiet", "--warmup", "0", "--out", png.to_str().unwrap()];
    args.extend_from_slice(&["--report", json.to_str().unwrap()]);
    args.extend_from_slice(extra);
    let out = shadowlab(&args);
    assert!(out.status.success(), "{args:?} failed:\n{}", String::from_utf8_lossy(&out.stderr));
    let img = image::open(&png).unwrap().to_rgba8();
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    (img, report)
}

/// Share of pixels that are not (nearly) the background colour, and the mean luminance.
fn image_stats(img: &image::RgbaImage) -> (f32, f32) {
    let bg = img.get_pixel(0, 0).0;
    let mut differ = 0usize;
    let mut sum = 0f32;
    for p in img.pixels() {
        let d: i32 = (0..3).map(|c| (p.0[c] as i32 - bg[c] as i32).abs()).sum();
        if d > 12 {
            differ += 1;
        }
        sum += (p.0[0] as f32 + p.0[1] as f32 + p.0[2] as f32) / 3.0;
    }
    let n = (img.width() * img.height()) as f32;
    (differ as f32 / n, sum / n)
}

#[test]
fn renders_each_builtin_scene_with_a_report() {
    for (scene, lights) in [("cornell", 32u64), ("arcade", 80), ("restaurant", 14)] {
        let (img, report) = render_ok(
            &format!("builtin-{scene}"),
            &["--scene", scene, "--width", "96", "--height", "64", "--shadow-res", "64"],
        );
        assert_eq!((img.width(), img.height()), (96, 64));
        let (share, mean) = image_stats(&img);
        assert!(mean > 10.0, "{scene}: image is black (mean {mean})");
        assert!(share > 0.2, "{scene}: image is mostly background");
        assert_eq!(report["frame"]["counts"]["lights_total"], lights, "{scene}");
        assert!(report["adapter"].as_str().unwrap().len() > 3);
        assert!(report["frame"]["counts"]["shadow_maps"].as_u64().unwrap() > 0, "{scene}");
        let passes = report["frame"]["passes"].as_array().unwrap();
        // Per pass in GPU timestamps; per step where `auto` chose the wall clock (a loaded machine can make it).
        let names: &[&str] = if report["frame"]["timing"]["source"] == "gpu_timestamps" {
            &["gbuffer", "shadow maps", "shading", "tonemap"]
        } else {
            &["gbuffer + ambient", "tonemap"]
        };
        for &name in names {
            assert!(passes.iter().any(|p| p["name"] == name), "{scene}: no '{name}' pass in {passes:?}");
        }
        assert_eq!(report["parameters"]["shadow_res"], "64");
    }
}

#[test]
fn renders_sponza_with_the_paper_layout() {
    let Some(scenes) = shared_scenes("renders_sponza_with_the_paper_layout") else { return };
    let sponza = scenes.join("dabrovic-sponza/sponza.obj");
    let (img, report) = render_ok(
        "sponza",
        &[
            "--scene",
            sponza.to_str().unwrap(),
            "--lights",
            "paper",
            "--camera=-14,2.5,0,10,3,0",
            "--z-far",
            "30",
            "--width",
            "96",
            "--height",
            "54",
            "--shadow-res",
            "64",
        ],
    );
    let (_, mean) = image_stats(&img);
    assert!(mean > 10.0, "sponza is black");
    let counts = &report["frame"]["counts"];
    assert_eq!(counts["lights_total"], 80);
    assert_eq!(counts["scene_triangles"], 66450);
    // Culling must remove most of the 6 x 66,450 triangles per cube map.
    let drawn = counts["shadow_triangles_submitted"].as_f64().unwrap();
    let culled = counts["shadow_triangles_culled"].as_f64().unwrap();
    assert!(culled > drawn, "chunk culling: drawn {drawn}, culled {culled}");
}

#[test]
fn random_layout_and_scene_file_with_scale() {
    let obj = fixtures().join("quad.obj");
    let (_, report) = render_ok(
        "random",
        &[
            "--scene",
            obj.to_str().unwrap(),
            "--scale",
            "2",
            "--lights",
            "random:50:1.5:3",
            "--width",
            "64",
            "--height",
            "48",
        ],
    );
    assert_eq!(report["frame"]["counts"]["lights_total"], 50);
    assert_eq!(report["scale"], 2.0);
}

#[test]
fn bad_input_gives_a_one_line_error() {
    let dir = out_dir("bad");
    let png = dir.join("x.png");
    let _ = std::fs::remove_file(&png);
    let png = png.to_str().unwrap();
    let broken = fixtures().join("broken_index.obj");
    let truncated = fixtures().join("truncated.glb");
    assert_fails_with(&["render", "--scene", "nowhere", "--out", png], "unknown built-in scene 'nowhere'");
    assert_fails_with(&["render", "--scene", "/no/such/file.obj", "--out", png], "file not found");
    assert_fails_with(&["render", "--scene", broken.to_str().unwrap(), "--out", png], "broken_index.obj");
    assert_fails_with(&["render", "--scene", truncated.to_str().unwrap(), "--out", png], "truncated.glb");
    assert_fails_with(&["render", "--scene", "cornell", "--lights", "random:abc", "--out", png], "random:abc");
    assert_fails_with(&["render", "--scene", "cornell", "--lights", "random:100001:1", "--out", png], "100001");
    assert_fails_with(&["render", "--scene", "cornell", "--lights", "random:5:nan", "--out", png], "random:5:nan");
    assert_fails_with(&["render", "--scene", "cornell", "--width", "0", "--out", png], "image size");
    assert_fails_with(&["render", "--scene", "cornell", "--width", "100000", "--out", png], "image size");
    assert_fails_with(&["render", "--scene", "cornell", "--shadow-res", "0", "--out", png], "shadow_res");
    assert_fails_with(&["render", "--scene", "cornell", "--param", "bias=inf", "--out", png], "bias");
    assert_fails_with(&["render", "--scene", "cornell", "--param", "nope=1", "--out", png], "no parameter 'nope'");
    assert_fails_with(&["render", "--scene", "cornell", "--technique", "magic", "--out", png], "unknown technique");
    assert_fails_with(&["render", "--scene", "cornell", "--out", "/tmp/x.jpg"], ".png");
    assert_fails_with(&["render", "--scene", "cornell", "--out", "/no/such/dir/x.png"], "does not exist");
    assert_fails_with(&["render", "--scene", "cornell", "--camera", "1,2,3", "--out", png], "--camera");
    assert_fails_with(&["render", "--scene", "cornell", "--z-far=-1", "--out", png], "--z-far");
    assert_fails_with(&["render", "--scene", "cornell", "--scale", "0", "--out", png], "scale");
    assert!(!Path::new(png).exists(), "a failed render must not write its output");
}

#[test]
fn a_sweep_in_rounds_gives_the_median_speedup_of_its_rounds_and_their_range() {
    let dir = out_dir("sweep-rounds");
    let csv = dir.join("rounds.csv");
    let png = dir.join("rounds.png");
    let mut args = vec!["sweep", "--quiet", "--scene", "cornell", "--technique", "lightcluster"];
    args.extend(["--param", "d_init=0.3,0.6", "--width", "48", "--height", "32", "--shadow-res", "32"]);
    args.extend(["--warmup", "0", "--repeat", "1", "--no-flip", "--rounds", "3"]);
    args.extend(["--out", csv.to_str().unwrap(), "--plot", png.to_str().unwrap()]);
    let out = shadowlab(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1 + 2, "one row per setting, not per round:\n{text}");
    let header: Vec<&str> = lines[0].split(',').collect();
    let value = |line: &str, name: &str| -> String {
        let i = header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name}"));
        line.split(',').nth(i).unwrap().to_string()
    };
    for line in &lines[1..] {
        assert_eq!(value(line, "rounds"), "3", "{line}");
        let number = |name: &str| value(line, name).parse::<f64>().unwrap();
        let (low, mid, high) = (number("speedup_min"), number("speedup"), number("speedup_max"));
        assert!(low > 0.0 && low <= mid && mid <= high, "{low} {mid} {high}: {line}");
    }
    assert!(png.exists());
    // One round is the plain sweep: its range is its one speedup.
    let one = dir.join("one.csv");
    let mut args = vec!["sweep", "--quiet", "--scene", "cornell", "--technique", "lightcluster"];
    args.extend(["--param", "d_init=0.3", "--width", "32", "--height", "24", "--shadow-res", "16"]);
    args.extend(["--warmup", "0", "--repeat", "1", "--no-flip", "--out", one.to_str().unwrap()]);
    assert!(shadowlab(&args).status.success());
    let text = std::fs::read_to_string(&one).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    let row: Vec<&str> = text.lines().nth(1).unwrap().split(',').collect();
    let at = |name: &str| row[header.iter().position(|h| *h == name).unwrap()];
    assert_eq!((at("rounds"), at("speedup_min"), at("speedup_max")), ("1", at("speedup"), at("speedup")));
    // Rounds need one light count, and a number of them from 1 to 50.
    let mut args = vec!["sweep", "--scene", "cornell", "--lights", "random:8:1:1", "--param", "lights=4,8"];
    args.extend(["--rounds", "2", "--out", one.to_str().unwrap()]);
    assert_fails_with(&args, "--rounds needs one light count");
    assert_fails_with(
        &["sweep", "--scene", "cornell", "--param", "d_init=0.3", "--rounds", "0", "--out", one.to_str().unwrap()],
        "rounds",
    );
}

#[test]
fn a_compare_in_rounds_reports_each_rounds_speedup_and_their_median() {
    let dir = out_dir("compare-rounds");
    let (png, json) = (dir.join("diff.png"), dir.join("r.json"));
    let mut args = vec!["compare", "--quiet", "--scene", "cornell", "--technique", "lightcluster"];
    args.extend(["--width", "48", "--height", "32", "--shadow-res", "32", "--warmup", "0", "--repeat", "1"]);
    args.extend(["--no-flip", "--rounds", "3", "--out", png.to_str().unwrap(), "--report", json.to_str().unwrap()]);
    let out = shadowlab(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let rounds = &r["rounds"];
    assert_eq!(rounds["count"], 3, "{r}");
    let ratios: Vec<f64> = rounds["ratios"].as_array().unwrap().iter().map(|v| v.as_f64().unwrap()).collect();
    assert_eq!(ratios.len(), 3);
    let (low, high) = (rounds["ratio_min"].as_f64().unwrap(), rounds["ratio_max"].as_f64().unwrap());
    let mut sorted = ratios.clone();
    sorted.sort_by(f64::total_cmp);
    let speedup = r["speedup"]["ratio"].as_f64().unwrap();
    assert_eq!((low, speedup, high), (sorted[0], sorted[1], sorted[2]), "the median of three, within their range");
    let (t, a) = (rounds["technique_ms"].as_f64().unwrap(), rounds["against_ms"].as_f64().unwrap());
    assert!(t > 0.0 && a > 0.0, "{rounds}");
    // One round (the default) writes no rounds; a count outside 1 to 50 is refused.
    let mut args = vec!["compare", "--quiet", "--scene", "cornell", "--technique", "lightcluster"];
    args.extend(["--width", "32", "--height", "24", "--shadow-res", "16", "--warmup", "0", "--repeat", "1"]);
    args.extend(["--no-flip", "--out", png.to_str().unwrap(), "--report", json.to_str().unwrap()]);
    assert!(shadowlab(&args).status.success());
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert!(r.get("rounds").is_none(), "{r}");
    assert_fails_with(&["compare", "--scene", "cornell", "--rounds", "51", "--out", png.to_str().unwrap()], "rounds");
}

#[test]
fn bad_sweeps_are_refused_before_rendering() {
    let csv = out_dir("bad-sweep").join("r.csv");
    let csv = csv.to_str().unwrap();
    let sweep = |extra: &[&'static str]| -> Vec<String> {
        let mut v: Vec<String> = ["sweep", "--scene", "cornell", "--width", "32", "--height", "24", "--out", csv]
            .iter()
            .map(|s| s.to_string())
            .collect();
        v.extend(extra.iter().map(|s| s.to_string()));
        v
    };
    let run = |extra: &[&'static str], expect: &str| {
        let args = sweep(extra);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        assert_fails_with(&args, expect);
    };
    // No swept parameter (it used to panic after rendering).
    run(&[], "at least one --param");
    // A range of 1e30 values (it used to overflow).
    run(&["--param", "d_init=0:1e30:1"], "at most 1000");
    // Three 1,000-value lists: a billion settings.
    run(
        &["--param", "d_init=0:999:1", "--param", "bias=0:0.999:0.001", "--param", "samples=1:1000:1"],
        "at most 10000",
    );
}

#[test]
fn zero_lights_render_and_report_no_shadow_maps() {
    let (img, report) =
        render_ok("zero", &["--scene", "cornell", "--lights", "random:0:1", "--width", "64", "--height", "48"]);
    assert_eq!(report["frame"]["counts"]["shadow_maps"], 0);
    assert_eq!(report["frame"]["counts"]["lights_total"], 0);
    let (_, mean) = image_stats(&img);
    assert!(mean < 60.0, "ambient only should be dark, mean {mean}");
}

#[test]
fn info_prints_scene_statistics() {
    let out = shadowlab(&["info", "--scene", "arcade"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("lights     80"), "{text}");
    assert!(text.contains("triangles"), "{text}");
}

#[test]
fn compare_writes_a_difference_image_and_metrics() {
    let dir = out_dir("compare");
    let diff = dir.join("diff.png");
    let json = dir.join("metrics.json");
    let figure = dir.join("figure.png");
    let out = shadowlab(&[
        "compare",
        "--quiet",
        "--figure",
        figure.to_str().unwrap(),
        "--scene",
        "cornell",
        "--technique",
        "lightcluster",
        "--param",
        "d_init=0.6",
        "--width",
        "96",
        "--height",
        "64",
        "--shadow-res",
        "64",
        "--warmup",
        "0",
        "--repeat",
        "3",
        "--mode",
        "signed",
        "--gain",
        "5",
        "--out",
        diff.to_str().unwrap(),
        "--report",
        json.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let img = image::open(&diff).unwrap();
    assert_eq!((img.width(), img.height()), (96, 64));
    // The figure: technique, reference and difference side by side, with captions.
    let fig = image::open(&figure).unwrap();
    // Captions wrap within 96-pixel panes: the figure is as wide as three panes and at least as tall.
    let (fw, fh) = shadowlab::figure::figure_size(96, 64, 3);
    assert!(fig.width() == fw && fig.height() >= fh, "{}x{}", fig.width(), fig.height());
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert!(r["metrics"]["rmse"].as_f64().unwrap() > 0.0);
    assert!(r["metrics"]["flip_mean"].as_f64().is_some());
    assert!(r["metrics"]["shadow_intensity_error"].as_f64().is_some());
    assert_eq!(r["technique_timing"]["frames"], 3);
    assert!(r["speedup"]["ratio"].as_f64().unwrap() > 0.0);
    // Both sides in one named clock, with the wall-clock ratio beside it.
    let clock = r["speedup"]["clock"].as_str().unwrap();
    assert!(["gpu_timestamps", "wall_clock_steps"].contains(&clock), "{clock}");
    assert!(r["speedup"]["wall_ratio"].as_f64().unwrap() > 0.0);
    assert!(r["technique_timing"]["clock"].as_str().is_some());
    assert!(r["technique_counts"]["clusters"].as_u64().unwrap() < 32);
    // The reference against itself is exact.
    let out = shadowlab(&[
        "compare",
        "--quiet",
        "--scene",
        "cornell",
        "--technique",
        "reference",
        "--width",
        "64",
        "--height",
        "48",
        "--shadow-res",
        "64",
        "--warmup",
        "0",
        "--no-flip",
        "--out",
        diff.to_str().unwrap(),
        "--report",
        json.to_str().unwrap(),
    ]);
    assert!(out.status.success());
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(r["metrics"]["rmse"].as_f64().unwrap(), 0.0);
    assert!(r["metrics"]["psnr_db"].is_null());
}

#[test]
fn a_bad_clock_is_refused_and_a_chosen_one_is_named() {
    let dir = out_dir("clock");
    let png = dir.join("out.png");
    let out = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(["render", "--scene", "cornell", "--width", "32", "--height", "24", "--out", png.to_str().unwrap()])
        .env("SHADOWLAB_TIMING", "fast")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    let last = stderr.lines().last().unwrap_or_default();
    assert!(last.starts_with("error: ") && last.contains("auto, gpu or cpu"), "{last}");

    let json = dir.join("report.json");
    let out = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(["render", "--quiet", "--scene", "cornell", "--width", "32", "--height", "24", "--warmup", "0"])
        .args(["--out", png.to_str().unwrap(), "--report", json.to_str().unwrap()])
        .env("SHADOWLAB_TIMING", "cpu")
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    let frame = if r["frame"].is_object() { &r["frame"] } else { &r };
    assert_eq!(frame["timing"]["source"], "wall_clock_steps", "{frame}");
    assert_eq!(frame["timing"]["mode"], "cpu");
}

#[test]
fn sweep_writes_one_row_per_setting() {
    let dir = out_dir("sweep");
    let csv = dir.join("sweep.csv");
    let md = dir.join("sweep.md");
    let png = dir.join("sweep.png");
    let out = shadowlab(&[
        "sweep",
        "--quiet",
        "--scene",
        "cornell",
        "--technique",
        "lightcluster",
        "--param",
        "d_init=0.4:0.6:0.2",
        "--param",
        "filter=pcf,pcss",
        "--width",
        "64",
        "--height",
        "48",
        "--shadow-res",
        "32",
        "--warmup",
        "0",
        "--no-flip",
        "--out",
        csv.to_str().unwrap(),
        "--markdown",
        md.to_str().unwrap(),
        "--plot",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1 + 4, "{text}");
    assert!(lines[0].starts_with("d_init,filter,clusters"));
    assert!(lines[1].starts_with("0.4,pcf,") && lines[4].starts_with("0.6,pcss,"), "{text}");
    // Fewer or equal clusters for the larger d_init.
    let clusters = |l: &str| l.split(',').nth(2).unwrap().parse::<u32>().unwrap();
    assert!(clusters(lines[4]) <= clusters(lines[1]));
    assert!(std::fs::read_to_string(&md).unwrap().starts_with("| d_init | filter |"));
    let plot = image::open(&png).unwrap();
    assert_eq!((plot.width(), plot.height()), (1200, 480));
    assert_fails_with(
        &[
            "sweep",
            "--scene",
            "cornell",
            "--param",
            "filter=pcf,pcss",
            "--out",
            csv.to_str().unwrap(),
            "--plot",
            png.to_str().unwrap(),
        ],
        "numeric first --param",
    );
    assert_fails_with(
        &["sweep", "--scene", "cornell", "--param", "d_init=1:0:0.1", "--out", csv.to_str().unwrap()],
        "START <= END",
    );
    assert_fails_with(
        &["sweep", "--scene", "cornell", "--param", "d_init=-5", "--out", csv.to_str().unwrap()],
        "d_init",
    );
}

#[test]
fn sweep_over_the_light_count_renders_insm_and_the_target_per_count() {
    let dir = out_dir("sweep-lights");
    let csv = dir.join("lights.csv");
    let png = dir.join("lights.png");
    let csv_arg = csv.to_str().unwrap();
    let common = [
        "sweep",
        "--quiet",
        "--scene",
        "cornell",
        "--lights",
        "random:64:1.5:1",
        "--technique",
        "insm",
        "--width",
        "64",
        "--height",
        "48",
        "--shadow-res",
        "32",
        "--warmup",
        "0",
        "--no-flip",
    ];
    let mut args = common.to_vec();
    args.extend(["--param", "lights=8,24", "--param", "insm_res=16,32", "--out", csv_arg, "--plot"]);
    args.push(png.to_str().unwrap());
    let out = shadowlab(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 1 + 4, "{text}");
    assert!(lines[0].starts_with("lights,insm_res,clusters,visible_lights,shadow_maps"), "{text}");
    // Each row renders its own number of lights: one cube map per visible light.
    let col = |l: &str, i: usize| l.split(',').nth(i).unwrap().parse::<usize>().unwrap();
    assert_eq!((col(lines[1], 0), col(lines[1], 4)), (8, col(lines[1], 3)));
    assert_eq!(col(lines[4], 0), 24);
    assert!(col(lines[4], 4) > col(lines[1], 4), "{text}");
    assert!(image::open(&png).is_ok());
    // The above layout's count is swept the same way.
    let mut above = common.to_vec();
    above[5] = "above:64:3:2";
    above.extend(["--param", "lights=4,12", "--out", csv_arg]);
    let out = shadowlab(&above);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    let counts: Vec<usize> = text.lines().skip(1).map(|l| col(l, 0)).collect();
    assert_eq!(counts, [4, 12], "{text}");
    // A light count needs a random or above layout; a bad count is refused before rendering.
    let mut bad = common.to_vec();
    bad[5] = "grid:4x4:1.5";
    bad.extend(["--param", "lights=8", "--out", csv_arg]);
    assert_fails_with(&bad, "a random or above layout");
    let mut bad = common.to_vec();
    bad.extend(["--param", "lights=many", "--out", csv_arg]);
    assert_fails_with(&bad, "not a light count");
    // Custom INSM viewpoints from the command line; a malformed one is a one-line error.
    let mut custom = common.to_vec();
    custom.extend(["--param", "placement=custom", "--param", "viewpoints=0 1.5 0.9 0 0.5 0 80", "--out", csv_arg]);
    let out = shadowlab(&custom);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let mut custom = common.to_vec();
    custom.extend(["--param", "viewpoints=0 1 0", "--out", csv_arg]);
    assert_fails_with(&custom, "7 numbers");
}

#[test]
fn bench_runs_the_standard_suite_on_the_builtin_scenes() {
    let dir = out_dir("bench");
    let md = dir.join("bench.md");
    let out = shadowlab(&[
        "bench",
        "--builtin-only",
        "--width",
        "64",
        "--height",
        "48",
        "--shadow-res",
        "32",
        "--warmup",
        "0",
        "--repeat",
        "1",
        "--out",
        md.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&md).unwrap();
    // Every technique of the registries on every built-in scene, against its own comparison target (the
    // suite is the registries': it named five direct techniques and no indirect one before).
    use shadowlab_core::technique::registry::{INDIRECT_REGISTRY, REGISTRY};
    for scene in ["cornell", "arcade", "restaurant"] {
        for e in REGISTRY {
            let against = if e.target == e.key { "(itself: a ground truth)" } else { e.target };
            let needle = format!("| {scene} | {} | {against} |", e.key);
            assert!(text.contains(&needle), "{needle} missing in\n{text}");
        }
        for e in INDIRECT_REGISTRY {
            let row = text
                .lines()
                .find(|l| l.starts_with(&format!("| {scene} | unshadowed + {}", e.key)))
                .unwrap_or_else(|| panic!("{scene}: no row for {} in\n{text}", e.key));
            let against = if e.target == e.key { "(itself: a ground truth)" } else { e.target };
            assert!(row.contains(&format!(" | {against} | ")), "{row}");
            if e.target != e.key {
                assert!(row.contains(" | x"), "a speedup against {against}: {row}");
            }
        }
    }
}

#[test]
fn indirect_light_renders_compares_and_sweeps_by_component() {
    let small = ["--scene", "cornell", "--width", "64", "--height", "48", "--vpls", "128"];
    // Total vs direct: the indirect part brightens the image; the report gives the VPL count.
    let mut args: Vec<&str> = small.to_vec();
    args.extend(["--indirect", "vpl-unshadowed"]);
    let (total, report) = render_ok("indirect-total", &args);
    let vpls = report["frame"]["indirect"]["vpls"].as_u64().expect("the report gives vpls");
    assert!(vpls > 0 && vpls <= 128, "{vpls} VPLs");
    let (direct, _) = render_ok("indirect-direct", &small);
    assert!(image_stats(&total).1 > image_stats(&direct).1, "indirect light adds nothing");
    // --vpls 0: no indirect light, said so, and the image equals the direct one.
    let dir = out_dir("indirect-zero");
    let png = dir.join("out.png");
    let mut args: Vec<&str> = vec!["render", "--warmup", "0", "--out", png.to_str().unwrap()];
    args.extend(&small[..6]);
    args.extend(["--indirect", "vpl-raytraced", "--vpls", "0"]);
    let out = shadowlab(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no indirect light"));
    assert!(image::open(&png).unwrap().to_rgba8() == direct, "--vpls 0 changed the image");

    // Comparing two indirect techniques over the same direct light on the indirect component.
    let dir = out_dir("indirect-compare");
    let (diff, json) = (dir.join("diff.png"), dir.join("report.json"));
    let mut args: Vec<&str> =
        vec!["compare", "--warmup", "0", "--out", diff.to_str().unwrap(), "--report", json.to_str().unwrap()];
    args.extend(small);
    args.extend(["--technique", "reference", "--against", "reference", "--indirect", "vpl-unshadowed"]);
    args.extend(["--against-indirect", "vpl-raytraced", "--component", "indirect"]);
    let out = shadowlab(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    // Both sides are named with both their parts, and the component is said.
    assert!(
        stderr.contains("reference + vpl-unshadowed vs reference + vpl-raytraced on cornell (64x48, indirect light)"),
        "{stderr}"
    );
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(r["component"], "indirect");
    assert_eq!(r["against_indirect"]["key"], "vpl-raytraced");
    // Unshadowed VPLs are brighter than visible ones: the indirect component differs.
    assert!(r["metrics"]["rmse"].as_f64().unwrap() > 0.0);
    // No shadow error on the indirect component alone (its shadow factors are not the direct lights'; it read 0).
    assert!(r["metrics"]["shadow_intensity_error"].is_null(), "{}", r["metrics"]);

    // Without --against-indirect, the indirect component of a technique is compared with its own target (the
    // same indirect technique on both sides differed by nothing: RMSE 0 whatever the technique).
    let mut args: Vec<&str> =
        vec!["compare", "--warmup", "0", "--out", diff.to_str().unwrap(), "--report", json.to_str().unwrap()];
    args.extend(small);
    args.extend(["--technique", "unshadowed", "--indirect", "val", "--component", "indirect", "--no-flip"]);
    let out = shadowlab(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("val against its own target, vpl-shadowmaps"), "{stderr}");
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(r["against_indirect"]["key"], "vpl-shadowmaps");
    // And under the same direct technique (a reference under the target's indirect light cost that side time the
    // technique's did not pay: x3.79 read as the indirect technique's speedup).
    assert_eq!(r["against"], "unshadowed", "{stderr}");
    assert!(stderr.contains("unshadowed + val vs unshadowed + vpl-shadowmaps"), "{stderr}");
    assert!(r["metrics"]["rmse"].as_f64().unwrap() > 0.0, "{}", r["metrics"]);

    // A sweep over an indirect parameter: one row per value, with the vpls column.
    let csv = dir.join("sweep.csv");
    let mut args: Vec<&str> = vec!["sweep", "--quiet", "--warmup", "0", "--no-flip", "--out", csv.to_str().unwrap()];
    args.extend(small);
    args.extend(["--technique", "unshadowed", "--against", "unshadowed", "--indirect", "vpl-shadowmaps"]);
    args.extend(["--indirect-param", "shadow_res=16,32", "--against-indirect", "vpl-raytraced"]);
    let out = shadowlab(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 3, "{text}");
    assert!(lines[0].starts_with("indirect.shadow_res,") && lines[0].contains(",vpls,"), "{}", lines[0]);
    // The technique's named figures are columns too, and its own passes.
    assert!(lines[0].contains(",indirect.figure.vpls"), "{}", lines[0]);
    // (a pass in GPU timestamps, the step in wall-clock steps, whichever clock the run chose)
    assert!(
        lines[0].contains(",indirect.pass.vpl gather_ms")
            || lines[0].contains(",indirect.pass.vpl shadow maps + gather_ms"),
        "{}",
        lines[0]
    );
}

#[test]
fn bad_indirect_input_gives_a_one_line_error() {
    let small = ["render", "--scene", "cornell", "--width", "32", "--height", "24", "--out", "/tmp/shadowlab-x.png"];
    let with = |extra: &[&'static str]| -> Vec<&'static str> {
        let mut v = small.to_vec();
        v.extend_from_slice(extra);
        v
    };
    assert_fails_with(&with(&["--indirect", "nope"]), "unknown indirect technique 'nope'");
    assert_fails_with(&with(&["--indirect", "vpl-raytraced", "--vpls", "1000000"]), "limit is 65536");
    assert_fails_with(&with(&["--vpl-source", "photons"]), "--vpl-source 'photons'");
    assert_fails_with(&with(&["--bounces", "0"]), "bounces 0");
    assert_fails_with(&with(&["--vpl-clamp", "NaN"]), "clamp");
    assert_fails_with(&with(&["--component", "both"]), "--component 'both'");
    assert_fails_with(&with(&["--indirect-gain", "0"]), "indirect gain");
    assert_fails_with(&with(&["--indirect", "pathtraced", "--indirect-param", "samples=0"]), "samples");
    assert_fails_with(&with(&["--indirect-param", "samples=4"]), "without an --indirect");
}

/// `shadowlab animate` of three frames of the Cornell box at 48x36, the indirect component over the unshadowed
/// direct light, with `extra` arguments; the CSV it wrote (into `dir`, as `name`).
fn animate_csv(dir: &std::path::Path, name: &str, extra: &[&str]) -> String {
    let csv = dir.join(name);
    let mut args = vec!["animate", "--quiet", "--scene", "cornell", "--width", "48", "--height", "36", "--frames", "3"];
    args.extend(["--technique", "unshadowed", "--component", "indirect", "--out", csv.to_str().unwrap()]);
    args.extend_from_slice(extra);
    let out = shadowlab(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    std::fs::read_to_string(&csv).unwrap()
}

#[test]
fn animate_measures_frame_to_frame_change_and_figures() {
    let dir = out_dir("animate");
    let text = animate_csv(&dir, "frames.csv", &["--vpls", "128", "--step", "0.05,0,0", "--indirect", "val"]);
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines.len(), 4, "{text}");
    assert!(
        lines[0].starts_with("frame,mean_change,mean_radiance") && lines[0].contains("indirect.figure.vals"),
        "{text}"
    );
    // Frame 0 has no previous frame; the lights move, so the later frames change.
    let change: f64 = lines[2].split(',').nth(1).unwrap().parse().unwrap();
    assert!(lines[1].split(',').nth(1).unwrap().is_empty() && change > 0.0, "{text}");
    assert_fails_with(&["animate", "--scene", "cornell", "--frames", "1", "--out", "/tmp/x.csv"], "--frames 1");
    assert_fails_with(&["animate", "--scene", "cornell", "--step", "1,2", "--out", "/tmp/x.csv"], "--step '1,2'");
    assert_fails_with(&["animate", "--scene", "cornell", "--orbit", "inf", "--out", "/tmp/x.csv"], "--orbit");
    assert_fails_with(
        &["animate", "--scene", "cornell", "--against-indirect-param", "shadow_res=64", "--out", "/tmp/x.csv"],
        "needs --against-indirect",
    );
}

#[test]
fn animate_turns_the_camera_and_measures_each_frame_against_a_target() {
    // The camera orbits (lights still); every frame is timed in one named clock and compared with the same
    // frame of another indirect technique. Against itself the error is zero; against the unshadowed VPL
    // gather (no indirect shadows) it is not, and the moving camera changes the image.
    let dir = out_dir("animate-orbit");
    let run = |target: &str, name: &str| {
        let extra = ["--vpls", "64", "--step", "0,0,0", "--orbit", "15", "--indirect", "vpl-shadowmaps"];
        let text = animate_csv(&dir, name, &[&extra[..], &["--against-indirect", target]].concat());
        let lines: Vec<String> = text.lines().map(str::to_string).collect();
        let header: Vec<&str> = lines[0].split(',').collect();
        let col = |row: &str, key: &str| -> String {
            let i = header.iter().position(|h| *h == key).unwrap_or_else(|| panic!("no column {key}: {text}"));
            row.split(',').nth(i).unwrap().to_string()
        };
        assert_eq!(lines.len(), 4, "{text}");
        let rows: Vec<(f64, f64, String, f64)> = lines[1..]
            .iter()
            .map(|r| {
                let change = col(r, "mean_change").parse().unwrap_or(-1.0);
                (col(r, "rmse").parse().unwrap(), col(r, "ms").parse().unwrap(), col(r, "clock"), change)
            })
            .collect();
        assert!(rows.iter().all(|r| r.1 > 0.0 && !r.2.is_empty() && r.2 == rows[0].2), "{text}");
        // The frame's work counts, the direct and the indirect technique's, beside its time.
        let vpl_work: f64 = col(&lines[1], "indirect.work.vpl_pixel_evaluations").parse().unwrap();
        assert!(vpl_work > 0.0 && header.contains(&"work.shaded_pixels"), "{text}");
        assert!(rows[1].3 > 0.0, "the camera moved, the image must change: {text}");
        rows.iter().map(|r| r.0).collect::<Vec<f64>>()
    };
    assert!(run("vpl-shadowmaps", "self.csv").iter().all(|&e| e == 0.0));
    assert!(run("vpl-unshadowed", "unshadowed.csv").iter().all(|&e| e > 0.0));
}

#[test]
fn sequence_writes_an_orbits_pngs_and_a_gif_of_them() {
    use image::AnimationDecoder;
    let dir = out_dir("sequence");
    let frames_dir = dir.join("orbit");
    let gif = dir.join("orbit.gif");
    let _ = std::fs::remove_dir_all(&frames_dir);
    let _ = std::fs::remove_file(&gif);
    let size = ["--width", "40", "--height", "30", "--shadow-res", "32"];
    let mut args = vec!["sequence", "--quiet", "--scene", "cornell", "--frames", "4", "--frame-ms", "120"];
    args.extend_from_slice(&size);
    args.extend_from_slice(&["--out-dir", frames_dir.to_str().unwrap(), "--gif", gif.to_str().unwrap()]);
    let out = shadowlab(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let pngs: Vec<image::RgbaImage> =
        (0..4).map(|i| image::open(frames_dir.join(format!("frame-{i:04}.png"))).unwrap().to_rgba8()).collect();
    assert!(!frames_dir.join("frame-0004.png").exists(), "exactly four frames");
    assert!(pngs.iter().all(|p| p.dimensions() == (40, 30)));
    assert!(pngs[0] != pngs[1] && pngs[1] != pngs[2], "the camera moved between frames");
    let file = std::io::BufReader::new(std::fs::File::open(&gif).unwrap());
    let decoded = image::codecs::gif::GifDecoder::new(file).unwrap().into_frames().collect_frames().unwrap();
    assert_eq!(decoded.len(), 4, "one GIF frame per PNG");
    for (g, p) in decoded.iter().zip(&pngs) {
        assert_eq!(g.buffer().dimensions(), (40, 30));
        assert_eq!(g.delay().numer_denom_ms(), (120, 1));
        // The GIF frame is the PNG frame through a 256-colour palette.
        let diff: f64 = g
            .buffer()
            .pixels()
            .zip(p.pixels())
            .map(|(a, b)| (0..3).map(|c| (a[c] as f64 - b[c] as f64).abs()).sum::<f64>())
            .sum::<f64>()
            / (40.0 * 30.0 * 3.0);
        assert!(diff < 6.0, "mean difference {diff} between the GIF frame and its PNG");
    }
    // The lights moving instead: frames differ, the camera stays.
    let lights_dir = dir.join("lights");
    let mut args = vec!["sequence", "--quiet", "--scene", "cornell", "--frames", "2", "--motion", "lights"];
    args.extend_from_slice(&size);
    args.extend_from_slice(&["--step", "0.3,0,0", "--out-dir", lights_dir.to_str().unwrap()]);
    let out = shadowlab(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let a = image::open(lights_dir.join("frame-0000.png")).unwrap();
    let b = image::open(lights_dir.join("frame-0001.png")).unwrap();
    assert!(a != b, "the lights moved");
    // With the default overlay layers (the lights' dots) drawn over each frame.
    let overlays_dir = dir.join("overlays");
    let mut args = vec!["sequence", "--quiet", "--scene", "cornell", "--frames", "2", "--motion", "lights"];
    args.extend_from_slice(&size);
    args.extend_from_slice(&["--step", "0.3,0,0", "--overlays", "--out-dir", overlays_dir.to_str().unwrap()]);
    let out = shadowlab(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(image::open(overlays_dir.join("frame-0000.png")).unwrap() != a, "the overlays are drawn");
    let mut args = vec!["sequence", "--scene", "cornell", "--frames", "1", "--overlay-layer", "nope"];
    args.extend_from_slice(&size);
    args.extend_from_slice(&["--out-dir", overlays_dir.to_str().unwrap()]);
    assert_fails_with(&args, "--overlay-layer 'nope'");
    let no_dir = ["--out-dir", "/tmp/shadowlab-seq"];
    assert_fails_with(&[&["sequence", "--frames", "0"][..], &no_dir].concat(), "--frames 0");
    assert_fails_with(&[&["sequence", "--gif", "x.png"][..], &no_dir].concat(), "must end in .gif");
    assert_fails_with(&[&["sequence", "--motion", "lights", "--step", "1"][..], &no_dir].concat(), "--step '1'");
}

#[test]
fn maps_out_saves_the_shadow_atlases() {
    let dir = out_dir("maps");
    let maps = dir.join("maps.png");
    let indirect = dir.join("maps-indirect.png");
    let _ = std::fs::remove_file(&maps);
    let _ = std::fs::remove_file(&indirect);
    let maps_arg = maps.to_str().unwrap().to_string();
    let extra = [
        "--scene",
        "cornell",
        "--width",
        "32",
        "--height",
        "24",
        "--shadow-res",
        "32",
        "--vpls",
        "64",
        "--indirect",
        "val",
        "--indirect-param",
        "shadow_res=32",
        "--maps-out",
        &maps_arg,
    ];
    render_ok("maps", &extra);
    let direct = image::open(&maps).unwrap().to_rgba8();
    let val = image::open(&indirect).unwrap().to_rgba8();
    // Drawn depth is grey to white somewhere, empty texels black.
    assert!(direct.pixels().any(|p| p[0] > 64) && val.pixels().any(|p| p[0] > 64));
    assert_eq!(val.width() % 32, 0);
    // INSM: its cube maps drawn from the meshes, and its intermediate images (4 of 32²: a 2x2 atlas).
    let images = dir.join("maps-images.png");
    let _ = std::fs::remove_file(&images);
    let insm = ["--scene", "cornell", "--width", "32", "--height", "24", "--shadow-res", "32", "--technique", "insm"];
    let insm_params = ["--param", "k=4", "--param", "insm_res=32", "--maps-out", &maps_arg];
    render_ok("maps", &[&insm[..], &insm_params[..]].concat());
    let images = image::open(&images).unwrap().to_rgba8();
    assert_eq!(images.dimensions(), (64, 64), "four 32² images");
    assert!(images.pixels().any(|p| p[0] > 64), "the images see the room");
    let png = dir.join("x.png");
    assert_fails_with(
        &[
            "render",
            "--scene",
            "cornell",
            "--technique",
            "unshadowed",
            "--out",
            png.to_str().unwrap(),
            "--maps-out",
            &maps_arg,
        ],
        "renders shadow maps",
    );
}

#[test]
fn rsm_out_saves_a_lights_reflective_shadow_map_with_its_vpls_marked() {
    let dir = out_dir("rsm");
    let rsm = dir.join("rsm.png");
    let _ = std::fs::remove_file(&rsm);
    let rsm_arg = rsm.to_str().unwrap().to_string();
    let scene = ["--scene", "cornell", "--width", "32", "--height", "24", "--technique", "unshadowed"];
    let with = ["--vpls", "512", "--indirect", "vpl-raytraced", "--rsm-light", "5", "--rsm-res", "32"];
    render_ok("rsm", &[&scene[..], &with[..], &["--rsm-out", &rsm_arg][..]].concat());
    let png = image::open(&rsm).unwrap().to_rgba8();
    // A point light's cube as a cross of 4 x 3 faces; inside the box the walls it reaches are lit, and the
    // texels its VPLs came from are marked.
    assert_eq!(png.dimensions(), (128, 96));
    let mark = [255, 60, 200, 255];
    assert!(png.pixels().any(|p| p.0 == mark), "no VPL marked");
    assert!(png.pixels().any(|p| p.0 != mark && p[0].max(p[1]) > 100), "nothing lit");
    // Normals without an indirect technique: no marks.
    let normals = ["--rsm-light", "0", "--rsm-show", "normal", "--rsm-out", &rsm_arg];
    render_ok("rsm", &[&scene[..], &normals[..]].concat());
    let png = image::open(&rsm).unwrap().to_rgba8();
    assert!(!png.pixels().any(|p| p.0 == mark), "marks without VPLs");
    let out = dir.join("x.png");
    let base = ["render", "--scene", "cornell", "--width", "8", "--height", "8", "--out", out.to_str().unwrap()];
    let bad_light = ["--rsm-out", &rsm_arg, "--rsm-light", "40"];
    assert_fails_with(&[&base[..], &bad_light[..]].concat(), "--rsm-light 40: the scene has 32 point lights");
    let bad_res = ["--rsm-out", &rsm_arg, "--rsm-res", "0"];
    assert_fails_with(&[&base[..], &bad_res[..]].concat(), "choose 1 to 512");
    assert_fails_with(&[&base[..], &["--rsm-out", "rsm.jpg"][..]].concat(), "rsm.jpg");
}

#[test]
fn a_scene_without_lights_gets_a_default_layout_and_says_so() {
    let dir = out_dir("unlit");
    let png = dir.join("out.png");
    let json = dir.join("report.json");
    let quad = fixtures().join("quad.obj");
    let args = [
        "render",
        "--warmup",
        "0",
        "--width",
        "48",
        "--height",
        "36",
        "--scene",
        quad.to_str().unwrap(),
        "--out",
        png.to_str().unwrap(),
        "--report",
        json.to_str().unwrap(),
    ];
    let out = shadowlab(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("has no lights; using --lights random:16:"), "{stderr}");
    let report: serde_json::Value = serde_json::from_slice(&std::fs::read(&json).unwrap()).unwrap();
    assert_eq!(report["frame"]["counts"]["lights_total"], 16);
}

#[test]
fn fuzzy_clustering_traces_particles_by_default_and_sweeps_its_time_split() {
    let small = ["--scene", "cornell", "--width", "64", "--height", "48", "--vpls", "128"];
    // `--vpl-source auto` (the default): fuzzy takes the traced particles of its paper; others take RSMs.
    let mut args: Vec<&str> = small.to_vec();
    args.extend([
        "--indirect",
        "fuzzy",
        "--overlays",
        "--indirect-param",
        "probe_x=32",
        "--indirect-param",
        "probe_y=30",
    ]);
    let (_, report) = render_ok("fuzzy-render", &args);
    assert_eq!(report["frame"]["indirect"]["vpl_source"], "traced");
    let figures = &report["frame"]["indirect"]["counts"];
    assert!(figures["k_sp"].as_f64().unwrap() > 0.0 && figures["k_vpl"].as_f64().unwrap() > 0.0, "{figures}");
    let mut args: Vec<&str> = small.to_vec();
    args.extend(["--indirect", "vpl-raytraced"]);
    let (_, report) = render_ok("fuzzy-rsm", &args);
    assert_eq!(report["frame"]["indirect"]["vpl_source"], "rsm");
    // A sweep over the visibility modes against vpl-raytraced: wall-clock columns and the technique's passes.
    let dir = out_dir("fuzzy-sweep");
    let csv = dir.join("modes.csv");
    let mut args: Vec<&str> = vec!["sweep", "--quiet", "--warmup", "0", "--out", csv.to_str().unwrap()];
    args.extend(small);
    args.extend(["--technique", "unshadowed", "--against", "unshadowed", "--component", "indirect"]);
    args.extend([
        "--indirect",
        "fuzzy",
        "--indirect-param",
        "mode=hard,weighted",
        "--against-indirect",
        "vpl-raytraced",
    ]);
    // The columns below are the wall-clock steps' names; `auto` may keep the timestamps (named per pass) when
    // the machine is loaded, so the clock is named.
    let runtime = std::env::temp_dir().join("shadowlab-xdg");
    std::fs::create_dir_all(&runtime).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(&args)
        .env("XDG_RUNTIME_DIR", &runtime)
        .env("SHADOWLAB_TIMING", "cpu")
        .output()
        .expect("run shadowlab");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
    for column in [
        "wall_ms",
        "against_wall_ms",
        "wall_speedup",
        "indirect.pass.fuzzy visibility_ms",
        "indirect.pass.fuzzy shading_ms",
        "indirect.pass.fuzzy clustering_ms",
        "indirect.pass.fuzzy readback_ms",
        "indirect.figure.k_sp",
    ] {
        assert!(header.contains(&column), "no column {column} in {header:?}");
    }
    assert_eq!(text.lines().count(), 3, "{text}");
    let wall = header.iter().position(|h| *h == "wall_ms").unwrap();
    for row in text.lines().skip(1) {
        let ms: f64 = row.split(',').nth(wall).unwrap().parse().unwrap();
        assert!(ms > 0.0, "{row}");
    }
}

#[test]
fn auto_exposure_scales_the_image_by_what_it_metered() {
    // lit_quad.gltf (an emissive quad and a 20 cd light, 0.03 W/sr): --auto-exposure meters the image, says
    // what it found, and the image is darker or brighter than at the fixed exposure as its scale says.
    let gltf = fixtures().join("lit_quad.gltf");
    let base = ["--width", "64", "--height", "48", "--scene", gltf.to_str().unwrap(), "--lights", "scene"];
    let (fixed, _) = render_ok("exposure-fixed", &base);
    let dir = out_dir("exposure-auto");
    let png = dir.join("out.png");
    let args = [&["render", "--warmup", "0", "--out", png.to_str().unwrap()][..], &base, &["--auto-exposure"]].concat();
    let out = shadowlab(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    let line =
        stderr.lines().find(|l| l.contains("auto exposure: log-average luminance")).expect("says what it metered");
    let scale: f32 = line.split("scale x").nth(1).and_then(|s| s.split_whitespace().next()).unwrap().parse().unwrap();
    assert!(scale.is_finite() && scale > 0.0 && (scale - 1.0).abs() > 0.2, "{line}");
    let auto = image::open(&png).unwrap().to_rgba8();
    let (_, fixed_mean) = image_stats(&fixed);
    let (_, auto_mean) = image_stats(&auto);
    if scale < 1.0 {
        assert!(auto_mean < fixed_mean - 5.0, "scale {scale}: mean grey auto {auto_mean}, fixed {fixed_mean}");
    } else {
        assert!(auto_mean > fixed_mean + 5.0, "scale {scale}: mean grey auto {auto_mean}, fixed {fixed_mean}");
    }
}

/// The rows of a trade-off CSV as maps from column to cell (no cell of these tests holds a comma).
fn tradeoff_rows(path: &Path) -> Vec<std::collections::BTreeMap<String, String>> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("a header").split(',').collect();
    lines.map(|l| header.iter().map(|h| h.to_string()).zip(l.split(',').map(String::from)).collect()).collect()
}

const TRADEOFF_VIEW: [&str; 10] =
    ["--quiet", "--scene", "cornell", "--width", "64", "--height", "48", "--shadow-res", "32", "--warmup"];

#[test]
fn tradeoff_flags_the_pareto_front_of_several_techniques() {
    let dir = out_dir("tradeoff");
    let csv = dir.join("t.csv");
    let png = dir.join("t.png");
    let mut args = vec!["tradeoff"];
    args.extend(TRADEOFF_VIEW);
    args.extend([
        "0",
        "--try",
        "lightcluster d_init=0.4,1.2 filter=pcf",
        "--try",
        "reference",
        "--try",
        "unshadowed",
        "--against",
        "reference",
        "--work-axis",
        "depth_triangles",
        "--out",
        csv.to_str().unwrap(),
        "--plot",
        png.to_str().unwrap(),
    ]);
    let out = shadowlab(&args);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let rows = tradeoff_rows(&csv);
    assert_eq!(rows.len(), 4, "{rows:?}");
    let num = |r: &std::collections::BTreeMap<String, String>, k: &str| r[k].parse::<f64>().unwrap();
    assert_eq!(rows[0]["parameters"], "d_init=0.4 filter=pcf");
    assert_eq!(rows[2]["try"], "reference");
    assert_eq!(num(&rows[2], "error"), 0.0, "the reference against itself");
    assert!(num(&rows[3], "error") > 0.0, "unshadowed misses every shadow");
    assert!(rows.iter().all(|r| r["clock"] == rows[0]["clock"] && r["metric"] == "RMSE"));
    // The flags are the front: a row is on it exactly when no other row is at most as slow and as wrong.
    for r in &rows {
        let dominated = rows.iter().any(|q| {
            let (qm, qe, rm, re) = (num(q, "ms"), num(q, "error"), num(r, "ms"), num(r, "error"));
            qm <= rm && qe <= re && (qm < rm || qe < re)
        });
        assert_eq!(r["pareto"], (!dominated).to_string(), "{r:?}");
    }
    assert!(rows.iter().any(|r| r["pareto"] == "true") && rows.iter().all(|r| r["pick"] == "false"));
    assert!(num(&rows[2], "work.depth_triangles") > 0.0, "work counts are columns");
    let plot = image::open(&png).unwrap();
    assert_eq!((plot.width(), plot.height()), (1440, 520), "two panels: time and work");
}

#[test]
fn tradeoff_tunes_to_a_budget_with_few_frames() {
    let dir = out_dir("tradeoff-budget");
    let csv = dir.join("t.csv");
    let run = |goal: &[&str]| {
        let mut args = vec!["tradeoff"];
        args.extend(TRADEOFF_VIEW);
        args.extend(["0", "--try", "lightcluster d_init=0.2:1.6:0.2", "--out", csv.to_str().unwrap()]);
        args.extend(goal);
        let out = shadowlab(&args);
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
        String::from_utf8_lossy(&out.stdout).to_string()
    };
    // Every setting fits: the two ends of the bracketed d_init tell so, and the pick is the fastest of them.
    let text = run(&["--max-error", "1e9"]);
    assert!(text.contains("pick: lightcluster d_init="), "{text}");
    assert!(text.contains("2 of the 8 configurations rendered"), "{text}");
    let rows = tradeoff_rows(&csv);
    assert_eq!(rows.len(), 2);
    let picked: Vec<_> = rows.iter().filter(|r| r["pick"] == "true").collect();
    assert_eq!(picked.len(), 1);
    let fastest = rows.iter().map(|r| r["ms"].parse::<f64>().unwrap()).fold(f64::INFINITY, f64::min);
    assert_eq!(picked[0]["ms"].parse::<f64>().unwrap(), fastest);
    // Nothing fits a budget no frame can meet: said, not a pick.
    let text = run(&["--budget-ms", "0.000001"]);
    assert!(text.contains("pick: nothing fits within 0.000001 ms"), "{text}");
    // Bad input is refused before anything renders.
    let base = ["tradeoff", "--scene", "cornell", "--out", csv.to_str().unwrap()];
    let with = |extra: &[&'static str]| base.iter().copied().chain(extra.iter().copied()).collect::<Vec<&str>>();
    assert_fails_with(&with(&["--try", "nosuch"]), "'nosuch' is not a technique");
    assert_fails_with(&with(&["--try", "reference", "--budget-ms=-1"]), "--budget-ms -1");
    assert_fails_with(&with(&["--try", "reference", "--work-axis", "nope"]), "--work-axis 'nope'");
    assert_fails_with(&with(&["--try", "lightcluster d_init=-3"]), "d_init");
    assert_fails_with(&with(&["--try", "reference", "--against", "raytraced bias=0.01,0.02"]), "the target takes one");
}

#[test]
fn app_times_must_be_seconds() {
    // Refused before any window opens: a NaN would never quit, a negative one at once.
    assert_fails_with(&["--quit-after", "nan"], "--quit-after NaN");
    assert_fails_with(&["--soak-secs=-3"], "--soak-secs -3");
}

#[test]
fn suns_from_the_command_line_light_the_scene_directly_and_through_vpls() {
    let base = ["--scene", "cornell", "--lights", "random:0:1", "--width", "64", "--height", "48"];
    let with = |name: &str, extra: &[&str]| render_ok(name, &[&base[..], extra].concat());
    let (dark, report) = with("sun-none", &[]);
    assert!(!report["frame"]["passes"].as_array().unwrap().iter().any(|p| p["name"] == "directional lights"));
    // The box is open on one side: one of two opposite suns shines in.
    let lit = ["0,40,4", "180,40,4"]
        .iter()
        .map(|sun| {
            let (img, report) = with(&format!("sun-{}", &sun[..1]), &["--sun", sun]);
            let passes = report["frame"]["passes"].as_array().unwrap();
            assert!(passes.iter().any(|p| p["name"] == "directional lights"), "--sun {sun}: {passes:?}");
            image_stats(&img).1
        })
        .fold(0.0f32, f32::max);
    assert!(lit > image_stats(&dark).1 + 2.0, "no sun lights the box: {lit} against {}", image_stats(&dark).1);
    // Its light makes VPLs: the indirect component of a sun-lit box without point lights is not black.
    let indirect = ["--indirect", "vpl-raytraced", "--component", "indirect", "--vpls", "128"];
    let (img, report) = with("sun-indirect", &[&indirect[..], &["--sun", "180,40,4", "--sun", "0,40,4"]].concat());
    assert!(report["frame"]["indirect"]["vpls"].as_u64().unwrap() > 0, "{}", report["frame"]["indirect"]);
    assert!(image_stats(&img).1 > 1.0, "the indirect light of the suns is black");
    // Bad suns are refused with a message.
    assert_fails_with(&["render", "--out", "x.png", "--sun", "1,2"], "AZIMUTH,ELEVATION,ILLUMINANCE");
    assert_fails_with(&["render", "--out", "x.png", "--sun", "0,95,1"], "elevation");
    assert_fails_with(&["render", "--out", "x.png", "--sun", "0,45,-1"], ">= 0");
    let five: Vec<&str> = (0..5).flat_map(|_| ["--sun", "0,45,1"]).collect();
    assert_fails_with(&[&["render", "--out", "x.png"][..], &five].concat(), "at most 4");
}

#[test]
fn a_tradeoff_of_the_indirect_light_alone_is_against_the_indirect_techniques_own_target() {
    // Without a target's indirect technique, VALs' indirect light was compared with the target's none (an
    // error of the whole indirect light); now with their own target, one shadow map per VPL, and said so.
    let dir = out_dir("tradeoff-indirect");
    let csv = dir.join("t.csv");
    let mut args = vec!["tradeoff", "--scene", "cornell", "--width", "32", "--height", "24", "--shadow-res", "16"];
    args.extend(["--warmup", "0", "--repeat", "1", "--vpls", "32", "--component", "indirect"]);
    args.extend(["--direct", "unshadowed", "--against", "unshadowed", "--try", "val vals=2", "--out"]);
    args.push(csv.to_str().unwrap());
    let out = shadowlab(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("val against its own target, vpl-shadowmaps"), "{stderr}");
    assert!(stderr.contains("against unshadowed + vpl-shadowmaps"), "{stderr}");
}

#[test]
fn a_sweep_names_each_sides_map_resolution_and_says_when_they_differ() {
    // The techniques' default map resolutions differ (the reference 1024², INSM 512²): a comparison at two
    // resolutions is named as such, on the terminal and in the CSV, and one `--shadow-res` sets both.
    let dir = out_dir("sweep-resolutions");
    let csv = dir.join("r.csv");
    let base = [
        "sweep",
        "--scene",
        "cornell",
        "--lights",
        "random:2:1.5:1",
        "--width",
        "32",
        "--height",
        "24",
        "--warmup",
        "0",
        "--no-flip",
        "--technique",
        "lightcluster",
        "--param",
        "d_init=0.4",
        "--against",
        "reference",
    ];
    let column = |text: &str, name: &str| -> String {
        let header: Vec<&str> = text.lines().next().unwrap().split(',').collect();
        let i = header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no column {name} in {header:?}"));
        text.lines().nth(1).unwrap().split(',').nth(i).unwrap().to_string()
    };
    let args = [
        &base[..],
        &["--param", "shadow_res=32", "--against-param", "shadow_res=64", "--out"],
        &[csv.to_str().unwrap()],
    ]
    .concat();
    let out = shadowlab(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("not at one resolution: maps lightcluster 32², reference 64²"), "{stderr}");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!((column(&text, "maps_res"), column(&text, "against_maps_res")), ("32".into(), "64".into()));
    assert_eq!(column(&text, "indirect_maps_res"), "");
    let args = [&base[..], &["--shadow-res", "32", "--out"], &[csv.to_str().unwrap()]].concat();
    let out = shadowlab(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(!stderr.contains("not at one resolution"), "{stderr}");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!((column(&text, "maps_res"), column(&text, "against_maps_res")), ("32".into(), "32".into()));
}
