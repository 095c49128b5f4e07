//! Safety pieces a plant applies on its side of the loop, whoever computes the actions —
//! the simulated plant here, or a Rust driver for real hardware:
//!
//! * saturation to the action limits, non-finite components replaced by the safe action
//!   (zero) and counted: [`crate::Plant::saturate`];
//! * the operating range, whose violation ends the trial (§6.4.2):
//!   [`crate::OperatingRange`];
//! * the stale-action [`Watchdog`]: no fresh action for a number of sample periods ⇒ the
//!   safe action until actions resume.

/// The stale-action watchdog, advanced once per sample period.
///
/// With `periods = 1` (the rig's setting, as `docs/driver.md` asks of drivers): a whole
/// period without a fresh action makes the safe action apply from the next sample
/// instant on, so the last action is in effect at most two periods after it arrived.
#[derive(Clone, Debug)]
pub struct Watchdog {
    periods: u32,
    silent: u32,
    trips: u64,
}

impl Watchdog {
    /// A watchdog that trips after `periods` (≥ 1) periods without a fresh action.
    pub fn new(periods: u32) -> Self {
        Self {
            periods: periods.max(1),
            silent: 0,
            trips: 0,
        }
    }

    /// Ends a sample period in which a fresh action did (`fresh`) or did not arrive;
    /// returns whether the safe action must apply from now on.
    pub fn period(&mut self, fresh: bool) -> bool {
        if fresh {
            self.silent = 0;
            return false;
        }
        self.silent = self.silent.saturating_add(1);
        if self.silent == self.periods {
            self.trips += 1;
        }
        self.silent >= self.periods
    }

    /// Restarts the count (a trial start: the plant is at rest under the safe action).
    pub fn reset(&mut self) {
        self.silent = 0;
    }

    /// How often the watchdog has tripped.
    pub fn trips(&self) -> u64 {
        self.trips
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trips_after_the_given_silent_periods_and_rearms_on_a_fresh_action() {
        let mut w = Watchdog::new(2);
        assert!(!w.period(true));
        assert!(!w.period(false));
        assert!(w.period(false), "two silent periods");
        assert!(w.period(false), "stays tripped");
        assert_eq!(w.trips(), 1);
        assert!(!w.period(true), "a fresh action re-arms it");
        assert!(!w.period(false));
        assert!(w.period(false));
        assert_eq!(w.trips(), 2);
        let mut one = Watchdog::new(0);
        assert!(one.period(false), "at least one period");
    }
}
