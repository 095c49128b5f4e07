//! What a run's configuration builds around the agent, the same in process
//! ([`crate::experiment`]) and in the process nodes ([`crate::process`]), so that both
//! measure, estimate and actuate the same numbers: the [`sensor`], the observer in its
//! timing ([`front`]) and the [`actuator`].

use std::sync::Arc;

use observer::config::{ObserverConfig, ObserverMode, SensorKind};
use observer::timing::Front;
use plant::Task;
use plant::delay::Actuator;
use plant::sensor::Sensor;

use crate::config::ExperimentConfig;

/// The sensor `o` asks for on `task`, its noise drawn from the run seed `run_seed`
/// (stream [`plant::sensor::NOISE_STREAM`]) — the same in process and in the plant
/// process of `rig run`, so both measure the same numbers.
pub fn sensor(task: &Task, o: &ObserverConfig, run_seed: u64) -> Sensor {
    match o.sensor {
        SensorKind::Full => Sensor::Full,
        SensorKind::Angle => {
            Sensor::angle(&task.angle_mask, o.counts_per_rev, o.noise_std, run_seed)
        }
    }
}

/// The observer `cfg` asks for on `task`, in the configured timing.
pub fn front(task: &Arc<Task>, cfg: &ExperimentConfig) -> Front {
    let o = cfg.observer();
    Front::new(
        task.clone(),
        observer::build(task.clone(), o, cfg.agent().model.as_ref()),
        o.mode == ObserverMode::Predictive,
    )
}

/// The actuation of run seed `run_seed` of `cfg`: its timing and its delays (a validated
/// configuration's delay file has been read once already).
pub fn actuator(task: &Task, cfg: &ExperimentConfig, run_seed: u64) -> Actuator {
    let delays = cfg
        .run()
        .delays_for_run(task, run_seed)
        .unwrap_or_else(|e| panic!("run.delay_from: {e}"));
    Actuator::new(
        task.action_dim(),
        cfg.observer().mode == ObserverMode::Predictive,
        delays,
    )
}
