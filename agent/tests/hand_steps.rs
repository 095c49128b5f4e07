//! One sample of MLAC and RMAC with LLR memories and an infinite horizon (discount
//! `γ ≠ 1`), every updated quantity computed by hand: the temporal difference (Eq. 2.19a
//! with `γ`), the critic's visit and TD update (§3.5.2, "Application to SAC"), MLAC's
//! actor update (Eq. 3.14 with `ũ_k = π(x_k)`, Eq. 3.5), RMAC's reference-model update
//! (Eq. 3.11; the reachable states of §3.4) and its action from the inverted model
//! (§3.5.2, "Application to RMAC"), and the process model's new sample (Algorithm 2
//! line 13, Algorithm 3 line 14).
//!
//! The task has one state `x` (not an angle) and one action `u ∈ [−½, ½]`, reward
//! `ρ = −x² − ½ u²` (Eq. 3.16 with `Q = 1`, `P = ½`), so `∂ρ/∂u = −u`. The memories are
//! filled with known samples first. With `K = 2` neighbours in one input, an LLR
//! prediction is the line through the two nearest samples (`β = Y Xᵀ (X Xᵀ)⁻¹` of two
//! points); the process model's samples (`K = 3`, inputs `[x, u]`, output the increment
//! `x' − x`) near the queries lie on the plane `P(x, u) = 0.1 x + 0.25 u + 0.05`, so its
//! predictions are that plane and `β_u = 0.25`. The LLR fit's ridge (1e-9 per
//! neighbour, keeping the solve well-conditioned) changes these values by less than
//! 1e-7; they are compared to 1e-6.
//!
//! Exploration acts on the first step of a trial only (every second step), so `u_0`
//! carries a random `Δu_0`, read back from the agent, and `u_1 = π(x_1)` exactly.

use agent::Agent;
use agent::actor_critic::{ActorCritic, Improver, Learning, TaskInfo};
use agent::approx::Approximator;
use agent::approx::llr::{Eviction, Llr, LlrParams, Search};
use agent::checkpoint::{CheckpointError, Persist, Reader, Snapshot};
use agent::critic::TdLambda;
use agent::explore::Exploration;
use agent::horizon::Horizon;
use agent::mlac::Mlac;
use agent::model::ProcessModel;
use agent::rmac::Rmac;
use plant::Reward;

const GAMMA: f64 = 0.9;
const LAMBDA: f64 = 0.6;
const ALPHA_C: f64 = 0.4;
const BOUND: f64 = 0.5;
const X0: f64 = 0.3;
const X1: f64 = 0.6;

/// The critic's samples `[x | V]`.
const CRITIC: [(f64, f64); 4] = [(0.0, -1.0), (0.4, -0.52), (0.7, -0.5), (1.2, -0.1)];
/// The process model's samples `[x, u | x' − x]`: three on the plane `P`, one far off it.
const MODEL: [(f64, f64, f64); 4] = [
    (0.2, 0.0, 0.07),
    (0.4, 0.5, 0.215),
    (0.3, -0.5, -0.045),
    (2.0, 0.0, 0.5),
];

/// The plane the process model's near samples lie on: `x' − x = P(x, u)`.
fn plane(x: f64, u: f64) -> f64 {
    0.1 * x + 0.25 * u + 0.05
}

/// The value at `x` of the line through `a` and `b`.
fn line(a: (f64, f64), b: (f64, f64), x: f64) -> f64 {
    a.1 + (b.1 - a.1) / (b.0 - a.0) * (x - a.0)
}

/// The slope of the line through `a` and `b`.
fn slope(a: (f64, f64), b: (f64, f64)) -> f64 {
    (b.1 - a.1) / (b.0 - a.0)
}

#[track_caller]
fn close(got: f64, want: f64, what: &str) {
    assert!((got - want).abs() < 1e-6, "{what}: {got}, by hand {want}");
}

fn llr(inputs: usize, neighbours: usize, bounds: Option<f64>) -> Llr {
    Llr::new(&LlrParams {
        memory: 10,
        neighbours,
        weights: vec![1.0; inputs],
        periodic: vec![false; inputs],
        outputs: 1,
        bounds: bounds.map(|b| (vec![-b], vec![b])),
        eviction: Eviction::Oldest,
        search: Search::KdTree,
        clip_to_neighbours: false,
    })
}

/// An LLR memory holding `samples` `[x | y]`, stored as observations (rate 0: nothing
/// else moves).
fn filled(samples: &[(f64, f64)], bounds: Option<f64>) -> Llr {
    let mut m = llr(1, 2, bounds);
    for &(x, y) in samples {
        m.fit(&[x], &[y], 0.0);
    }
    m
}

fn model() -> ProcessModel {
    let mut m = llr(2, 3, None);
    for (x, u, dx) in MODEL {
        m.fit(&[x, u], &[dx], 0.0);
    }
    ProcessModel::new(Box::new(m), vec![false], 0.0)
}

fn info() -> TaskInfo {
    TaskInfo {
        action_low: vec![-BOUND],
        action_high: vec![BOUND],
        angle_mask: vec![false],
        reward: Reward {
            q: vec![1.0],
            p: vec![0.5],
            reference: vec![0.0],
            terminal: vec![1.0],
            angle_mask: vec![false],
            terms: Vec::new(),
        },
        horizon: Horizon::Infinite,
    }
}

fn agent(improver: Box<dyn Improver>) -> ActorCritic {
    ActorCritic::new(
        info(),
        Learning {
            gamma: GAMMA,
            lambda: LAMBDA,
        },
        Box::new(TdLambda::new(Box::new(filled(&CRITIC, None)), ALPHA_C)),
        improver,
        Exploration::new(0.2, 2, 7),
    )
}

/// One LLR memory of a snapshot: its samples' inputs, outputs and eligibility traces, in
/// the order stored.
#[derive(Debug)]
struct Memory {
    inputs: Vec<f64>,
    outputs: Vec<f64>,
    trace: Vec<f64>,
}

fn memory(r: &mut Reader) -> Result<Memory, CheckpointError> {
    r.scope("llr", |r| {
        let inputs = r.f64s("inputs")?.to_vec();
        let outputs = r.f64s("outputs")?.to_vec();
        r.u64s("seq")?;
        let trace = r.f64s("trace")?.to_vec();
        r.u64s("next_seq")?;
        Ok(Memory {
            inputs,
            outputs,
            trace,
        })
    })
}

/// The critic's memory and the improver's two (actor or reference model, then the
/// process model) of `agent`.
fn memories(agent: &ActorCritic, policy: &'static str) -> (Memory, Memory, Memory) {
    let mut s = Snapshot::default();
    agent.save(&mut s);
    let mut r = s.reader();
    let critic = r.scope("critic", memory).unwrap();
    let (policy, model) = r
        .scope("improver", |r| {
            Ok((r.scope(policy, memory)?, r.scope("model", memory)?))
        })
        .unwrap();
    (critic, policy, model)
}

/// Runs the first sample of a trial from `X0` into `X1`; returns `u_0`, the reward
/// `r_1 = ρ(x_0, u_0)` given and `u_1`.
fn first_sample(agent: &mut ActorCritic) -> (f64, f64, f64) {
    let mut u = [0.0];
    agent.start_trial(&[X0], &mut u);
    let u0 = u[0];
    let r = -X0 * X0 - 0.5 * u0 * u0;
    agent.learn(r, &[X1], Some(&mut u));
    (u0, r, u[0])
}

/// The critic's part of the step, the same for both learners (§3.5.2, "Application to
/// SAC"; Eq. 2.19): `[x_0 | V(x_0)]` is stored with eligibility 1 for it and its nearest
/// neighbour (the critic memory held no traces), `V(x_1)` is read from the memory with
/// it, `δ_0 = r_1 + γ V(x_1) − V(x_0)`, and both traced samples move by `α_c δ_0`.
/// Returns `V(x_0)` (the new sample's value before the update).
fn check_critic(critic: &Memory, r: f64) -> f64 {
    // Neighbours of x_0 = 0.3: 0.4 (distance 0.1) and 0.0 (0.3).
    let v0 = line(CRITIC[1], CRITIC[0], X0);
    // Neighbours of x_1 = 0.6 after the insertion: 0.7 (0.1) and 0.4 (0.2).
    let v1 = line(CRITIC[2], CRITIC[1], X1);
    let td = r + GAMMA * v1 - v0;
    assert_eq!(critic.inputs, [0.0, 0.4, 0.7, 1.2, X0]);
    let want = [
        CRITIC[0].1,
        CRITIC[1].1 + ALPHA_C * td,
        CRITIC[2].1,
        CRITIC[3].1,
        v0 + ALPHA_C * td,
    ];
    for (i, (got, want)) in critic.outputs.iter().zip(want).enumerate() {
        close(*got, want, &format!("critic sample {i}"));
    }
    assert_eq!(critic.trace, [0.0, 1.0, 0.0, 0.0, 1.0]);
    v0
}

/// The process model stores the observed transition `[x_0, u_0 | x_1 − x_0]` (with the
/// applied, explored action); its other samples do not change.
fn check_model(model: &Memory, u0: f64) {
    let mut inputs: Vec<f64> = MODEL.iter().flat_map(|&(x, u, _)| [x, u]).collect();
    inputs.extend([X0, u0]);
    let mut outputs: Vec<f64> = MODEL.iter().map(|s| s.2).collect();
    outputs.push(X1 - X0);
    assert_eq!(model.inputs, inputs);
    for (i, (got, want)) in model.outputs.iter().zip(outputs).enumerate() {
        close(*got, want, &format!("model sample {i}"));
    }
}

/// MLAC/LLR (Algorithm 2, §3.5.2 "Application to MLAC"), infinite horizon.
#[test]
fn mlac_llr_step_by_hand() {
    const ALPHA_A: f64 = 0.3;
    // The actor's samples [x | u].
    const ACTOR: [(f64, f64); 3] = [(0.1, 0.4), (0.6, -0.2), (1.5, 0.45)];
    let actor = filled(&ACTOR, Some(BOUND));
    let mlac = Mlac::new(info(), Box::new(actor), model(), ALPHA_A, GAMMA, 0.0);
    let mut agent = agent(Box::new(mlac));
    let (u0, r, u1) = first_sample(&mut agent);

    // π(x_0): neighbours 0.1 (distance 0.2) and 0.6 (0.3).
    let pi0 = line(ACTOR[0], ACTOR[1], X0);
    close(pi0, 0.16, "π(x_0)");
    assert!(u0 != pi0 && u0.abs() <= BOUND, "u_0 = {u0}: explored");
    // Line 9: u_1 = π(x_1) before the actor update, no exploration: the sample at 0.6
    // and its neighbour 0.1 (1.5 is 0.9 away).
    close(u1, line(ACTOR[1], ACTOR[0], X1), "u_1");

    let (critic, actor, model) = memories(&agent, "actor");
    let v0 = check_critic(&critic, r);

    // Eq. 3.4–3.5: ũ_0 = π(x_0), x̃_1 = f̂(x_0, ũ_0) = x_0 + P(x_0, ũ_0) (model
    // neighbours (0.2, 0) at 0.19, (0.4, 0.5) at 0.35, (0.3, −0.5) at 0.66), ∂f̂/∂u = 0.25.
    let x_tilde = X0 + plane(X0, pi0);
    close(x_tilde, 0.42, "x̃_1");
    // ∂V/∂x at x̃_1 from the critic as the policy improvement reads it — after the visit,
    // before the TD update: neighbours 0.4 (0.02) and the new sample at 0.3 (0.12).
    let dv = slope((X0, v0), CRITIC[1]);
    // Eq. 3.14: the new sample [x_0 | π(x_0)] and its nearest neighbour (0.1) move by
    // α_a {∂ρ/∂u(ũ_0) + γ ∂V/∂x β_u}, ∂ρ/∂u = −2 P ũ_0 = −ũ_0.
    let step = ALPHA_A * (-pi0 + GAMMA * dv * 0.25);
    assert!(step.abs() > 0.01, "step {step}");
    assert_eq!(actor.inputs, [0.1, 0.6, 1.5, X0]);
    let want = [ACTOR[0].1 + step, ACTOR[1].1, ACTOR[2].1, pi0 + step];
    for (i, (got, want)) in actor.outputs.iter().zip(want).enumerate() {
        close(*got, want, &format!("actor sample {i}"));
    }
    check_model(&model, u0);

    // The greedy policy after the step: π(x_0) is now the new sample's action.
    let mut u = [0.0];
    agent.greedy(0, &[X0], &[0.0], &mut u);
    close(u[0], pi0 + step, "π(x_0) after the step");
}

/// RMAC/LLR (Algorithm 3, §3.5.2 "Application to RMAC"), infinite horizon.
///
/// The reference model stores desired increments `x̂ − x` (`agent::rmac`). Eq. 3.11,
/// `η ← η + α_r (x_r − R(x_k)) ∇_η R(x_k)`, with LLR moves the increments of `x_k`'s
/// neighbours towards `x_r − x_k` and stores `[x_k | x_r − x_k]`: in desired states, the
/// neighbour at `x_i` moves towards `x_r + (x_i − x_k)`. §3.5.2 writes the update in
/// desired states, `x̂_i ← x̂_i + α_r (x_r − x̂_i)`, which differs from this by
/// `α_r (x_i − x_k)` for each neighbour (here 0.1 and −0.125).
#[test]
fn rmac_llr_step_by_hand() {
    const ALPHA_R: f64 = 0.5;
    // Inversion ridge of `agent::rmac` on β_uᵀ β_u.
    const RIDGE: f64 = 1e-6;
    // The reference model's samples [x | desired increment].
    const REFERENCE: [(f64, f64); 3] = [(0.05, 0.2), (0.5, 0.1), (1.4, -0.3)];
    let reference = filled(&REFERENCE, None);
    let rmac = Rmac::new(info(), Box::new(reference), model(), ALPHA_R);
    let mut agent = agent(Box::new(rmac));
    let (u0, r, u1) = first_sample(&mut agent);

    // u = u_prev + (β_uᵀβ_u)⁻¹ β_uᵀ (R(x) − P(x, u_prev)), the model linearised around
    // (x, u_prev) (its neighbours there are the plane's three samples), β_u = 0.25.
    let invert = |want: f64, got: f64, u_prev: f64| {
        (u_prev + 0.25 * (want - got) / (0.25 * 0.25 + RIDGE)).clamp(-BOUND, BOUND)
    };
    // π(x_0) with u_prev = 0: R(x_0) from 0.5 (distance 0.2) and 0.05 (0.25).
    let pi0 = invert(line(REFERENCE[0], REFERENCE[1], X0), plane(X0, 0.0), 0.0);
    assert!(pi0.abs() > 0.1 && pi0.abs() < BOUND, "π(x_0) = {pi0}");
    assert!(u0 != pi0 && u0.abs() <= BOUND, "u_0 = {u0}: explored");
    // Line 9–10: u_1 from the reference model before its update, around u_0: R(x_1) from
    // 0.5 (0.1) and 0.05 (0.55).
    let want1 = line(REFERENCE[0], REFERENCE[1], X1);
    close(u1, invert(want1, plane(X1, u0), u0), "u_1");

    let (critic, reference, model) = memories(&agent, "reference");
    let v0 = check_critic(&critic, r);

    // Line 11: the reachable states from x_0 under the extreme actions ∓½ are
    // x_0 + P(x_0, ∓½) = 0.255 and 0.505; their values (the critic after the visit,
    // before the TD update): 0.255 from 0.3 (new) and 0.4, on the line through them;
    // 0.505 from 0.4 and 0.7. The better is x_r.
    let reach = [X0 + plane(X0, -BOUND), X0 + plane(X0, BOUND)];
    let values = [
        line((X0, v0), CRITIC[1], reach[0]),
        line(CRITIC[1], CRITIC[2], reach[1]),
    ];
    assert!(values[1] > values[0], "{values:?}");
    let target = reach[1] - X0;
    close(target, 0.205, "x_r − x_0");
    // Eq. 3.11: the neighbours of x_0 (0.5 at 0.2, 0.05 at 0.25) move towards the target
    // increment by α_r; [x_0 | x_r − x_0] is stored.
    assert_eq!(reference.inputs, [0.05, 0.5, 1.4, X0]);
    let want = [
        REFERENCE[0].1 + ALPHA_R * (target - REFERENCE[0].1),
        REFERENCE[1].1 + ALPHA_R * (target - REFERENCE[1].1),
        REFERENCE[2].1,
        target,
    ];
    for (i, (got, want)) in reference.outputs.iter().zip(want).enumerate() {
        close(*got, want, &format!("reference sample {i}"));
    }
    check_model(&model, u0);
}
