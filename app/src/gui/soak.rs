//! A long run (`--soak-secs N`, hidden; `scripts/measure-memory`): the lights animated, the direct technique
//! switched through the registry every [`SWITCH_SECS`], and the process's resident memory and the device's GPU
//! allocations printed at the start, every [`REPORT_SECS`] and at the end, with the growth, so a leak shows.

use shadowlab_core::technique::registry::REGISTRY;

use super::session::Animation;
use super::ShadowLabApp;

/// How long each technique runs.
pub const SWITCH_SECS: f64 = 20.0;
/// How often the memory is printed.
pub const REPORT_SECS: f64 = 60.0;

/// The process's resident set in MiB (Linux; None elsewhere).
pub fn resident_mib() -> Option<f64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: f64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096.0 / (1024.0 * 1024.0))
}

impl ShadowLabApp {
    /// One UI frame of a long run.
    pub(super) fn soak_frame(&mut self) {
        let Some(soak) = self.soak.as_mut() else { return };
        let t = soak.started.elapsed().as_secs_f64();
        self.session.animation = Animation::Orbit;
        if t >= soak.next_switch {
            let entry = &REGISTRY[soak.switches % REGISTRY.len()];
            self.session.technique = entry.key.to_string();
            soak.switches += 1;
            soak.next_switch += SWITCH_SECS;
        }
        if t >= soak.next_report {
            soak.next_report += REPORT_SECS;
            let wanted = soak.first.is_none() && soak.switches > REGISTRY.len();
            let line = self.memory_line(t);
            if let (Some(line), true) = (&line, wanted) {
                if let Some(soak) = self.soak.as_mut() {
                    soak.first = Some(line.1);
                    soak.first_t = t;
                }
            }
            if let Some((text, _)) = line {
                println!("{text}");
            }
        }
    }

    /// `memory: t=... rss=... MiB gpu_allocated=... MiB gpu_reserved=... MiB technique=...`, and its figures.
    fn memory_line(&self, t: f64) -> Option<(String, (f64, f64, f64))> {
        let rss = resident_mib().unwrap_or(f64::NAN);
        let report = self.views.gpu.as_ref().and_then(|g| g.ctx.device.generate_allocator_report());
        let mib = |b: u64| b as f64 / (1024.0 * 1024.0);
        let (allocated, reserved) =
            report.map(|r| (mib(r.total_allocated_bytes), mib(r.total_reserved_bytes))).unwrap_or((f64::NAN, f64::NAN));
        let text = format!(
            "memory: t={t:.0}s rss={rss:.1} MiB gpu_allocated={allocated:.1} MiB gpu_reserved={reserved:.1} MiB \
             technique={}",
            self.session.technique
        );
        Some((text, (rss, allocated, reserved)))
    }

    /// The last line of a long run: the memory now against the first report.
    pub(super) fn soak_summary(&self) -> Option<String> {
        let soak = self.soak.as_ref()?;
        let t = soak.started.elapsed().as_secs_f64();
        let (now, (rss, allocated, reserved)) = self.memory_line(t)?;
        let (rss0, allocated0, reserved0) = soak.first?;
        let growth = |a: f64, b: f64| (b / a - 1.0) * 100.0;
        Some(format!(
            "{now}\nmemory growth from t={:.0}s (every technique has run) to t={t:.0}s ({} technique switches): rss \
             {:+.1} %, gpu_allocated {:+.1} %, gpu_reserved {:+.1} %",
            soak.first_t,
            soak.switches,
            growth(rss0, rss),
            growth(allocated0, allocated),
            growth(reserved0, reserved)
        ))
    }
}
