//! `scripts/measure-gpu`, the papers' headline comparisons at the papers' scale for a real GPU: its smoke run
//! (tiny sizes, on the software adapter too) gives one table row per comparison with a speedup and a clock,
//! headed by the adapter; without `--smoke` it refuses a software adapter with exit code 2.

use std::path::PathBuf;
use std::process::{Command, Output};

fn runtime_dir() -> PathBuf {
    let runtime = std::env::temp_dir().join("shadowlab-xdg");
    std::fs::create_dir_all(&runtime).unwrap();
    runtime
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// `scripts/measure-gpu ARGS` with the binary under test (never a cargo build of its own).
fn measure_gpu(args: &[&str]) -> Output {
    Command::new(repo().join("scripts/measure-gpu"))
        .args(args)
        .env("SHADOWLAB", env!("CARGO_BIN_EXE_shadowlab"))
        // Quiets Mesa's "XDG_RUNTIME_DIR is invalid" noise.
        .env("XDG_RUNTIME_DIR", runtime_dir())
        .env_remove("SHADOWLAB_TIMING")
        .env_remove("WARMUP")
        .env_remove("REPEAT")
        // The shared scenes where the tests look for them (`../shared/scenes`), not a user's other folder.
        .env_remove("SHADOWLAB_SCENES")
        .output()
        .expect("run scripts/measure-gpu")
}

/// The adapter as `shadowlab info` names it ("NAME (BACKEND, TYPE)"); a failure fails the test (GPU tests
/// never skip without an adapter).
fn adapter() -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_shadowlab"))
        .args(["info", "--scene", "cornell"])
        .env("XDG_RUNTIME_DIR", runtime_dir())
        .output()
        .expect("run shadowlab info");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "shadowlab info failed:\n{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    stdout
        .lines()
        .find_map(|l| l.strip_prefix("adapter"))
        .map(|a| a.trim().to_string())
        .unwrap_or_else(|| panic!("shadowlab info named no adapter:\n{stdout}"))
}

/// As the script decides: device type `Cpu`, or a known software rasterizer's name.
fn is_software(adapter: &str) -> bool {
    let lower = adapter.to_lowercase();
    adapter.ends_with(", Cpu)")
        || ["llvmpipe", "lavapipe", "swiftshader", "softpipe", "basic render"].iter().any(|n| lower.contains(n))
}

const COMPARISONS: [&str; 18] = [
    "LightCluster d_init=0.5 vs reference",
    "LightCluster d_init=0.5, maps from a simplified copy",
    "LightCluster d_init=1.6 vs reference",
    "LightCluster d_init=1.6, maps from a simplified copy",
    "LightCluster d_init=0.5, centers by greedy covering",
    "LightCluster d_init=1.6, simplified copy and cluster maps at half resolution",
    "INSM vs reference",
    "INSM, whole tiles merged only",
    "INSM, meshes simplified",
    "VALs vs one shadow map per VPL",
    "VALs, M = ",
    "VALs, M = ",
    "VALs, M = ",
    "VALs, M = ",
    "VALs, M = ",
    "ray-traced VPL visibility interleaved",
    "fuzzy clustering vs exact VPL visibility",
    "unshadowed vs reference",
];

/// The rows that compute FLIP (the others skip it: it costs seconds on the CPU at the papers' sizes).
const WITH_FLIP: [&str; 2] = ["VALs, M = ", "ray-traced VPL visibility interleaved"];

#[test]
fn smoke_run_gives_one_row_per_comparison_with_speedup_and_clock() {
    let adapter = adapter();
    let out = measure_gpu(&["--smoke"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "measure-gpu --smoke failed ({:?}):\n{stdout}\n{stderr}", out.status);
    assert!(!stderr.contains("panicked"), "a run panicked:\n{stderr}");

    // Headed by the adapter, and marked as no measurement.
    let heading = stdout.lines().next().unwrap_or_default();
    assert_eq!(heading, format!("### {adapter}"), "the table is not headed by the adapter:\n{stdout}");
    assert!(stdout.contains("smoke run: tiny sizes, not a measurement"), "no smoke label:\n{stdout}");
    assert!(stdout.contains("SHADOWLAB_TIMING=gpu"), "the clock setting is not below the table:\n{stdout}");
    assert!(stdout.contains("Command: `scripts/measure-gpu --smoke`"), "no command line:\n{stdout}");

    let table: Vec<Vec<&str>> = stdout
        .lines()
        .filter(|l| l.starts_with('|'))
        .map(|l| l.trim_matches('|').split('|').map(str::trim).collect())
        .collect();
    assert!(table.len() >= 2, "no table:\n{stdout}");
    let header = &table[0];
    let col = |name: &str| {
        header.iter().position(|h| *h == name).unwrap_or_else(|| panic!("no '{name}' column in {header:?}"))
    };
    let (speedup, clock, wall, rmse) = (col("speedup"), col("clock"), col("wall-clock ratio"), col("RMSE"));
    let flip = col("FLIP");
    let (tech_ms, against_ms) = (col("technique ms"), col("against ms"));
    let rows = &table[2..];
    assert_eq!(rows.len(), COMPARISONS.len(), "one row per comparison (both d_init values):\n{stdout}");
    let ratio = |cell: &str| -> f64 {
        let v = cell.strip_prefix('x').and_then(|v| v.parse::<f64>().ok());
        v.unwrap_or_else(|| panic!("'{cell}' is no ratio like x1.23"))
    };
    let number = |cell: &str| -> f64 { cell.replace(',', "").parse().unwrap_or_else(|_| panic!("'{cell}' no number")) };
    for (row, name) in rows.iter().zip(COMPARISONS) {
        assert_eq!(row.len(), header.len(), "row {row:?}");
        assert!(row[0].starts_with(name), "expected the comparison '{name}', got {row:?}");
        let s = ratio(row[speedup]);
        assert!(s.is_finite() && s > 0.0, "speedup {s} in {row:?}");
        assert!(ratio(row[wall]) > 0.0, "wall-clock ratio in {row:?}");
        assert!(["gpu_timestamps", "wall_clock_steps"].contains(&row[clock]), "clock in {row:?}");
        assert!(number(row[tech_ms]) > 0.0 && number(row[against_ms]) > 0.0, "times in {row:?}");
        let e = number(row[rmse]);
        assert!(e.is_finite() && e >= 0.0, "RMSE in {row:?}");
        if WITH_FLIP.contains(&name) {
            let f = number(row[flip]);
            assert!(f.is_finite() && (0.0..=1.0).contains(&f), "FLIP in {row:?}");
        } else {
            assert_eq!(row[flip], "-", "FLIP computed where it is skipped: {row:?}");
        }
    }

    // The same table in the smoke folder (never over a real run's target/measure-gpu/table.md).
    let saved = std::fs::read_to_string(repo().join("target/measure-gpu/smoke/table.md")).unwrap();
    assert_eq!(saved, stdout, "the saved table differs from the printed one");
}

#[test]
fn full_run_refuses_a_software_adapter() {
    let adapter = adapter();
    if !is_software(&adapter) {
        // A real GPU: the full run is the measurement itself (minutes), not a test.
        eprintln!("NOT RUN: the adapter is no software one ({adapter}), and the full run is no test");
        return;
    }
    let out = measure_gpu(&[]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "expected the refusal (exit 2):\n{stdout}\n{stderr}");
    assert!(stdout.is_empty(), "a refused run prints no table:\n{stdout}");
    assert!(stderr.contains("refusing to run on a software adapter"), "no refusal message:\n{stderr}");
    assert!(stderr.contains(&adapter), "the refusal does not name the adapter:\n{stderr}");
    assert!(stderr.contains("100x slower") && stderr.contains("--smoke"), "the refusal does not say why:\n{stderr}");
}

#[test]
fn smoke_tradeoff_run_writes_three_curves_each_with_a_pareto_front_and_the_orbit() {
    let adapter = adapter();
    let out = measure_gpu(&["--smoke", "--tradeoff"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "measure-gpu --smoke --tradeoff failed ({:?}):\n{stdout}\n{stderr}", out.status);
    assert!(!stderr.contains("panicked"), "a run panicked:\n{stderr}");
    let heading = stdout.lines().next().unwrap_or_default();
    assert_eq!(heading, format!("### {adapter}: trade-off curves"), "not headed by the adapter:\n{stdout}");
    assert!(stdout.contains("smoke run: tiny sizes, not a measurement"), "no smoke label:\n{stdout}");
    let dir = repo().join("target/measure-gpu/smoke/tradeoff");
    // Each curve: its CSV with every setting tried (the target not among them), a front, and its plot.
    for (name, settings, metric) in
        [("lightcluster", 4 + 6 + 3, "RMSE"), ("insm", 2 + 2, "shadow error"), ("val", 4 + 2 + 2, "FLIP")]
    {
        let csv = std::fs::read_to_string(dir.join(format!("{name}.csv"))).unwrap();
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |h: &str| header.iter().position(|c| *c == h).unwrap_or_else(|| panic!("no {h} in {name}.csv"));
        let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
        assert_eq!(rows.len(), settings, "{name}: one row per setting:\n{csv}");
        assert!(rows.iter().all(|r| r[col("metric")] == metric), "{name}: the metric is not {metric}:\n{csv}");
        assert!(rows.iter().any(|r| r[col("pareto")] == "true"), "{name}: no setting on the front:\n{csv}");
        assert!(rows.iter().all(|r| r[col("ms")].parse::<f64>().is_ok_and(|v| v > 0.0)), "{name}: times:\n{csv}");
        let png = std::fs::metadata(dir.join(format!("{name}.png"))).unwrap();
        assert!(png.len() > 1000, "{name}.png is {} bytes", png.len());
        assert!(stdout.contains(&format!("{name} (")), "{name} is not in the summary:\n{stdout}");
    }
    // The orbit runs on the shared scenes: there with them (in CI they must be there), left out and said so
    // without them.
    let shared = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/scenes");
    if shared.is_dir() {
        let orbit = std::fs::read_to_string(dir.join("fuzzy-orbit.md")).unwrap();
        for scene in ["conference", "sponza", "cornell"] {
            assert!(orbit.lines().any(|l| l.starts_with(&format!("| {scene} |")) && l.contains('%')), "{orbit}");
        }
        assert!(stdout.contains("fuzzy clustering while the camera moves"), "no orbit in the summary:\n{stdout}");
    } else {
        assert!(
            !std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false"),
            "the shared scenes are missing at {}: the orbit needs them",
            shared.display()
        );
        assert!(stderr.contains("orbit left out"), "the orbit's absence is not said:\n{stderr}");
        eprintln!("NOT RUN: the fuzzy orbit part (no shared scenes at {})", shared.display());
    }
}
