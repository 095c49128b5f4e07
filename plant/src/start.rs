//! Start states drawn from a distribution (`[start_distribution]` of a task file): a
//! uniform box or a normal distribution with a standard deviation per state component.
//!
//! Learning trial `n` of a run starts from the draw of stream [`STREAM`] of the run seed
//! at position `n`: a ChaCha8 generator keyed by the run seed, on stream [`STREAM`],
//! advanced to word `n · 2³²` — so a trial's start depends on the run seed and the trial's
//! number alone, the same in every process and after a resume, and no two trials share
//! numbers. A normal draw outside the operating range (or beyond the largest f64) is
//! drawn again (at most [`REDRAWS`] times; then the mean, which lies inside, is the
//! start).

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal, Uniform};

use crate::operating_range::OperatingRange;

/// Stream id of the start states' draws (see the module documentation).
pub const STREAM: u64 = 5;

/// Draws of a normal start outside the operating range before its mean is taken.
pub const REDRAWS: u32 = 100;

/// Words of the stream each trial's draw may use (see the module documentation).
const WORDS_PER_TRIAL: u128 = 1 << 32;

/// Where learning trials start.
#[derive(Clone, Debug, PartialEq)]
pub enum StartDistribution {
    /// Each component uniform in `[low_i, high_i]` (`low_i = high_i`: fixed).
    Uniform {
        /// Lower bounds.
        low: Vec<f64>,
        /// Upper bounds.
        high: Vec<f64>,
    },
    /// Each component normal, `N(mean_i, std_i²)` (`std_i = 0`: fixed).
    Normal {
        /// The means.
        mean: Vec<f64>,
        /// The standard deviations.
        std: Vec<f64>,
    },
}

impl StartDistribution {
    /// The start state of learning trial `trial` (from 1) of the run seeded `run_seed`,
    /// inside `range` if there is one.
    pub fn draw(&self, run_seed: u64, trial: u32, range: Option<&OperatingRange>) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(run_seed);
        rng.set_stream(STREAM);
        rng.set_word_pos(u128::from(trial) * WORDS_PER_TRIAL);
        match self {
            StartDistribution::Uniform { low, high } => low
                .iter()
                .zip(high)
                .map(|(&lo, &hi)| {
                    if lo == hi {
                        lo
                    } else {
                        Uniform::new_inclusive(lo, hi)
                            .expect("checked: finite, low ≤ high")
                            .sample(&mut rng)
                    }
                })
                .collect(),
            StartDistribution::Normal { mean, std } => {
                let mut draw = || -> Vec<f64> {
                    mean.iter()
                        .zip(std)
                        .map(|(&m, &s)| {
                            let z: f64 = StandardNormal.sample(&mut rng);
                            m + s * z
                        })
                        .collect()
                };
                (0..REDRAWS)
                    .map(|_| draw())
                    .find(|x| {
                        x.iter().all(|v| v.is_finite()) && range.is_none_or(|r| !r.excludes(x))
                    })
                    .unwrap_or_else(|| mean.clone())
            }
        }
    }

    /// Appends the distribution's canonical bytes to `b` (the task's hash): a kind byte, 0
    /// uniform and 1 normal, then per component `low, high` or `mean, std` as
    /// little-endian `f64`.
    pub fn digest(&self, b: &mut Vec<u8>) {
        let (kind, first, second) = match self {
            StartDistribution::Uniform { low, high } => (0u8, low, high),
            StartDistribution::Normal { mean, std } => (1u8, mean, std),
        };
        crate::task::digest::kind_and_pairs(b, kind, first, second);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_trials_start_depends_on_the_seed_and_the_trial_alone() {
        let u = StartDistribution::Uniform {
            low: vec![-1.0, 2.0],
            high: vec![1.0, 2.0],
        };
        let a: Vec<Vec<f64>> = (1..=20).map(|n| u.draw(7, n, None)).collect();
        let again: Vec<Vec<f64>> = (1..=20).rev().map(|n| u.draw(7, n, None)).collect();
        assert!(a.iter().eq(again.iter().rev()), "in any order");
        assert!(
            a.iter()
                .all(|x| (-1.0..=1.0).contains(&x[0]) && x[1] == 2.0)
        );
        assert_ne!(a[0], a[1], "trials differ");
        assert_ne!(a[0], u.draw(8, 1, None), "seeds differ");
    }

    #[test]
    fn normal_draws_stay_in_the_operating_range() {
        let n = StartDistribution::Normal {
            mean: vec![0.0, 0.0],
            std: vec![1.0, 0.0],
        };
        let range = OperatingRange {
            limits: vec![(-0.5, 0.5), (f64::NEG_INFINITY, f64::INFINITY)],
            penalty: -1.0,
        };
        let xs: Vec<Vec<f64>> = (1..=200).map(|t| n.draw(3, t, Some(&range))).collect();
        assert!(xs.iter().all(|x| x[0].abs() <= 0.5 && x[1] == 0.0));
        let outside = (1..=200).filter(|&t| n.draw(3, t, None)[0].abs() > 0.5);
        assert!(outside.count() > 50, "redrawn, not all inside by chance");
    }
}
