//! Checkpoints: an agent's learned state at the end of a trial, to resume a run after a
//! crash (`rig run --resume`).
//!
//! * [`Persist`] — what every learned component (approximator, critic, improver, agent)
//!   implements: it writes its learned state into a [`Snapshot`] as named arrays, and
//!   reads it back, in the same order, into a component freshly built from the same
//!   configuration. Only what learning changes is stored (weights, LLR memories, LSTD
//!   statistics, random-stream positions); the shapes come from the configuration, and a
//!   section of another shape is an error that names it.
//! * [`Checkpoint`] — a snapshot with what it belongs to (system, algorithm, seed, run,
//!   the configuration's fingerprint, the trial), stored as a versioned file: the magic
//!   bytes `RIGCKPT\0`, the format version (u32, little endian), a CRC-32 of the payload
//!   (u32), then the payload (postcard). Written atomically (temporary file, rename), so a
//!   crashed process leaves the previous checkpoint or the new one, never half of one.
//!
//! A restored agent continues bit for bit as the agent that wrote the checkpoint would
//! have (tests: `tests/tests/checkpoint.rs`).

use std::io::Write;
use std::path::Path;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The checkpoint format version this build writes and reads.
pub const VERSION: u32 = 1;

const MAGIC: &[u8; 8] = b"RIGCKPT\0";

/// What a differently configured agent's checkpoint says in each error about it.
const OTHER_AGENT: &str = "it was written by a differently configured agent";

/// Why a checkpoint cannot be read or does not fit.
#[derive(Debug, thiserror::Error)]
pub enum CheckpointError {
    /// The file cannot be read.
    #[error("{}: cannot read ({error})", path.display())]
    Read {
        /// The file.
        path: std::path::PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// The file's contents are not a checkpoint that fits.
    #[error("{}: {error}", path.display())]
    File {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong with its contents.
        error: Box<CheckpointError>,
    },
    /// No `RIGCKPT` header.
    #[error("not a rig checkpoint (no RIGCKPT header)")]
    NoHeader,
    /// Another format version.
    #[error("checkpoint format version {0}; this rig reads version {VERSION}")]
    Version(u32),
    /// The checksum does not match.
    #[error("the checkpoint is corrupt (checksum mismatch)")]
    Checksum,
    /// The payload does not decode.
    #[error("the checkpoint is corrupt ({0})")]
    Corrupt(postcard::Error),
    /// The sections end where the agent expects section `0`.
    #[error("the checkpoint ends where the agent expects `{0}`: {OTHER_AGENT}")]
    Ends(String),
    /// Another section where the agent expects one.
    #[error("the checkpoint has `{found}` where the agent expects `{want}`: {OTHER_AGENT}")]
    Misplaced {
        /// The section there.
        found: String,
        /// The section expected.
        want: String,
    },
    /// Integers where numbers are expected, or the other way round.
    #[error("checkpoint section `{section}` holds {found}, not {want}")]
    Kind {
        /// The section.
        section: String,
        /// What it holds (`integers`, `numbers`).
        found: &'static str,
        /// What the agent expects.
        want: &'static str,
    },
    /// A section of another length than the agent's.
    #[error(
        "checkpoint section `{section}` has {found} values where the configured agent has {want}: {OTHER_AGENT}"
    )]
    Length {
        /// The section.
        section: String,
        /// Its length.
        found: usize,
        /// The agent's.
        want: usize,
    },
    /// A section read as a random stream that is not one.
    #[error("checkpoint section `{0}` is not a random stream")]
    NotRng(String),
    /// Sections beyond what the agent reads.
    #[error("the checkpoint has `{0}` beyond what the agent expects: {OTHER_AGENT}")]
    Beyond(String),
    /// A component's section that does not fit the component, as it says.
    #[error("checkpoint section `{section}` {why}")]
    Unfit {
        /// The section.
        section: &'static str,
        /// How it does not fit.
        why: String,
    },
    /// A checkpoint of another system.
    #[error("the checkpoint is from system {have}, but the run's configuration is for {want}")]
    System {
        /// The checkpoint's.
        have: String,
        /// The run's.
        want: String,
    },
    /// A checkpoint of another learner.
    #[error("the checkpoint is from learner {have}, but the run's configuration uses {want}")]
    Learner {
        /// The checkpoint's.
        have: String,
        /// The run's.
        want: String,
    },
    /// A checkpoint of another seed or run.
    #[error(
        "the checkpoint is from seed {} run {}, but the run's configuration has seed {} run {}",
        .have.0, .have.1, .want.0, .want.1
    )]
    Run {
        /// The checkpoint's seed and run.
        have: (u64, u32),
        /// The run's.
        want: (u64, u32),
    },
    /// A checkpoint written under other learning parameters.
    #[error(
        "the checkpoint was written under different learning parameters than the run's configuration"
    )]
    Parameters,
}

/// The values of one section.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
enum Data {
    F64(Vec<f64>),
    U64(Vec<u64>),
}

/// A named array of a component's learned state.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
struct Section {
    name: String,
    data: Data,
}

/// Learned state as an ordered list of named arrays. Components write into it with
/// [`Snapshot::f64s`]/[`Snapshot::u64s`] inside [`Snapshot::scope`]s, so each array's
/// name says whose it is (`critic.llr.outputs`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Snapshot {
    sections: Vec<Section>,
    #[serde(skip)]
    prefix: Vec<&'static str>,
}

impl Snapshot {
    fn name(&self, name: &str) -> String {
        let mut s = self.prefix.join(".");
        if !s.is_empty() {
            s.push('.');
        }
        s.push_str(name);
        s
    }

    /// Writes the sections of `f` under the scope `name`.
    pub fn scope(&mut self, name: &'static str, f: impl FnOnce(&mut Self)) {
        self.prefix.push(name);
        f(self);
        self.prefix.pop();
    }

    /// Adds an array of numbers.
    pub fn f64s(&mut self, name: &str, v: &[f64]) {
        let name = self.name(name);
        self.sections.push(Section {
            name,
            data: Data::F64(v.to_vec()),
        });
    }

    /// Adds an array of integers.
    pub fn u64s(&mut self, name: &str, v: &[u64]) {
        let name = self.name(name);
        self.sections.push(Section {
            name,
            data: Data::U64(v.to_vec()),
        });
    }

    /// Adds a random stream's position (seed, stream id, word position).
    pub fn rng(&mut self, name: &str, rng: &ChaCha8Rng) {
        let seed = rng.get_seed();
        let mut v: Vec<u64> = seed
            .chunks(8)
            .map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes")))
            .collect();
        let pos = rng.get_word_pos();
        v.extend([rng.get_stream(), pos as u64, (pos >> 64) as u64]);
        self.u64s(name, &v);
    }

    /// A reader over the sections, from the first.
    pub fn reader(&self) -> Reader<'_> {
        Reader {
            sections: &self.sections,
            next: 0,
            prefix: Vec::new(),
        }
    }

    /// Number of sections.
    pub fn len(&self) -> usize {
        self.sections.len()
    }

    /// Whether there are no sections.
    pub fn is_empty(&self) -> bool {
        self.sections.is_empty()
    }
}

/// Reads a [`Snapshot`]'s sections back in the order they were written, checking names
/// and lengths.
pub struct Reader<'a> {
    sections: &'a [Section],
    next: usize,
    prefix: Vec<&'static str>,
}

impl<'a> Reader<'a> {
    fn take(&mut self, name: &str) -> Result<&'a Data, CheckpointError> {
        let mut want = self.prefix.join(".");
        if !want.is_empty() {
            want.push('.');
        }
        want.push_str(name);
        let Some(s) = self.sections.get(self.next) else {
            return Err(CheckpointError::Ends(want));
        };
        if s.name != want {
            return Err(CheckpointError::Misplaced {
                found: s.name.clone(),
                want,
            });
        }
        self.next += 1;
        Ok(&s.data)
    }

    /// Reads the sections of `f` under the scope `name`.
    pub fn scope<T>(
        &mut self,
        name: &'static str,
        f: impl FnOnce(&mut Self) -> Result<T, CheckpointError>,
    ) -> Result<T, CheckpointError> {
        self.prefix.push(name);
        let r = f(self);
        self.prefix.pop();
        r
    }

    /// Reads an array of numbers of any length.
    pub fn f64s(&mut self, name: &str) -> Result<&'a [f64], CheckpointError> {
        match self.take(name)? {
            Data::F64(v) => Ok(v),
            Data::U64(_) => Err(CheckpointError::Kind {
                section: name.to_string(),
                found: "integers",
                want: "numbers",
            }),
        }
    }

    /// Reads an array of integers of any length.
    pub fn u64s(&mut self, name: &str) -> Result<&'a [u64], CheckpointError> {
        match self.take(name)? {
            Data::U64(v) => Ok(v),
            Data::F64(_) => Err(CheckpointError::Kind {
                section: name.to_string(),
                found: "numbers",
                want: "integers",
            }),
        }
    }

    /// Reads an array of numbers into `out`, which must have its length.
    pub fn f64s_into(&mut self, name: &str, out: &mut [f64]) -> Result<(), CheckpointError> {
        let v = self.f64s(name)?;
        if v.len() != out.len() {
            return Err(CheckpointError::Length {
                section: name.to_string(),
                found: v.len(),
                want: out.len(),
            });
        }
        out.copy_from_slice(v);
        Ok(())
    }

    /// Reads a random stream's position written by [`Snapshot::rng`].
    pub fn rng(&mut self, name: &str) -> Result<ChaCha8Rng, CheckpointError> {
        let v = self.u64s(name)?;
        if v.len() != 7 {
            return Err(CheckpointError::NotRng(name.to_string()));
        }
        let mut seed = [0u8; 32];
        for (c, w) in seed.chunks_mut(8).zip(&v[..4]) {
            c.copy_from_slice(&w.to_le_bytes());
        }
        let mut rng = ChaCha8Rng::from_seed(seed);
        rng.set_stream(v[4]);
        rng.set_word_pos(u128::from(v[5]) | (u128::from(v[6]) << 64));
        Ok(rng)
    }

    /// Checks that every section was read.
    pub fn finish(&self) -> Result<(), CheckpointError> {
        match self.sections.get(self.next) {
            None => Ok(()),
            Some(s) => Err(CheckpointError::Beyond(s.name.clone())),
        }
    }
}

/// Learned state that can be saved into a [`Snapshot`] and restored from one.
pub trait Persist {
    /// Writes the learned state.
    fn save(&self, s: &mut Snapshot);
    /// Reads the learned state written by [`Persist::save`] of a component built from
    /// the same configuration.
    fn restore(&mut self, r: &mut Reader) -> Result<(), CheckpointError>;
}

/// What a checkpoint belongs to.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Origin {
    /// The system (`pendulum`, `arm-6.4`, ...).
    pub system: String,
    /// `algo/approx/horizon`, e.g. `mlac/llr/infinite`.
    pub learner: String,
    /// The experiment seed.
    pub seed: u64,
    /// The run index within the experiment.
    pub run: u32,
    /// [`fingerprint`] of the configuration's learning-relevant part, as the caller
    /// defines it (every key but those that only say how long and how often to run).
    pub fingerprint: u64,
}

/// A fingerprint of `bytes` (a configuration's text, for [`Origin::fingerprint`]):
/// FNV-1a, 64 bit, stable across builds and platforms.
pub fn fingerprint(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

/// An agent's learned state after a trial, with where it belongs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The run it belongs to.
    pub origin: Origin,
    /// The last completed learning trial (1-based).
    pub trial: u32,
    /// Simulated learning time at the end of that trial \[s\] (trials that left the
    /// operating range count only the samples run).
    pub sim_time_s: f64,
    /// The learned state.
    pub state: Snapshot,
}

impl Checkpoint {
    /// Encodes the checkpoint as file contents.
    pub fn to_bytes(&self) -> Vec<u8> {
        let payload = postcard::to_stdvec(self).expect("a checkpoint always serialises");
        let mut out = Vec::with_capacity(payload.len() + 16);
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&crc32fast::hash(&payload).to_le_bytes());
        out.extend_from_slice(&payload);
        out
    }

    /// Decodes file contents written by [`Checkpoint::to_bytes`].
    pub fn from_bytes(bytes: &[u8]) -> Result<Self, CheckpointError> {
        if bytes.len() < 16 || &bytes[..8] != MAGIC {
            return Err(CheckpointError::NoHeader);
        }
        let version = u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes"));
        if version != VERSION {
            return Err(CheckpointError::Version(version));
        }
        let crc = u32::from_le_bytes(bytes[12..16].try_into().expect("4 bytes"));
        let payload = &bytes[16..];
        if crc32fast::hash(payload) != crc {
            return Err(CheckpointError::Checksum);
        }
        postcard::from_bytes(payload).map_err(CheckpointError::Corrupt)
    }

    /// Writes the checkpoint to `path` atomically: a temporary file beside it, renamed
    /// over `path` — a process killed at any moment leaves the old file or the new one.
    /// It is not synced to disk (measured: an `fsync` per trial made the default
    /// `rig run` about 50 % slower on a 2-core VM); after a power failure the newest
    /// checkpoint may be corrupt, which its CRC reveals.
    pub fn write(&self, path: &Path) -> std::io::Result<()> {
        let tmp = path.with_extension("ckpt.tmp");
        let written = std::fs::File::create(&tmp)
            .and_then(|mut f| f.write_all(&self.to_bytes()))
            .and_then(|()| std::fs::rename(&tmp, path));
        if written.is_err() {
            // What did fit (a full disk) is of no use.
            let _ = std::fs::remove_file(&tmp);
        }
        written
    }

    /// Reads a checkpoint file; the error names the file.
    pub fn read(path: &Path) -> Result<Self, CheckpointError> {
        let bytes = std::fs::read(path).map_err(|error| CheckpointError::Read {
            path: path.to_owned(),
            error,
        })?;
        Self::from_bytes(&bytes).map_err(|e| CheckpointError::File {
            path: path.to_owned(),
            error: Box::new(e),
        })
    }

    /// Restores `agent`, built for the run `want` describes, to the learned state of this
    /// checkpoint, after checking that the checkpoint belongs to that run.
    pub fn restore(
        &self,
        want: &Origin,
        agent: &mut dyn crate::Agent,
    ) -> Result<(), CheckpointError> {
        self.check_origin(want)?;
        let mut r = self.state.reader();
        agent.restore(&mut r)?;
        r.finish()
    }

    /// Checks that the checkpoint belongs to the run `want` describes.
    pub fn check_origin(&self, want: &Origin) -> Result<(), CheckpointError> {
        let have = &self.origin;
        if have.system != want.system {
            return Err(CheckpointError::System {
                have: have.system.clone(),
                want: want.system.clone(),
            });
        }
        if have.learner != want.learner {
            return Err(CheckpointError::Learner {
                have: have.learner.clone(),
                want: want.learner.clone(),
            });
        }
        if (have.seed, have.run) != (want.seed, want.run) {
            return Err(CheckpointError::Run {
                have: (have.seed, have.run),
                want: (want.seed, want.run),
            });
        }
        if have.fingerprint != want.fingerprint {
            return Err(CheckpointError::Parameters);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng;

    fn sample() -> Checkpoint {
        let mut s = Snapshot::default();
        s.scope("critic", |s| {
            s.f64s("theta", &[1.0, -2.5, f64::MIN_POSITIVE]);
            s.u64s("seq", &[3, u64::MAX]);
        });
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        rng.set_stream(1);
        let _: u64 = rng.next_u64();
        s.rng("exploration", &rng);
        Checkpoint {
            origin: pendulum(0),
            trial: 7,
            sim_time_s: 21.0,
            state: s,
        }
    }

    fn pendulum(run: u32) -> Origin {
        Origin {
            system: "pendulum".into(),
            learner: "mlac/llr/infinite".into(),
            seed: 1,
            run,
            fingerprint: fingerprint(b"[learning]\ngamma = 0.97\n"),
        }
    }

    #[test]
    fn round_trips_bit_for_bit() {
        let c = sample();
        let back = Checkpoint::from_bytes(&c.to_bytes()).unwrap();
        assert_eq!(back, c);
        let mut r = back.state.reader();
        r.scope("critic", |r| {
            let mut theta = [0.0; 3];
            r.f64s_into("theta", &mut theta)?;
            assert_eq!(theta, [1.0, -2.5, f64::MIN_POSITIVE]);
            assert_eq!(r.u64s("seq")?, &[3, u64::MAX]);
            Ok(())
        })
        .unwrap();
        let mut rng = r.rng("exploration").unwrap();
        let mut want = ChaCha8Rng::seed_from_u64(5);
        want.set_stream(1);
        let _: u64 = want.next_u64();
        assert_eq!(rng.next_u64(), want.next_u64());
        r.finish().unwrap();
    }

    #[test]
    fn corruption_version_and_shape_errors_say_what() {
        let bytes = sample().to_bytes();
        let mut flipped = bytes.clone();
        let last = flipped.len() - 1;
        flipped[last] ^= 1;
        let e = Checkpoint::from_bytes(&flipped).unwrap_err().to_string();
        assert!(e.contains("corrupt"), "{e}");
        let e = Checkpoint::from_bytes(&bytes[..bytes.len() / 2])
            .unwrap_err()
            .to_string();
        assert!(e.contains("corrupt"), "{e}");
        let mut newer = bytes.clone();
        newer[8] = 2;
        let e = Checkpoint::from_bytes(&newer).unwrap_err().to_string();
        assert!(e.contains("version 2"), "{e}");
        let e = Checkpoint::from_bytes(b"hello").unwrap_err().to_string();
        assert!(e.contains("not a rig checkpoint"), "{e}");

        let c = sample();
        let mut r = c.state.reader();
        let e = r
            .scope("critic", |r| r.f64s_into("theta", &mut [0.0; 4]))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("`theta` has 3 values") || e.contains("critic.theta"),
            "{e}"
        );
        let mut r = c.state.reader();
        let e = r.f64s("actor").unwrap_err().to_string();
        assert!(
            e.contains("`critic.theta` where the agent expects `actor`"),
            "{e}"
        );
    }

    #[test]
    fn origin_mismatches_are_named() {
        let c = sample();
        c.check_origin(&pendulum(0)).unwrap();
        let e = c.check_origin(&pendulum(1)).unwrap_err().to_string();
        assert!(e.contains("run 1"), "{e}");
        let arm = Origin {
            system: "arm-vertical".into(),
            ..pendulum(0)
        };
        let e = c.check_origin(&arm).unwrap_err().to_string();
        assert!(e.contains("from system pendulum"), "{e}");
        let sac = Origin {
            learner: "sac/llr/infinite".into(),
            ..pendulum(0)
        };
        let e = c.check_origin(&sac).unwrap_err().to_string();
        assert!(e.contains("from learner mlac/llr/infinite"), "{e}");
        let tuned = Origin {
            fingerprint: fingerprint(b"[learning]\ngamma = 0.5\n"),
            ..pendulum(0)
        };
        let e = c.check_origin(&tuned).unwrap_err().to_string();
        assert!(e.contains("different learning parameters"), "{e}");
    }

    #[test]
    fn the_fingerprint_is_fnv_1a() {
        // The published FNV-1a 64 test vectors: a checkpoint's fingerprint never changes.
        assert_eq!(fingerprint(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fingerprint(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fingerprint(b"foobar"), 0x8594_4171_f739_67e8);
    }
}
