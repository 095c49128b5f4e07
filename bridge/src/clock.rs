//! Two hosts, two clocks: round trips measured honestly, and the driver's stamps placed
//! on the rig's clock.
//!
//! A ping leaves the rig's host at `t0` (its clock), arrives at the driver's host at
//! `t1` and is answered at `t2` (the driver's clock), and is back at `t3`. Whatever the
//! clocks' offset, the network's round trip is `(t3 − t0) − (t2 − t1)`, each difference
//! taken on one clock. The offset `θ = ((t1 − t0) + (t2 − t3)) / 2` (driver minus rig)
//! is exact only if both directions take equally long; its error is at most half the
//! round trip, so the exchange with the shortest round trip of the recent ones gives the
//! best estimate (NTP's). One-way delays are only measured where both hosts read one
//! clock (`--same-clock`: namespaces of one machine, or clocks synchronised by other
//! means); otherwise the bridge reports round trips.

use std::collections::VecDeque;

use crate::message::Ping;

/// Exchanges the offset estimate is chosen from (the most recent ones).
const WINDOW: usize = 64;

/// One ping's round trip and offset estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exchange {
    /// The network's round trip (ns): the answer's time on the driver's host excluded.
    pub round_trip: u64,
    /// The driver's clock minus the rig's (ns), exact if both directions took as long.
    pub offset: i64,
}

impl Exchange {
    /// The exchange of ping `p`, back on the rig's host at `received`.
    pub fn of(p: &Ping, received: u64) -> Self {
        let (t0, t1, t2, t3) = (
            p.sent as i128,
            p.arrived as i128,
            p.answered as i128,
            received as i128,
        );
        Self {
            round_trip: ((t3 - t0) - (t2 - t1)).max(0) as u64,
            offset: (((t1 - t0) + (t2 - t3)) / 2) as i64,
        }
    }
}

/// Maps the driver's host's monotonic stamps onto the rig's host's.
#[derive(Clone, Debug)]
pub struct ClockMap {
    same: bool,
    recent: VecDeque<Exchange>,
}

impl ClockMap {
    /// A map for hosts that read one clock (`same`: stamps pass unchanged), or two.
    pub fn new(same: bool) -> Self {
        Self {
            same,
            recent: VecDeque::with_capacity(WINDOW),
        }
    }

    /// Whether both hosts read one clock.
    pub fn same(&self) -> bool {
        self.same
    }

    /// Takes an exchange into account.
    pub fn add(&mut self, e: Exchange) {
        if self.recent.len() == WINDOW {
            self.recent.pop_front();
        }
        self.recent.push_back(e);
    }

    /// The exchange the offset is taken from: the shortest recent round trip.
    pub fn best(&self) -> Option<Exchange> {
        self.recent.iter().copied().min_by_key(|e| e.round_trip)
    }

    /// Whether stamps can be mapped: one clock, or an exchange measured.
    pub fn ready(&self) -> bool {
        self.same || !self.recent.is_empty()
    }

    /// The driver's clock minus the rig's (ns): 0 on one clock.
    pub fn offset(&self) -> i64 {
        if self.same {
            0
        } else {
            self.best().map_or(0, |e| e.offset)
        }
    }

    /// How far a mapped stamp may be off (ns): half the best round trip; 0 on one clock.
    pub fn uncertainty(&self) -> u64 {
        if self.same {
            0
        } else {
            self.best().map_or(u64::MAX, |e| e.round_trip / 2)
        }
    }

    /// A stamp of the driver's host on the rig's clock (0 stays 0: "none").
    pub fn to_rig(&self, t: u64) -> u64 {
        shift(t, -self.offset())
    }

    /// A stamp of the rig's host on the driver's clock (0 stays 0).
    pub fn to_driver(&self, t: u64) -> u64 {
        shift(t, self.offset())
    }
}

fn shift(t: u64, by: i64) -> u64 {
    if t == 0 {
        0
    } else {
        t.saturating_add_signed(by)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A driver clock 5 s ahead, 0.3 ms out and 0.1 ms back, 0.05 ms to answer.
    #[test]
    fn the_round_trip_needs_no_common_clock_and_the_offset_errs_by_the_asymmetry() {
        let rig = 1_000_000_000u64;
        let ahead = 5_000_000_000u64;
        let p = Ping {
            sent: rig,
            arrived: rig + ahead + 300_000,
            answered: rig + ahead + 350_000,
        };
        let e = Exchange::of(&p, rig + 450_000);
        assert_eq!(e.round_trip, 400_000);
        // ((0.3 + 5 s) + (5 s − 0.1)) / 2 = 5 s + 0.1 ms: off by half the asymmetry.
        assert_eq!(e.offset, 5_000_100_000);
        let mut map = ClockMap::new(false);
        assert!(!map.ready());
        map.add(e);
        map.add(Exchange {
            round_trip: 900_000,
            offset: 4_000_000_000,
        });
        assert_eq!(
            map.offset(),
            5_000_100_000,
            "the shortest round trip decides"
        );
        assert_eq!(map.uncertainty(), 200_000);
        assert_eq!(map.to_rig(p.arrived), rig + 200_000);
        assert_eq!(map.to_driver(map.to_rig(123_456_789_000)), 123_456_789_000);
        assert_eq!(map.to_rig(0), 0);
        let one = ClockMap::new(true);
        assert!(one.ready());
        assert_eq!(one.to_rig(77), 77);
    }
}
