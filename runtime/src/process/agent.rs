//! The agent process: state estimates in, actions out; learns as it goes.

use ::agent::checkpoint::{Checkpoint, Origin, Snapshot};
use ::agent::config::ObserverMode;
use ::observer::timing::{Call, ToAgent, act};
use ::plant::Task;
use anyhow::{Result, anyhow, bail};
use wire::{Action, Bus, Estimate, flags, now_ns, topic};

use super::{AgentArgs, SILENCE, STARTUP, pack, wire_err};
use crate::resume::CheckpointWriter;

/// Runs the agent side of a run until the plant announces its end.
pub fn run(args: &AgentArgs) -> Result<()> {
    let node = &args.node;
    super::set_rt_priority(node.scheduling.rt_priority)?;
    if node.scheduling.pin_cpus {
        super::pin(super::Cpus::Rest)?;
    }
    let cfg = node.config()?;
    let task = Task::new(cfg.system);
    let mut agent = ::agent::build(
        &task,
        &cfg,
        ::agent::seed::run_seed(cfg.run.seed, node.run_index),
    );
    let origin = Origin::of(&cfg, node.run_index);
    // The first learning trial this process runs.
    let mut expect_trial = 1;
    if let Some(path) = &args.resume {
        let c = Checkpoint::read(path).map_err(|e| anyhow!("{e}"))?;
        c.restore(&cfg, node.run_index, agent.as_mut())
            .map_err(|e| anyhow!("{}: {e}", path.display()))?;
        expect_trial = u64::from(c.trial) + 1;
    }
    let mut checkpoints = args
        .checkpoints
        .as_deref()
        .map(CheckpointWriter::new)
        .transpose()?;
    let bus = Bus::join(&node.run_id, "agent").map_err(wire_err)?;
    let estimates = bus.rx::<Estimate>(topic::ESTIMATE).map_err(wire_err)?;
    let out = bus.tx::<Action>(topic::ACTION).map_err(wire_err)?;
    out.wait_for_receivers(node.receivers, STARTUP, &bus)
        .map_err(wire_err)?;
    let m = task.action_dim();
    let predictive = cfg.observer.mode == ObserverMode::Predictive;
    loop {
        let e = estimates
            .recv(&bus, STARTUP.max(SILENCE))
            .map_err(wire_err)?;
        let t_received_ns = now_ns();
        let f = e.header.flags;
        let x = &e.x[..e.n_x as usize];
        let mut u = vec![0.0; m];
        if f & flags::SHUTDOWN == 0 && !args.trivial {
            let call = super::observer::call_of(f);
            let greedy = f & flags::GREEDY != 0;
            if !greedy && call == Call::Start {
                if e.header.trial != expect_trial {
                    bail!(
                        "the plant started trial {} where trial {expect_trial} was due (a resumed agent continues after its checkpoint's trial)",
                        e.header.trial
                    );
                }
                expect_trial += 1;
            }
            let t = ToAgent {
                call,
                reward: e.reward,
                x,
                u_prev: &e.u_applied[..m],
                // The sample the action applies at: the next in predictive timing (but the
                // answer to the start state, u_0, applies at the start).
                step: e.header.step as usize + usize::from(predictive && call != Call::Start),
            };
            act(agent.as_mut(), greedy, &t, &mut u);
            if !greedy && f & flags::END != 0 {
                // The trial's learning is complete: checkpoint it before acknowledging.
                if let Some(w) = &mut checkpoints {
                    let mut state = Snapshot::default();
                    agent.save(&mut state);
                    w.save(Checkpoint {
                        origin: origin.clone(),
                        trial: e.header.trial as u32,
                        sim_time_s: e.header.t_sim,
                        state,
                    })?;
                }
            }
        }
        let a = Action {
            header: e.header,
            n_u: m as u64,
            u: pack(&u),
            t_sample_ns: e.t_sample_ns,
            t_received_ns,
            t_publish_ns: now_ns(),
        };
        out.send(a).map_err(wire_err)?;
        if f & flags::SHUTDOWN != 0 {
            if let Some(w) = &mut checkpoints {
                w.finish()?;
            }
            return Ok(());
        }
    }
}
