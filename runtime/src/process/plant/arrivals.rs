//! The actions that arrive within one realtime sample interval, and how the realtime
//! plant waits for them without letting the transport delay the next sampling instant.

use crate::process::Result;
use wire::{Action, Inbox, MAX_U, Monotonic};

/// The last stretch before a sampling instant in which the realtime plant only reads the
/// clock: no transport call, whose duration varies, runs into the instant. An action
/// that arrives within it is found after the instant — for the answer, a deadline miss
/// \[ns\].
const APPROACH_NS: u64 = 20_000;

/// The actions that arrived within one realtime interval, with their arrival times.
/// One per trial, cleared at every instant: the loop allocates nothing per interval.
pub(super) struct Arrivals {
    /// `(t_arrival_ns, u)` in order of arrival.
    pub(super) list: Vec<(u64, [f64; MAX_U])>,
    /// When the answer to the interval's sample arrived.
    pub(super) answered: Option<u64>,
    /// The sequence number of the trial's first sample: an action answering an earlier
    /// one (a late answer to the last trial's END sample) is not this trial's.
    first_seq: u64,
    /// An action received only after the instant it was waited for: the next
    /// interval's.
    late: Option<(u64, Action)>,
    /// The newest sample of the trial answered so far (before the trial: the one
    /// before its first).
    pub(super) newest: u64,
    /// The time the arrivals are read on.
    time: Monotonic,
}

impl Arrivals {
    /// The arrivals of a trial whose first sample has sequence number `first_seq`,
    /// timed on `time`.
    pub(super) fn new(first_seq: u64, time: Monotonic) -> Self {
        Self {
            list: Vec::with_capacity(8),
            answered: None,
            first_seq,
            late: None,
            newest: first_seq.saturating_sub(1),
            time,
        }
    }

    /// Starts the next interval.
    fn clear(&mut self) {
        self.list.clear();
        self.answered = None;
    }

    /// Notes action `a`, arrived at `t_a`; it answers the interval's sample if its
    /// sequence number is `waiting_for`. An answer to the previous trial is dropped.
    fn push(&mut self, a: &Action, t_a: u64, waiting_for: u64) {
        if a.header.seq < self.first_seq {
            return;
        }
        self.list.push((t_a, a.u));
        self.newest = self.newest.max(a.header.seq);
        if a.header.seq == waiting_for {
            self.answered = Some(t_a);
        }
    }

    /// Collects the actions of `actions` arriving until `deadline` (monotonic ns), the
    /// answer awaited being the one to sample `waiting_for`, and returns at the deadline.
    /// The plant waits for them (`Rx::wait_until`: woken by an arrival, or at `spin_ns`
    /// before the deadline, to the high-resolution timer's precision); in those last
    /// `spin_ns` it polls without sleeping, and in the last [`APPROACH_NS`] it only reads
    /// the clock, so that the next sampling instant depends neither on when the
    /// operating system wakes it nor on the transport.
    pub(super) fn collect(
        &mut self,
        actions: &impl Inbox<Action>,
        deadline: u64,
        waiting_for: u64,
        spin_ns: u64,
    ) -> Result<()> {
        self.clear();
        if let Some((t_a, a)) = self.late.take() {
            self.push(&a, t_a.min(deadline), waiting_for);
        }
        loop {
            let now = self.time.now_ns();
            if now + APPROACH_NS >= deadline {
                break;
            }
            let Some(a) = actions.try_recv()? else {
                let left = deadline - now;
                if left > spin_ns {
                    actions.wait_until(deadline - spin_ns)?;
                } else {
                    std::hint::spin_loop();
                }
                continue;
            };
            let t_a = self.time.now_ns();
            if t_a >= deadline {
                // Received across the instant (the call was held up): the next
                // interval's.
                self.late = Some((t_a, a));
                break;
            }
            self.push(&a, t_a, waiting_for);
        }
        while self.time.now_ns() < deadline {
            std::hint::spin_loop();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::time::Duration;
    use wire::Scripted;

    fn action(seq: u64, u: f64) -> Action {
        let mut a = Action::default();
        a.header.seq = seq;
        a.n_u = 1;
        a.u[0] = u;
        a
    }

    /// A late answer to the previous trial's END sample is not applied in the next
    /// trial; the answer to the interval's sample is marked; `clear` starts afresh.
    #[test]
    fn arrivals_keep_this_trials_actions() {
        let mut arrivals = Arrivals::new(10, Monotonic::host());
        arrivals.push(&action(9, 0.0), 100, 10);
        assert!(arrivals.list.is_empty() && arrivals.answered.is_none());
        arrivals.push(&action(10, 1.5), 200, 10);
        arrivals.push(&action(11, -2.0), 300, 10);
        assert_eq!(arrivals.answered, Some(200));
        let applied: Vec<(u64, f64)> = arrivals.list.iter().map(|(t, u)| (*t, u[0])).collect();
        assert_eq!(applied, [(200, 1.5), (300, -2.0)]);
        arrivals.clear();
        assert!(arrivals.list.is_empty() && arrivals.answered.is_none());
        arrivals.push(&action(11, -2.0), 400, 11);
        assert_eq!(arrivals.answered, Some(400));
    }

    /// On a mock clock, an interval of 10 ms from 0: actions that arrive within it are
    /// its own, at their arrival; one whose receipt is held up across the deadline is the
    /// next interval's, from its receipt on; `collect` returns no earlier than the
    /// deadline.
    #[test]
    fn an_action_received_after_the_deadline_is_the_next_intervals() {
        let (clock, time) = Monotonic::mock();
        time.step_each_reading(Duration::from_micros(1));
        let inbox = Scripted::new(&time)
            .arrives(3_000_000, action(10, 1.0), Duration::ZERO)
            .arrives(9_000_000, action(11, 2.0), Duration::from_micros(1_500));
        let mut arrivals = Arrivals::new(10, clock.clone());
        arrivals.collect(&inbox, 10_000_000, 10, 50_000).unwrap();
        // Received at its arrival, a reading (1 µs) later.
        let at = 3_000_000..3_010_000;
        assert!(arrivals.answered.is_some_and(|t| at.contains(&t)));
        assert!(matches!(arrivals.list[..], [(t, u)] if at.contains(&t) && u[0] == 1.0));
        // Not before the deadline: the receipt held up until 10.5 ms.
        assert!((10_500_000..10_510_000).contains(&time.now_ns()));
        arrivals.collect(&inbox, 20_000_000, 11, 50_000).unwrap();
        let at = 10_500_000..10_510_000;
        assert!(arrivals.answered.is_some_and(|t| at.contains(&t)));
        assert!(matches!(arrivals.list[..], [(t, u)] if at.contains(&t) && u[0] == 2.0));
    }
}
