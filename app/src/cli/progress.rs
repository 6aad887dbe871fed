//! Progress of a long command on stderr.

use std::io::{IsTerminal, Write};
use std::time::Instant;

/// Progress on stderr: a rewritten line on a terminal, a line per 10% otherwise.
pub struct Progress {
    label: String,
    unit: &'static str,
    tty: bool,
    last_decile: usize,
    started: Instant,
    quiet: bool,
}

impl Progress {
    pub fn new(label: &str, quiet: bool) -> Progress {
        Progress {
            label: label.into(),
            unit: "batch",
            tty: std::io::stderr().is_terminal(),
            last_decile: usize::MAX,
            started: Instant::now(),
            quiet,
        }
    }
    /// Count `unit`s instead of batches.
    pub fn with_unit(mut self, unit: &'static str) -> Progress {
        self.unit = unit;
        self
    }

    pub fn update(&mut self, done: usize, total: usize) {
        if self.quiet || total == 0 {
            return;
        }
        let secs = self.started.elapsed().as_secs_f32();
        if self.tty {
            let width = 30;
            let filled = done * width / total;
            eprint!(
                "\r{}: [{}{}] {} {done}/{total} ({secs:.1} s)",
                self.label,
                "#".repeat(filled),
                "-".repeat(width - filled),
                self.unit
            );
            if done == total {
                eprintln!();
            }
            let _ = std::io::stderr().flush();
        } else {
            let decile = done * 10 / total;
            if decile != self.last_decile {
                self.last_decile = decile;
                eprintln!("{}: {} {done}/{total} ({secs:.1} s)", self.label, self.unit);
            }
        }
    }
}
