//! What the rig's bridge measured of the link: round trips, and one-way hops where the
//! hosts share a clock ([`crate::clock`]), summarised by percentiles.

use crate::clock::ClockMap;

/// The link's measurements.
#[derive(Clone, Debug)]
pub struct LinkTiming {
    /// The clocks' map at the end.
    pub clock: ClockMap,
    /// Pings' round trips (the network's, the answer's time excluded).
    pub ping: Durations,
    /// Command → acknowledging sample, the time on the driver's host excluded.
    pub command_round_trip: Durations,
    /// Rig's bridge → driver's bridge (one clock only).
    pub command_hop: Durations,
    /// Driver's bridge → rig's bridge (one clock only).
    pub sample_hop: Durations,
}

impl LinkTiming {
    /// The summary lines.
    pub fn summary(&self) -> String {
        let clock = &self.clock;
        let mut s = format!(
            "  round trip, pings:          {}\n  round trip, command→sample: {}\n",
            self.ping.summary(),
            self.command_round_trip.summary()
        );
        if clock.same() {
            s += &format!(
                "  one way rig→driver:         {}\n  one way driver→rig:         {}\n  (one clock on both hosts)",
                self.command_hop.summary(),
                self.sample_hop.summary()
            );
        } else if clock.ready() {
            s += &format!(
                "  one-way hops not measured (two clocks); driver's clock − rig's: {:.3} ms ± {:.3} ms",
                clock.offset() as f64 * 1e-6,
                clock.uncertainty() as f64 * 1e-6
            );
        } else {
            s += "  one-way hops not measured (two clocks); the clocks' offset not measured (no round trip)";
        }
        s
    }
}

/// Durations collected for a summary: count, median and tail percentiles.
#[derive(Clone, Debug, Default)]
pub struct Durations(Vec<u64>);

impl Durations {
    /// Adds one duration (ns).
    pub fn push(&mut self, ns: u64) {
        self.0.push(ns);
    }

    /// How many were added.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// Whether none were added.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// The `q`-quantile (0 ≤ q ≤ 1, nearest rank) in ms, if any.
    pub fn quantile_ms(&self, q: f64) -> Option<f64> {
        let mut v = self.0.clone();
        v.sort_unstable();
        nearest_rank_ms(&v, q)
    }

    /// "n 1200, p50 0.21 ms, p99 0.48 ms, p99.9 1.20 ms, max 3.02 ms", or "none".
    pub fn summary(&self) -> String {
        let mut v = self.0.clone();
        v.sort_unstable();
        let q = |q| nearest_rank_ms(&v, q).unwrap_or(f64::NAN);
        match v.len() {
            0 => "none".into(),
            n => format!(
                "n {n}, p50 {:.3} ms, p99 {:.3} ms, p99.9 {:.3} ms, max {:.3} ms",
                q(0.5),
                q(0.99),
                q(0.999),
                q(1.0)
            ),
        }
    }
}

/// The `q`-quantile of `sorted` (ns) by nearest rank, in ms.
fn nearest_rank_ms(sorted: &[u64], q: f64) -> Option<f64> {
    let i = ((q * sorted.len() as f64).ceil() as usize).clamp(1, sorted.len().max(1)) - 1;
    sorted.get(i).map(|&ns| ns as f64 * 1e-6)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn durations_summarise_by_nearest_rank() {
        let mut d = Durations::default();
        assert_eq!(d.summary(), "none");
        for ms in 1..=1000u64 {
            d.push(ms * 1_000_000);
        }
        assert_eq!(d.quantile_ms(0.5), Some(500.0));
        assert_eq!(d.quantile_ms(0.99), Some(990.0));
        assert_eq!(d.quantile_ms(0.999), Some(999.0));
        assert!(
            d.summary().starts_with("n 1000, p50 500.000 ms"),
            "{}",
            d.summary()
        );
    }
}
