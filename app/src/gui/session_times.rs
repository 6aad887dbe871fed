//! The session's measured configurations and the speedups between them.
//!
//! Every complete frame is kept under its whole configuration: the scene, the view fingerprint of the frame
//! report (camera, lights, renderer settings with size and VPL settings), the indirect technique with its
//! parameters, and the technique with its parameters. A speedup is shown only between two entries of one view
//! (the same scene, lights, camera, size, settings and indirect technique), and in one clock: the timestamps
//! when both frames used them, else both frames' wall-clock steps. A time measured for another configuration is
//! never used.

use std::collections::BTreeMap;

use shadowlab_core::timing::{common_clock, TimingSource};
use shadowlab_core::FrameReport;

/// The name of a frame's techniques in the session table: the direct one, and `+ indirect` when it had one.
fn session_name(report: &FrameReport) -> String {
    crate::measure::technique_pair(&report.technique, report.indirect.as_ref().map(|i| i.technique.as_str()))
}

/// One configuration's last complete frame.
#[derive(Clone, Debug, PartialEq)]
pub struct SessionTime {
    /// The technique (with its indirect technique, as the panel names it).
    pub technique: String,
    /// The direct technique's key.
    pub key: String,
    /// The parameters, as the panel shows them.
    pub parameters: String,
    /// Which view the frame measured (see the module doc).
    pub view: u64,
    /// "restaurant · 64 lights · 640x360", for the panel's sentence.
    pub view_text: String,
    /// The frame's time in wall-clock steps and, where it used them, in GPU timestamps (both with the CPU
    /// stages).
    pub steps_ms: f64,
    pub timestamps_ms: Option<f64>,
    /// When it was recorded (to pick the latest of several reference entries).
    pub order: u64,
}

impl SessionTime {
    pub fn clock(&self) -> TimingSource {
        if self.timestamps_ms.is_some() {
            TimingSource::GpuTimestamps
        } else {
            TimingSource::WallClockSteps
        }
    }

    pub fn ms_in(&self, clock: TimingSource) -> f64 {
        shadowlab_core::timing::in_clock(clock, self.steps_ms, self.timestamps_ms)
    }
}

/// A row of the panel: an entry of the current view and its speedup over the reference of that view.
#[derive(Clone, Debug, PartialEq)]
pub struct SpeedupRow {
    pub entry: SessionTime,
    /// (ratio, clock) against the reference entry of the same view; None for the reference itself or without
    /// one.
    pub speedup: Option<(f64, TimingSource)>,
}

#[derive(Debug)]
pub struct SessionTimes {
    entries: BTreeMap<(u64, String, String), SessionTime>,
    next: u64,
    /// False while frames are not the user's own configurations (an Explain step's): [`SessionTimes::record`]
    /// then keeps nothing.
    pub recording: bool,
}

impl Default for SessionTimes {
    fn default() -> Self {
        SessionTimes { entries: BTreeMap::new(), next: 0, recording: true }
    }
}

impl SessionTimes {
    /// Keep `report`'s frame as the time of its configuration (`scene` names the scene, `parameters` the
    /// technique's and indirect technique's parameters as shown).
    pub fn record(&mut self, scene: &str, report: &FrameReport) {
        if !self.recording {
            return;
        }
        let indirect = report.indirect.as_ref().map(|i| (i.technique.clone(), i.parameters.clone()));
        let view = view_of(scene, report);
        let technique = session_name(report);
        let mut parameters = describe(&report.parameters);
        if let Some((_, p)) = &indirect {
            if !p.is_empty() {
                parameters = format!("{parameters} | {}", describe(p)).trim().to_string();
            }
        }
        let used_timestamps = report.timing.comparable_source() == TimingSource::GpuTimestamps;
        self.next += 1;
        let entry = SessionTime {
            technique: technique.clone(),
            key: report.technique.clone(),
            parameters: parameters.clone(),
            view,
            view_text: format!("{scene} · {} lights · {}x{}", report.counts.lights_total, report.width, report.height),
            steps_ms: report.frame_ms_in(TimingSource::WallClockSteps),
            timestamps_ms: used_timestamps.then(|| report.frame_ms_in(TimingSource::GpuTimestamps)),
            order: self.next,
        };
        self.entries.insert((view, technique, parameters), entry);
    }

    /// Every entry, of every view.
    pub fn entries(&self) -> impl Iterator<Item = &SessionTime> {
        self.entries.values()
    }

    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// How many entries measured other views than `view`.
    pub fn other_views(&self, view: u64) -> usize {
        self.entries.values().filter(|e| e.view != view).count()
    }

    /// The view of the latest entry, when there is one.
    pub fn latest_view(&self) -> Option<u64> {
        self.entries.values().max_by_key(|e| e.order).map(|e| e.view)
    }

    /// The latest entry of `reference` (a technique key) measured in `view`.
    pub fn reference(&self, view: u64, reference: &str) -> Option<&SessionTime> {
        self.entries.values().filter(|e| e.view == view && e.key == reference).max_by_key(|e| e.order)
    }

    /// The entries of `view`, each with its speedup over the latest `reference` entry of the same view.
    pub fn rows(&self, view: u64, reference: &str) -> Vec<SpeedupRow> {
        let base = self.reference(view, reference);
        self.entries
            .values()
            .filter(|e| e.view == view)
            .map(|e| SpeedupRow {
                entry: e.clone(),
                speedup: base.filter(|b| b.order != e.order).map(|b| {
                    let clock = common_clock(b.clock(), e.clock());
                    (b.ms_in(clock) / e.ms_in(clock).max(1e-9), clock)
                }),
            })
            .collect()
    }
}

/// The view `report` measured on `scene` (see the module doc).
pub fn view_of(scene: &str, report: &FrameReport) -> u64 {
    let indirect = report.indirect.as_ref().map(|i| (&i.technique, &i.parameters));
    shadowlab_core::fingerprint::fingerprint(&(scene, report.view_fingerprint, indirect))
}

fn describe(params: &BTreeMap<String, String>) -> String {
    params.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(" ")
}

#[cfg(test)]
mod tests {
    use super::*;
    use shadowlab_core::timing::{FrameTiming, TimingMode};

    fn report(technique: &str, fingerprint: u64, timestamps: Option<f64>, steps: f64) -> FrameReport {
        FrameReport {
            technique: technique.into(),
            parameters: BTreeMap::from([("shadow_res".to_string(), "256".to_string())]),
            width: 64,
            height: 32,
            view_fingerprint: fingerprint,
            timing: FrameTiming {
                mode: TimingMode::Auto,
                source: if timestamps.is_some() { TimingSource::GpuTimestamps } else { TimingSource::WallClockSteps },
                reason: None,
                timestamps_ms: timestamps,
                steps_wall_ms: steps,
            },
            passes: Vec::new(),
            total_ms: timestamps.unwrap_or(steps),
            steps: Vec::new(),
            stage_passes: Vec::new(),
            work: Default::default(),
            cpu_stages: Vec::new(),
            wall_ms: steps,
            counts: Default::default(),
            indirect: None,
        }
    }

    #[test]
    fn a_speedup_needs_the_same_view_and_one_clock() {
        let mut t = SessionTimes::default();
        t.record("box", &report("reference", 1, Some(8.0), 10.0));
        t.record("box", &report("lightcluster", 1, Some(2.0), 5.0));
        let view = t.latest_view().unwrap();
        let rows = t.rows(view, "reference");
        let lc = rows.iter().find(|r| r.entry.key == "lightcluster").unwrap();
        assert_eq!(lc.speedup, Some((4.0, TimingSource::GpuTimestamps)));
        assert_eq!(rows.iter().find(|r| r.entry.key == "reference").unwrap().speedup, None);

        // A technique measured in wall-clock steps is compared in wall-clock steps on both sides.
        t.record("box", &report("insm", 1, None, 2.5));
        let rows = t.rows(view, "reference");
        let insm = rows.iter().find(|r| r.entry.key == "insm").unwrap();
        assert_eq!(insm.speedup, Some((4.0, TimingSource::WallClockSteps)));

        // Another camera (fingerprint) or another scene is another view: its reference is not used.
        t.record("box", &report("lightcluster", 2, Some(1.0), 2.0));
        let moved = t.latest_view().unwrap();
        assert_ne!(moved, view);
        let rows = t.rows(moved, "reference");
        assert_eq!(rows.len(), 1);
        assert_eq!(rows[0].speedup, None, "the reference of another camera must not be used");
        assert_eq!(t.other_views(moved), 3);
        t.record("room", &report("reference", 1, Some(8.0), 10.0));
        assert_ne!(t.latest_view().unwrap(), view, "the same fingerprint on another scene is another view");
    }

    #[test]
    fn other_parameters_are_another_entry() {
        let mut t = SessionTimes::default();
        let mut a = report("lightcluster", 1, Some(2.0), 5.0);
        t.record("box", &a);
        a.parameters.insert("d_init".into(), "0.5".into());
        t.record("box", &a);
        assert_eq!(t.rows(t.latest_view().unwrap(), "reference").len(), 2);
    }
}
