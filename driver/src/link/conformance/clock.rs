//! The driver's clock, judged from its samples' stamps: lateness against a regular
//! grid, the intervals, and what a large lateness says about the clock.

/// Each sample's lateness against a regular grid placed at the earliest sample, sorted
/// \[ns\]; `stamps` are `(seq, t_sample_ns)` in order, at least two. The grid's period is
/// the median of the sample-to-sample periods, so that one late sample is one outlier: the
/// mean from the first to the last sample would tilt the grid when either of those is the
/// late one (a first sample 12 ms late spread 0–12 ms of "lateness" over all the others).
pub(super) fn lateness(stamps: &[(u64, u64)]) -> Vec<f64> {
    let grid = percentile(&intervals(stamps), 0.5);
    let (seq0, t0) = stamps[0];
    let offsets: Vec<f64> = stamps
        .iter()
        .map(|&(seq, t)| (t - t0) as f64 - (seq - seq0) as f64 * grid)
        .collect();
    let earliest = offsets.iter().copied().fold(f64::INFINITY, f64::min);
    let mut late: Vec<f64> = offsets.iter().map(|o| o - earliest).collect();
    late.sort_by(f64::total_cmp);
    late
}

/// The sample-to-sample intervals per period, sorted \[ns\]; `stamps` as for
/// [`lateness`].
pub(super) fn intervals(stamps: &[(u64, u64)]) -> Vec<f64> {
    let mut steps: Vec<f64> = stamps
        .windows(2)
        .map(|w| (w[1].1 - w[0].1) as f64 / (w[1].0 - w[0].0) as f64)
        .collect();
    steps.sort_by(f64::total_cmp);
    steps
}

/// How far each interval is from the median interval, sorted \[ns\]: how irregular the
/// driver's clock is from one sample to the next. Lateness against a grid sums such
/// errors when a driver times each sample from the previous one rather than from its
/// start.
pub(super) fn interval_jitter(stamps: &[(u64, u64)]) -> Vec<f64> {
    let steps = intervals(stamps);
    let median = percentile(&steps, 0.5);
    let mut off: Vec<f64> = steps.iter().map(|s| (s - median).abs()).collect();
    off.sort_by(f64::total_cmp);
    off
}

/// What a lateness p99 beyond `bound` says about the driver's clock, given the p99 of
/// its interval jitter (all in ns): either the period itself is irregular, or each
/// interval is fine and their errors accumulate.
pub(super) fn clock_diagnosis(late_p99: f64, interval_p99: f64, bound: f64) -> Option<String> {
    if late_p99 <= bound {
        None
    } else if interval_p99 > bound {
        Some(format!(
            "the driver's clock is irregular: its intervals differ from the period by up to {:.3} ms (p99); sample on an absolute clock (docs/driver.md, \"Keeping time\")",
            interval_p99 * 1e-6
        ))
    } else {
        Some(format!(
            "the driver's clock drifts: each interval is within {:.3} ms (p99) of the period, but the instants stray from a regular grid, as when each sample is timed from the previous one; sample at t_start + k·period (docs/driver.md, \"Keeping time\")",
            interval_p99 * 1e-6
        ))
    }
}

/// Percentile `p` (0..=1) of sorted values.
pub(super) fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// 167 samples on a 30 ms grid, sample `late` delayed by 12 ms.
    fn grid_with_late(late: usize) -> Vec<(u64, u64)> {
        (0..167u64)
            .map(|k| {
                let delay = if k as usize == late { 12_000_000 } else { 0 };
                (k, 1_000_000_000 + k * 30_000_000 + delay)
            })
            .collect()
    }

    #[test]
    fn one_late_sample_is_one_outlier_wherever_it_is() {
        for late in [0, 80, 166] {
            let l = lateness(&grid_with_late(late));
            assert_eq!(l.len(), 167);
            assert!(percentile(&l, 0.99).abs() < 1.0, "late {late}: {l:?}");
            assert!((l[166] - 12e6).abs() < 1.0, "late {late}: max {}", l[166]);
        }
    }

    /// A clock that times each sample from the previous one, each wait off by ±2 ms: every
    /// interval is within 2 ms of the period, the lateness against the grid grows past it,
    /// and the diagnosis says the clock drifts; a clock whose intervals themselves exceed
    /// the bound is called irregular.
    #[test]
    fn an_accumulating_clock_is_told_from_an_irregular_one() {
        let mut t = 0u64;
        let stamps: Vec<(u64, u64)> = (0..200u64)
            .map(|k| {
                // A fixed pattern of ±2 ms errors whose sum wanders (no random source).
                let e = [2_000_000i64, 1_500_000, 1_000_000, -500_000, 2_000_000][k as usize % 5]
                    * if (k / 25) % 2 == 0 { 1 } else { -1 };
                t = (t as i64 + 30_000_000 + e) as u64;
                (k, t)
            })
            .collect();
        let late = percentile(&lateness(&stamps), 0.99);
        let steps = percentile(&interval_jitter(&stamps), 0.99);
        assert!(
            steps <= 2.5e6 && late > 10e6,
            "intervals {steps}, lateness {late}"
        );
        let d = clock_diagnosis(late, steps, 3e6).unwrap();
        assert!(d.contains("drifts") && d.contains("Keeping time"), "{d}");
        assert!(clock_diagnosis(late, steps, 2.0 * late).is_none());
        let d = clock_diagnosis(late, 5e6, 3e6).unwrap();
        assert!(d.contains("irregular"), "{d}");
    }

    #[test]
    fn lateness_follows_a_jittered_clock() {
        // Every third sample 2 ms late, a missed period at 50.
        let stamps: Vec<(u64, u64)> = (0..100u64)
            .filter(|&k| k != 50)
            .map(|k| (k, k * 30_000_000 + if k % 3 == 0 { 2_000_000 } else { 0 }))
            .collect();
        let l = lateness(&stamps);
        assert!(percentile(&l, 0.5).abs() < 1.0);
        assert!((percentile(&l, 0.99) - 2e6).abs() < 1.0);
    }
}
