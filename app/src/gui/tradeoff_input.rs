//! What the Trade-off section edits (the ticked techniques, each over ranges of its parameters, the metric, the
//! budget or error bound, the plot's axis): the panel's state, kept in the chrome between UI frames and drawn by
//! `panels/tradeoff.rs`.

use std::collections::BTreeMap;

use eframe::egui;
use shadowlab_core::technique::{ParamKind, ParamValue};

use crate::tradeoff::Metric;

/// One technique of the trade-off: ticked or not, and the parameters it is tried over (none: as set); the
/// configurations are every combination of their values.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TryInput {
    pub on: bool,
    pub params: Vec<ParamRange>,
}

/// A parameter of a try: a numeric one over `count` values from `from` to `to`, a choice over all its options,
/// a flag over both.
#[derive(Clone, Debug, PartialEq)]
pub struct ParamRange {
    pub key: String,
    pub from: f64,
    pub to: f64,
    pub count: usize,
}

impl ParamRange {
    /// The range a parameter starts with: its whole span (an integer's up to 16 times its minimum).
    pub fn of(key: &str, kind: &ParamKind) -> ParamRange {
        let (from, to) = match *kind {
            ParamKind::Float { min, max } => (min as f64, max as f64),
            ParamKind::Int { min, max } => (min as f64, (max as f64).min(min as f64 * 16.0).max(min as f64 + 1.0)),
            _ => (0.0, 1.0),
        };
        ParamRange { key: key.to_string(), from, to, count: 4 }
    }

    /// Its values as `--try` takes them (`0.2,0.6,1.0`; `pcf,pcss`; `true,false`).
    pub(crate) fn values(&self, kind: &ParamKind) -> String {
        match kind {
            ParamKind::Choice(options) => options.join(","),
            ParamKind::Bool => "false,true".to_string(),
            _ => values_text(kind, self.from, self.to, self.count),
        }
    }
}

/// What the Trade-off section edits.
#[derive(Clone, Debug, PartialEq)]
pub struct TradeoffInput {
    pub tries: BTreeMap<String, TryInput>,
    pub metric: Metric,
    pub use_budget: bool,
    pub budget_ms: f64,
    /// The fastest configuration within this error (in `metric`), instead of the lowest error within the time.
    pub use_max_error: bool,
    pub max_error: f64,
    /// The plot's x axis: None for the time per frame, else a work count (`shadowlab tradeoff --work-axis`).
    pub x_axis: Option<String>,
    /// Where the last UI frame drew each row's point on screen (what a pointer hovers and clicks).
    pub drawn: Vec<egui::Pos2>,
}

impl Default for TradeoffInput {
    fn default() -> Self {
        TradeoffInput {
            tries: BTreeMap::new(),
            metric: Metric::Rmse,
            use_budget: false,
            budget_ms: 100.0,
            use_max_error: false,
            max_error: 0.05,
            x_axis: None,
            drawn: Vec::new(),
        }
    }
}

/// The values of a range for a parameter kind, as `sweep --param` writes them.
fn values_text(kind: &ParamKind, from: f64, to: f64, count: usize) -> String {
    crate::gui::sweep::values(kind, from, to, count)
        .iter()
        .map(ParamValue::to_string)
        .collect::<Vec<_>>()
        .into_iter()
        .fold(Vec::<String>::new(), |mut v, x| {
            if !v.contains(&x) {
                v.push(x);
            }
            v
        })
        .join(",")
}
