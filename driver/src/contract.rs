//! The driver contract: how a process that owns the hardware (or a simulation of it)
//! talks to the rig. `docs/driver.md` is the human-readable version of this module; a
//! test checks its layout tables against these structs.
//!
//! ```text
//!            rig/driver/<id>/info     (DriverInfo,   driver → rig, at least once a second)
//! driver ──► rig/driver/<id>/sample   (DriverSample, driver → rig, once per period) ──► rig
//!        ◄── rig/driver/<id>/command  (DriverCommand, rig → driver: ACTION or RESET) ◄──
//! ```
//!
//! The driver is the clock: it samples every `period_ns` on its own and publishes the
//! sample whether or not actions arrive. It applies an action from the moment it
//! arrives (clamped to its limits; a non-finite action is rejected and the safe action,
//! zero, applied), falls back to zero when actions stop ([`DriverInfo::watchdog_periods`]),
//! and brings the system to rest at a requested start state when told to reset,
//! reporting when it is done ([`status::READY`] with [`DriverSample::reset_id`]).
//! Trials, rewards and learning are the rig's: the driver never sees them.
//!
//! A driver serves it with [`crate::kit`]; the rig's end of it is [`crate::link`].

use std::time::Duration;

use iceoryx2::prelude::*;

use wire::{Bus, MAX_U, MAX_X, Qos};

use crate::error::{Error, InfoError, LastSample, SampleError};

// A task's states and actions fit the messages: the plant's bounds are the wire's (a
// build fails where they part).
const _: () = assert!(plant::MAX_STATE == MAX_X && plant::MAX_ACTION == MAX_U);
// A task's name fits [`DriverInfo::task`] (32 bytes) with a NUL after it.
const _: () = assert!(plant::task::file::MAX_NAME < 32);

/// The protocol version in [`DriverInfo::version`].
pub const VERSION: u64 = 3;

/// Settings of every driver service: one publisher (one driver per id; one rig
/// commanding it at a time), up to eight subscribers (the rig's plant process, its
/// recorder, `rig check-driver`, monitors), 256 samples of buffer, the oldest
/// overwritten when full (a driver never waits for a reader).
pub const DRIVER_QOS: Qos = Qos {
    max_publishers: 1,
    max_subscribers: 8,
    buffer: 256,
    safe_overflow: true,
};

/// Topics of a driver, below `rig/driver/<id>/`.
pub mod topic {
    /// Driver → rig: what the driver is and its limits.
    pub const INFO: &str = "info";
    /// Driver → rig: one per sample period.
    pub const SAMPLE: &str = "sample";
    /// Rig → driver: actions and reset requests.
    pub const COMMAND: &str = "command";
    /// The rig's bridge → rig, across hosts only: what the network did with each sample
    /// ([`super::LinkSample`], docs/across-hosts.md).
    pub const LINK: &str = "link";
    /// The rig's bridge → rig, across hosts only: what the driver's side said of this
    /// rig's commands ([`super::DriverNotice`], docs/across-hosts.md).
    pub const NOTICE: &str = "notice";
}

/// Bits of [`DriverSample::status`].
pub mod status {
    /// The last reset is done and actions are applied.
    pub const READY: u64 = 1;
    /// A reset is in progress: actions are ignored.
    pub const RESETTING: u64 = 2;
    /// The watchdog applies the safe action: no action arrived for
    /// [`super::DriverInfo::watchdog_periods`] periods (cleared by the next action or
    /// a reset).
    pub const WATCHDOG: u64 = 4;
}

/// Bits of [`DriverInfo::provides`]: what a driver computes besides the samples.
pub mod provides {
    /// Each sample carries the reward of the period it closes and the trial's ending
    /// ([`super::DriverSample::reward`], [`super::DriverSample::ending`]); the rig learns
    /// them as they are instead of computing the task's reward and operating range.
    pub const REWARD: u64 = 1;
}

/// Bits of [`DriverSample::ending`], with [`provides::REWARD`]: how the trial ends at
/// this sample (at most one).
pub mod ending {
    /// The state is terminal (a goal reached, a failure): nothing follows, its value is
    /// zero, the learners bootstrap nothing past it.
    pub const TERMINATED: u64 = 1;
    /// The trial's time is up: the state goes on, the learners bootstrap through it.
    pub const TRUNCATED: u64 = 2;
}

/// Values of [`DriverInfo::clock`].
pub mod clock {
    /// The driver samples every period on its own, whether or not actions arrive:
    /// hardware, or a simulation in real time.
    pub const REALTIME: u64 = 0;
    /// A simulation that publishes sample `k + 1` only after the action answering sample
    /// `k` arrived (or a reset): it runs as fast as the loop, and the same commands give
    /// the same samples.
    pub const LOCKSTEP: u64 = 1;
}

/// Values of [`DriverCommand::kind`].
pub mod kind {
    /// Apply `u` from now on.
    pub const ACTION: u64 = 1;
    /// Bring the system to rest at `x0`, then report READY with `reset_id = seq`.
    pub const RESET: u64 = 2;
}

/// Driver → rig: what the driver drives and its limits. Published at start and again
/// at least once a second (a rig that starts later learns it from the next one).
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.DriverInfo.v3")]
pub struct DriverInfo {
    /// Protocol version: [`VERSION`].
    pub version: u64,
    /// The task's name (its task file's `name`), ASCII, NUL-padded: a built-in system's
    /// `pendulum`, `arm-vertical`, `arm-horizontal`, `arm-6.4`, `double-integrator`, or
    /// a task file's.
    pub task: [u8; 32],
    /// The task's content hash ([`plant::Task::hash`], `docs/tasks.md`).
    pub task_hash: u64,
    /// How the driver keeps time: [`clock`].
    pub clock: u64,
    /// State components in [`DriverSample::x`].
    pub n_x: u64,
    /// Action components in [`DriverCommand::u`] and [`DriverSample::u_applied`].
    pub n_u: u64,
    /// Sample period on the monotonic clock \[ns\].
    pub period_ns: u64,
    /// Simulated seconds per monotonic-clock second: 1 for hardware; a simulation that
    /// runs faster than real time reports its speed-up. The physical sample time is
    /// `period_ns · time_scale`.
    pub time_scale: f64,
    /// Lower action limits (first `n_u` used).
    pub u_min: [f64; MAX_U],
    /// Upper action limits (first `n_u` used).
    pub u_max: [f64; MAX_U],
    /// Whole periods without an action after which the driver applies the safe action
    /// (protocol version 1: 1).
    pub watchdog_periods: u64,
    /// When this driver instance started (monotonic ns): changes when it restarts.
    pub t_start_ns: u64,
    /// When this message was published (monotonic ns).
    pub t_publish_ns: u64,
    /// [`provides`] bits: 0, or [`provides::REWARD`] for a driver whose samples carry
    /// the reward and the trial's endings.
    pub provides: u64,
}

/// Driver → rig: one sample, published every period.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.DriverSample.v2")]
pub struct DriverSample {
    /// Period index since the driver started: `t_sample_ns ≈ t_start_ns + seq ·
    /// period_ns`. A gap means the driver missed periods.
    pub seq: u64,
    /// When the state was sampled (monotonic ns).
    pub t_sample_ns: u64,
    /// When this message was published (monotonic ns).
    pub t_publish_ns: u64,
    /// [`status`] bits.
    pub status: u64,
    /// `seq` of the last RESET command: in progress (RESETTING) or done (READY); 0 before
    /// the first.
    pub reset_id: u64,
    /// `seq` of the last ACTION command applied; 0 before the first.
    pub last_command: u64,
    /// Used components of `x`.
    pub n_x: u64,
    /// Used components of `u_applied`.
    pub n_u: u64,
    /// The measured state at `t_sample_ns` (units and order: `docs/driver.md`).
    pub x: [f64; MAX_X],
    /// The action in effect at `t_sample_ns`, i.e. at the end of the period this sample
    /// closes (after clamping; zero when the safe action is applied).
    pub u_applied: [f64; MAX_U],
    /// ACTION commands clamped to the limits so far (any component).
    pub clamped: u64,
    /// Commands rejected so far: a non-finite component, a wrong `n_u`/`n_x`, an unknown
    /// kind, or an action while not READY.
    pub rejected: u64,
    /// Times the watchdog engaged so far.
    pub watchdog_trips: u64,
    /// With [`provides::REWARD`]: the reward of the period this sample closes (finite;
    /// 0 at a reset's READY sample); otherwise 0.
    pub reward: f64,
    /// With [`provides::REWARD`]: [`ending`] bits, how the trial ends at this sample (0:
    /// it goes on); otherwise 0.
    pub ending: u64,
}

/// Rig → driver: apply an action, or reset.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.DriverCommand.v1")]
pub struct DriverCommand {
    /// Strictly increasing, also across runs of the rig (the rig starts from its
    /// monotonic clock).
    pub seq: u64,
    /// [`kind`].
    pub kind: u64,
    /// ACTION: the [`DriverSample::seq`] this action answers (information only).
    pub sample_seq: u64,
    /// When this message was published (monotonic ns).
    pub t_publish_ns: u64,
    /// ACTION: used components of `u`.
    pub n_u: u64,
    /// ACTION: the action (units: `docs/driver.md`).
    pub u: [f64; MAX_U],
    /// RESET: used components of `x0`.
    pub n_x: u64,
    /// RESET: the state to bring the system to rest at.
    pub x0: [f64; MAX_X],
}

/// The rig's bridge → rig, one per driver sample it forwards, when the driver is on
/// another host (docs/across-hosts.md): the link's share of the loop, recorded as
/// `/driver/link`. Durations in ns on one clock each; 0 where not measured.
#[repr(C)]
#[derive(Debug, Clone, Copy, Default, PartialEq, ZeroCopySend)]
#[type_name("rig.LinkSample.v1")]
pub struct LinkSample {
    /// The driver sample's `seq`.
    pub seq: u64,
    /// When it arrived on the rig's host (its monotonic clock).
    pub t_received_ns: u64,
    /// Driver's bridge → rig's bridge; only where both hosts read one clock.
    pub sample_hop_ns: u64,
    /// Through the command this sample is the first to acknowledge: the rig's bridge
    /// sent it, the driver's host held it until this sample (excluded), back here.
    pub command_round_trip_ns: u64,
    /// That command's rig's bridge → driver's bridge; only on one clock.
    pub command_hop_ns: u64,
    /// The latest ping's round trip (the network's and the bridges').
    pub ping_round_trip_ns: u64,
    /// The driver's clock minus the rig's, as the samples' stamps were shifted by.
    pub clock_offset_ns: i64,
    /// How far that offset may be off: half the round trip it was taken from.
    pub clock_uncertainty_ns: u64,
}

/// The most bytes of text a [`DriverNotice`] carries.
pub const NOTICE_BYTES: usize = 240;

/// The rig's bridge → rig, when the driver is on another host (docs/across-hosts.md):
/// one line the driver's side said of this rig's commands — that another rig's session
/// holds the driver, naming it — for the rig to name in its own error.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, ZeroCopySend)]
#[type_name("rig.DriverNotice.v1")]
pub struct DriverNotice {
    /// When the rig's bridge received it (its monotonic clock).
    pub t_received_ns: u64,
    /// The used bytes of `text`.
    pub len: u64,
    /// The line, UTF-8, `len` bytes.
    pub text: [u8; NOTICE_BYTES],
}

impl DriverNotice {
    /// The notice `line` (cut at a character boundary to [`NOTICE_BYTES`]), received at
    /// `t_received_ns`.
    pub fn new(line: &str, t_received_ns: u64) -> Self {
        let mut end = line.len().min(NOTICE_BYTES);
        while !line.is_char_boundary(end) {
            end -= 1;
        }
        let mut text = [0; NOTICE_BYTES];
        text[..end].copy_from_slice(&line.as_bytes()[..end]);
        Self {
            t_received_ns,
            len: end as u64,
            text,
        }
    }

    /// The line.
    pub fn line(&self) -> String {
        let n = (self.len as usize).min(NOTICE_BYTES);
        String::from_utf8_lossy(&self.text[..n]).into_owned()
    }
}

impl DriverInfo {
    /// The task's name as text (up to the first NUL).
    pub fn task_name(&self) -> String {
        let end = self
            .task
            .iter()
            .position(|&b| b == 0)
            .unwrap_or(self.task.len());
        String::from_utf8_lossy(&self.task[..end]).into_owned()
    }

    /// Whether the driver runs in lockstep ([`clock::LOCKSTEP`]).
    pub fn lockstep(&self) -> bool {
        self.clock == clock::LOCKSTEP
    }

    /// The physical sample time `period_ns · time_scale` \[s\].
    pub fn ts(&self) -> f64 {
        self.period_ns as f64 * 1e-9 * self.time_scale
    }

    /// The period on the monotonic clock.
    pub fn period(&self) -> Duration {
        Duration::from_nanos(self.period_ns)
    }

    /// How long the driver may stay silent before it counts as stopped. A driver on a
    /// clock publishes every period, also while it resets: 20 periods, at least 1 s. A
    /// driver in lockstep answers once its simulation has stepped, however long that takes
    /// on a loaded machine or in a heavy simulator: `step_limit`.
    pub fn silence_limit(&self, step_limit: Duration) -> Duration {
        if self.lockstep() {
            step_limit
        } else {
            (self.period() * 20).max(Duration::from_secs(1))
        }
    }

    /// Checks what holds for any driver: the version, dimensions within the message
    /// sizes, a positive period and time scale, finite and ordered limits, a watchdog of
    /// one period.
    pub fn validate(&self) -> Result<(), InfoError> {
        if self.version != VERSION {
            return Err(InfoError::Version {
                found: self.version,
                speaks: VERSION,
            });
        }
        if !(1..=MAX_X as u64).contains(&self.n_x) || !(1..=MAX_U as u64).contains(&self.n_u) {
            return Err(InfoError::Dimensions {
                n_x: self.n_x,
                n_u: self.n_u,
                max_x: MAX_X,
                max_u: MAX_U,
            });
        }
        if self.period_ns == 0 || !(self.time_scale.is_finite() && self.time_scale > 0.0) {
            return Err(InfoError::Period {
                period_ns: self.period_ns,
                time_scale: self.time_scale,
            });
        }
        for i in 0..self.n_u as usize {
            let (lo, hi) = (self.u_min[i], self.u_max[i]);
            if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                return Err(InfoError::Limits { i, lo, hi });
            }
        }
        if self.clock > clock::LOCKSTEP {
            return Err(InfoError::Clock {
                found: self.clock,
                realtime: clock::REALTIME,
                lockstep: clock::LOCKSTEP,
            });
        }
        if self.watchdog_periods != 1 {
            return Err(InfoError::Watchdog {
                found: self.watchdog_periods,
                version: VERSION,
            });
        }
        if self.provides & !provides::REWARD != 0 {
            return Err(InfoError::Provides {
                found: self.provides,
                reward: provides::REWARD,
            });
        }
        Ok(())
    }

    /// Whether the driver's samples carry the reward and the endings
    /// ([`provides::REWARD`]).
    pub fn provides_reward(&self) -> bool {
        self.provides & provides::REWARD != 0
    }
}

impl DriverSample {
    /// The state, `n_x` components.
    pub fn state(&self) -> &[f64] {
        &self.x[..(self.n_x as usize).min(MAX_X)]
    }

    /// The applied action, `n_u` components.
    pub fn applied(&self) -> &[f64] {
        &self.u_applied[..(self.n_u as usize).min(MAX_U)]
    }

    /// Whether the status has bit `bit`.
    pub fn has(&self, bit: u64) -> bool {
        self.status & bit != 0
    }

    /// Whether the trial ends at this sample in a terminal state ([`ending::TERMINATED`]).
    pub fn terminated(&self) -> bool {
        self.ending & ending::TERMINATED != 0
    }

    /// Whether the trial's time is up at this sample ([`ending::TRUNCATED`]).
    pub fn truncated(&self) -> bool {
        self.ending & ending::TRUNCATED != 0
    }

    /// Whether the driver measures positions only: the velocities — the second half of
    /// the state, `[positions…, velocities…]` — are NaN (not measured; an encoder-only
    /// setup such as the physical pendulum of §6.4.1). The rig's observer estimates them.
    pub fn positions_only(&self) -> bool {
        let x = self.state();
        x[x.len() / 2..].iter().all(|v| v.is_nan())
    }

    /// The measured components of the state: the positions if the driver measures
    /// [`Self::positions_only`], else the whole state.
    pub fn measured(&self) -> &[f64] {
        let x = self.state();
        if self.positions_only() {
            &x[..x.len() / 2]
        } else {
            x
        }
    }

    /// Checks that the sample fits the driver's info: the dimensions, finite values —
    /// except velocities that are all NaN ([`Self::positions_only`]).
    pub fn validate(&self, info: &DriverInfo) -> Result<(), SampleError> {
        if self.n_x != info.n_x || self.n_u != info.n_u {
            return Err(SampleError::Dimensions {
                seq: self.seq,
                n_x: self.n_x,
                n_u: self.n_u,
                info_n_x: info.n_x,
                info_n_u: info.n_u,
            });
        }
        let x = self.state();
        for (name, v) in [("x", self.measured()), ("u_applied", self.applied())] {
            if let Some(i) = v.iter().position(|c| !c.is_finite()) {
                let hint = if name == "x" && v[i].is_nan() && i >= x.len() / 2 {
                    " (a driver that does not measure velocities sends NaN for all of them)"
                } else {
                    ""
                };
                return Err(SampleError::NotFinite {
                    seq: self.seq,
                    name,
                    i,
                    value: v[i],
                    hint,
                });
            }
        }
        self.validate_outcome(info)
    }

    /// Checks the reward and the ending: with [`provides::REWARD`] a finite reward and
    /// at most one [`ending`] bit; without it both zero.
    fn validate_outcome(&self, info: &DriverInfo) -> Result<(), SampleError> {
        let provided = info.provides_reward();
        if provided && !self.reward.is_finite() {
            return Err(SampleError::Reward {
                seq: self.seq,
                reward: self.reward,
            });
        }
        let known = ending::TERMINATED | ending::TRUNCATED;
        let consistent = if provided {
            self.ending & !known == 0 && self.ending != known
        } else {
            self.ending == 0 && self.reward == 0.0
        };
        if !consistent {
            return Err(SampleError::Ending {
                seq: self.seq,
                ending: self.ending,
                reward: self.reward,
                provided,
            });
        }
        Ok(())
    }
}

/// The service name of a driver topic: `rig/driver/<id>/<topic>`.
pub fn service(driver_id: &str, topic: &str) -> String {
    format!("rig/driver/{driver_id}/{topic}")
}

/// The iceoryx2 node name a driver should use: `rig-driver-<id>` (the rig lists nodes
/// to say which drivers are running).
pub fn node_name(driver_id: &str) -> String {
    wire::node_name(wire::DRIVER_RUN, driver_id)
}

/// The connection of driver `driver_id`'s process: node `rig-driver-<id>`
/// ([`node_name`]), which the rig lists to say which drivers are running; its services
/// are opened with [`Bus::tx_on`] and [`Bus::rx_on`] on [`service`] names.
pub fn bus(driver_id: &str) -> Result<Bus, Error> {
    check_id(driver_id)?;
    Ok(Bus::with_node(&node_name(driver_id), wire::DRIVER_RUN)?)
}

/// Checks a driver id: letters, digits, '-' and '_'.
pub fn check_id(driver_id: &str) -> Result<(), Error> {
    if driver_id.is_empty()
        || !driver_id
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_')
    {
        return Err(Error::Id(driver_id.to_string()));
    }
    Ok(())
}

impl From<&DriverSample> for LastSample {
    fn from(s: &DriverSample) -> Self {
        Self {
            seq: s.seq,
            status: s.status,
            reset_id: s.reset_id,
            x: s.state().to_vec(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::mem::{align_of, size_of};

    #[test]
    fn layouts_are_fixed() {
        // Version 3: DriverInfo.v3 + provides, DriverSample.v2 + reward, ending.
        assert_eq!(size_of::<DriverInfo>(), 184);
        assert_eq!(size_of::<DriverSample>(), 200);
        assert_eq!(size_of::<DriverCommand>(), 144);
        assert_eq!(size_of::<LinkSample>(), 64);
        assert_eq!(size_of::<DriverNotice>(), 256);
        assert_eq!(align_of::<DriverInfo>(), 8);
        assert_eq!(align_of::<DriverSample>(), 8);
        assert_eq!(align_of::<DriverCommand>(), 8);
    }

    #[test]
    fn a_notice_keeps_its_line_cut_at_a_character() {
        let n = DriverNotice::new("held by user rig at tcp/10.0.0.2:4711", 7);
        assert_eq!(n.line(), "held by user rig at tcp/10.0.0.2:4711");
        // 239 ASCII bytes and a two-byte character: the character does not fit.
        let long = format!("{}é", "a".repeat(NOTICE_BYTES - 1));
        assert_eq!(
            DriverNotice::new(&long, 0).line(),
            "a".repeat(NOTICE_BYTES - 1)
        );
    }

    #[test]
    fn info_validation_names_the_problem() {
        let mut i = DriverInfo {
            version: VERSION,
            n_x: 2,
            n_u: 1,
            period_ns: 30_000_000,
            time_scale: 1.0,
            watchdog_periods: 1,
            ..Default::default()
        };
        i.u_min[0] = -3.0;
        i.u_max[0] = 3.0;
        i.task[..8].copy_from_slice(b"pendulum");
        assert_eq!(i.validate(), Ok(()));
        assert_eq!(i.task_name(), "pendulum");
        assert!((i.ts() - 0.03).abs() < 1e-12);
        let mut bad = i;
        bad.u_max[0] = f64::NAN;
        assert!(bad.validate().unwrap_err().to_string().contains("u[0]"));
        assert!(matches!(
            bad.validate(),
            Err(InfoError::Limits { i: 0, .. })
        ));
        let mut bad = i;
        bad.watchdog_periods = 3;
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("watchdog_periods")
        );
        let mut bad = i;
        bad.version = 1;
        assert!(bad.validate().unwrap_err().to_string().contains("version"));
        let mut bad = i;
        bad.clock = 2;
        assert!(bad.validate().unwrap_err().to_string().contains("clock"));
    }

    /// Velocities may be unmeasured (all NaN); positions, a single NaN velocity and
    /// infinities may not.
    #[test]
    fn sample_validation_allows_unmeasured_velocities_only() {
        let info = DriverInfo {
            n_x: 4,
            n_u: 2,
            ..Default::default()
        };
        let sample = |x: [f64; 4]| {
            let mut s = DriverSample {
                seq: 7,
                n_x: 4,
                n_u: 2,
                ..Default::default()
            };
            s.x[..4].copy_from_slice(&x);
            s
        };
        let nan = f64::NAN;
        let full = sample([0.1, -0.2, 0.3, 0.4]);
        assert_eq!(full.validate(&info), Ok(()));
        assert!(!full.positions_only());
        let encoder = sample([0.1, -0.2, nan, nan]);
        assert_eq!(encoder.validate(&info), Ok(()));
        assert!(encoder.positions_only());
        let one = sample([0.1, -0.2, 0.3, nan])
            .validate(&info)
            .unwrap_err()
            .to_string();
        assert!(
            one.contains("x[3] = NaN") && one.contains("NaN for all of them"),
            "{one}"
        );
        let position = sample([nan, -0.2, nan, nan])
            .validate(&info)
            .unwrap_err()
            .to_string();
        assert!(position.starts_with("sample 7: x[0] = NaN"), "{position}");
        assert!(!position.contains("all of them"), "{position}");
        let inf = sample([0.1, -0.2, f64::INFINITY, 0.0]).validate(&info);
        assert!(inf.unwrap_err().to_string().contains("x[2] = inf"));
        let wrong = DriverSample { n_u: 1, ..full };
        assert!(matches!(
            wrong.validate(&info),
            Err(SampleError::Dimensions {
                n_u: 1,
                info_n_u: 2,
                ..
            })
        ));
    }

    /// A driver that provides the reward sends a finite one and at most one ending; a
    /// driver that does not sends neither.
    #[test]
    fn sample_validation_checks_the_reward_and_the_ending() {
        let mut info = DriverInfo {
            n_x: 2,
            n_u: 1,
            provides: provides::REWARD,
            ..Default::default()
        };
        let sample = |reward: f64, ending: u64| DriverSample {
            seq: 4,
            n_x: 2,
            n_u: 1,
            reward,
            ending,
            ..Default::default()
        };
        assert_eq!(sample(-1.5, 0).validate(&info), Ok(()));
        assert_eq!(sample(0.0, ending::TERMINATED).validate(&info), Ok(()));
        assert_eq!(sample(2.0, ending::TRUNCATED).validate(&info), Ok(()));
        assert!(sample(0.0, ending::TRUNCATED).truncated());
        assert!(!sample(0.0, ending::TRUNCATED).terminated());
        let nan = sample(f64::NAN, 0).validate(&info).unwrap_err().to_string();
        assert_eq!(
            nan,
            "sample 4: reward = NaN: a driver that provides the reward sends a finite one"
        );
        assert!(matches!(
            sample(f64::INFINITY, 0).validate(&info),
            Err(SampleError::Reward { .. })
        ));
        for bad in [3, 4] {
            let e = sample(0.0, bad).validate(&info).unwrap_err().to_string();
            assert!(e.contains("ending must be 0, 1 (terminated) or 2"), "{e}");
        }
        info.provides = 0;
        assert_eq!(sample(0.0, 0).validate(&info), Ok(()));
        for (reward, ending) in [(1.0, 0), (0.0, ending::TERMINATED)] {
            let e = sample(reward, ending)
                .validate(&info)
                .unwrap_err()
                .to_string();
            assert!(e.contains("does not provide the reward"), "{e}");
        }
        let mut valid = DriverInfo {
            version: VERSION,
            period_ns: 30_000_000,
            time_scale: 1.0,
            watchdog_periods: 1,
            provides: provides::REWARD,
            ..info
        };
        valid.u_max[0] = 1.0;
        assert_eq!(valid.validate(), Ok(()));
        valid.provides = 2;
        assert_eq!(
            valid.validate(),
            Err(InfoError::Provides {
                found: 2,
                reward: provides::REWARD
            })
        );
    }
}
