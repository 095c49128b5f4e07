//! Safety on the plant's side of the loop, whoever computes the actions — the simulated
//! plant here, or a Rust driver for real hardware. One [`SafetyLayer`] per actuator:
//!
//! * every action passes [`SafetyLayer::admit`] before it reaches the actuator: clamped
//!   to the task's limits (counted); an action with a non-finite component is rejected
//!   whole and the safe action (zero) applies instead (counted);
//! * [`SafetyLayer::period`] at every sample instant runs the stale-action [`Watchdog`]:
//!   no fresh action for a whole period ⇒ the safe action until actions resume;
//! * [`SafetyLayer::check`] on every new state: leaving the task's operating range
//!   (§6.4.2: the arm's ±1.2 rad) ends the trial with the thesis's penalty — and, not a
//!   safety matter but decided at the same place by every plant, reaching the task's
//!   goal ends it with the goal's reward;
//! * [`SafetyLayer::counts`] reports all of it.
//!
//! A Rust driver for a DC motor would, per sample instant `t_k`:
//!
//! ```
//! use plant::safety::SafetyLayer;
//! use plant::{SystemName, Task};
//! let task = Task::new(SystemName::Arm64);
//! let mut safety = SafetyLayer::new(&task);
//! let mut torque = [0.0; 2];
//! // An action arrived during the last period (say from `rig plant --driver`):
//! safety.admit(&[0.5, f64::NAN], &mut torque);
//! assert_eq!(torque, [0.0, 0.0]); // rejected whole: the safe action
//! safety.admit(&[0.5, -0.02], &mut torque);
//! assert_eq!(torque, [0.1, -0.02]); // clamped to ±0.1 N m
//! // At the next sample instant: was there a fresh action, is the state in range?
//! if safety.period(true) {
//!     torque = [0.0; 2];
//! }
//! assert_eq!(safety.check(&[1.3, 0.0, 0.0, 0.0]), Some(-4e4)); // out of range: stop
//! let c = safety.counts();
//! assert_eq!((c.clamped, c.rejected, c.range_stops), (1, 1, 1));
//! ```

use crate::{Goal, OperatingRange, Task};

/// What [`SafetyLayer::admit`] did with an action.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Admission {
    /// Within the limits: applied as it is.
    Applied,
    /// Beyond a limit: clamped to it.
    Clamped,
    /// A non-finite component: rejected; the safe action applies.
    Rejected,
}

/// `u` clamped to `[low, high]` into `out`, or zero if a component is not finite.
pub(crate) fn limit(low: &[f64], high: &[f64], u: &[f64], out: &mut [f64]) -> Admission {
    if u.iter().any(|v| !v.is_finite()) {
        out.fill(0.0);
        return Admission::Rejected;
    }
    let mut clamped = false;
    for i in 0..out.len() {
        out[i] = u[i].clamp(low[i], high[i]);
        clamped |= out[i] != u[i];
    }
    if clamped {
        Admission::Clamped
    } else {
        Admission::Applied
    }
}

/// How often each safety measure acted.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SafetyCounts {
    /// Actions clamped to the limits.
    pub clamped: u64,
    /// Actions rejected for a non-finite component.
    pub rejected: u64,
    /// Times the watchdog engaged.
    pub watchdog_trips: u64,
    /// Trials stopped because the state left the operating range.
    pub range_stops: u64,
}

impl std::fmt::Display for SafetyCounts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} actions clamped, {} rejected (non-finite), {} watchdog trips, {} operating-range stops",
            self.clamped, self.rejected, self.watchdog_trips, self.range_stops
        )
    }
}

/// The plant side's safety layer: limits, non-finite actions, the stale-action
/// watchdog and the operating range of one task (see the module documentation).
#[derive(Clone, Debug)]
pub struct SafetyLayer {
    low: Vec<f64>,
    high: Vec<f64>,
    range: Option<OperatingRange>,
    goal: Option<Goal>,
    angles: Vec<bool>,
    watchdog: Watchdog,
    counts: SafetyCounts,
}

impl SafetyLayer {
    /// The safety layer of `task`'s action limits and operating range, with a watchdog of
    /// one period (`docs/driver.md`).
    pub fn new(task: &Task) -> Self {
        Self {
            low: task.action_low.clone(),
            high: task.action_high.clone(),
            range: task.operating_range.clone(),
            goal: task.goal.clone(),
            angles: task.angle_mask.clone(),
            watchdog: Watchdog::new(1),
            counts: SafetyCounts::default(),
        }
    }

    /// The action to apply for the requested `u`, into `out`: `u` clamped to the limits,
    /// or the safe action (zero) if a component of `u` is not finite.
    pub fn admit(&mut self, u: &[f64], out: &mut [f64]) -> Admission {
        let a = limit(&self.low, &self.high, u, out);
        match a {
            Admission::Applied => {}
            Admission::Clamped => self.counts.clamped += 1,
            Admission::Rejected => self.counts.rejected += 1,
        }
        a
    }

    /// Ends a sample period in which a fresh action was (`fresh`) or was not admitted;
    /// returns whether the safe action must apply from now on ([`Watchdog::period`]).
    pub fn period(&mut self, fresh: bool) -> bool {
        let trips = self.watchdog.trips();
        let safe = self.watchdog.period(fresh);
        self.counts.watchdog_trips += self.watchdog.trips() - trips;
        safe
    }

    /// A trial starts with the system at rest under the safe action: the watchdog's
    /// count restarts.
    pub fn start_trial(&mut self) {
        self.watchdog.reset();
    }

    /// Whether the trial ends at state `x`, and with which reward: `Some(penalty)` if `x`
    /// lies outside the operating range (a non-finite component counts as outside;
    /// counted), else `Some(reward)` of the goal if `x` lies in it, else `None`.
    pub fn check(&mut self, x: &[f64]) -> Option<f64> {
        if let Some(range) = &self.range
            && range.excludes(x)
        {
            self.counts.range_stops += 1;
            return Some(range.penalty);
        }
        let goal = self.goal.as_ref()?;
        goal.region.contains(x, &self.angles).then_some(goal.reward)
    }

    /// How often each measure acted so far.
    pub fn counts(&self) -> SafetyCounts {
        self.counts
    }
}

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
