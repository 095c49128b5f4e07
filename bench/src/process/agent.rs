//! The agent process: state estimates in, actions out; learns as it goes.

use ::plant::Task;
use anyhow::Result;
use wire::{Action, Bus, Estimate, flags, now_ns, topic};

use super::{ProcessArgs, SILENCE, STARTUP, pack, wire_err};

/// Runs the agent side of a run until the plant announces its end.
pub fn run(args: &ProcessArgs) -> Result<()> {
    let cfg = args.config()?;
    let task = Task::new(cfg.system);
    let mut agent = ::agent::build(
        &task,
        &cfg,
        ::agent::seed::run_seed(cfg.run.seed, args.run_index),
    );
    let bus = Bus::join(&args.run_id, "agent").map_err(wire_err)?;
    let estimates = bus.rx::<Estimate>(topic::ESTIMATE).map_err(wire_err)?;
    let out = bus.tx::<Action>(topic::ACTION).map_err(wire_err)?;
    out.wait_for_receivers(args.receivers, STARTUP, &bus)
        .map_err(wire_err)?;
    let m = task.action_dim();
    loop {
        let e = estimates
            .recv(&bus, STARTUP.max(SILENCE))
            .map_err(wire_err)?;
        let t_received_ns = now_ns();
        let f = e.header.flags;
        let x = &e.x[..e.n_x as usize];
        let mut u = vec![0.0; m];
        if f & flags::SHUTDOWN == 0 && !args.trivial {
            if f & flags::GREEDY != 0 {
                if f & flags::END == 0 {
                    agent.greedy(e.header.step as usize, x, &e.u_applied[..m], &mut u);
                }
            } else if f & flags::START != 0 {
                agent.start_trial(x, &mut u);
            } else if f & flags::TERMINAL != 0 {
                agent.learn_terminal(e.reward, x);
            } else if f & flags::END != 0 {
                agent.learn(e.reward, x, None);
            } else {
                agent.learn(e.reward, x, Some(&mut u));
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
            return Ok(());
        }
    }
}
