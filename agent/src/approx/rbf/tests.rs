use super::super::Differentiable;
use super::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::PI;

fn pendulum_rbf(outputs: usize) -> Rbf {
    let mut rbf = Rbf::new(&RbfParams {
        centres: vec![15, 10],
        range: vec![(-PI, PI), (-8.0 * PI, 8.0 * PI)],
        periodic: vec![true, false],
        intersection: 0.7,
        outputs,
        initial: 0.0,
        bounds: None,
    });
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for t in &mut rbf.theta {
        *t = rng.random_range(-10.0..10.0);
    }
    rbf
}

#[test]
fn features_are_normalised() {
    let rbf = pendulum_rbf(1);
    let mut sum = 0.0;
    rbf.features(&[0.3, -4.0], |_, phi, _| sum += phi);
    assert!((sum - 1.0).abs() < 1e-12);
}

/// The traversal visits every basis function once, in grid order (last axis
/// fastest), with `φᵢ = Π_j exp(−½ d_j² / b_j) / Σ` computed directly from the centres.
#[test]
fn features_in_grid_order() {
    let counts = [3usize, 4, 2];
    let rbf = Rbf::new(&RbfParams {
        centres: counts.to_vec(),
        range: vec![(-PI, PI), (-2.0, 2.0), (0.0, 1.0)],
        periodic: vec![true, false, false],
        intersection: 0.6,
        outputs: 1,
        initial: 0.0,
        bounds: None,
    });
    let x = [2.9, -0.7, 0.2];
    let gauss = |j: usize, c: f64| {
        let mut d = x[j] - c;
        if rbf.period[j] > 0.0 {
            d -= rbf.period[j] * (d / rbf.period[j]).round();
        }
        (-0.5 * d * d * rbf.inv_b[j]).exp()
    };
    let raw = |idx: &[usize]| -> f64 { (0..3).map(|j| gauss(j, rbf.centres[j][idx[j]])).product() };
    let mut all = Vec::new();
    for a in 0..counts[0] {
        for b in 0..counts[1] {
            for c in 0..counts[2] {
                all.push(raw(&[a, b, c]));
            }
        }
    }
    let sum: f64 = all.iter().sum();
    let mut seen = 0;
    rbf.features(&x, |i, phi, idx| {
        assert_eq!(i, seen);
        assert_eq!(i, (idx[0] * counts[1] + idx[1]) * counts[2] + idx[2]);
        assert!((phi - all[i] / sum).abs() < 1e-15, "φ_{i}: {phi}");
        seen += 1;
    });
    assert_eq!(seen, 24);
}

#[test]
fn gradient_equals_finite_difference() {
    let rbf = pendulum_rbf(2);
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    for _ in 0..100 {
        let x = [rng.random_range(-PI..PI), rng.random_range(-30.0..30.0)];
        let (mut y, mut jac) = ([0.0; 2], [0.0; 4]);
        rbf.value_and_jacobian(&x, &mut y, &mut jac);
        let mut y0 = [0.0; 2];
        rbf.value(&x, &mut y0);
        assert_eq!(y, y0);
        for j in 0..2 {
            let h = 1e-6 * (1.0 + x[j].abs());
            let (mut a, mut b) = (x, x);
            a[j] += h;
            b[j] -= h;
            let (mut ya, mut yb) = ([0.0; 2], [0.0; 2]);
            rbf.value(&a, &mut ya);
            rbf.value(&b, &mut yb);
            for o in 0..2 {
                let fd = (ya[o] - yb[o]) / (2.0 * h);
                let an = jac[o * 2 + j];
                assert!(
                    (fd - an).abs() < 1e-5 * (1.0 + an.abs()),
                    "∂y{o}/∂x{j}: fd {fd} analytic {an}"
                );
            }
        }
    }
}

/// More outputs than the local sums hold (`MAX_OUT`; SARSA's Q on the arm has nine):
/// the same sums, in the same order, as from the basis functions; the Jacobian by
/// finite differences.
#[test]
fn more_outputs_than_max_out() {
    let m = MAX_OUT + 1;
    let rbf = pendulum_rbf(m);
    let x = [0.4, -3.0];
    let mut phi = vec![0.0; rbf.len()];
    rbf.basis(&x, &mut phi);
    let mut want = vec![0.0; m];
    for (i, p) in phi.iter().enumerate() {
        for o in 0..m {
            want[o] += rbf.theta[i * m + o] * p;
        }
    }
    let (mut y, mut y2, mut jac) = (vec![0.0; m], vec![0.0; m], vec![0.0; 2 * m]);
    rbf.value(&x, &mut y);
    assert_eq!(y, want);
    rbf.value_and_jacobian(&x, &mut y2, &mut jac);
    assert_eq!(y2, want);
    let h = 1e-6;
    let (mut ya, mut yb) = (vec![0.0; m], vec![0.0; m]);
    rbf.value(&[x[0], x[1] + h], &mut ya);
    rbf.value(&[x[0], x[1] - h], &mut yb);
    for o in 0..m {
        let fd = (ya[o] - yb[o]) / (2.0 * h);
        assert!(
            (fd - jac[o * 2 + 1]).abs() < 1e-5 * (1.0 + fd.abs()),
            "output {o}"
        );
    }
}

/// The fixed-shape sums equal the general ones bit for bit, for every fixed shape.
#[test]
fn fixed_shapes_equal_the_general_sums() {
    let mut rng = ChaCha8Rng::seed_from_u64(9);
    for (m, n) in [(1, 2), (1, 3), (1, 4), (1, 5), (2, 2), (2, 3), (4, 6)] {
        let mut rbf = Rbf::new(&RbfParams {
            centres: vec![4; n],
            range: vec![(-2.0, 2.0); n],
            periodic: (0..n).map(|j| j == 0).collect(),
            intersection: 0.6,
            outputs: m,
            initial: 0.0,
            bounds: None,
        });
        for t in &mut rbf.theta {
            *t = rng.random_range(-5.0..5.0);
        }
        let x: Vec<f64> = (0..n).map(|_| rng.random_range(-2.5..2.5)).collect();
        let (mut y, mut jac) = (vec![0.0; m], vec![0.0; m * n]);
        rbf.value_and_jacobian(&x, &mut y, &mut jac);
        let mut axes = rbf.axes(&x);
        axes.centre_r();
        let (mut y2, mut jac2) = (vec![0.0; m], vec![0.0; m * n]);
        rbf.sums(&axes, &mut y2, &mut jac2);
        assert_eq!((y, jac), (y2, jac2), "shape ({m}, {n})");
    }
}

#[test]
fn continuous_across_the_angle_wrap() {
    let rbf = pendulum_rbf(1);
    let (mut a, mut b) = ([0.0], [0.0]);
    rbf.value(&[PI - 1e-9, 2.0], &mut a);
    rbf.value(&[-PI + 1e-9, 2.0], &mut b);
    assert!((a[0] - b[0]).abs() < 1e-6);
}

#[test]
fn intersection_sets_the_width() {
    let rbf = Rbf::new(&RbfParams {
        centres: vec![5],
        range: vec![(0.0, 4.0)],
        periodic: vec![false],
        intersection: 0.5,
        outputs: 1,
        initial: 0.0,
        bounds: None,
    });
    // Midway between centres 1 and 2 the non-normalised Gaussians are both 0.5.
    let axes = rbf.axes(&[1.5]);
    assert!((axes.g(0)[1] - 0.5).abs() < 1e-12 && (axes.g(0)[2] - 0.5).abs() < 1e-12);
}

#[test]
fn shift_stops_at_the_output_bounds() {
    let mut rbf = Rbf::new(&RbfParams {
        centres: vec![15, 10],
        range: vec![(-PI, PI), (-8.0 * PI, 8.0 * PI)],
        periodic: vec![true, false],
        intersection: 0.9,
        outputs: 1,
        initial: 0.0,
        bounds: Some((vec![-3.0], vec![3.0])),
    });
    let x = [0.5, 1.0];
    let raw = |rbf: &mut Rbf| {
        let bounds = rbf.bounds.take();
        let v = super::super::scalar(&*rbf, &x);
        rbf.bounds = bounds;
        v
    };
    // Pushing outwards approaches the bound but never crosses it...
    for _ in 0..2000 {
        rbf.shift(&x, &[-2.0]);
        assert!(raw(&mut rbf) >= -3.0 - 1e-12);
    }
    assert!(raw(&mut rbf) < -3.0 + 1e-6);
    // ...so a step back in takes effect at once.
    rbf.shift(&x, &[1.0]);
    assert!(super::super::scalar(&rbf, &x) > -3.0 + 0.01);
}

#[test]
fn fit_converges_to_a_constant_target() {
    let mut rbf = pendulum_rbf(1);
    for _ in 0..200 {
        rbf.fit(&[1.0, 2.0], &[5.0], 0.5);
    }
    assert!((super::super::scalar(&rbf, &[1.0, 2.0]) - 5.0).abs() < 1e-3);
}
