//! The plant node's end of the run topics: measurements (and ground truth) out, actions
//! in; the headers of a trial's samples.

use std::sync::Arc;

use crate::process::{NodeError, Result};
use ::plant::Task;
use ::plant::episode::Step;
use ::plant::schedule::Trial;
use ::plant::sensor::Sensor;
use wire::{Action, Bus, Header, Measurement, Monotonic, Truth, flags, topic};

use super::super::pack;

/// The plant process's end of the run topics: measurements out, actions in.
pub(super) struct Link {
    pub(super) task: Arc<Task>,
    pub(super) bus: Bus,
    /// The time the plant's messages are stamped on (the realtime plant's deadlines
    /// too).
    pub(super) time: Monotonic,
    pub(super) out: wire::Tx<Measurement>,
    /// What the plant measures of the true state.
    sensor: Sensor,
    /// The last measurement `y_k`.
    y: Vec<f64>,
    /// Ground truth for the supervisor, when the sensor does not measure the full state.
    truth: Option<wire::Tx<Truth>>,
    pub(super) actions: wire::Rx<Action>,
    /// The next sample's sequence number.
    pub(super) seq: u64,
    /// What the next measurement reports as [`Measurement::u_next`] (NaN: not known).
    pub(super) u_next: Vec<f64>,
    /// What the next measurement reports as [`Measurement::delay_s`].
    pub(super) delay_s: f64,
    /// What the next measurement reports as [`Measurement::t_action_ns`]; 0 again once
    /// published.
    pub(super) t_action_ns: u64,
    /// Publish-to-action time of every sample \[ns\].
    pub(super) latencies: Vec<u64>,
    /// Realtime: per sample `[seq, t_sample_ns, t_woke_ns, t_action_ns]` (see
    /// [`super::CYCLES_HEADER`]).
    pub(super) cycles: Vec<[u64; 4]>,
    /// Deadlines missed so far (realtime, external driver).
    pub(super) misses: u64,
    /// Flags of every message from here on: [`flags::DRIVER_REWARD`] with a driver that
    /// provides the rewards; otherwise [`flags::ESTIMATED_REWARD`] once a driver turned
    /// out to measure positions only.
    pub(super) run_flags: u64,
}

impl Link {
    /// The plant's topics on `bus`: actions in, measurements out — and, when `sensor`
    /// does not measure the full state, ground truth on [`topic::TRUTH`]. The first
    /// sample's sequence number is `first_seq`; its messages are stamped on `time`.
    pub(super) fn join(
        (bus, time): (Bus, Monotonic),
        task: Arc<Task>,
        sensor: Sensor,
        first_seq: u64,
    ) -> Result<Self> {
        let actions = bus.rx::<Action>(topic::ACTION)?;
        let out = bus.tx::<Measurement>(topic::MEASUREMENT)?;
        let truth = match sensor {
            Sensor::Full => None,
            Sensor::Angle(_) => Some(bus.tx::<Truth>(topic::TRUTH)?),
        };
        Ok(Self {
            y: vec![0.0; task.state_dim()],
            sensor,
            truth,
            u_next: vec![f64::NAN; task.action_dim()],
            task,
            bus,
            time,
            out,
            actions,
            seq: first_seq,
            delay_s: 0.0,
            t_action_ns: 0,
            latencies: Vec::new(),
            cycles: Vec::new(),
            misses: 0,
            run_flags: 0,
        })
    }

    /// Publishes a sample of the true state `x`: the ground truth first (if published),
    /// then the sensor's measurement of `x` — at a trial start (and its repetition,
    /// primed, in predictive timing) `x` itself, as in process (the state is known there;
    /// the sensor, and its noise stream, are not used).
    /// Returns when the measurement was published (monotonic ns).
    pub(super) fn publish(
        &mut self,
        header: Header,
        reward: f64,
        x: &[f64],
        u_applied: &[f64],
        t_sample_ns: u64,
    ) -> Result<u64> {
        let n = self.task.state_dim();
        let header = Header {
            flags: header.flags | self.run_flags,
            ..header
        };
        if header.flags & (flags::START | flags::PRIMED) != 0 {
            self.y.copy_from_slice(&x[..n]);
        } else {
            self.sensor.measure(&x[..n], &mut self.y);
        }
        if let Some(truth) = &self.truth {
            truth.send(Truth {
                header,
                n_x: n as u64,
                x: pack(&x[..n]),
                t_sample_ns,
            })?;
        }
        let m = Measurement {
            header,
            n_x: n as u64,
            n_u: self.task.action_dim() as u64,
            reward,
            y: pack(&self.y),
            u_applied: pack(u_applied),
            u_next: pack(&self.u_next),
            delay_s: self.delay_s,
            t_sample_ns,
            t_publish_ns: self.time.now_ns(),
            t_action_ns: match std::mem::take(&mut self.t_action_ns) {
                _ if header.flags & flags::START != 0 => 0,
                t => t,
            },
            deadline_misses: self.misses,
        };
        self.out.send(m)?;
        self.seq += 1;
        Ok(m.t_publish_ns)
    }

    /// From now on the rewards are the observer's, from its estimate: the driver measures
    /// positions only ([`flags::ESTIMATED_REWARD`]). That needs a sensor that leaves the
    /// velocities to the observer (`--sensor angle`).
    pub(super) fn estimate_rewards(&mut self, driver_id: &str) -> Result<()> {
        if matches!(self.sensor, Sensor::Full) {
            return Err(NodeError::PositionsOnly {
                driver: driver_id.to_string(),
            });
        }
        if self.run_flags & flags::DRIVER_REWARD == 0 {
            self.run_flags |= flags::ESTIMATED_REWARD;
        }
        Ok(())
    }

    /// Checks that action `a` answers sample `seq`.
    pub(super) fn check_answer(a: &Action, seq: u64) -> Result<()> {
        if a.header.seq != seq {
            return Err(NodeError::ActionOutOfTurn {
                got: a.header.seq,
                want: seq,
            });
        }
        Ok(())
    }

    /// The end of the run, stamped with the run's final simulated time `t_sim` and the
    /// monotonic time now ([`flags::SHUTDOWN`]).
    pub(super) fn shutdown(&mut self, t_sim: f64) -> Result<()> {
        let header = Header {
            seq: self.seq,
            flags: flags::SHUTDOWN | self.run_flags,
            t_sim,
            ..Header::default()
        };
        let now = self.time.now_ns();
        self.out.send(Measurement {
            header,
            t_sample_ns: now,
            t_publish_ns: now,
            deadline_misses: self.misses,
            ..Measurement::default()
        })?;
        Ok(())
    }
}

/// Headers of one trial's samples.
pub(super) struct TrialHeader {
    trial: u64,
    /// 0 (learning) or [`flags::GREEDY`].
    mode: u64,
    /// Simulated time at the trial's start \[s\].
    t0: f64,
    /// Sample time \[s\].
    ts: f64,
}

impl TrialHeader {
    /// The headers of `trial`'s samples, `ts` apart.
    pub(super) fn new(trial: &Trial, ts: f64) -> Self {
        Self {
            trial: trial.number.into(),
            mode: if trial.greedy { flags::GREEDY } else { 0 },
            t0: trial.t0,
            ts,
        }
    }

    /// The header of sample `step` of the trial, with sequence number `seq`.
    pub(super) fn at(&self, seq: u64, step: usize, flags: u64) -> Header {
        Header {
            seq,
            trial: self.trial,
            step: step as u64,
            flags: flags | self.mode,
            t_sim: self.t0 + step as f64 * self.ts,
        }
    }
}

/// The flags that end a trial after `step`: [`flags::END`] on its last sample,
/// [`flags::END`] | [`flags::TERMINAL`] when the operating range was left.
pub(super) fn end_flags(step: &Step) -> u64 {
    if step.terminated {
        flags::END | flags::TERMINAL
    } else if step.truncated {
        flags::END
    } else {
        0
    }
}
