//! The agent's step of MLAC with its learned-model controllers on the acrobot, sample by
//! sample: the median and the percentiles of `Agent::learn` (learning from the
//! transition and choosing the next action — what the rig times as
//! `/timing/agent/action`), in one process, no transport: its wall-clock time and the
//! CPU time of the thread (which does not count the time others' processes take the
//! processor).
//!
//! * `ilqr` — the swing-up (`examples/acrobot/acrobot.toml`) with
//!   `examples/acrobot/mlac-ilqr.toml`'s settings: MLAC/LLR planning by the iterative LQR
//!   (20 samples, 3 iterations), a process model of 8000 samples, the most redundant
//!   evicted;
//! * `lqr` — the balance (`examples/acrobot/acrobot-balance.toml`) with
//!   `examples/acrobot/mlac-lqr.toml`'s: MLAC/LLR with the regulator of its learned model.
//!
//! The acrobot is simulated here as `examples/acrobot/acrobot.py` simulates it (the same
//! equations, RK4 in steps of 5 ms, the joint speeds clipped), so that the bench needs no
//! driver. The agent learns `--trials` trials untimed, then `--timed` more, each step
//! timed; then one greedy trial. It prints the step's percentiles, the greedy return and
//! a digest of every action the agent chose (FNV-1a of their bits): two builds whose
//! digests agree chose the same actions, bit for bit.
//!
//! ```sh
//! cargo bench -p agent --bench planning_step -- [ilqr|lqr] [--trials N] [--timed N] [--seed S]
//! ```
//!
//! Figures: `docs/results/planning-speed.md`.

use std::path::Path;
use std::time::Instant;

use agent::Agent;
use agent::config::{
    Algo, ApproxKind, Component, EvictionRule, HorizonKind, LqrConfig, PlanningConfig,
    PlanningMethod,
};
use plant::Task;

/// The acrobot of `examples/acrobot/acrobot.py`: Gymnasium Acrobot-v1's links.
mod acrobot {
    use std::f64::consts::PI;

    use plant::angle::wrap;

    const L1: f64 = 1.0;
    const LC: f64 = 0.5;
    const I: f64 = 1.0;
    const G: f64 = 9.8;
    const MAX_VEL: [f64; 2] = [4.0 * PI, 9.0 * PI];
    const H_MAX: f64 = 0.005;

    /// `s' = f(s, τ)` for `s = [q_1, q_2, q_1', q_2']`, `q_1` from hanging (unit masses).
    fn derivative(s: [f64; 4], tau: f64) -> [f64; 4] {
        let [q1, q2, dq1, dq2] = s;
        let d1 = LC * LC + (L1 * L1 + LC * LC + 2.0 * L1 * LC * q2.cos()) + 2.0 * I;
        let d2 = LC * LC + L1 * LC * q2.cos() + I;
        let phi2 = LC * G * (q1 + q2 - PI / 2.0).cos();
        let phi1 = -L1 * LC * dq2 * dq2 * q2.sin() - 2.0 * L1 * LC * dq2 * dq1 * q2.sin()
            + (LC + L1) * G * (q1 - PI / 2.0).cos()
            + phi2;
        let ddq2 = (tau + d2 / d1 * phi1 - L1 * LC * dq1 * dq1 * q2.sin() - phi2)
            / (LC * LC + I - d2 * d2 / d1);
        let ddq1 = -(d2 * ddq2 + phi1) / d1;
        [dq1, dq2, ddq1, ddq2]
    }

    fn rk4(s: [f64; 4], tau: f64, h: f64) -> [f64; 4] {
        let add = |a: [f64; 4], k: [f64; 4], f: f64| std::array::from_fn(|i| a[i] + f * k[i]);
        let k1 = derivative(s, tau);
        let k2 = derivative(add(s, k1, 0.5 * h), tau);
        let k3 = derivative(add(s, k2, 0.5 * h), tau);
        let k4 = derivative(add(s, k3, h), tau);
        std::array::from_fn(|i| s[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
    }

    /// The joint state `[q_1, q_2, q_1', q_2']`.
    pub struct Acrobot(pub [f64; 4]);

    impl Acrobot {
        /// At the task's state `x` (`θ_1` from upright).
        pub fn at(x: &[f64]) -> Self {
            Self([wrap(x[0] + PI), wrap(x[1]), x[2], x[3]])
        }

        /// Holds `tau` for `dt` seconds.
        pub fn step(&mut self, tau: f64, dt: f64) {
            let n = ((dt / H_MAX - 1e-9).ceil() as usize).max(1);
            for _ in 0..n {
                self.0 = rk4(self.0, tau, dt / n as f64);
            }
            for (j, max) in MAX_VEL.iter().enumerate() {
                self.0[2 + j] = self.0[2 + j].clamp(-max, *max);
            }
        }

        /// The task's state.
        pub fn state(&self) -> Vec<f64> {
            let [q1, q2, dq1, dq2] = self.0;
            vec![wrap(q1 - PI), wrap(q2), dq1, dq2]
        }
    }
}

/// Which learner on which task.
#[derive(Clone, Copy, PartialEq)]
enum Case {
    Ilqr,
    Lqr,
}

struct Args {
    case: Case,
    trials: usize,
    timed: usize,
    seed: u64,
}

fn args() -> Args {
    let mut a = Args {
        case: Case::Ilqr,
        trials: 40,
        timed: 10,
        seed: 1,
    };
    let mut it = std::env::args().skip(1);
    let number = |flag: &str, v: Option<String>| -> u64 {
        v.and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("{flag} takes a whole number"))
    };
    while let Some(arg) = it.next() {
        match arg.as_str() {
            "ilqr" => a.case = Case::Ilqr,
            "lqr" => a.case = Case::Lqr,
            "--trials" => a.trials = number("--trials", it.next()) as usize,
            "--timed" => a.timed = number("--timed", it.next()) as usize,
            "--seed" => a.seed = number("--seed", it.next()),
            "--bench" => {}
            "-h" | "--help" => {
                println!(
                    "planning_step [ilqr|lqr] [--trials N (40)] [--timed N (10)] [--seed S (1)]"
                );
                std::process::exit(0);
            }
            other if other.starts_with('-') => {
                panic!("unknown option {other:?}; --help lists them")
            }
            // A filter for the other benches (`cargo bench -p agent -- NAME`), as
            // criterion's: nothing of this bench matches it.
            other => {
                println!("planning_step: no case named {other:?} (ilqr, lqr): nothing run");
                std::process::exit(0);
            }
        }
    }
    a
}

/// The task and the agent of `case`, as `rig run --task … --config …` builds them.
fn setup(case: Case, seed: u64) -> (Task, Box<dyn Agent>) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/acrobot");
    let file = match case {
        Case::Ilqr => "acrobot.toml",
        Case::Lqr => "acrobot-balance.toml",
    };
    let task = Task::from_file(&root.join(file)).expect("the acrobot's task file");
    let mut cfg =
        agent::preset::for_task(&task, Algo::Mlac, ApproxKind::Llr, HorizonKind::Infinite)
            .expect("MLAC/LLR's preset")
            .agent;
    cfg.learning.gamma = 0.99;
    match case {
        Case::Ilqr => {
            cfg.learning.sigma = 2.0;
            cfg.planning = Some(PlanningConfig {
                method: PlanningMethod::Ilqr,
                horizon: 20,
                samples: None,
                elites: None,
                iterations: 3,
                start_from_regulator: false,
            });
            if let Some(Component::Llr(a)) = &mut cfg.actor {
                a.alpha = 0.02;
            }
            if let Component::Llr(c) = &mut cfg.critic {
                c.alpha = 0.15;
            }
            if let Some(Component::Llr(m)) = &mut cfg.model {
                m.memory = 8000;
                m.eviction = EvictionRule::Redundant;
                m.redundancy_radius = 0.02;
            }
        }
        Case::Lqr => cfg.lqr = Some(LqrConfig::default()),
    }
    let learner = cfg.resolve(&task).expect("the configuration resolves");
    let agent = agent::build(&task, &learner, seed);
    (task, agent)
}

/// FNV-1a over the bits of the actions chosen.
struct Digest(u64);

impl Digest {
    fn add(&mut self, u: &[f64]) {
        for v in u {
            for b in v.to_bits().to_le_bytes() {
                self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
            }
        }
    }
}

/// Whether `x` has left the task's operating range.
fn outside(task: &Task, x: &[f64]) -> bool {
    task.operating_range.as_ref().is_some_and(|r| {
        x.iter()
            .zip(&r.limits)
            .any(|(v, (lo, hi))| v < lo || v > hi)
    })
}

/// The CPU time this thread has used, in seconds: what a step costs whatever else the
/// machine runs.
fn thread_cpu_time() -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `t` is a valid timespec for the call to write.
    let ok = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
    assert_eq!(ok, 0, "the thread's CPU clock");
    t.tv_sec as f64 + 1e-9 * t.tv_nsec as f64
}

/// Each timed step's wall-clock and CPU time, in seconds.
#[derive(Default)]
struct Times {
    wall: Vec<f64>,
    cpu: Vec<f64>,
}

/// One learning trial from the `trial`-th start state; the step times go to `times` if
/// given.
fn learn_trial(
    task: &Task,
    agent: &mut dyn Agent,
    trial: usize,
    digest: &mut Digest,
    mut times: Option<&mut Times>,
) {
    let x0 = &task.initial_states[trial % task.initial_states.len()];
    let mut plant = acrobot::Acrobot::at(x0);
    let mut x = x0.clone();
    let mut u = vec![0.0; task.action_dim()];
    agent.start_trial(&x, &mut u);
    digest.add(&u);
    let steps = task.steps_per_trial();
    for k in 0..steps {
        let mut applied = u.clone();
        task.saturate(&u, &mut applied);
        let r = task.reward.reward(&x, &applied);
        plant.step(applied[0], task.ts);
        x = plant.state();
        if outside(task, &x) {
            let penalty = task.operating_range.as_ref().expect("a range").penalty;
            agent.learn_terminal(penalty, &x);
            return;
        }
        let last = k + 1 == steps;
        let (start, cpu) = (Instant::now(), thread_cpu_time());
        agent.learn(r, &x, (!last).then_some(&mut u[..]));
        if let Some(t) = times.as_deref_mut() {
            t.cpu.push(thread_cpu_time() - cpu);
            t.wall.push(start.elapsed().as_secs_f64());
        }
        if !last {
            digest.add(&u);
        }
    }
}

/// The return of a greedy trial from the first start state.
fn greedy_return(task: &Task, agent: &mut dyn Agent, digest: &mut Digest) -> f64 {
    let x0 = &task.initial_states[0];
    let mut plant = acrobot::Acrobot::at(x0);
    let mut x = x0.clone();
    let (mut u, mut u_prev) = (vec![0.0; task.action_dim()], vec![0.0; task.action_dim()]);
    agent.start_greedy_trial();
    let mut total = 0.0;
    for k in 0..task.steps_per_trial() {
        agent.greedy(k, &x, &u_prev, &mut u);
        digest.add(&u);
        let mut applied = u.clone();
        task.saturate(&u, &mut applied);
        total += task.reward.reward(&x, &applied);
        plant.step(applied[0], task.ts);
        x = plant.state();
        if outside(task, &x) {
            return total + task.operating_range.as_ref().expect("a range").penalty;
        }
        u_prev.copy_from_slice(&u);
    }
    total
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted[((p * (sorted.len() - 1) as f64).round() as usize).min(sorted.len() - 1)]
}

fn main() {
    let a = args();
    let (task, mut agent) = setup(a.case, a.seed);
    let mut digest = Digest(0xcbf2_9ce4_8422_2325);
    let begin = Instant::now();
    for trial in 0..a.trials {
        learn_trial(&task, agent.as_mut(), trial, &mut digest, None);
    }
    let untimed = begin.elapsed().as_secs_f64();
    let mut times = Times::default();
    for trial in a.trials..a.trials + a.timed {
        learn_trial(&task, agent.as_mut(), trial, &mut digest, Some(&mut times));
    }
    let ret = greedy_return(&task, agent.as_mut(), &mut digest);
    println!(
        "{} seed {}: {} trials learned in {untimed:.1} s; memories {:?}",
        match a.case {
            Case::Ilqr => "ilqr (acrobot swing-up)",
            Case::Lqr => "lqr (acrobot balance)",
        },
        a.seed,
        a.trials,
        agent.memories()
    );
    for (what, mut t) in [("wall-clock", times.wall), ("CPU", times.cpu)] {
        t.sort_by(f64::total_cmp);
        let ms = |p: f64| 1e3 * percentile(&t, p);
        println!(
            "agent step ({what}) over {} steps of {} trials: median {:.3} ms, p90 {:.3} ms, p99 {:.3} ms, max {:.3} ms",
            t.len(),
            a.timed,
            ms(0.5),
            ms(0.9),
            ms(0.99),
            ms(1.0)
        );
    }
    println!("greedy return {ret:.2}; actions digest {:016x}", digest.0);
}
