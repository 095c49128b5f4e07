//! Exploration: `Δu ~ N(0, σ²)` added to the policy's action (Algorithm 1 line 14,
//! §3.6: every step, σ = 1; §6.4.1: once every three steps).
//!
//! Each agent owns its exploration stream, a ChaCha8 generator keyed by the run seed and
//! a fixed stream id, so runs are reproducible and streams independent.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// Stream ids of the random streams derived from a run seed: each its own, so that no
/// two uses of randomness in a run draw the same numbers.
pub mod stream {
    /// The agent's exploration noise.
    pub const EXPLORATION: u64 = 1;
    /// The plant's sensor noise (an angle encoder with `noise_std > 0`).
    pub const SENSOR_NOISE: u64 = plant::sensor::NOISE_STREAM;
    /// The sample-to-actuation delays drawn from a recorded distribution.
    pub const DELAYS: u64 = plant::delay::STREAM;
    /// SARSA's ε-greedy draws (its own stream, apart from the sensor noise's).
    pub const SARSA: u64 = 4;
    /// The learning trials' start states drawn from a task's start distribution.
    pub const STARTS: u64 = plant::start::STREAM;
    /// The planner's candidate action sequences (`crate::plan`).
    pub const PLANNING: u64 = 6;
    /// All of them.
    pub const ALL: [u64; 6] = [EXPLORATION, SENSOR_NOISE, DELAYS, SARSA, STARTS, PLANNING];
}

/// Gaussian exploration, every `every`-th step of a trial; learning trial `t` (1-based)
/// explores with `σ · decay^(t−1)` (decay 1: the thesis's constant `σ`).
pub struct Exploration {
    sigma: f64,
    sigma0: f64,
    decay: f64,
    trials: u64,
    every: u32,
    step: u32,
    rng: ChaCha8Rng,
}

impl Exploration {
    /// Exploration with standard deviation `sigma` on steps `0, every, 2·every, …` of each
    /// trial, drawing from stream [`stream::EXPLORATION`] of `seed`.
    pub fn new(sigma: f64, every: u32, seed: u64) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream::EXPLORATION);
        Self {
            sigma,
            sigma0: sigma,
            decay: 1.0,
            trials: 0,
            every: every.max(1),
            step: 0,
            rng,
        }
    }

    /// The same exploration with `σ` multiplied by `decay` from one learning trial to
    /// the next (`[learning] sigma_decay`).
    pub fn with_decay(mut self, decay: f64) -> Self {
        self.decay = decay;
        self
    }

    /// Restarts the every-n-th-step count at a learning trial's start and sets that
    /// trial's `σ`.
    pub fn start_trial(&mut self) {
        self.step = 0;
        if self.decay != 1.0 {
            self.sigma = self.sigma0 * self.decay.powf(self.trials as f64);
        }
        self.trials += 1;
    }

    /// Writes the next `Δu` (zero on non-exploring steps) into `du`.
    pub fn draw(&mut self, du: &mut [f64]) {
        if self.step.is_multiple_of(self.every) && self.sigma > 0.0 {
            for d in du.iter_mut() {
                let z: f64 = StandardNormal.sample(&mut self.rng);
                *d = self.sigma * z;
            }
        } else {
            du.fill(0.0);
        }
        self.step = self.step.wrapping_add(1);
    }
}

/// The random stream's position, the step count and, with a decay, the learning trials
/// so far.
impl crate::checkpoint::Persist for Exploration {
    fn save(&self, s: &mut crate::checkpoint::Snapshot) {
        s.scope("exploration", |s| {
            s.rng("rng", &self.rng);
            if self.decay == 1.0 {
                s.u64s("step", &[u64::from(self.step)]);
            } else {
                s.u64s("step", &[u64::from(self.step), self.trials]);
            }
        });
    }
    fn restore(
        &mut self,
        r: &mut crate::checkpoint::Reader,
    ) -> Result<(), crate::checkpoint::CheckpointError> {
        r.scope("exploration", |r| {
            self.rng = r.rng("rng")?;
            let counts = r.u64s("step")?;
            self.step = counts.first().copied().unwrap_or(0) as u32;
            self.trials = counts.get(1).copied().unwrap_or(0);
            if self.decay != 1.0 {
                self.sigma = self.sigma0 * self.decay.powf(self.trials.saturating_sub(1) as f64);
            }
            Ok(())
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_random_stream_has_its_own_id() {
        let mut ids = stream::ALL.to_vec();
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), stream::ALL.len(), "{:?}", stream::ALL);
        assert!(stream::ALL.contains(&crate::sarsa::STREAM));
        assert!(stream::ALL.contains(&crate::plan::STREAM));
    }

    #[test]
    fn sigma_decays_per_learning_trial_and_resumes_from_a_checkpoint() {
        use crate::checkpoint::{Persist, Snapshot};
        let mut e = Exploration::new(2.0, 1, 9).with_decay(0.5);
        let mut du = [0.0];
        let mut sigmas = Vec::new();
        for _ in 0..3 {
            e.start_trial();
            sigmas.push(e.sigma);
            e.draw(&mut du);
        }
        assert_eq!(sigmas, [2.0, 1.0, 0.5]);
        let mut s = Snapshot::default();
        e.save(&mut s);
        let mut resumed = Exploration::new(2.0, 1, 9).with_decay(0.5);
        resumed.restore(&mut s.reader()).unwrap();
        assert_eq!(resumed.sigma, 0.5);
        e.start_trial();
        resumed.start_trial();
        assert_eq!((e.sigma, resumed.sigma), (0.25, 0.25));
        let mut constant = Exploration::new(2.0, 1, 9);
        for _ in 0..3 {
            constant.start_trial();
        }
        assert_eq!(constant.sigma, 2.0);
    }

    #[test]
    fn explores_every_third_step_reproducibly() {
        let (mut a, mut b) = (Exploration::new(1.0, 3, 9), Exploration::new(1.0, 3, 9));
        let mut c = Exploration::new(1.0, 3, 10);
        let (mut da, mut db, mut dc) = ([0.0], [0.0], [0.0]);
        let mut differs = false;
        for k in 0..30 {
            a.draw(&mut da);
            b.draw(&mut db);
            c.draw(&mut dc);
            assert_eq!(da, db);
            assert_eq!(da[0] != 0.0, k % 3 == 0);
            differs |= da != dc;
        }
        assert!(differs, "different seeds give different noise");
    }
}
