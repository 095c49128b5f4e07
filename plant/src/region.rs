//! Regions of the state space: a box or a ball, which a task's goals are
//! (`[reward.goal]`, a bonus per sample inside; `[goal]`, reaching it ends the trial).
//!
//! An angle's extent is taken on the circle: its offset from the box's middle or the
//! ball's centre is wrapped to [−π, π) before it is compared, so a region around the
//! upright pendulum at `±π` is one region, not two. A component without a bound — an
//! infinite box side, an infinite ball radius — does not count.

use crate::angle::wrap;

/// A box or a ball in the state space (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub enum Region {
    /// `low[i] ≤ x_i ≤ high[i]` for every component (angles on the circle).
    Box {
        /// Lower bounds (`-inf`: none).
        low: Vec<f64>,
        /// Upper bounds (`inf`: none).
        high: Vec<f64>,
    },
    /// `Σ_i ((x_i − centre_i) / radius_i)² ≤ 1` over the components of finite radius
    /// (angles' offsets wrapped): an ellipsoid, a ball in the state scaled by the radii.
    Ball {
        /// The centre.
        centre: Vec<f64>,
        /// The radius along each component (`inf`: that component does not count).
        radius: Vec<f64>,
    },
}

impl Region {
    /// Whether `x` lies inside (a non-finite component lies outside); `angles` marks the
    /// angle components.
    pub fn contains(&self, x: &[f64], angles: &[bool]) -> bool {
        if x.iter().any(|v| !v.is_finite()) {
            return false;
        }
        let offset = |i: usize, from: f64| {
            let d = x[i] - from;
            if angles[i] { wrap(d) } else { d }
        };
        match self {
            Region::Box { low, high } => (0..x.len()).all(|i| {
                let (lo, hi) = (low[i], high[i]);
                if !(lo.is_finite() && hi.is_finite() && angles[i]) {
                    return (lo..=hi).contains(&x[i]);
                }
                // On the circle: the offset from the middle within the half-width.
                let half = 0.5 * (hi - lo);
                half >= std::f64::consts::PI || offset(i, lo + half).abs() <= half
            }),
            Region::Ball { centre, radius } => {
                let s: f64 = (0..x.len())
                    .filter(|&i| radius[i].is_finite())
                    .map(|i| (offset(i, centre[i]) / radius[i]).powi(2))
                    .sum();
                s <= 1.0
            }
        }
    }

    /// Appends the region's canonical bytes to `b` (the task's hash): a kind byte, 0 for
    /// a box and 1 for a ball, then per component `low, high` or `centre, radius` as
    /// little-endian `f64`.
    pub fn digest(&self, b: &mut Vec<u8>) {
        let (kind, first, second) = match self {
            Region::Box { low, high } => (0u8, low, high),
            Region::Ball { centre, radius } => (1u8, centre, radius),
        };
        crate::task::digest::kind_and_pairs(b, kind, first, second);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn a_box_around_an_angle_wraps_and_unbounded_sides_do_not_count() {
        let upright = Region::Box {
            low: vec![PI - 0.2, f64::NEG_INFINITY],
            high: vec![PI + 0.2, 1.0],
        };
        let angles = [true, false];
        assert!(upright.contains(&[-PI + 0.1, -50.0], &angles));
        assert!(upright.contains(&[PI - 0.1, 1.0], &angles));
        assert!(!upright.contains(&[PI - 0.3, 0.0], &angles));
        assert!(!upright.contains(&[PI, 1.5], &angles));
        assert!(!upright.contains(&[PI, f64::NAN], &angles));
        // Not an angle: the bounds as they are.
        assert!(!upright.contains(&[-PI + 0.1, 0.0], &[false, false]));
    }

    #[test]
    fn a_ball_is_scaled_by_its_radii_and_infinite_radii_do_not_count() {
        let ball = Region::Ball {
            centre: vec![0.0, 0.0, 5.0],
            radius: vec![0.5, 2.0, f64::INFINITY],
        };
        let angles = [true, false, false];
        assert!(ball.contains(&[0.3, 1.0, -100.0], &angles)); // 0.36 + 0.25
        assert!(!ball.contains(&[0.4, 1.5, 5.0], &angles)); // 0.64 + 0.5625
        assert!(
            ball.contains(&[2.0 * PI - 0.1, 0.0, 0.0], &angles),
            "wrapped"
        );
    }
}
