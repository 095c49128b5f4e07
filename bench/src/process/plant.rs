//! The plant process: the simulated system ([`plant::Plant`]), clock and episode master.

use std::sync::Arc;

use ::plant::{Plant, Task};
use anyhow::{Result, bail};
use wire::{Action, Bus, Header, Measurement, flags, now_ns, topic};

use super::{ProcessArgs, SILENCE, STARTUP, pack, wire_err};

/// Runs the plant side of a run: every trial of the configuration, greedy evaluation
/// trials where due, then announces the end of the run.
pub fn run(args: &ProcessArgs) -> Result<()> {
    let cfg = args.config()?;
    let task = Arc::new(Task::new(cfg.system));
    let bus = Bus::join(&args.run_id, "plant").map_err(wire_err)?;
    let actions = bus.rx::<Action>(topic::ACTION).map_err(wire_err)?;
    let out = bus
        .tx::<Measurement>(topic::MEASUREMENT)
        .map_err(wire_err)?;
    out.wait_for_receivers(args.receivers, STARTUP, &bus)
        .map_err(wire_err)?;
    let mut p = PlantLoop {
        plant: Plant::new(task.clone()),
        task,
        bus,
        out,
        actions,
        seq: 0,
        latencies: Vec::new(),
    };
    let eval_every = cfg.run.eval_every;
    for trial in 1..=u64::from(cfg.run.trials) {
        let x0 = p.start_state(trial);
        let t_sim = (trial - 1) as f64 * p.task.trial_seconds;
        p.trial(trial, &x0, 0, t_sim)?;
        if eval_every > 0 && trial.is_multiple_of(u64::from(eval_every)) {
            p.trial(
                trial,
                &x0,
                flags::GREEDY,
                trial as f64 * p.task.trial_seconds,
            )?;
        }
    }
    let header = Header {
        seq: p.seq,
        flags: flags::SHUTDOWN,
        ..Header::default()
    };
    p.out
        .send(Measurement {
            header,
            ..Measurement::default()
        })
        .map_err(wire_err)?;
    if let Some(path) = &args.latency_out {
        let text: String = p.latencies.iter().map(|ns| format!("{ns}\n")).collect();
        std::fs::write(path, text).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    }
    Ok(())
}

struct PlantLoop {
    task: Arc<Task>,
    plant: Plant,
    bus: Bus,
    out: wire::Tx<Measurement>,
    actions: wire::Rx<Action>,
    seq: u64,
    /// Publish-to-action time of every sample \[ns\].
    latencies: Vec<u64>,
}

impl PlantLoop {
    fn start_state(&self, trial: u64) -> Vec<f64> {
        let s = &self.task.initial_states;
        s[(trial as usize - 1) % s.len()].clone()
    }

    /// Publishes the current sample and waits for the action that answers it.
    fn exchange(&mut self, header: Header, reward: f64) -> Result<Vec<f64>> {
        let t_sample_ns = now_ns();
        let m = Measurement {
            header,
            n_x: self.task.state_dim() as u64,
            n_u: self.task.action_dim() as u64,
            reward,
            y: pack(self.plant.state()),
            u_applied: pack(self.plant.applied_action()),
            t_sample_ns,
            t_publish_ns: now_ns(),
        };
        self.out.send(m).map_err(wire_err)?;
        let a = self.actions.recv(&self.bus, SILENCE).map_err(wire_err)?;
        self.latencies.push(now_ns() - m.t_publish_ns);
        if a.header.seq != header.seq {
            bail!(
                "action for sample {} arrived while waiting for sample {}",
                a.header.seq,
                header.seq
            );
        }
        self.seq += 1;
        Ok(a.u[..self.task.action_dim()].to_vec())
    }

    /// One trial from `x0`; `mode` is 0 (learning) or [`flags::GREEDY`].
    fn trial(&mut self, trial: u64, x0: &[f64], mode: u64, t0: f64) -> Result<()> {
        let steps = self.task.steps_per_trial();
        self.plant.reset(x0);
        let ts = self.task.ts;
        let header = |seq, step: usize, f| Header {
            seq,
            trial,
            step: step as u64,
            flags: f | mode,
            t_sim: t0 + step as f64 * ts,
        };
        let mut u = self.exchange(header(self.seq, 0, flags::START), 0.0)?;
        for k in 0..steps {
            let r = self.plant.step(&u);
            let last = if k + 1 == steps { flags::END } else { 0 };
            u = self.exchange(header(self.seq, k + 1, last), r)?;
        }
        Ok(())
    }
}
