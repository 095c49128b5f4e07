//! A run folder's recording read back for replay: the configuration attached, the
//! metadata, and the loop's messages decoded into the wire's layouts.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use wire::{Action, Estimate, Measurement, Truth};

use super::{FORMAT, ReplayError};
use crate::config::{ExperimentConfig, Overrides, resolve};
use crate::record::channels::decode::{FieldError, Flat};
use crate::record::channels::{ACTION, ESTIMATE, MEASUREMENT, TRUTH};
use crate::record::reader::{NAME, PART, RunFile};

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
        let path = dir.join(NAME);
        if !path.exists() {
            return Err(if dir.join(PART).exists() {
                ReplayError::Unfinished { dir: dir.into() }
            } else {
                ReplayError::NoRecording { path }
            });
        }
        let file = RunFile::read(&path).map_err(|e| ReplayError::Io {
            path: path.clone(),
            cause: e.to_string(),
        })?;
        let foreign = |why: String| ReplayError::Foreign {
            path: path.clone(),
            why,
        };
        let summary = file
            .summary()
            .map_err(|e| foreign(format!("not a readable MCAP file ({e})")))?
            .ok_or_else(|| foreign("an MCAP file without a summary".into()))?;
        let about = file
            .metadata(&summary, "run")
            .ok_or_else(|| foreign("it has no metadata `run`".into()))?;
        check_format(&path, &about)?;
        let config = file
            .attachment(&summary, "config.toml")
            .ok_or_else(|| foreign("it has no attachment config.toml".into()))?;
        let cfg = configuration(&path, &config)?;
        let mut rec = Recording {
            path,
            cfg,
            about,
            measurements: Vec::new(),
            estimates: BTreeMap::new(),
            actions: BTreeMap::new(),
            truth: BTreeMap::new(),
        };
        rec.decode(&file)?;
        Ok(rec)
    }

    /// Decodes the loop's messages of `file`.
    fn decode(&mut self, file: &RunFile) -> Result<(), ReplayError> {
        let task = self.cfg.task();
        let (n, m) = (task.state_dim(), task.action_dim());
        let stream = file.messages().map_err(|e| self.unreadable("", 0, e))?;
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
