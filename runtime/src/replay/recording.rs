//! A run folder's recording read back for replay: the configuration attached, the
//! metadata, and the loop's messages decoded into the wire's layouts.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde_json::{Map, Value as Json};
use wire::{Action, Estimate, Header, MAX_U, MAX_X, Measurement, Truth};

use super::{FORMAT, ReplayError};
use crate::config::{ExperimentConfig, Overrides, resolve};

/// The loop's topics, as `rig run` records them.
pub const MEASUREMENT: &str = "/plant/measurement";
/// The observer's estimates.
pub const ESTIMATE: &str = "/observer/estimate";
/// The agent's actions.
pub const ACTION: &str = "/agent/action";
/// The true state, recorded with a sensor that does not measure it.
pub const TRUTH: &str = "/plant/truth";

/// What a recording holds that a replay needs.
pub struct Recording {
    /// `DIR/run.mcap`.
    pub path: PathBuf,
    /// The configuration attached (`config.toml`), resolved.
    pub cfg: ExperimentConfig,
    /// The metadata `run`: seed, timing, versions, ...
    pub about: BTreeMap<String, String>,
    /// Every measurement, in the order recorded (the order of their sequence numbers).
    pub measurements: Vec<Measurement>,
    /// The estimates by sequence number.
    pub estimates: BTreeMap<u64, Estimate>,
    /// The actions by sequence number.
    pub actions: BTreeMap<u64, Action>,
    /// The true states by sequence number (a sensor that does not measure the state).
    pub truth: BTreeMap<u64, Truth>,
}

impl Recording {
    /// Reads `dir/run.mcap`, the recording of a finished `rig run`.
    pub fn read(dir: &Path) -> Result<Self, ReplayError> {
        let path = dir.join("run.mcap");
        if !path.exists() {
            return Err(if dir.join("run.mcap.part").exists() {
                ReplayError::Unfinished { dir: dir.into() }
            } else {
                ReplayError::NoRecording { path }
            });
        }
        let bytes = std::fs::read(&path).map_err(|e| ReplayError::Io {
            path: path.clone(),
            cause: e.to_string(),
        })?;
        let foreign = |why: String| ReplayError::Foreign {
            path: path.clone(),
            why,
        };
        let summary = mcap::Summary::read(&bytes)
            .map_err(|e| foreign(format!("not a readable MCAP file ({e})")))?
            .ok_or_else(|| foreign("an MCAP file without a summary".into()))?;
        let about = summary
            .metadata_indexes
            .iter()
            .filter(|i| i.name == "run")
            .find_map(|i| mcap::read::metadata(&bytes, i).ok())
            .ok_or_else(|| foreign("it has no metadata `run`".into()))?
            .metadata;
        check_format(&path, &about)?;
        let config = summary
            .attachment_indexes
            .iter()
            .filter(|i| i.name == "config.toml")
            .find_map(|i| mcap::read::attachment(&bytes, i).ok())
            .ok_or_else(|| foreign("it has no attachment config.toml".into()))?;
        let cfg = configuration(&path, &config.data)?;
        let mut rec = Recording {
            path,
            cfg,
            about,
            measurements: Vec::new(),
            estimates: BTreeMap::new(),
            actions: BTreeMap::new(),
            truth: BTreeMap::new(),
        };
        rec.decode(&bytes)?;
        Ok(rec)
    }

    /// Decodes the loop's messages of `bytes`.
    fn decode(&mut self, bytes: &[u8]) -> Result<(), ReplayError> {
        let task = self.cfg.task();
        let (n, m) = (task.state_dim(), task.action_dim());
        let stream = mcap::MessageStream::new(bytes).map_err(|e| self.unreadable("", 0, e))?;
        for (i, msg) in stream.enumerate() {
            let msg = msg.map_err(|e| self.unreadable("", i, e))?;
            let topic = msg.channel.topic.as_str();
            if ![MEASUREMENT, ESTIMATE, ACTION, TRUTH].contains(&topic) {
                continue;
            }
            let flat = Flat::parse(&msg.data).map_err(|e| self.unreadable(topic, i, e))?;
            let decoded = match topic {
                MEASUREMENT => flat.measurement(n, m).map(|x| self.measurements.push(x)),
                ESTIMATE => flat.estimate(n, m).map(|x| {
                    self.estimates.insert(x.header.seq, x);
                }),
                ACTION => flat.action(m).map(|x| {
                    self.actions.insert(x.header.seq, x);
                }),
                _ => flat.truth(n).map(|x| {
                    self.truth.insert(x.header.seq, x);
                }),
            };
            decoded.map_err(|e| self.old_or_unreadable(topic, i, e))?;
        }
        Ok(())
    }

    fn unreadable(&self, topic: &str, index: usize, e: impl std::fmt::Display) -> ReplayError {
        ReplayError::Unreadable {
            path: self.path.clone(),
            topic: topic.into(),
            index,
            cause: e.to_string(),
        }
    }

    /// A field missing from a recording without a format is an older recording's.
    fn old_or_unreadable(&self, topic: &str, index: usize, e: FieldError) -> ReplayError {
        match (e, self.about.contains_key("recording_format")) {
            (FieldError::Missing(field), false) => ReplayError::Format {
                path: self.path.clone(),
                found: format!("an older format (its {topic} has no field {field})"),
            },
            (e, _) => self.unreadable(topic, index, e),
        }
    }
}

/// Refuses a recording whose metadata names another format. Without the key (written by
/// an older `rig run`), the messages decide: their fields are this format's or not.
fn check_format(path: &Path, about: &BTreeMap<String, String>) -> Result<(), ReplayError> {
    match about.get("recording_format") {
        Some(f) if f.parse() == Ok(FORMAT) => Ok(()),
        Some(f) => Err(ReplayError::Format {
            path: path.into(),
            found: format!("format {f}"),
        }),
        None => Ok(()),
    }
}

/// The configuration attached to the recording at `path`, resolved as `rig run` did.
fn configuration(path: &Path, toml: &[u8]) -> Result<ExperimentConfig, ReplayError> {
    let name = PathBuf::from(format!("{}:config.toml", path.display()));
    let text = String::from_utf8_lossy(toml);
    resolve(Some((&name, &text)), &Overrides::default())
        .map_err(|e| ReplayError::Config(e.to_string()))
}

/// Why a message's field could not be decoded.
#[derive(Debug, thiserror::Error)]
enum FieldError {
    #[error("no field {0}")]
    Missing(String),
    #[error("field {0} is not {1}")]
    Type(String, &'static str),
    #[error("not a JSON object: {0}")]
    Json(String),
}

/// One recorded message: a flat JSON object of numbers (`null` for NaN).
struct Flat(Map<String, Json>);

impl Flat {
    fn parse(data: &[u8]) -> Result<Self, FieldError> {
        serde_json::from_slice(data)
            .map(Flat)
            .map_err(|e| FieldError::Json(e.to_string()))
    }

    fn get(&self, key: &str) -> Result<&Json, FieldError> {
        self.0
            .get(key)
            .ok_or_else(|| FieldError::Missing(key.into()))
    }

    fn int(&self, key: &str) -> Result<u64, FieldError> {
        self.get(key)?
            .as_u64()
            .ok_or_else(|| FieldError::Type(key.into(), "an unsigned integer"))
    }

    /// A number; `null` is NaN (the recorder writes NaN and ±∞ so).
    fn num(&self, key: &str) -> Result<f64, FieldError> {
        match self.get(key)? {
            Json::Null => Ok(f64::NAN),
            v => v
                .as_f64()
                .ok_or_else(|| FieldError::Type(key.into(), "a number")),
        }
    }

    /// The fields `name_0 .. name_{len-1}`, the rest zero.
    fn array<const N: usize>(&self, name: &str, len: usize) -> Result<[f64; N], FieldError> {
        let mut a = [0.0; N];
        for (i, v) in a.iter_mut().enumerate().take(len) {
            *v = self.num(&format!("{name}_{i}"))?;
        }
        Ok(a)
    }

    fn header(&self) -> Result<Header, FieldError> {
        Ok(Header {
            seq: self.int("seq")?,
            trial: self.int("trial")?,
            step: self.int("step")?,
            flags: self.int("flags")?,
            t_sim: self.num("t_sim")?,
        })
    }

    fn measurement(&self, n: usize, m: usize) -> Result<Measurement, FieldError> {
        Ok(Measurement {
            header: self.header()?,
            n_x: n as u64,
            n_u: m as u64,
            reward: self.num("reward")?,
            y: self.array::<MAX_X>("y", n)?,
            u_applied: self.array::<MAX_U>("u_applied", m)?,
            u_next: self.array::<MAX_U>("u_next", m)?,
            delay_s: self.num("delay_s")?,
            ..Measurement::default()
        })
    }

    fn estimate(&self, n: usize, m: usize) -> Result<Estimate, FieldError> {
        Ok(Estimate {
            header: self.header()?,
            n_x: n as u64,
            n_u: m as u64,
            reward: self.num("reward")?,
            x: self.array::<MAX_X>("x", n)?,
            u_applied: self.array::<MAX_U>("u_applied", m)?,
            ..Estimate::default()
        })
    }

    fn action(&self, m: usize) -> Result<Action, FieldError> {
        Ok(Action {
            header: self.header()?,
            n_u: m as u64,
            u: self.array::<MAX_U>("u", m)?,
            ..Action::default()
        })
    }

    fn truth(&self, n: usize) -> Result<Truth, FieldError> {
        Ok(Truth {
            header: self.header()?,
            n_x: n as u64,
            x: self.array::<MAX_X>("x", n)?,
            ..Truth::default()
        })
    }
}
