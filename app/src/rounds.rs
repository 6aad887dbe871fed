//! Measuring in rounds (`compare --rounds`, `sweep --rounds`): the target and the technique rendered K times
//! over, alternating, so that a load that comes and goes on a shared machine falls on both sides. Each round
//! gives a speedup against the target of its own round; the result is their median, with their range.

use serde::Serialize;
use shadowlab_core::timing::TimingSource;

use crate::measure::{median, TimingSummary};

/// One round: each side's median frame in the comparison's clock, and in the wall clock.
#[derive(Clone, Copy, Debug)]
pub struct Round {
    pub ms: f64,
    pub against_ms: f64,
    pub wall_ms: f64,
    pub against_wall_ms: f64,
    pub wall_min_ms: f64,
    pub against_wall_min_ms: f64,
}

impl Round {
    /// `technique` against `target`, both read in `clock` (the first round's, so that every round is read in one).
    pub fn of(technique: &TimingSummary, target: &TimingSummary, clock: TimingSource) -> Round {
        Round {
            ms: technique.median_in(clock),
            against_ms: target.median_in(clock),
            wall_ms: technique.wall_median_ms,
            against_wall_ms: target.wall_median_ms,
            wall_min_ms: technique.wall_min_ms,
            against_wall_min_ms: target.wall_min_ms,
        }
    }

    /// The round's speedup: the target's time over the technique's.
    pub fn ratio(&self) -> f64 {
        self.against_ms / self.ms.max(1e-9)
    }
}

/// The rounds summed up: the median speedup of the rounds and their range, each side's median time.
#[derive(Clone, Debug, Serialize)]
pub struct Rounds {
    pub count: usize,
    /// Each round's speedup, in the comparison's clock.
    pub ratios: Vec<f64>,
    /// The median of `ratios` (what the comparison reports as its speedup).
    #[serde(skip)]
    pub ratio: f64,
    pub ratio_min: f64,
    pub ratio_max: f64,
    /// The medians over the rounds of each side's median frame, in the comparison's clock.
    pub technique_ms: f64,
    pub against_ms: f64,
    /// The medians over the rounds of each side's median wall-clock frame.
    pub wall_ms: f64,
    pub against_wall_ms: f64,
    /// Each side's fastest wall-clock frame over all rounds (the least disturbed).
    pub wall_min_ms: f64,
    pub against_wall_min_ms: f64,
}

impl Rounds {
    /// At least one round.
    pub fn of(rounds: &[Round]) -> Rounds {
        assert!(!rounds.is_empty(), "at least one round");
        let ratios: Vec<f64> = rounds.iter().map(Round::ratio).collect();
        let mid = |f: fn(&Round) -> f64| median(rounds.iter().map(f).collect());
        let least = |f: fn(&Round) -> f64| rounds.iter().map(f).fold(f64::INFINITY, f64::min);
        Rounds {
            count: rounds.len(),
            ratio: median(ratios.clone()),
            ratio_min: ratios.iter().copied().fold(f64::INFINITY, f64::min),
            ratio_max: ratios.iter().copied().fold(0.0, f64::max),
            ratios,
            technique_ms: mid(|r| r.ms),
            against_ms: mid(|r| r.against_ms),
            wall_ms: mid(|r| r.wall_ms),
            against_wall_ms: mid(|r| r.against_wall_ms),
            wall_min_ms: least(|r| r.wall_min_ms),
            against_wall_min_ms: least(|r| r.against_wall_min_ms),
        }
    }

    /// The median of the rounds' wall-clock ratios.
    pub fn wall_ratio(rounds: &[Round]) -> f64 {
        median(rounds.iter().map(|r| r.against_wall_ms / r.wall_ms.max(1e-9)).collect())
    }
}

/// `--rounds` takes 1 to 50.
pub fn check(rounds: u32) -> anyhow::Result<()> {
    if !(1..=50).contains(&rounds) {
        anyhow::bail!("--rounds takes 1 to 50 rounds, not {rounds}");
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round(ms: f64, against_ms: f64) -> Round {
        Round {
            ms,
            against_ms,
            wall_ms: ms,
            against_wall_ms: against_ms,
            wall_min_ms: ms,
            against_wall_min_ms: against_ms,
        }
    }

    #[test]
    fn the_rounds_give_the_median_speedup_its_range_and_each_sides_median() {
        // A load on the target in the second round: its ratio is the outlier, the median the middle one.
        let rounds = [round(10.0, 50.0), round(10.0, 90.0), round(12.0, 48.0)];
        let r = Rounds::of(&rounds);
        assert_eq!(r.count, 3);
        assert_eq!(r.ratios, vec![5.0, 9.0, 4.0]);
        assert_eq!((r.ratio, r.ratio_min, r.ratio_max), (5.0, 4.0, 9.0));
        assert_eq!((r.technique_ms, r.against_ms), (10.0, 50.0));
        assert_eq!((r.wall_min_ms, r.against_wall_min_ms), (10.0, 48.0));
        assert_eq!(Rounds::wall_ratio(&rounds), 5.0);
        assert!(check(0).is_err() && check(51).is_err() && check(1).is_ok() && check(50).is_ok());
    }
}
