//! The message layouts, their flags and the run topics.

use iceoryx2::prelude::*;

/// State components a message can carry.
pub const MAX_X: usize = 8;
/// Action components a message can carry.
pub const MAX_U: usize = 4;

/// Bits of the `flags` field.
pub mod flags {
    /// The sample is a trial's start state `x_0` (no reward yet).
    pub const START: u64 = 1;
    /// The sample is a trial's last; the agent learns but its action is not applied.
    pub const END: u64 = 2;
    /// The trial is a greedy evaluation: no exploration, no learning.
    pub const GREEDY: u64 = 4;
    /// The run is over: forward and exit.
    pub const SHUTDOWN: u64 = 8;
    /// With [`END`]: the trial ended early because the state left the operating range
    /// (§6.4.2); the state is terminal, its value zero.
    pub const TERMINAL: u64 = 16;
    /// Observer → agent, predictive timing: the agent's last transition of the trial;
    /// learn it, no action follows.
    pub const LAST: u64 = 32;
    /// Observer → agent, predictive timing: nothing to learn or act on (the agent's
    /// trial is already closed); acknowledge.
    pub const HOLD: u64 = 64;
    /// Plant → observer, predictive timing: the start state again, right after the
    /// [`START`] exchange and before the trial's first interval, with `u_next` now the
    /// answer to [`START`] — the first interval's action `u_0`, computed from the known
    /// start state. The agent learns `(x_0, u_0) → x̂_{1|0}` and answers `u_1`.
    pub const PRIMED: u64 = 128;
    /// Plant → observer (and on, in every message of the run): the plant does not know
    /// the rewards — its driver measures positions only — so a measurement's `reward`
    /// is NaN (a terminal penalty excepted) and the observer computes `ρ(x̂_k, u_k)`
    /// from its estimate; the estimates carry the rewards the learning curves sum.
    pub const ESTIMATED_REWARD: u64 = 256;
    /// Plant → observer (with [`END`]): the loop lost its timing before this sample —
    /// samples went missing, or this one reached the plant process more than a period
    /// after its instant. The transition into it is not learned (no agent call learns
    /// it), the trial's attempt ends here, cut short, and the trial is run again.
    pub const GAP: u64 = 512;
    /// Plant → observer (and on, in every message of the run): the rewards and the
    /// trials' endings are the external driver's own (its info provides them,
    /// `docs/driver.md`), not the task's `ρ`: [`END`] with [`TERMINAL`] where the driver
    /// said terminated, [`END`] alone where it said truncated.
    pub const DRIVER_REWARD: u64 = 1024;
}

/// Header fields shared by all messages.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.Header.v1")]
pub struct Header {
    /// Sample counter over the whole run (one per plant sample).
    pub seq: u64,
    /// Learning trial number, 1-based; a greedy trial carries the number of the learning
    /// trial after which it runs.
    pub trial: u64,
    /// Sample index within the trial; 0 is the start state.
    pub step: u64,
    /// [`flags`] bits.
    pub flags: u64,
    /// Simulated time since the start of the run \[s\] (learning trials only advance it).
    pub t_sim: f64,
}

/// Plant → observer: what the sensor measured at sample `step`.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.Measurement.v4")]
pub struct Measurement {
    /// Sample identification.
    pub header: Header,
    /// Used components of `y` and `u_applied`.
    pub n_x: u64,
    /// Used components of `u_applied`.
    pub n_u: u64,
    /// `r_k = ρ(x_{k−1}, u_{k−1})`, the reward of the transition into this sample (0 at a
    /// trial start).
    pub reward: f64,
    /// The measurement `y_k` (the full state with full-state sensing). Components the
    /// sensor does not measure (an encoder's velocities) are NaN, bit for bit as the
    /// sensor wrote them; the recording writes them as JSON `null`. At a trial start
    /// ([`flags::START`]) `y` is the true start state: the plant has just been put there.
    pub y: [f64; MAX_X],
    /// The action the plant applied over the interval before this sample.
    pub u_applied: [f64; MAX_U],
    /// The action the plant applies from this sample on, as the agent sent it: in
    /// predictive timing (`observer.mode`) the one that arrived for it a sample ahead (zero
    /// at a trial start); NaN in direct timing, where it is not known at the sample
    /// instant (the recording writes `null`).
    pub u_next: [f64; MAX_U],
    /// The sample-to-actuation delay drawn for the interval before this sample \[s\]
    /// (`run.delay_ms` / `run.delay_from`, lockstep; in predictive timing the action
    /// arrived this long after its sample and was held until this one). 0 at a trial
    /// start and in real time.
    pub delay_s: f64,
    /// Monotonic time at which the plant sampled \[ns\].
    pub t_sample_ns: u64,
    /// Monotonic time at which the plant published \[ns\].
    pub t_publish_ns: u64,
    /// Monotonic time at which the last action that arrived within the interval before
    /// this sample reached the plant \[ns\]; 0 if none arrived in it (the plant held its
    /// action or applied the safe one) and at a trial start.
    pub t_action_ns: u64,
    /// Deadlines missed so far in the run (realtime timing: no action arrived within a
    /// sample interval; always 0 in lockstep).
    pub deadline_misses: u64,
}

/// Observer → agent: the state the agent acts on — the estimate `x̂_k` in direct timing,
/// the prediction `x̂_{k+1|k}` in predictive timing — and the agent call it makes
/// (`observer::timing`; the flags [`flags::LAST`] and [`flags::HOLD`]).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.Estimate.v1")]
pub struct Estimate {
    /// Copied from the measurement.
    pub header: Header,
    /// Used components of `x` and `u_applied`.
    pub n_x: u64,
    /// Used components of `u_applied`.
    pub n_u: u64,
    /// The reward the agent learns: the measurement's in direct timing; in predictive
    /// timing `ρ(x̂_k, u_k)` from the estimate (the range penalty on a terminal sample).
    pub reward: f64,
    /// What the agent acts on: `x̂_k` (direct) or `x̂_{k+1|k}` (predictive).
    pub x: [f64; MAX_X],
    /// The action in effect over the interval `x` starts (direct: the measurement's
    /// `u_applied`; predictive: its `u_next`, made safe as the plant makes it).
    pub u_applied: [f64; MAX_U],
    /// The plant's sample time \[ns\].
    pub t_sample_ns: u64,
    /// Monotonic time at which the observer received the measurement \[ns\].
    pub t_received_ns: u64,
    /// Monotonic time at which the observer published \[ns\].
    pub t_publish_ns: u64,
}

/// Agent → plant: the action for the next interval.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.Action.v1")]
pub struct Action {
    /// Copied from the estimate it answers.
    pub header: Header,
    /// Used components of `u`.
    pub n_u: u64,
    /// The action `u_k` (the plant saturates it).
    pub u: [f64; MAX_U],
    /// The plant's sample time \[ns\].
    pub t_sample_ns: u64,
    /// Monotonic time at which the agent received the estimate \[ns\].
    pub t_received_ns: u64,
    /// Monotonic time at which the agent published \[ns\].
    pub t_publish_ns: u64,
}

/// Plant → supervisor only: the true state at sample `step` — the *evaluation* channel
/// (ground truth for observer errors and a finite horizon's terminal reward). Published
/// only when the sensor does not measure the full state (with full-state sensing the
/// [`Measurement`] is the truth), on its own topic [`topic::TRUTH`], which the observer
/// and the agent never open: they see the sensor output only.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.Truth.v1")]
pub struct Truth {
    /// The header of the [`Measurement`] of the same sample (published right after this).
    pub header: Header,
    /// Used components of `x`.
    pub n_x: u64,
    /// The true state `x_k` (angles wrapped).
    pub x: [f64; MAX_X],
    /// Monotonic time at which the plant sampled \[ns\].
    pub t_sample_ns: u64,
}

/// Topics, relative to a run.
pub mod topic {
    /// Plant → observer.
    pub const MEASUREMENT: &str = "measurement";
    /// Observer → agent.
    pub const ESTIMATE: &str = "estimate";
    /// Agent → plant.
    pub const ACTION: &str = "action";
    /// Plant → supervisor (`rig run`): ground truth, for evaluation only ([`super::Truth`]).
    pub const TRUTH: &str = "truth";
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layouts_are_fixed() {
        // Changing a layout must change the type name's version: these sizes pin them.
        assert_eq!(std::mem::size_of::<Header>(), 40);
        // v3: + u_next, delay_s; v4: + t_action_ns.
        assert_eq!(
            std::mem::size_of::<Measurement>(),
            40 + 3 * 8 + 8 * 8 + 2 * 4 * 8 + 8 + 32
        );
        assert_eq!(
            std::mem::size_of::<Estimate>(),
            40 + 3 * 8 + 8 * 8 + 4 * 8 + 24
        );
        assert_eq!(std::mem::size_of::<Action>(), 40 + 8 + 4 * 8 + 24);
        assert_eq!(std::mem::size_of::<Truth>(), 40 + 8 + 8 * 8 + 8);
        assert_eq!(std::mem::align_of::<Measurement>(), 8);
    }
}
