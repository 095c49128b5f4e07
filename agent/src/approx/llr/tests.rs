use super::super::Traced;
use super::super::kdtree::dist2;
use super::*;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub(super) fn params(n: usize, m: usize, memory: usize, k: usize) -> LlrParams {
    LlrParams {
        memory,
        neighbours: k,
        weights: vec![1.0; n],
        periodic: vec![false; n],
        outputs: m,
        bounds: None,
        eviction: Eviction::Oldest,
        search: Search::KdTree,
        clip_to_neighbours: false,
    }
}

fn neighbours(llr: &Llr, x: &[f64]) -> Vec<u32> {
    let mut found = Vec::new();
    llr.nearest(&llr.scale(x), llr.k, &mut found);
    found.iter().map(|c| c.slot).collect()
}

/// The reference: every sample, fully sorted by (distance, newer first).
fn brute_force(llr: &Llr, x: &[f64]) -> Vec<u32> {
    let q = llr.scale(x);
    let mut all: Vec<Candidate> = (0..llr.len as u32)
        .map(|slot| Candidate {
            d2: dist2(llr.coords(slot), &q[..llr.n], &llr.period),
            seq: llr.seq[slot as usize],
            slot,
        })
        .collect();
    all.sort_by(|a, b| a.d2.total_cmp(&b.d2).then(b.seq.cmp(&a.seq)));
    all.iter().take(llr.k).map(|c| c.slot).collect()
}

/// `y = x + 2u`, stored as a process model stores (rate 0). Three samples at `u = 0` surround the query `(0.3, 0)`, one at
/// `u = 2` shares its state. Nearest to `(0.3, 0)` in `(x, u)` are the three at
/// `u = 0`: no slope along `u`. Nearest to `x = 0.3` alone (`lead = 1`) are the
/// samples at `x = 0.3` (both), `0.31` and `0.29`: the exact `∂y/∂u = 2`, `∂y/∂x = 1`.
#[test]
fn near_chooses_the_neighbours_by_the_leading_inputs() {
    let mut llr = Llr::new(&params(2, 1, 10, 4));
    for xu in [
        [0.3, 0.0],
        [0.31, 0.0],
        [0.29, 0.0],
        [0.3, 2.0],
        [0.5, -2.0],
    ] {
        llr.fit(&xu, &[xu[0] + 2.0 * xu[1]], 0.0);
    }
    let mut llr3 = Llr::new(&params(2, 1, 10, 3));
    for xu in [[0.3, 0.0], [0.31, 0.0], [0.29, 0.0], [0.3, 2.0]] {
        llr3.fit(&xu, &[xu[0] + 2.0 * xu[1]], 0.0);
    }
    let (mut y, mut jac) = ([0.0], [0.0; 2]);
    llr3.value_and_jacobian(&[0.3, 0.0], &mut y, &mut jac);
    assert_eq!(jac[1], 0.0, "all three neighbours at u = 0");
    llr.value_and_jacobian_near(&[0.3, 0.0], 1, &mut y, &mut jac);
    // Exact up to the ridge (relative 2·10⁻⁵ on the small spread along x).
    assert!(
        (jac[0] - 1.0).abs() < 1e-4 && (jac[1] - 2.0).abs() < 1e-6,
        "{jac:?}"
    );
    assert!((y[0] - 0.3).abs() < 1e-6);
    // The action of the query moves the prediction along the fit, not the neighbours.
    llr.value_and_jacobian_near(&[0.3, 1.0], 1, &mut y, &mut jac);
    assert!((y[0] - 2.3).abs() < 1e-6 && (jac[1] - 2.0).abs() < 1e-6);
    // With all inputs leading it is the ordinary query.
    let (mut y2, mut jac2) = ([0.0], [0.0; 2]);
    llr.value_and_jacobian_near(&[0.3, 1.0], 2, &mut y, &mut jac);
    llr.value_and_jacobian(&[0.3, 1.0], &mut y2, &mut jac2);
    assert_eq!((y, jac), (y2, jac2));
}

#[test]
fn reproduces_an_affine_function_exactly() {
    let mut llr = Llr::new(&LlrParams {
        weights: vec![1.0, 0.1, 2.0],
        ..params(3, 2, 500, 12)
    });
    let f = |x: &[f64]| {
        [
            1.5 - 2.0 * x[0] + 0.3 * x[1] + 4.0 * x[2],
            -0.5 + x[0] - x[2],
        ]
    };
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    for _ in 0..400 {
        let x = [
            rng.random_range(-3.0..3.0),
            rng.random_range(-20.0..20.0),
            rng.random_range(-1.0..1.0),
        ];
        llr.fit(&x, &f(&x), 0.0);
    }
    for _ in 0..50 {
        let x = [
            rng.random_range(-3.0..3.0),
            rng.random_range(-20.0..20.0),
            rng.random_range(-1.0..1.0),
        ];
        let (mut y, mut jac) = ([0.0; 2], [0.0; 6]);
        llr.value_and_jacobian(&x, &mut y, &mut jac);
        let want = f(&x);
        assert!(
            (y[0] - want[0]).abs() < 1e-6 && (y[1] - want[1]).abs() < 1e-6,
            "{y:?} vs {want:?}"
        );
        let want_jac = [-2.0, 0.3, 4.0, 1.0, 0.0, -1.0];
        for (a, b) in jac.iter().zip(&want_jac) {
            assert!((a - b).abs() < 1e-6, "{jac:?}");
        }
    }
}

#[test]
fn kd_tree_and_scan_match_brute_force() {
    for (n, periodic) in [
        (2, vec![true, false]),
        (3, vec![true, false, false]),
        (6, vec![true, true, false, false, false, false]),
    ] {
        let mut p = params(n, 1, 700, 25);
        p.periodic = periodic;
        p.weights = (0..n).map(|j| 1.0 / (j + 1) as f64).collect();
        let mut tree = Llr::new(&p);
        let mut scan = Llr::new(&LlrParams {
            search: Search::Scan,
            ..p
        });
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let pi = [std::f64::consts::PI; 8];
        for i in 0..1500 {
            let x: Vec<f64> = (0..n).map(|_| rng.random_range(-4.0..4.0)).collect();
            tree.fit(&x, &[i as f64], 0.0);
            scan.fit(&x, &[i as f64], 0.0);
            // Exact duplicates, as learning produces them.
            if i % 5 == 0 {
                tree.fit(&pi[..n], &[0.0], 0.0);
                scan.fit(&pi[..n], &[0.0], 0.0);
            }
        }
        let queries = (0..300).map(|_| {
            (0..n)
                .map(|_| rng.random_range(-4.0..4.0))
                .collect::<Vec<f64>>()
        });
        for x in queries.chain([pi[..n].to_vec()]) {
            let want = brute_force(&tree, &x);
            assert_eq!(neighbours(&tree, &x), want);
            assert_eq!(neighbours(&scan, &x), want);
        }
    }
}

#[test]
fn neighbourhood_after_insertion_equals_a_fresh_search() {
    for eviction in [Eviction::Oldest, Eviction::Redundant(0.3)] {
        let mut p = params(2, 1, 300, 15);
        p.periodic = vec![true, false];
        p.eviction = eviction;
        let mut llr = Llr::new(&p);
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for i in 0..2000 {
            // Coarse coordinates: many exact and near duplicates, full memory.
            let x = [
                (rng.random_range(-6..6) as f64) * 0.5,
                (rng.random_range(-20..20) as f64) * 0.5,
            ];
            let (_, after) = llr.insert_here(&x);
            let after: Vec<u32> = after.iter().map(|c| c.slot).collect();
            assert_eq!(after, brute_force(&llr, &x), "insertion {i}");
        }
    }
}

#[test]
fn remembered_searches_stay_exact_across_insertions() {
    for eviction in [Eviction::Oldest, Eviction::Redundant(0.3)] {
        let mut p = params(2, 1, 200, 10);
        p.periodic = vec![true, false];
        p.eviction = eviction;
        let mut llr = Llr::new(&p);
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let mut point = || {
            [
                (rng.random_range(-6..6) as f64) * 0.5,
                (rng.random_range(-20..20) as f64) * 0.5,
            ]
        };
        let queries: Vec<[f64; 2]> = (0..4).map(|_| point()).collect();
        for i in 0..1500 {
            let q = queries[i % 4];
            // Ask, insert elsewhere, ask again: the second answer comes from the cache.
            let _ = neighbours(&llr, &q);
            let x = point();
            llr.fit(&x, &[0.0], 0.0);
            assert_eq!(neighbours(&llr, &q), brute_force(&llr, &q), "step {i}");
            let (_, after) = llr.insert_here(&q);
            let after: Vec<u32> = after.iter().map(|c| c.slot).collect();
            assert_eq!(after, brute_force(&llr, &q), "step {i}");
        }
    }
}

#[test]
fn clipping_stops_extrapolation_but_keeps_the_slope() {
    let mut p = params(1, 1, 10, 3);
    let mut plain = Llr::new(&p);
    p.clip_to_neighbours = true;
    let mut clipped = Llr::new(&p);
    for x in [0.0, 1.0, 2.0] {
        plain.fit(&[x], &[2.0 * x], 0.0);
        clipped.fit(&[x], &[2.0 * x], 0.0);
    }
    assert!((super::super::scalar(&plain, &[5.0]) - 10.0).abs() < 1e-6);
    assert!((super::super::scalar(&clipped, &[5.0]) - 4.0).abs() < 1e-12);
    assert!(
        (super::super::scalar(&clipped, &[1.5]) - 3.0).abs() < 1e-6,
        "interpolation unchanged"
    );
    let (mut y, mut jac) = ([0.0], [0.0]);
    clipped.value_and_jacobian(&[5.0], &mut y, &mut jac);
    assert!((jac[0] - 2.0).abs() < 1e-6);
}

#[test]
fn angles_wrap_in_the_distance() {
    let mut p = params(1, 1, 10, 1);
    p.periodic = vec![true];
    let mut llr = Llr::new(&p);
    llr.fit(&[3.1], &[1.0], 0.0);
    llr.fit(&[0.0], &[2.0], 0.0);
    assert_eq!(super::super::scalar(&llr, &[-3.1]), 1.0);
}

#[test]
fn repeated_samples_give_finite_predictions() {
    let mut llr = Llr::new(&params(3, 2, 200, 10));
    for i in 0..1000 {
        llr.fit(&[std::f64::consts::PI, 0.0, 3.0], &[i as f64, 1.0], 0.0);
    }
    let (mut y, mut jac) = ([0.0; 2], [0.0; 6]);
    llr.value_and_jacobian(&[std::f64::consts::PI, 0.0, 3.0], &mut y, &mut jac);
    assert!(y.iter().chain(&jac).all(|v| v.is_finite()));
    assert!(
        jac.iter().all(|v| *v == 0.0),
        "no slope from identical inputs"
    );
    // The mean of the 10 newest duplicates.
    assert!((y[0] - (990..1000).map(|i| i as f64).sum::<f64>() / 10.0).abs() < 1e-9);
    // Fewer samples than n + 1 (under-determined): finite, mean-like.
    let mut small = Llr::new(&params(3, 1, 200, 10));
    small.fit(&[0.0, 0.0, 0.0], &[1.0], 0.0);
    small.fit(&[1.0, 0.0, 0.0], &[3.0], 0.0);
    let v = super::super::scalar(&small, &[0.5, 0.0, 0.0]);
    assert!((v - 2.0).abs() < 1e-6, "{v}");
}

#[test]
fn oldest_sample_is_purged() {
    let mut llr = Llr::new(&params(1, 1, 3, 1));
    for i in 0..5 {
        llr.fit(&[i as f64], &[i as f64], 0.0);
    }
    assert_eq!(llr.len(), 3);
    let mut xs: Vec<f64> = llr.samples().map(|(x, _)| x[0]).collect();
    xs.sort_by(f64::total_cmp);
    assert_eq!(xs, vec![2.0, 3.0, 4.0]);
}

#[test]
fn redundant_sample_replaces_its_twin() {
    let mut p = params(1, 1, 3, 1);
    p.eviction = Eviction::Redundant(0.01);
    let mut llr = Llr::new(&p);
    llr.fit(&[0.0], &[0.0], 0.0);
    llr.fit(&[1.0], &[1.0], 0.0);
    llr.fit(&[2.0], &[2.0], 0.0);
    llr.fit(&[0.001], &[5.0], 0.0); // replaces the sample at 0, not the oldest
    let mut xs: Vec<(f64, f64)> = llr.samples().map(|(x, y)| (x[0], y[0])).collect();
    xs.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert_eq!(xs, vec![(0.001, 5.0), (1.0, 1.0), (2.0, 2.0)]);
}

#[test]
fn output_bounds_saturate_the_memory() {
    let mut p = params(1, 1, 10, 3);
    p.bounds = Some((vec![-3.0], vec![3.0]));
    let mut llr = Llr::new(&p);
    llr.fit(&[0.0], &[1.0], 0.0);
    for _ in 0..10 {
        llr.shift(&[0.0], &[2.0]);
    }
    assert!(llr.samples().all(|(_, y)| y[0] <= 3.0));
    assert_eq!(super::super::scalar(&llr, &[0.0]), 3.0);
}

#[test]
fn traces_follow_replacing_eligibility() {
    let mut llr = Llr::new(&params(1, 1, 10, 1));
    llr.visit(&[0.0], 0.5); // sample A, trace 1
    llr.visit(&[10.0], 0.5); // A decays to 0.5, sample B trace 1
    llr.apply_td(2.0);
    let mut ys: Vec<(f64, f64)> = llr.samples().map(|(x, y)| (x[0], y[0])).collect();
    ys.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert_eq!(ys, vec![(0.0, 1.0), (10.0, 2.0)]);
    llr.clear_traces();
    llr.apply_td(2.0);
    assert!(llr.samples().all(|(_, y)| y[0] <= 2.0));
}
