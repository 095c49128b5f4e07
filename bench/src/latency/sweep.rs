//! `rig latency --sweep`: the fastest period the loop sustains without a deadline miss.

use std::fmt::Write as _;

use runtime::error::AtFile;

use super::error::LatencyError;
use runtime::output::write_atomic;

use runtime::clock::Clock;

use super::{LatencyOptions, LatencyReport, latency};
use crate::loop_bench::Stats;

/// One period of a [`sweep`].
#[derive(Clone, Debug)]
pub struct SweepPoint {
    /// Sampling period \[ms\].
    pub period_ms: f64,
    /// What was measured at it.
    pub report: LatencyReport,
}

/// `rig latency --sweep`: [`latency`] at `opts.period_ms`, then at periods shortened by
/// `factor` each (each into `DIR/period-<ms>/`), until a period misses a deadline or the
/// period would go below 0.1 ms. Writes `DIR/sweep.csv` (one row per period) and
/// returns the periods measured; the fastest sustained is the last without misses.
pub fn sweep(opts: &LatencyOptions, factor: f64) -> Result<Vec<SweepPoint>, LatencyError> {
    if !(factor.is_finite() && factor > 1.0) {
        return Err(LatencyError::SweepFactor(factor));
    }
    let Some(first) = opts.clock.period() else {
        return Err(LatencyError::SweepDriver);
    };
    std::fs::create_dir_all(&opts.out).at("cannot create", &opts.out)?;
    let mut points = Vec::new();
    let mut csv = String::from(
        "period_ms,cycles,deadline_misses,jitter_p999_us,sample_to_actuation_p50_us,sample_to_actuation_p99_us,sample_to_actuation_p999_us,sample_to_actuation_max_us,raw_hop_p50_us\n",
    );
    let mut period = first.as_nanos() as f64 * 1e-6;
    while period >= 0.1 {
        let sub = LatencyOptions {
            clock: Clock::Realtime {
                period: super::period(period)?,
            },
            out: opts.out.join(format!("period-{period:.3}")),
            ..opts.clone()
        };
        let report = latency(&sub)?;
        let stat = |name: &str| report.stage(name).cloned();
        let (jitter, e2e) = (stat("jitter"), stat("sample_to_actuation"));
        let f = |s: &Option<Stats>, g: fn(&Stats) -> f64| s.as_ref().map_or(f64::NAN, g);
        let _ = writeln!(
            csv,
            "{period:.3},{},{},{:.1},{:.1},{:.1},{:.1},{:.1},{:.2}",
            report.cycles,
            report.misses,
            f(&jitter, |s| s.p999),
            f(&e2e, |s| s.p50),
            f(&e2e, |s| s.p99),
            f(&e2e, |s| s.p999),
            f(&e2e, |s| s.max),
            report.raw_hop_p50()
        );
        write_atomic(&opts.out.join("sweep.csv"), &csv)?;
        let missed = report.misses > 0;
        points.push(SweepPoint {
            period_ms: period,
            report,
        });
        if missed {
            break;
        }
        period = (period / factor * 1000.0).round() / 1000.0;
    }
    Ok(points)
}
