//! Speed of the learning core, on this machine, with criterion (medians in
//! `target/criterion/*/new/estimates.json`; `cargo bench -p agent`).
//!
//! * `agent_step/mlac_llr_full` — one MLAC/LLR agent step (`Agent::learn` with the next
//!   action) with the pendulum preset (Table 3.2) and actor and critic memories full
//!   (2000 samples each; asserted before timing). The transitions replayed are recorded
//!   from a learning run, so only the agent is timed, not the plant.
//! * `llr_query/*` — one LLR query (value and Jacobian) plus one insertion, on a full
//!   memory of 2000 samples, K = 25: the dynamic k-d tree against a partial-selection
//!   scan of the whole memory.
//! * `rbf/*` — one evaluation of a scalar normalised RBF network (`value`, and `value`
//!   with the Jacobian) at random inputs: the 20 × 20 grid of the VGBP-LSTD and SARSA
//!   critics (§6.4.1; VGBP's search of Eq. 6.6 makes about 100 `value` calls per step)
//!   and the 9 × 9 × 9 grid of the finite-horizon critics (§4.4).

use std::hint::black_box;
use std::sync::Arc;

use agent::Agent;
use agent::approx::llr::{Eviction, Llr, LlrParams, Search};
use agent::approx::rbf::{Rbf, RbfParams};
use agent::approx::{Approximator, Differentiable};
use agent::config::{Algo, ApproxKind, HorizonKind};
use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use plant::{Plant, Task};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A recorded transition: reward, next state, whether it is a trial's first.
type Recorded = (f64, Vec<f64>, bool);

/// Learns until every actor and critic memory is full; returns the agent and the
/// transitions of the last ten trials.
fn trained_mlac_llr() -> (Box<dyn Agent>, Vec<Recorded>) {
    let system = plant::SystemName::Pendulum;
    let preset = agent::preset::preset(system, Algo::Mlac, ApproxKind::Llr, HorizonKind::Infinite)
        .expect("the default preset");
    let task = Arc::new(Task::new(system));
    let learner = preset.agent.resolve(&task).expect("a preset resolves");
    let mut agent = agent::build(&task, &learner, 1);
    let mut plant = Plant::new(task.clone());
    let steps = task.steps_per_trial();
    let mut record = Vec::new();
    for trial in 0..2000 {
        let full = agent
            .memories()
            .iter()
            .filter(|m| m.0 != "model")
            .all(|m| m.1 == m.2);
        if full && trial % 10 == 0 && record.len() >= 10 * steps {
            break;
        }
        if trial % 10 == 0 {
            record.clear();
        }
        let x0 = task.initial_states[0].clone();
        plant.reset(&x0);
        let mut u = vec![0.0; 1];
        agent.start_trial(&x0, &mut u);
        for k in 0..steps {
            let r = plant.step(&u);
            record.push((r, plant.state().to_vec(), k == 0));
            agent.learn(r, plant.state(), (k + 1 < steps).then_some(&mut u[..]));
        }
    }
    let mems = agent.memories();
    for (name, stored, cap) in &mems {
        if *name != "model" {
            assert_eq!(stored, cap, "{name} memory not full: {mems:?}");
        }
    }
    eprintln!("memories: {mems:?}");
    (agent, record)
}

fn agent_step(c: &mut Criterion) {
    let (mut agent, record) = trained_mlac_llr();
    let x0 = Task::pendulum().initial_states[0].clone();
    let mut u = [0.0];
    let mut i = 0;
    let mut g = c.benchmark_group("agent_step");
    g.bench_function("mlac_llr_full", |b| {
        b.iter(|| {
            let (r, x, start) = &record[i % record.len()];
            if *start {
                agent.start_trial(&x0, &mut u);
            }
            agent.learn(*r, black_box(x), Some(&mut u));
            i += 1;
        })
    });
    g.finish();
}

fn full_memory(search: Search, dim: usize, rng: &mut ChaCha8Rng) -> Llr {
    let mut llr = Llr::new(&LlrParams {
        memory: 2000,
        neighbours: 25,
        weights: [1.0, 0.1, 1.0][..dim].to_vec(),
        periodic: [true, false, false][..dim].to_vec(),
        outputs: dim,
        bounds: None,
        eviction: Eviction::Oldest,
        search,
        clip_to_neighbours: false,
    });
    for _ in 0..2500 {
        let x: Vec<f64> = (0..dim).map(|_| rng.random_range(-9.0..9.0)).collect();
        llr.fit(&x, &vec![1.0; dim], 0.0);
    }
    llr
}

fn llr_query(c: &mut Criterion) {
    let mut g = c.benchmark_group("llr_query");
    for dim in [2usize, 3] {
        for search in [Search::KdTree, Search::Scan] {
            let mut rng = ChaCha8Rng::seed_from_u64(11);
            let mut llr = full_memory(search, dim, &mut rng);
            let name = match search {
                Search::KdTree => "kdtree",
                Search::Scan => "scan",
            };
            let (mut y, mut jac) = (vec![0.0; dim], vec![0.0; dim * dim]);
            g.bench_with_input(
                BenchmarkId::new(name, format!("dim{dim}")),
                &dim,
                |b, &dim| {
                    b.iter(|| {
                        let x: Vec<f64> = (0..dim).map(|_| rng.random_range(-9.0..9.0)).collect();
                        llr.value_and_jacobian(black_box(&x), &mut y, &mut jac);
                        llr.fit(&x, &y.clone(), 0.0);
                    })
                },
            );
        }
    }
    g.finish();
}

fn rbf(c: &mut Criterion) {
    let mut g = c.benchmark_group("rbf");
    for centres in [vec![20usize, 20], vec![9, 9, 9]] {
        let n = centres.len();
        let name = centres
            .iter()
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join("x");
        let mut rbf = Rbf::new(&RbfParams {
            range: vec![(-3.0, 3.0); n],
            periodic: (0..n).map(|j| j == 0).collect(),
            centres,
            intersection: 0.5,
            outputs: 1,
            initial: 0.0,
            bounds: None,
        });
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        for t in rbf.parameters_mut() {
            *t = rng.random_range(-1.0..1.0);
        }
        let inputs: Vec<Vec<f64>> = (0..1024)
            .map(|_| (0..n).map(|_| rng.random_range(-3.5..3.5)).collect())
            .collect();
        let (mut y, mut jac, mut k) = ([0.0], vec![0.0; n], 0usize);
        g.bench_function(BenchmarkId::new("value", &name), |b| {
            b.iter(|| {
                k = (k + 1) % inputs.len();
                rbf.value(black_box(&inputs[k]), &mut y);
                y[0]
            })
        });
        g.bench_function(BenchmarkId::new("value_and_jacobian", &name), |b| {
            b.iter(|| {
                k = (k + 1) % inputs.len();
                rbf.value_and_jacobian(black_box(&inputs[k]), &mut y, &mut jac);
                y[0] + jac[0]
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(50)
        .measurement_time(std::time::Duration::from_secs(4))
        .warm_up_time(std::time::Duration::from_secs(1));
    targets = agent_step, llr_query, rbf
}
criterion_main!(benches);
