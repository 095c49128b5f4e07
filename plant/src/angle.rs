//! Angle wrapping.

use std::f64::consts::PI;

/// Wraps an angle to [-π, π).
#[inline]
pub fn wrap(a: f64) -> f64 {
    if (-PI..PI).contains(&a) {
        return a;
    }
    let w = (a + PI).rem_euclid(2.0 * PI) - PI;
    // rem_euclid can return exactly 2π for tiny negative inputs after rounding.
    if w >= PI { w - 2.0 * PI } else { w }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wraps_into_half_open_interval() {
        assert_eq!(wrap(PI), -PI);
        assert_eq!(wrap(-PI), -PI);
        assert!((wrap(3.0 * PI + 0.1) - (-PI + 0.1)).abs() < 1e-12);
        assert!((wrap(-0.5) + 0.5).abs() < 1e-15);
        for i in -1000..1000 {
            let w = wrap(i as f64 * 0.37);
            assert!((-PI..PI).contains(&w));
        }
    }
}
