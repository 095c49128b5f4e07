//! A small dense symmetric-positive-definite solve (Cholesky), used by LLR's
//! least-squares fit (§3.5.2) and RMAC's local model inversion (§3.5.2 "Application to
//! RMAC") on matrices of at most 8 × 8, on the stack, without allocation.

/// Largest system size.
pub const MAX_N: usize = 8;

/// Solves `A X = B` in place for symmetric positive definite `A` (`n × n`, row-major in
/// `a`) and `B` (`n × m`, row-major in `b`, overwritten by `X`). Returns `false` if `A`
/// is not numerically positive definite (then `b` is unspecified).
#[inline(always)]
pub fn cholesky_solve(a: &mut [f64], n: usize, b: &mut [f64], m: usize) -> bool {
    debug_assert!(n <= MAX_N);
    // Factor A = L Lᵀ, L stored in the lower triangle of a.
    for j in 0..n {
        let mut d = a[j * n + j];
        for k in 0..j {
            d -= a[j * n + k] * a[j * n + k];
        }
        if d <= 0.0 || !d.is_finite() {
            return false;
        }
        let d = d.sqrt();
        a[j * n + j] = d;
        for i in j + 1..n {
            let mut s = a[i * n + j];
            for k in 0..j {
                s -= a[i * n + k] * a[j * n + k];
            }
            a[i * n + j] = s / d;
        }
    }
    for c in 0..m {
        // L y = b
        for i in 0..n {
            let mut s = b[i * m + c];
            for k in 0..i {
                s -= a[i * n + k] * b[k * m + c];
            }
            b[i * m + c] = s / a[i * n + i];
        }
        // Lᵀ x = y
        for i in (0..n).rev() {
            let mut s = b[i * m + c];
            for k in i + 1..n {
                s -= a[k * n + i] * b[k * m + c];
            }
            b[i * m + c] = s / a[i * n + i];
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_a_known_system() {
        // A = [[4, 2], [2, 3]], X = [[1, -1], [2, 0.5]] → B = A X = [[8, -3], [8, -0.5]]
        let mut a = [4.0, 2.0, 2.0, 3.0];
        let mut b = [8.0, -3.0, 8.0, -0.5];
        assert!(cholesky_solve(&mut a, 2, &mut b, 2));
        let x = [1.0, -1.0, 2.0, 0.5];
        for i in 0..4 {
            assert!((b[i] - x[i]).abs() < 1e-12);
        }
    }

    #[test]
    fn rejects_indefinite() {
        let mut a = [1.0, 2.0, 2.0, 1.0];
        let mut b = [1.0, 1.0];
        assert!(!cholesky_solve(&mut a, 2, &mut b, 1));
    }
}
