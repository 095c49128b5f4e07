//! The run's MCAP recording: one channel per topic, the wall-clock stamps on their
//! own `/timing/...` channels, the trials' returns, the loop's latency and the system's
//! picture; log time simulated (lockstep) or the plant's (realtime).

use std::collections::BTreeMap;
use std::path::Path;

use super::error::{Result, RunError};
use crate::error::AtFile;
use driver::contract::{DriverCommand, DriverSample, LinkSample};
use wire::{Action, Estimate, Header, Measurement, Truth, flags};

use crate::config::ExperimentConfig;
use crate::experiment::TrialRecord;
use crate::record::channels::{self, fields, schema};
use crate::record::scene::{Scene, SceneMaker};
use crate::record::{ChannelId, RecordError, Recorder, Tap, Value};
use crate::resume::ResumePoint;

/// The MCAP recording: one channel per topic, and one `/timing/...` channel per topic
/// for the wall-clock timestamps, which differ from run to run by nature. Log time is
/// simulated time.
pub(super) struct RecordingWriter {
    pub(super) rec: Recorder,
    pub(super) measurement: ChannelId,
    pub(super) estimate: ChannelId,
    pub(super) action: ChannelId,
    /// `/plant/truth`, with a sensor that does not measure the full state.
    pub(super) truth: Option<ChannelId>,
    pub(super) t_measurement: ChannelId,
    pub(super) t_estimate: ChannelId,
    pub(super) t_action: ChannelId,
    /// `/driver/sample`, `/driver/command` and `/driver/link`, with an external driver.
    pub(super) driver: Option<(ChannelId, ChannelId, ChannelId)>,
    pub(super) n: usize,
    pub(super) m: usize,
    pub(super) values: Vec<Value>,
    /// Log time: simulated time (lockstep) or the plant's sample time (realtime).
    pub(super) realtime: bool,
    /// The current sample's plant sample time (monotonic ns).
    pub(super) t_sample_ns: u64,
    /// `/returns`: a row of `returns.csv` per trial ([`Self::trial`]).
    returns: ChannelId,
    /// `/latency`: per action the time from the sample to the action and the agent's
    /// share of it, in µs.
    latency: ChannelId,
    /// `/scene`: the system drawn from each sample's state, when the application draws it.
    scene: Option<Pictures>,
    /// The log time of the last message of the loop recorded.
    pub(super) log_time_ns: u64,
}

/// The system's pictures: their channel, their painter, the picture being encoded.
struct Pictures {
    channel: ChannelId,
    scene: Box<dyn Scene>,
    buf: Vec<u8>,
}

/// The recording's metadata `run`.
fn metadata(about: &About) -> BTreeMap<String, String> {
    let (cfg, task) = (about.cfg, about.task);
    [
        ("run_id", about.run_id.to_string()),
        ("seed", cfg.run().seed.to_string()),
        ("system", cfg.system().to_string()),
        ("task", cfg.task_name()),
        ("algo", cfg.agent().algo.to_string()),
        ("approx", cfg.agent().approx.to_string()),
        ("horizon", cfg.agent().horizon.to_string()),
        ("timing", about.timing.clone()),
        ("rig_version", env!("CARGO_PKG_VERSION").to_string()),
        // What `rig replay` reads: the channels' fields and what the observer and the
        // agent consume (crate::replay::FORMAT).
        ("recording_format", crate::replay::FORMAT.to_string()),
        // The reward's weights, so that a reader can recompute a finite horizon's
        // terminal reward τ_N(x_N) = −eᵀQ_N e (Eq. 4.1; tests/python/check_mcap.py).
        ("reward_q", join(&task.reward.q)),
        ("reward_terminal", join(&task.reward.terminal)),
        ("reward_reference", join(&task.reward.reference)),
        (
            "reward_angles",
            join(task.reward.angle_mask.iter().map(|&a| u8::from(a))),
        ),
        (
            "resumed_after_trial",
            about.point.map_or("-".to_string(), |p| p.trial.to_string()),
        ),
    ]
    .into_iter()
    .chain(
        about
            .driver_reward
            .then(|| ("reward_from", "driver".to_string())),
    )
    .map(|(k, v)| (k.to_string(), v))
    .collect()
}

/// `a,b,c`: values in Rust's shortest round-trip form, which a reader parses exactly.
pub(super) fn join<T: std::fmt::Display>(values: impl IntoIterator<Item = T>) -> String {
    values
        .into_iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

/// What a run's recording describes beside its messages.
pub(super) struct About<'a> {
    pub(super) cfg: &'a ExperimentConfig,
    pub(super) task: &'a plant::Task,
    pub(super) run_id: &'a str,
    /// Lockstep, realtime or the external driver's clock, in words.
    pub(super) timing: String,
    /// Log times are the plant's sample times (realtime or an external driver).
    pub(super) realtime: bool,
    /// An external driver's traffic is recorded too.
    pub(super) driver: bool,
    /// The driver provides the rewards and the trials' endings (metadata `reward_from =
    /// driver`; absent otherwise, where the rig computes the task's reward).
    pub(super) driver_reward: bool,
    /// Where a resumed run continues.
    pub(super) point: Option<&'a ResumePoint>,
    /// Draws the system's pictures for `/scene` (none without).
    pub(super) scene: Option<SceneMaker>,
}

impl RecordingWriter {
    /// Creates `DIR/run.mcap` for the run `about` describes: its channels, the
    /// configuration attached, the metadata `run`, and, when resumed, the messages of the
    /// trials it keeps (the old recording is replaced).
    pub(super) fn open(dir: &Path, about: &About) -> Result<Self> {
        let (cfg, task) = (about.cfg, about.task);
        let path = dir.join(crate::record::reader::NAME);
        // Written as `run.mcap.part` until finished: a resumed run's old recording,
        // which holds what it keeps, stays until copied.
        let mut rec = Recorder::create(&path)?;
        // The configuration and the metadata before the channels: each closes the open
        // chunk, and a chunk of channel records without a message is refused by some
        // readers (Lichtblick 1.10's, when the messages start at log time 0).
        rec.attach("config.toml", "application/toml", cfg.to_toml().as_bytes())?;
        rec.metadata("run", &metadata(about))?;
        let mut r = Self::create(rec, task.state_dim(), task.action_dim())?;
        r.realtime = about.realtime;
        if let Some(make) = about.scene {
            r.add_scene(make(task))?;
        }
        if about.driver {
            r.add_driver()?;
        }
        if cfg.observer().sensor != ::observer::config::SensorKind::Full {
            r.add_truth()?;
        }
        if let Some(p) = about.point {
            r.keep(p, &path)?;
        }
        Ok(r)
    }

    /// Copies the messages a resumed run keeps from `old` into this recording, then
    /// removes `old` (so that only the new one holds them).
    fn keep(&mut self, p: &ResumePoint, old: &Path) -> Result<()> {
        for m in &p.messages {
            self.rec
                .write_encoded(&m.topic, m.log_time, m.publish_time, &m.data)
                .map_err(|source| RunError::Channels {
                    path: old.to_owned(),
                    source,
                })?;
        }
        self.rec.flush()?;
        if old.exists() {
            std::fs::remove_file(old).at("cannot remove", old)?;
        }
        Ok(())
    }

    /// The recording's channels in `rec`, for a task of `n` states and `m` actions.
    pub(super) fn create(mut rec: Recorder, n: usize, m: usize) -> Result<Self, RecordError> {
        use channels::{ACTION, ESTIMATE, MEASUREMENT, TIMING};
        let measurement =
            rec.channel(MEASUREMENT, schema::MEASUREMENT, &fields::measurement(n, m))?;
        let estimate = rec.channel(ESTIMATE, schema::ESTIMATE, &fields::estimate(n, m))?;
        let action = rec.channel(ACTION, schema::ACTION, &fields::action(m))?;
        let timing = |rec: &mut Recorder, i: usize, stamps: &[&str]| {
            rec.channel(TIMING[i], schema::TIMING[i], &fields::timing(stamps))
        };
        let t_measurement = timing(&mut rec, 0, &fields::MEASUREMENT_STAMPS)?;
        let t_estimate = timing(&mut rec, 1, &fields::STAMPS)?;
        let t_action = timing(&mut rec, 2, &fields::STAMPS)?;
        let returns = rec.channel(channels::RETURNS, schema::RETURNS, &fields::returns())?;
        let latency = rec.channel(channels::LATENCY, schema::LATENCY, &fields::latency())?;
        Ok(Self {
            rec,
            measurement,
            estimate,
            action,
            truth: None,
            t_measurement,
            t_estimate,
            t_action,
            driver: None,
            n,
            m,
            values: Vec::new(),
            realtime: false,
            t_sample_ns: 0,
            returns,
            latency,
            scene: None,
            log_time_ns: 0,
        })
    }

    /// Hands every channel and message to `tap` too (a live view).
    pub(super) fn live(&mut self, tap: Box<dyn Tap>) {
        self.rec.set_tap(tap);
    }

    /// Adds `/scene`, the system drawn by `scene` from each sample's state.
    fn add_scene(&mut self, scene: Box<dyn Scene>) -> Result<(), RecordError> {
        let channel = self
            .rec
            .encoded_channel(channels::SCENE, &scene.encoding())?;
        self.scene = Some(Pictures {
            channel,
            scene,
            buf: Vec::new(),
        });
        Ok(())
    }

    /// The picture of the state `x` of the sample with header `h`, at log time `t` (no
    /// picture of the shutdown, which has no state).
    fn picture(&mut self, h: &Header, x: &[f64], t: u64) -> Result<(), RecordError> {
        let Some(p) = &mut self.scene else {
            return Ok(());
        };
        if h.flags & flags::SHUTDOWN != 0 {
            return Ok(());
        }
        p.scene.draw(x, t, &mut p.buf);
        self.rec.write_bytes(p.channel, t, t, &p.buf)
    }

    /// A trial's row of `returns.csv` on `/returns`, at log time `t`; its greedy return
    /// `null` when it had no evaluation.
    pub(super) fn trial(&mut self, r: &TrialRecord, t: u64) -> Result<(), RecordError> {
        self.values.clear();
        self.values.extend([
            Value::Int(r.trial.into()),
            Value::Num(r.ret),
            Value::Num(r.greedy.unwrap_or(f64::NAN)),
            Value::Num(r.sim_time_s),
        ]);
        self.rec.write(self.returns, t, t, &self.values)
    }

    /// An action's latency on `/latency`.
    fn latency(&mut self, msg: &Action, t: u64) -> Result<(), RecordError> {
        let us = |from: u64, to: u64| (to as f64 - from as f64) / 1e3;
        self.values.clear();
        self.values.extend([
            Value::Int(msg.header.seq),
            Value::Num(us(msg.t_sample_ns, msg.t_publish_ns)),
            Value::Num(us(msg.t_received_ns, msg.t_publish_ns)),
        ]);
        self.rec.write(self.latency, t, t, &self.values)
    }

    /// Starts a message with the header fields; returns its log time (simulated, ns).
    pub(super) fn header(&mut self, h: &Header) -> u64 {
        self.values.clear();
        self.values.extend([
            Value::Int(h.seq),
            Value::Int(h.trial),
            Value::Int(h.step),
            Value::Int(h.flags),
            Value::Num(h.t_sim),
        ]);
        if self.realtime {
            self.t_sample_ns
        } else {
            (h.t_sim * 1e9).round() as u64
        }
    }

    pub(super) fn write(
        &mut self,
        ch: ChannelId,
        t: u64,
        timing: ChannelId,
        seq: u64,
        stamps: &[u64],
    ) -> Result<(), RecordError> {
        self.rec.write(ch, t, t, &self.values)?;
        self.values.clear();
        self.values.push(Value::Int(seq));
        self.values.extend(stamps.iter().map(|&s| Value::Int(s)));
        self.log_time_ns = t;
        self.rec.write(timing, t, t, &self.values)
    }

    pub(super) fn nums(&mut self, v: &[f64]) {
        self.values.extend(v.iter().map(|&x| Value::Num(x)));
    }

    pub(super) fn measurement(&mut self, msg: &Measurement) -> Result<(), RecordError> {
        self.t_sample_ns = msg.t_sample_ns;
        let t = self.header(&msg.header);
        self.nums(&[msg.reward]);
        self.nums(&msg.y[..self.n]);
        self.nums(&msg.u_applied[..self.m]);
        self.nums(&msg.u_next[..self.m]);
        self.nums(&[msg.delay_s]);
        self.write(
            self.measurement,
            t,
            self.t_measurement,
            msg.header.seq,
            &[msg.t_sample_ns, msg.t_publish_ns, msg.t_action_ns],
        )?;
        // The state measured is drawn, unless the truth is recorded.
        match self.truth {
            Some(_) => Ok(()),
            None => self.picture(&msg.header, &msg.y[..self.n], t),
        }
    }

    /// Adds the channel of the plant's ground truth.
    pub(super) fn add_truth(&mut self) -> Result<(), RecordError> {
        let fields = fields::truth(self.n);
        self.truth = Some(self.rec.channel(channels::TRUTH, schema::TRUTH, &fields)?);
        Ok(())
    }

    /// Records the ground truth of a sample, with the log time of its measurement.
    pub(super) fn truth(&mut self, msg: &Truth) -> Result<(), RecordError> {
        let Some(ch) = self.truth else {
            return Ok(());
        };
        self.t_sample_ns = msg.t_sample_ns;
        let t = self.header(&msg.header);
        self.nums(&msg.x[..self.n]);
        self.rec.write(ch, t, t, &self.values)?;
        self.picture(&msg.header, &msg.x[..self.n], t)
    }

    pub(super) fn estimate(&mut self, msg: &Estimate) -> Result<(), RecordError> {
        self.t_sample_ns = msg.t_sample_ns;
        let t = self.header(&msg.header);
        self.nums(&[msg.reward]);
        self.nums(&msg.x[..self.n]);
        self.nums(&msg.u_applied[..self.m]);
        self.write(
            self.estimate,
            t,
            self.t_estimate,
            msg.header.seq,
            &[msg.t_sample_ns, msg.t_received_ns, msg.t_publish_ns],
        )
    }

    /// Adds the channels of an external driver's samples and commands.
    pub(super) fn add_driver(&mut self) -> Result<(), RecordError> {
        let (n, m) = (self.n, self.m);
        let s = self.rec.channel(
            channels::DRIVER_SAMPLE,
            schema::DRIVER_SAMPLE,
            &fields::driver_sample(n, m),
        )?;
        let c = self.rec.channel(
            channels::DRIVER_COMMAND,
            schema::DRIVER_COMMAND,
            &fields::driver_command(n, m),
        )?;
        let l = self.rec.channel(
            channels::DRIVER_LINK,
            schema::DRIVER_LINK,
            &fields::driver_link(),
        )?;
        self.driver = Some((s, c, l));
        Ok(())
    }

    /// The link's timing of one driver sample (across hosts).
    pub(super) fn driver_link(&mut self, l: &LinkSample) -> Result<(), RecordError> {
        let Some((_, _, ch)) = self.driver else {
            return Ok(());
        };
        self.values.clear();
        self.values.extend(
            [
                l.seq,
                l.t_received_ns,
                l.sample_hop_ns,
                l.command_round_trip_ns,
                l.command_hop_ns,
                l.ping_round_trip_ns,
                l.clock_uncertainty_ns,
            ]
            .map(Value::Int),
        );
        self.values.push(Value::Num(l.clock_offset_ns as f64));
        self.rec
            .write(ch, l.t_received_ns, l.t_received_ns, &self.values)
    }

    pub(super) fn driver_sample(&mut self, s: &DriverSample) -> Result<(), RecordError> {
        let Some((ch, _, _)) = self.driver else {
            return Ok(());
        };
        self.values.clear();
        self.values
            .extend([s.seq, s.t_sample_ns, s.status, s.reset_id, s.last_command].map(Value::Int));
        self.nums(&s.x[..self.n]);
        self.nums(&s.u_applied[..self.m]);
        self.values
            .extend([s.clamped, s.rejected, s.watchdog_trips].map(Value::Int));
        self.rec
            .write(ch, s.t_sample_ns, s.t_sample_ns, &self.values)
    }

    pub(super) fn driver_command(&mut self, c: &DriverCommand) -> Result<(), RecordError> {
        let Some((_, ch, _)) = self.driver else {
            return Ok(());
        };
        self.values.clear();
        self.values
            .extend([c.seq, c.kind, c.sample_seq, c.t_publish_ns].map(Value::Int));
        self.nums(&c.u[..self.m]);
        self.nums(&c.x0[..self.n]);
        self.rec
            .write(ch, c.t_publish_ns, c.t_publish_ns, &self.values)
    }

    pub(super) fn action(&mut self, msg: &Action) -> Result<(), RecordError> {
        self.t_sample_ns = msg.t_sample_ns;
        let t = self.header(&msg.header);
        self.nums(&msg.u[..self.m]);
        self.write(
            self.action,
            t,
            self.t_action,
            msg.header.seq,
            &[msg.t_sample_ns, msg.t_received_ns, msg.t_publish_ns],
        )?;
        self.latency(msg, t)
    }
}
