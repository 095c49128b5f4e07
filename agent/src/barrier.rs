//! The operating range (§6.4.2) as a cost a planner can see.
//!
//! Leaving the operating range ends a trial with the task's penalty, a cliff that a
//! plan's gradients and curvatures cannot see coming. The barrier is a smooth stand-in:
//! for each finite bound `b_i` of state component `i`, at distance `d_i = |b_i − x_{r,i}|`
//! from the reward's reference, it is zero up to an inner bound a quarter of that
//! distance short of `b_i` and grows quadratically beyond it,
//!
//! ```text
//! ℓ_b(x) = Σ_i w_i max(0, x_i − h_i)² + w_i max(0, l_i − x_i)²,
//! h_i = b_i^high − δ_i,   l_i = b_i^low + δ_i,   δ_i = MARGIN · d_i,
//! w_i = |penalty| (1 − γ) / δ_i²,
//! ```
//!
//! so that a plan resting at the range's edge costs, summed over an infinite horizon
//! discounted by `γ`, about the penalty of leaving it. A task without an operating range,
//! or whose penalty is zero, has no barrier.

use plant::task::OperatingRange;

/// The share of the distance from the reference to a bound over which the barrier rises.
pub const MARGIN: f64 = 0.25;

/// One side of one state component: `w max(0, s (x_i − edge))²`, `s` = +1 for an upper
/// bound, −1 for a lower one.
#[derive(Clone, Debug, PartialEq)]
struct Wall {
    i: usize,
    edge: f64,
    side: f64,
    weight: f64,
}

/// The operating range's barrier; empty where the task has none.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Barrier {
    walls: Vec<Wall>,
}

impl Barrier {
    /// The barrier of `range` around the reward's reference `x_r`, for discount `γ`.
    pub fn of(range: Option<&OperatingRange>, reference: &[f64], gamma: f64) -> Self {
        let Some(range) = range else {
            return Self::default();
        };
        let scale = range.penalty.abs() * (1.0 - gamma);
        let mut walls = Vec::new();
        for (i, &(low, high)) in range.limits.iter().enumerate() {
            let reference = reference[i];
            for (bound, side) in [(high, 1.0), (low, -1.0)] {
                let d = side * (bound - reference);
                if !(d.is_finite() && d > 0.0 && scale > 0.0) {
                    continue;
                }
                let delta = MARGIN * d;
                walls.push(Wall {
                    i,
                    edge: bound - side * delta,
                    side,
                    weight: scale / (delta * delta),
                });
            }
        }
        Self { walls }
    }

    /// Whether the barrier is zero everywhere.
    pub fn is_empty(&self) -> bool {
        self.walls.is_empty()
    }

    /// `ℓ_b(x)`.
    pub fn cost(&self, x: &[f64]) -> f64 {
        self.walls
            .iter()
            .map(|w| w.weight * w.excess(x).powi(2))
            .sum()
    }

    /// Adds `∂ℓ_b/∂x` to `grad` and the diagonal of `∂²ℓ_b/∂x²` to `curvature`.
    pub fn add_derivatives(&self, x: &[f64], grad: &mut [f64], curvature: &mut [f64]) {
        for w in &self.walls {
            let e = w.excess(x);
            if e > 0.0 {
                grad[w.i] += 2.0 * w.weight * w.side * e;
                curvature[w.i] += 2.0 * w.weight;
            }
        }
    }
}

impl Wall {
    /// How far `x` is beyond the inner bound, 0 inside it.
    fn excess(&self, x: &[f64]) -> f64 {
        (self.side * (x[self.i] - self.edge)).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ORIGIN: [f64; 2] = [0.0, 0.0];

    fn range(penalty: f64) -> OperatingRange {
        OperatingRange {
            limits: vec![(-2.0, 2.0), (f64::NEG_INFINITY, f64::INFINITY)],
            penalty,
        }
    }

    #[test]
    fn zero_inside_the_inner_bounds_and_rising_beyond_them() {
        let b = Barrier::of(Some(&range(-40_000.0)), &ORIGIN, 0.99);
        // δ = 0.5: inner bounds ±1.5; w = 40 000 · 0.01 / 0.25 = 1600
        assert_eq!(b.cost(&[1.5, 100.0]), 0.0);
        assert_eq!(b.cost(&[-1.5, -100.0]), 0.0);
        assert!((b.cost(&[2.0, 0.0]) - 1600.0 * 0.25).abs() < 1e-9);
        assert!((b.cost(&[-1.75, 0.0]) - 1600.0 * 0.0625).abs() < 1e-9);
    }

    #[test]
    fn its_derivatives_are_those_of_its_cost() {
        let b = Barrier::of(Some(&range(-40_000.0)), &ORIGIN, 0.99);
        for x in [[1.8, 0.0], [-1.9, 3.0], [0.3, 0.0]] {
            let (mut g, mut h) = ([0.0; 2], [0.0; 2]);
            b.add_derivatives(&x, &mut g, &mut h);
            let eps = 1e-6;
            let numeric = (b.cost(&[x[0] + eps, x[1]]) - b.cost(&[x[0] - eps, x[1]])) / (2.0 * eps);
            assert!(
                (g[0] - numeric).abs() < 1e-3,
                "{x:?}: {} vs {numeric}",
                g[0]
            );
            assert_eq!(g[1], 0.0);
            let want = if x[0].abs() > 1.5 { 3200.0 } else { 0.0 };
            assert!((h[0] - want).abs() < 1e-9, "{x:?}: {}", h[0]);
        }
    }

    #[test]
    fn none_without_a_range_a_penalty_or_room_around_the_reference() {
        assert!(Barrier::of(None, &ORIGIN, 0.99).is_empty());
        assert!(Barrier::of(Some(&range(0.0)), &ORIGIN, 0.99).is_empty());
        let b = Barrier::of(Some(&range(-1.0)), &[2.0, 0.0], 0.99);
        assert_eq!(b.walls.len(), 1, "only the lower bound has room: {b:?}");
        assert_eq!(b.walls[0].side, -1.0);
    }
}
