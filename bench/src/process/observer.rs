//! The observer process: measurements in, state estimates out.
//!
//! It sees the plant's sensor output only (`Measurement.y`; with an encoder the
//! velocities are NaN — not measured), never the ground truth, and runs the observer
//! the configuration asks for ([`::observer::build`], as the in-process driver does).

use std::sync::Arc;

use ::observer::Observer;
use ::plant::Task;
use anyhow::Result;
use wire::{Bus, Estimate, Measurement, flags, now_ns, topic};

use super::{ProcessArgs, SILENCE, STARTUP, pack, wire_err};

/// Runs the observer side of a run until the plant announces its end.
pub fn run(args: &ProcessArgs) -> Result<()> {
    super::set_rt_priority(args.rt_priority)?;
    let cfg = args.config()?;
    let task = Arc::new(Task::new(cfg.system));
    let mut observer: Box<dyn Observer> =
        ::observer::build(task, &cfg.observer, cfg.model.as_ref());
    let bus = Bus::join(&args.run_id, "observer").map_err(wire_err)?;
    let measurements = bus
        .rx::<Measurement>(topic::MEASUREMENT)
        .map_err(wire_err)?;
    let out = bus.tx::<Estimate>(topic::ESTIMATE).map_err(wire_err)?;
    out.wait_for_receivers(args.receivers, STARTUP, &bus)
        .map_err(wire_err)?;
    loop {
        let m = measurements
            .recv(&bus, STARTUP.max(SILENCE))
            .map_err(wire_err)?;
        let t_received_ns = now_ns();
        let (n, nu) = (m.n_x as usize, m.n_u as usize);
        let x: Vec<f64> = if m.header.flags & flags::SHUTDOWN != 0 {
            Vec::new()
        } else if m.header.flags & flags::START != 0 {
            observer.reset(&m.y[..n]);
            m.y[..n].to_vec()
        } else {
            observer.update(&m.y[..n], &m.u_applied[..nu]).to_vec()
        };
        let e = Estimate {
            header: m.header,
            n_x: m.n_x,
            n_u: m.n_u,
            reward: m.reward,
            x: pack(&x),
            u_applied: m.u_applied,
            t_sample_ns: m.t_sample_ns,
            t_received_ns,
            t_publish_ns: now_ns(),
        };
        out.send(e).map_err(wire_err)?;
        if m.header.flags & flags::SHUTDOWN != 0 {
            return Ok(());
        }
    }
}
