//! What the plant's sensor measures of the true state.
//!
//! * [`Sensor::Full`] — the full state `y_k = x_k` (the thesis's simulations).
//! * [`Sensor::Angle`] — an incremental encoder on each joint (the physical pendulum of
//!   §6.4.1 has one on the motor shaft): only the positions are measured, quantised to
//!   `2π / counts_per_rev`, optionally after adding Gaussian noise; the velocity entries of
//!   `y_k` are NaN (not measured — an observer must not read them).
//!
//! States are `[positions…, velocities…]` (every system of this crate): the first half of
//! the state is what an encoder measures. The noise stream is a ChaCha8 generator keyed
//! by the run seed with its own stream id [`NOISE_STREAM`], so a run is reproducible and
//! its sensor noise independent of the agent's exploration.
//!
//! The true state stays with the plant ([`crate::Plant::state`]): it is the *evaluation*
//! channel (rewards, ground truth for observer errors), never what an observer or agent
//! reads.

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

use crate::angle::wrap;

/// Stream id of the sensor-noise stream derived from a run seed (the list of all:
/// `agent::explore::stream`).
pub const NOISE_STREAM: u64 = 2;

/// A sensor model.
pub enum Sensor {
    /// Full-state measurement.
    Full,
    /// Angle-only encoder.
    Angle(Box<Encoder>),
}

/// An angle-only encoder: quantisation `q = 2π / counts_per_rev`, Gaussian noise of
/// standard deviation `noise_std` \[rad\] added before quantisation.
pub struct Encoder {
    q: f64,
    noise_std: f64,
    rng: ChaCha8Rng,
    angle_mask: Vec<bool>,
}

impl Sensor {
    /// An angle-only encoder for a system whose angle components are `angle_mask` (the
    /// measured positions are wrapped only where the system wraps them), with
    /// `counts_per_rev ≥ 1` and `noise_std ≥ 0`, noise drawn from `run_seed`.
    pub fn angle(angle_mask: &[bool], counts_per_rev: u32, noise_std: f64, run_seed: u64) -> Self {
        assert!(counts_per_rev >= 1 && noise_std.is_finite() && noise_std >= 0.0);
        let mut rng = ChaCha8Rng::seed_from_u64(run_seed);
        rng.set_stream(NOISE_STREAM);
        Sensor::Angle(Box::new(Encoder {
            q: std::f64::consts::TAU / f64::from(counts_per_rev),
            noise_std,
            rng,
            angle_mask: angle_mask.to_vec(),
        }))
    }

    /// Writes the measurement `y_k` of the true state `x` into `y` (same length).
    pub fn measure(&mut self, x: &[f64], y: &mut [f64]) {
        match self {
            Sensor::Full => y.copy_from_slice(x),
            Sensor::Angle(e) => {
                let half = x.len() / 2;
                for i in 0..x.len() {
                    y[i] = if i < half {
                        let noise = if e.noise_std > 0.0 {
                            let z: f64 = StandardNormal.sample(&mut e.rng);
                            e.noise_std * z
                        } else {
                            0.0
                        };
                        let v = ((x[i] + noise) / e.q).round() * e.q;
                        if e.angle_mask[i] { wrap(v) } else { v }
                    } else {
                        f64::NAN
                    };
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_encoder_quantises_and_leaves_velocities_unmeasured() {
        let mut s = Sensor::angle(&[true, false], 4096, 0.0, 1);
        let mut y = [0.0; 2];
        s.measure(&[1.0, 5.0], &mut y);
        let q = std::f64::consts::TAU / 4096.0;
        assert!((y[0] - 1.0).abs() <= q / 2.0 && y[1].is_nan());
        assert_eq!((y[0] / q).round() * q, y[0]);
    }

    #[test]
    fn noise_is_reproducible_from_the_seed() {
        let run = |seed| {
            let mut s = Sensor::angle(&[true, false], 4096, 0.01, seed);
            let mut y = [0.0; 2];
            (0..10)
                .map(|_| {
                    s.measure(&[0.5, 0.0], &mut y);
                    y[0]
                })
                .collect::<Vec<_>>()
        };
        assert_eq!(run(3), run(3));
        assert_ne!(run(3), run(4));
    }

    #[test]
    fn full_state_is_passed_on() {
        let mut y = [0.0; 2];
        Sensor::Full.measure(&[1.0, 2.0], &mut y);
        assert_eq!(y, [1.0, 2.0]);
    }
}
