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

/// Gaussian exploration, every `every`-th step of a trial.
pub struct Exploration {
    sigma: f64,
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
            every: every.max(1),
            step: 0,
            rng,
        }
    }

    /// Restarts the every-n-th-step count at a trial start.
    pub fn start_trial(&mut self) {
        self.step = 0;
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

/// The random stream's position and the step count.
impl crate::checkpoint::Persist for Exploration {
    fn save(&self, s: &mut crate::checkpoint::Snapshot) {
        s.scope("exploration", |s| {
            s.rng("rng", &self.rng);
            s.u64s("step", &[u64::from(self.step)]);
        });
    }
    fn restore(
        &mut self,
        r: &mut crate::checkpoint::Reader,
    ) -> Result<(), crate::checkpoint::CheckpointError> {
        r.scope("exploration", |r| {
            self.rng = r.rng("rng")?;
            self.step = r.u64s("step")?.first().copied().unwrap_or(0) as u32;
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
