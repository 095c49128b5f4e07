//! What a node is given: one settings file per process (`rig plant|observer|agent
//! --node FILE`), written by `rig run` into the run folder (`DIR/nodes/<role>.toml`) or
//! by hand. Every node takes a [`NodeSettings`] (`[node]`); the plant and the agent add
//! their own keys ([`PlantSettings`], [`AgentSettings`]). A node validates its settings
//! itself: a node started by hand is checked as one `rig run` starts.

use std::path::{Path, PathBuf};

use super::Result;
use crate::error::AtFile;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use wire::{Bus, Waiting};

use super::{Scheduling, Spin, Wait, WaitKind};
use crate::clock::{Checked, Clock};
use crate::config::{ExperimentConfig, Overrides, resolve};

/// A settings file that cannot be read, written or used; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum SettingsError {
    /// The file cannot be read.
    #[error("{}: cannot read: {error}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// The file cannot be written.
    #[error("{}: cannot write: {error}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// The file is not valid TOML of the role's settings.
    #[error("{}: line {line}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// The line (1-based; 0 when the parser did not say).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A setting of the right type and a value it may not have.
    #[error("{}: {problem}", path.display())]
    Invalid {
        /// The file.
        path: PathBuf,
        /// Which setting, and what it may be.
        problem: Invalid,
    },
}

/// A setting with a value it may not have.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum Invalid {
    /// A real-time priority outside 1–99.
    #[error("`rt_priority` {0} is out of range: must be in 1..=99")]
    Priority(u8),
    /// A resumed plant's simulated time that is not a time.
    #[error("`resume.sim_time` {0} is not a time")]
    SimTime(f64),
}

/// What every node takes (`[node]`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeSettings {
    /// Run id: the processes of one run share it; runs with different ids never see
    /// each other (letters, digits, '-', '_').
    pub run_id: String,
    /// The run's configuration (a `config.toml` written by `rig run`/`rig learn`, or any
    /// file `rig config` describes).
    pub config: PathBuf,
    /// Receivers to wait for before publishing: the next process, plus the recorder of
    /// `rig run` if one is listening.
    #[serde(default = "one")]
    pub receivers: usize,
    /// Which run of the experiment this is (seeds the random streams as run `N` of
    /// `rig learn` would be).
    #[serde(default)]
    pub run_index: u32,
    /// How the process is scheduled by the operating system.
    #[serde(default)]
    pub scheduling: Scheduling,
    /// How the process waits for its next message [default: block].
    #[serde(default)]
    pub wait: Wait,
}

fn one() -> usize {
    1
}

impl NodeSettings {
    /// The settings of a node of run `run_id` on configuration `config`, scheduled
    /// and waiting as given.
    pub fn new(run_id: &str, config: &Path, scheduling: Scheduling, waiting: Waiting) -> Self {
        Self {
            run_id: run_id.to_string(),
            config: config.to_owned(),
            receivers: 1,
            run_index: 0,
            scheduling,
            wait: Wait::of(waiting),
        }
    }

    /// How the process waits for its next message.
    pub fn waiting(&self) -> Waiting {
        self.wait.waiting(WaitKind::Block)
    }

    /// Joins the run as process `role`, waiting as `wait` says.
    pub fn join(&self, role: &str) -> Result<Bus> {
        Ok(Bus::join(&self.run_id, role)?.with_waiting(self.waiting()))
    }

    /// Reads and validates the run's configuration.
    pub fn experiment(&self) -> Result<ExperimentConfig> {
        let text = std::fs::read_to_string(&self.config).at("cannot read", &self.config)?;
        Ok(resolve(Some((&self.config, &text)), &Overrides::default())?)
    }

    /// Checks what a settings file can get wrong beyond its types.
    fn check(&self) -> Result<(), Invalid> {
        self.scheduling.check()
    }
}

/// Where a resumed run's plant continues.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Continuation {
    /// The run continues after this trial (its greedy evaluations done).
    pub after_trial: u32,
    /// The simulated learning time at that trial's end \[s\].
    pub sim_time: f64,
    /// The sequence number of the first sample.
    pub first_seq: u64,
}

/// The plant node's settings ([`super::plant::run`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlantSettings {
    /// What every node takes.
    pub node: NodeSettings,
    /// What moves the run from one sample to the next [default: lockstep].
    #[serde(default = "lockstep")]
    pub clock: Clock,
    /// `clock_checked = true`: `rig run` checked `clock` against the experiment where
    /// it set the run up ([`Clock::check`]), and the node does not check it again. A
    /// file by hand leaves it out: the node checks its clock as `rig run` does.
    #[serde(
        default,
        rename = "clock_checked",
        with = "checked",
        skip_serializing_if = "Option::is_none"
    )]
    pub checked: Option<Checked>,
    /// Real time: how the plant waits for a sampling instant.
    #[serde(default)]
    pub spin: Spin,
    /// Real time and an external driver: learn across a gap in the loop's timing instead
    /// of cutting the trial's attempt short and running it again.
    #[serde(default)]
    pub learn_across_gaps: bool,
    /// Write the time from publishing each measurement to receiving its action (ns, one
    /// per line) to this file.
    #[serde(default)]
    pub latency_out: Option<PathBuf>,
    /// Real time: write every sample's timing to this CSV file
    /// ([`super::plant::CYCLES_HEADER`]).
    #[serde(default)]
    pub cycles_out: Option<PathBuf>,
    /// Continue a run ([`crate::resume`]).
    #[serde(default)]
    pub resume: Option<Continuation>,
}

fn lockstep() -> Clock {
    Clock::Lockstep
}

/// [`PlantSettings::checked`] in a settings file: `true`, or absent.
mod checked {
    use serde::de::Error;
    use serde::{Deserialize, Deserializer, Serializer};

    use crate::clock::Checked;

    pub fn serialize<S: Serializer>(c: &Option<Checked>, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_bool(c.is_some())
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Checked>, D::Error> {
        match bool::deserialize(d)? {
            true => Ok(Some(Checked(()))),
            false => Err(D::Error::custom(
                "`clock_checked` is `true` or absent: leave it out to have the clock checked",
            )),
        }
    }
}

impl PlantSettings {
    /// The plant of `node` in lockstep, from the start of the run.
    pub fn new(node: NodeSettings) -> Self {
        Self {
            node,
            clock: Clock::Lockstep,
            checked: None,
            spin: Spin::default(),
            learn_across_gaps: false,
            latency_out: None,
            cycles_out: None,
            resume: None,
        }
    }
}

/// The agent node's settings ([`super::agent::run`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AgentSettings {
    /// What every node takes.
    pub node: NodeSettings,
    /// Answer every estimate with a zero action, without learning (for loop benchmarks).
    #[serde(default)]
    pub trivial: bool,
    /// Write a checkpoint of the learned state at the end of every learning trial into
    /// this directory (`trial-NNNNNN.ckpt`, atomically).
    #[serde(default)]
    pub checkpoints: Option<PathBuf>,
    /// With `checkpoints`: keep only the N newest (0: keep all; `rig run` keeps all and
    /// removes those a resume can no longer need itself).
    #[serde(default = "two")]
    pub keep_checkpoints: usize,
    /// Start from this checkpoint's learned state (the run's trials continue after the
    /// checkpoint's trial; the plant continues after it too).
    #[serde(default)]
    pub resume: Option<PathBuf>,
}

fn two() -> usize {
    2
}

impl AgentSettings {
    /// The agent of `node`, learning, two checkpoints kept if any are written.
    pub fn new(node: NodeSettings) -> Self {
        Self {
            node,
            trivial: false,
            checkpoints: None,
            keep_checkpoints: 2,
            resume: None,
        }
    }
}

/// The observer node's settings ([`super::observer::run`]): what every node takes.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObserverSettings {
    /// What every node takes.
    pub node: NodeSettings,
}

/// A node's settings file.
pub trait Settings: Serialize + DeserializeOwned {
    /// What every node takes.
    fn node(&self) -> &NodeSettings;

    /// Checks the role's own settings (the node's are checked by [`Settings::read`]).
    fn check(&self) -> Result<(), Invalid> {
        Ok(())
    }

    /// Reads and checks the settings file `path`; an error names it.
    fn read(path: &Path) -> Result<Self, SettingsError> {
        let text = std::fs::read_to_string(path).map_err(|error| SettingsError::Read {
            path: path.to_owned(),
            error,
        })?;
        let s: Self = toml::from_str(&text).map_err(|e| SettingsError::Parse {
            path: path.to_owned(),
            line: e
                .span()
                .map_or(0, |r| text[..r.start].matches('\n').count() + 1),
            message: e.message().to_string(),
        })?;
        s.node()
            .check()
            .and_then(|()| s.check())
            .map_err(|problem| SettingsError::Invalid {
                path: path.to_owned(),
                problem,
            })?;
        Ok(s)
    }

    /// Writes the settings to `path`.
    fn write(&self, path: &Path) -> Result<(), SettingsError> {
        let error = |error| SettingsError::Write {
            path: path.to_owned(),
            error,
        };
        let text = toml::to_string(self).map_err(|e| error(std::io::Error::other(e)))?;
        std::fs::write(path, text).map_err(error)
    }
}

impl Settings for PlantSettings {
    fn node(&self) -> &NodeSettings {
        &self.node
    }

    fn check(&self) -> Result<(), Invalid> {
        match self.resume {
            Some(c) if !(c.sim_time.is_finite() && c.sim_time >= 0.0) => {
                Err(Invalid::SimTime(c.sim_time))
            }
            _ => Ok(()),
        }
    }
}

impl Settings for AgentSettings {
    fn node(&self) -> &NodeSettings {
        &self.node
    }
}

impl Settings for ObserverSettings {
    fn node(&self) -> &NodeSettings {
        &self.node
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_settings_file_by_hand_needs_the_run_and_its_configuration_only() {
        let dir = std::env::temp_dir().join(format!("node-settings-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("plant.toml");
        std::fs::write(&file, "[node]\nrun_id = \"lab1\"\nconfig = \"c.toml\"\n").unwrap();
        let plant = PlantSettings::read(&file).unwrap();
        let node = NodeSettings::new(
            "lab1",
            Path::new("c.toml"),
            Scheduling::default(),
            Waiting::Block,
        );
        // No `wait` in the file: the node blocks.
        let unsaid = NodeSettings {
            wait: Wait::default(),
            ..node.clone()
        };
        assert_eq!(plant, PlantSettings::new(unsaid));
        assert_eq!(plant.node.waiting(), Waiting::Block);
        assert_eq!(plant.node.receivers, 1);
        // What `rig run` writes is read back as it was.
        let resumed = PlantSettings {
            clock: Clock::Realtime {
                period: std::time::Duration::from_micros(2500),
            },
            resume: Some(Continuation {
                after_trial: 12,
                sim_time: 36.0,
                first_seq: 4321,
            }),
            ..PlantSettings::new(NodeSettings {
                receivers: 2,
                ..node
            })
        };
        resumed.write(&file).unwrap();
        assert_eq!(PlantSettings::read(&file).unwrap(), resumed);
        // The check `rig run` made goes with the clock, and comes back.
        let checked = PlantSettings {
            checked: Some(Checked(())),
            ..resumed
        };
        checked.write(&file).unwrap();
        let text = std::fs::read_to_string(&file).unwrap();
        assert!(text.contains("clock_checked = true"), "{text}");
        assert_eq!(PlantSettings::read(&file).unwrap(), checked);
        // A key the file may not have, a priority out of range: one line naming the file.
        for (text, says) in [
            (
                "[node]\nrun_id = \"a\"\nconfig = \"c\"\nrt_priority = 5\n",
                "unknown field `rt_priority`",
            ),
            (
                "[node]\nrun_id = \"a\"\nconfig = \"c\"\nscheduling = { rt_priority = 0 }\n",
                "`rt_priority` 0 is out of range",
            ),
            (
                "resume = { after_trial = 1, sim_time = -1.0, first_seq = 0 }\n[node]\nrun_id = \"a\"\nconfig = \"c\"\n",
                "is not a time",
            ),
            (
                "clock_checked = false\n[node]\nrun_id = \"a\"\nconfig = \"c\"\n",
                "`clock_checked` is `true` or absent",
            ),
        ] {
            std::fs::write(&file, text).unwrap();
            let e = format!("{:#}", PlantSettings::read(&file).unwrap_err());
            assert!(
                e.contains("plant.toml") && e.contains(says) && e.lines().count() == 1,
                "{e}"
            );
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
