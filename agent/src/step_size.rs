//! A learning rate's schedule over the trials: constant, as the thesis's learners have it
//! (Template 2.1 with a fixed `α`), or decaying,
//!
//! ```text
//! α_k = α_0 · (τ / (τ + k))^p,     k = the learning trials before this one
//! ```
//!
//! which satisfies the step-size conditions the thesis states for an actor-critic's
//! convergence (§2.3.3, Eq. 2.21–2.22, after Konda and Tsitsiklis, 2003): deterministic,
//! non-increasing, `Σ_k α_k = ∞` (`p ≤ 1`) and `Σ_k α_k² < ∞` (`p > 1/2`). The actor
//! moves on a slower time scale than the critic, `Σ_k (α_{a,k} / α_{c,k})^d < ∞` for some
//! `d`, when the actor's power exceeds the critic's (`α_a/α_c ∝ k^{p_c − p_a}`). `k`
//! counts trials rather than samples: within a trial the rate stays, and since every
//! trial has at most `N` samples the sums keep their verdicts.
//!
//! The trial count is learned state: a checkpoint keeps it, so that a resumed run goes on
//! with the rate it left off with. A constant rate writes nothing.

use crate::checkpoint::{CheckpointError, Persist, Reader, Snapshot};

/// The decay of a schedule: `τ` and `p` of `α_k = α_0 (τ / (τ + k))^p`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decay {
    /// `τ`, in trials: the rate is halved (for `p = 1`) after `τ` trials.
    pub trials: f64,
    /// `p`, in `(1/2, 1]`.
    pub power: f64,
}

/// A learning rate `α_k` and the count `k` it is at.
#[derive(Clone, Debug, PartialEq)]
pub struct StepSize {
    alpha0: f64,
    decay: Option<Decay>,
    /// Learning trials begun.
    begun: u64,
    /// `α_k` of the current trial: computed when a trial begins, read at every update.
    alpha: f64,
}

impl StepSize {
    /// `α_0`, decaying as `decay` says, or constant without one.
    pub fn new(alpha0: f64, decay: Option<Decay>) -> Self {
        let mut s = Self {
            alpha0,
            decay,
            begun: 0,
            alpha: alpha0,
        };
        s.alpha = s.rate();
        s
    }

    /// The rate of the current trial, `α_k`.
    pub fn alpha(&self) -> f64 {
        self.alpha
    }

    /// A learning trial begins: `k` is the number of those before it.
    pub fn start_trial(&mut self) {
        self.begun += 1;
        self.alpha = self.rate();
    }

    /// `α_k = α_0 (τ / (τ + k))^p` with `k` the trials before the current one.
    fn rate(&self) -> f64 {
        let Some(Decay { trials: tau, power }) = self.decay else {
            return self.alpha0;
        };
        let k = self.begun.saturating_sub(1) as f64;
        self.alpha0 * (tau / (tau + k)).powf(power)
    }
}

/// A constant rate.
impl From<f64> for StepSize {
    fn from(alpha: f64) -> Self {
        Self::new(alpha, None)
    }
}

/// A decaying schedule keeps the trials begun (`schedule.trials`); a constant one nothing.
impl Persist for StepSize {
    fn save(&self, s: &mut Snapshot) {
        if self.decay.is_some() {
            s.u64s("schedule.trials", &[self.begun]);
        }
    }
    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError> {
        if self.decay.is_some() {
            let v = r.u64s("schedule.trials")?;
            self.begun = match v {
                [n] => *n,
                _ => {
                    return Err(CheckpointError::Unfit {
                        section: "schedule.trials",
                        why: format!("has {} values where a schedule has 1", v.len()),
                    });
                }
            };
            self.alpha = self.rate();
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn decaying(alpha0: f64, trials: f64, power: f64) -> StepSize {
        StepSize::new(alpha0, Some(Decay { trials, power }))
    }

    /// The rate at the first trial and after `k` trials, `α_0 (τ / (τ + k))^p`.
    fn rates(mut s: StepSize, n: usize) -> Vec<f64> {
        (0..n)
            .map(|_| {
                s.start_trial();
                s.alpha()
            })
            .collect()
    }

    #[test]
    fn the_rate_follows_the_schedule_trial_by_trial() {
        let r = rates(decaying(0.2, 100.0, 1.0), 301);
        assert_eq!(r[0], 0.2);
        assert!((r[100] - 0.1).abs() < 1e-15, "{}", r[100]);
        assert!((r[300] - 0.05).abs() < 1e-15, "{}", r[300]);
        // p = 1/2 + ε: after τ trials α_0 / √2.
        let r = rates(decaying(1.0, 50.0, 0.5), 51);
        assert!((r[50] - 0.5f64.sqrt()).abs() < 1e-15, "{}", r[50]);
        assert!(r.windows(2).all(|w| w[1] < w[0]), "non-increasing");
    }

    #[test]
    fn without_a_decay_the_rate_is_constant_and_nothing_is_saved() {
        let s = StepSize::from(0.15);
        assert!(rates(s.clone(), 1000).iter().all(|&a| a == 0.15));
        let mut snap = Snapshot::default();
        s.save(&mut snap);
        assert!(snap.is_empty());
    }

    /// A schedule restored from a checkpoint after 40 trials goes on as the one that
    /// wrote it: the 41st trial's rate is `α_0 τ / (τ + 40)`, not `α_0`.
    #[test]
    fn a_restored_schedule_continues_where_it_was_saved() {
        let mut s = decaying(0.02, 200.0, 1.0);
        for _ in 0..40 {
            s.start_trial();
        }
        let mut snap = Snapshot::default();
        s.save(&mut snap);
        let mut resumed = decaying(0.02, 200.0, 1.0);
        let mut r = snap.reader();
        resumed.restore(&mut r).unwrap();
        r.finish().unwrap();
        let next = rates(resumed, 5);
        assert!(
            (next[0] - 0.02 * 200.0 / 240.0).abs() < 1e-15,
            "{}",
            next[0]
        );
        assert_eq!(next, rates(s, 5));
    }
}
