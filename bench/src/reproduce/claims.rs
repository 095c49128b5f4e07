//! The thesis's qualitative claims as checks on the measured curves: each says whether
//! the new data confirm the claim, and why.

use std::collections::BTreeMap;

use super::measures::{Measured, common_target};

/// A claim checked on the measured curves: whether they confirm it, and why (the
/// numbers compared).
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Verdict {
    /// Whether the curves confirm the claim.
    pub(super) confirmed: bool,
    /// The numbers the check compared.
    pub(super) why: String,
}

impl Verdict {
    /// A verdict: `confirmed` or not, for reason `why`.
    pub(super) fn new(confirmed: bool, why: String) -> Self {
        Self { confirmed, why }
    }

    /// Both verdicts: confirmed if both are, with both reasons.
    pub(super) fn and(self, other: Verdict) -> Verdict {
        Verdict::new(
            self.confirmed && other.confirmed,
            format!("{}; {}", self.why, other.why),
        )
    }
}

pub(super) fn find<'a>(m: &'a [Measured], label: &str) -> &'a Measured {
    m.iter()
        .find(|c| c.label == label)
        .expect("a curve of the figure")
}

/// `a` learns faster than `b`: its smoothed learning curve reaches the common target
/// ([`common_target`]) first.
pub(super) fn faster(m: &[Measured], a: &str, b: &str) -> Verdict {
    let (x, y) = (find(m, a), find(m, b));
    let level = common_target([x, y]);
    let (tx, ty) = (x.minutes_to(level), y.minutes_to(level));
    let text = format!("to the common level {level:.0}: {a} {tx:.1} min, {b} {ty:.1} min");
    Verdict::new(tx < ty, text)
}

/// `a`'s final greedy return is higher than `b`'s.
pub(super) fn better(m: &[Measured], a: &str, b: &str) -> Verdict {
    let (x, y) = (find(m, a), find(m, b));
    let text = format!(
        "final greedy return {a} {:.1} ± {:.1}, {b} {:.1} ± {:.1}",
        x.final_greedy, x.final_greedy_sd, y.final_greedy, y.final_greedy_sd
    );
    Verdict::new(x.final_greedy > y.final_greedy, text)
}

/// SAC/LLR needs at most half the simulated time SAC/RBF needs to the common level.
pub(super) fn llr_share(m: &[Measured]) -> Verdict {
    let (x, y) = (find(m, "SAC/LLR"), find(m, "SAC/RBF"));
    let level = common_target([x, y]);
    let share = x.minutes_to(level) / y.minutes_to(level);
    let text = format!(
        "to the common level {level:.0}: SAC/LLR {:.1} min, SAC/RBF {:.1} min ({:.0} %)",
        x.minutes_to(level),
        y.minutes_to(level),
        100.0 * share
    );
    Verdict::new(share <= 0.5, text)
}

/// `a`'s final greedy return is higher than `b`'s by more than the 95 % margin of the
/// difference (Welch: 1.96 standard errors).
pub(super) fn clearly_better(m: &[Measured], a: &str, b: &str) -> Verdict {
    let (x, y) = (find(m, a), find(m, b));
    let se = (x.final_greedy_sd.powi(2) / x.runs as f64
        + y.final_greedy_sd.powi(2) / y.runs as f64)
        .sqrt();
    let diff = x.final_greedy - y.final_greedy;
    let text = format!(
        "final greedy return {a} {:.1} ± {:.1}, {b} {:.1} ± {:.1} (difference {diff:.1}, 95 % margin {:.1})",
        x.final_greedy,
        x.final_greedy_sd,
        y.final_greedy,
        y.final_greedy_sd,
        1.96 * se
    );
    Verdict::new(diff > 1.96 * se, text)
}

/// The deepest fall of `c`'s smoothed learning curve below its running maximum between
/// simulated minutes `from` and `to` (the running maximum taken from `from` on).
pub(super) fn dip(c: &Measured, from: f64, to: f64) -> f64 {
    let mut best = f64::NEG_INFINITY;
    let mut deepest: f64 = 0.0;
    for &(_, v) in c.smoothed.iter().filter(|p| p.0 >= from && p.0 <= to) {
        best = best.max(v);
        deepest = deepest.max(best - v);
    }
    deepest
}

/// §5.5: SAC/RBF's learning curve dips between 10 and 30 simulated minutes (the
/// optimistic initialisation of its RBFs), the LLR learners' less.
pub(super) fn rbf_dip(m: &[Measured]) -> Verdict {
    let d = |l: &str| dip(find(m, l), 10.0, 30.0);
    let (rbf, sac, mlac) = (d("SAC/RBF"), d("SAC/LLR"), d("MLAC/LLR"));
    let text = format!(
        "deepest fall below the running maximum between 10 and 30 min: SAC/RBF {rbf:.0}, SAC/LLR {sac:.0}, MLAC/LLR {mlac:.0}"
    );
    Verdict::new(rbf > sac && rbf > mlac, text)
}

/// The opposite of a check.
pub(super) fn not(r: Verdict) -> Verdict {
    Verdict::new(!r.confirmed, r.why)
}

/// `a` reaches the common target ([`common_target`]) of all curves first.
pub(super) fn fastest(m: &[Measured], a: &str) -> Verdict {
    fastest_of(m, a, "")
}

/// As [`fastest`], among the curves but `left_out` (a variant not in the comparison).
pub(super) fn fastest_of(m: &[Measured], a: &str, left_out: &str) -> Verdict {
    let kept: Vec<Measured> = m.iter().filter(|c| c.label != left_out).cloned().collect();
    let m = &kept[..];
    let level = common_target(m);
    let best = find(m, a).minutes_to(level);
    let text = format!(
        "to the common level {level:.0}: {}",
        m.iter()
            .map(|c| format!("{} {:.1} min", c.label, c.minutes_to(level)))
            .collect::<Vec<_>>()
            .join(", ")
    );
    Verdict::new(m.iter().all(|c| c.minutes_to(level) >= best), text)
}

/// How many runs' final policies swing up with how many swings, e.g.
/// `2 swings: 12, 3 swings: 8, never upright: 0`.
pub(super) fn swing_counts(c: &Measured) -> (BTreeMap<Option<usize>, usize>, String) {
    let mut counts = BTreeMap::new();
    for s in &c.swings {
        *counts.entry(*s).or_insert(0) += 1;
    }
    let text = counts
        .iter()
        .map(|(k, n)| match k {
            Some(1) => format!("1 swing: {n}"),
            Some(k) => format!("{k} swings: {n}"),
            None => format!("never upright: {n}"),
        })
        .collect::<Vec<_>>()
        .join(", ");
    (counts, format!("{} ({text})", c.label))
}
