//! The channels of `run.mcap`, in one place: their topics, their schemas' names and
//! fields ([`fields`]), how a message of the loop is read back into the wire's layouts
//! ([`decode`]), and which messages a resumed run keeps ([`Keep`]). `rig run` writes
//! them (`crate::run`), `rig replay` and `rig run --resume` read them with the one reader
//! of the file ([`super::reader`]).

use serde::Deserialize;

pub mod decode;
pub mod fields;

/// The plant's measurements.
pub const MEASUREMENT: &str = "/plant/measurement";
/// The observer's estimates.
pub const ESTIMATE: &str = "/observer/estimate";
/// The agent's actions.
pub const ACTION: &str = "/agent/action";
/// The true state, recorded with a sensor that does not measure it.
pub const TRUTH: &str = "/plant/truth";
/// The loop's three topics, in the order of the loop.
pub const LOOP: [&str; 3] = [MEASUREMENT, ESTIMATE, ACTION];
/// The wall-clock stamps of the loop's topics, in the same order.
pub const TIMING: [&str; 3] = [
    "/timing/plant/measurement",
    "/timing/observer/estimate",
    "/timing/agent/action",
];
/// An external driver's samples.
pub const DRIVER_SAMPLE: &str = "/driver/sample";
/// The plant process's commands to an external driver.
pub const DRIVER_COMMAND: &str = "/driver/command";
/// A driver's link across hosts.
pub const DRIVER_LINK: &str = "/driver/link";
/// What every channel of an external driver's traffic begins with.
pub const DRIVER_PREFIX: &str = "/driver/";
/// A row of `returns.csv` per trial.
pub const RETURNS: &str = "/returns";
/// Per action, the time from its sample to it and the agent's share.
pub const LATENCY: &str = "/latency";
/// The system drawn from each sample's state (`super::scene`).
pub const SCENE: &str = "/scene";

/// The schema of each channel, by name (channels of one kind share one).
pub mod schema {
    /// `/plant/measurement`.
    pub const MEASUREMENT: &str = "rig.Measurement";
    /// `/observer/estimate`.
    pub const ESTIMATE: &str = "rig.Estimate";
    /// `/agent/action`.
    pub const ACTION: &str = "rig.Action";
    /// `/plant/truth`.
    pub const TRUTH: &str = "rig.Truth";
    /// The `/timing/...` channels, in the order of [`super::TIMING`].
    pub const TIMING: [&str; 3] = [
        "rig.Timing.Measurement",
        "rig.Timing.Estimate",
        "rig.Timing.Action",
    ];
    /// `/driver/sample`.
    pub const DRIVER_SAMPLE: &str = "rig.DriverSample";
    /// `/driver/command`.
    pub const DRIVER_COMMAND: &str = "rig.DriverCommand";
    /// `/driver/link`.
    pub const DRIVER_LINK: &str = "rig.LinkSample";
    /// `/returns`.
    pub const RETURNS: &str = "rig.Returns";
    /// `/latency`.
    pub const LATENCY: &str = "rig.Latency";
}

/// The head of a recorded message of the loop or its timing: its sample's sequence
/// number, trial and flags (those without the last two read as 0).
#[derive(Clone, Copy, Debug, Deserialize)]
pub struct Head {
    /// The sample's sequence number.
    pub seq: u64,
    /// Its trial.
    #[serde(default)]
    pub trial: u64,
    /// Its flags (`wire::flags`).
    #[serde(default)]
    pub flags: u64,
}

impl Head {
    /// The head of the JSON message `data`, if it has one.
    pub fn of(data: &[u8]) -> Result<Head, serde_json::Error> {
        serde_json::from_slice(data)
    }
}

/// The trial of a `/returns` message.
pub fn row_trial(data: &[u8]) -> Option<u64> {
    #[derive(Deserialize)]
    struct Row {
        trial: u64,
    }
    serde_json::from_slice::<Row>(data).ok().map(|r| r.trial)
}

/// Which of a recording's messages a run resumed before sample `first_seq`, after trial
/// `c`, keeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Keep {
    /// A message of the loop: those of the samples before, but the shutdown.
    Loop,
    /// A message of a sample (its timing, its latency): those of the samples before.
    Sample,
    /// A row of `returns.csv`: those of trials up to `c`.
    Row,
    /// A picture, one per measurement but the shutdown: as many as measurements are kept.
    Picture,
    /// Any other: those logged up to the last kept measurement.
    Logged,
}

impl Keep {
    /// How the messages of `topic` are kept.
    pub fn of(topic: &str) -> Keep {
        match topic {
            _ if LOOP.contains(&topic) => Keep::Loop,
            _ if TIMING.contains(&topic) => Keep::Sample,
            LATENCY => Keep::Sample,
            RETURNS => Keep::Row,
            SCENE => Keep::Picture,
            _ => Keep::Logged,
        }
    }
}
