//! The observer process: measurements in, state estimates out.
//!
//! It sees the plant's sensor output only (`Measurement.y`; with an encoder the
//! velocities are NaN — not measured), never the ground truth, and runs the observer
//! the configuration asks for ([`::observer::build`], as the in-process runner does).

use super::Result;
use ::observer::timing::{Call, Front, Sample};
use wire::{Estimate, Measurement, Monotonic, flags, topic};

use super::{ObserverSettings, SILENCE, STARTUP, pack};

/// The [`flags`] an estimate carries for agent call `call`: the measurement's, plus
/// [`flags::LAST`] / [`flags::HOLD`] where predictive timing makes the agent's trial end
/// before the plant's.
pub fn call_flags(measured: u64, call: Call) -> u64 {
    measured
        | match call {
            Call::Last if measured & flags::END == 0 => flags::LAST,
            Call::Hold => flags::HOLD,
            _ => 0,
        }
}

/// The agent call an estimate's [`flags`] ask for (the inverse of [`call_flags`]); a
/// sample after a gap ([`flags::GAP`]) asks for none.
pub fn call_of(f: u64) -> Call {
    if f & flags::START != 0 {
        Call::Start
    } else if f & (flags::HOLD | flags::GAP) != 0 {
        Call::Hold
    } else if f & flags::TERMINAL != 0 {
        Call::Terminal
    } else if f & (flags::END | flags::LAST) != 0 {
        Call::Last
    } else {
        Call::Learn
    }
}

/// The estimate the observer sends for measurement `m`, the observer's step
/// (`front`) taken unless `m` announces the run's end; its own wall-clock stamps
/// (`t_received_ns`, `t_publish_ns`) are left 0 for the caller. `rig replay` takes the
/// same step over a recording.
pub fn estimate(front: &mut Front, m: &Measurement) -> Estimate {
    let (n, nu) = (m.n_x as usize, m.n_u as usize);
    let f = m.header.flags;
    let mut e = Estimate {
        header: m.header,
        n_x: m.n_x,
        n_u: m.n_u,
        reward: m.reward,
        u_applied: m.u_applied,
        t_sample_ns: m.t_sample_ns,
        ..Estimate::default()
    };
    if f & flags::SHUTDOWN == 0 {
        let t = front.sample(&Sample {
            step: m.header.step as usize,
            start: f & flags::START != 0,
            primed: f & flags::PRIMED != 0,
            end: f & flags::END != 0,
            terminal: f & flags::TERMINAL != 0,
            y: &m.y[..n],
            reward: m.reward,
            u_applied: &m.u_applied[..nu],
            u_next: &m.u_next[..nu],
        });
        e.header.flags = call_flags(f, t.call);
        // After a gap there is no transition, and no reward, to learn.
        e.reward = if f & flags::GAP != 0 { 0.0 } else { t.reward };
        e.x = pack(t.x);
        e.u_applied = pack(t.u_prev);
    }
    e
}

/// Runs the observer side of a run until the plant announces its end.
pub fn run(settings: &ObserverSettings) -> Result<()> {
    let args = &settings.node;
    super::set_rt_priority(args.scheduling.rt_priority)?;
    args.scheduling.place(super::Part::Node)?;
    let cfg = args.experiment()?;
    let task = cfg.task();
    let mut front = crate::build::front(&task, &cfg);
    let bus = args.join("observer")?;
    let measurements = bus.rx::<Measurement>(topic::MEASUREMENT)?;
    let out = bus.tx::<Estimate>(topic::ESTIMATE)?;
    let linger = super::Linger::open(&bus, args.receivers)?;
    out.wait_for_receivers(args.receivers, STARTUP, &bus)?;
    // The time the estimates are stamped on.
    let time = Monotonic::host();
    loop {
        let m = measurements.recv(&bus, STARTUP.max(SILENCE))?;
        let t_received_ns = time.now_ns();
        let f = m.header.flags;
        let mut e = estimate(&mut front, &m);
        e.t_received_ns = t_received_ns;
        e.t_publish_ns = time.now_ns();
        out.send(e)?;
        if f & flags::SHUTDOWN != 0 {
            return linger.wait(&bus);
        }
    }
}
