//! The cycles of a realtime run: each sample's stamps, from the plant's cycle file
//! (the plant node's `cycles_out`) and the recording's `/timing/...` channels, and the
//! stages between them ([`super::STAGES`]).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use runtime::error::AtFile;
use runtime::record::channels::{DRIVER_PREFIX, TIMING};
use runtime::record::reader::{NAME, RunFile};

use super::error::LatencyError;

use super::{STAGES, STAMPS};

/// Every cycle of a run.
pub(super) struct Cycles {
    /// `latency.csv`: per cycle its stamps, its stages and whether it missed.
    pub(super) csv: String,
    /// The stages' names, in `csv`'s and `stage_ns`'s order.
    pub(super) names: &'static [&'static str],
    /// Per stage, its duration in every cycle where it was measured \[ns\].
    pub(super) stage_ns: Vec<Vec<u64>>,
    /// Cycles timed.
    pub(super) cycles: usize,
    /// Cycles whose action did not arrive within the period.
    pub(super) misses: usize,
}

impl Cycles {
    /// No cycles yet, with these stamp and stage columns.
    pub(super) fn new(stamps: &[&str], stages: &'static [&'static str]) -> Self {
        Self {
            csv: format!(
                "seq,{},{},deadline_miss\n",
                stamps.join(","),
                stages.join(",")
            ),
            names: stages,
            stage_ns: vec![Vec::new(); stages.len()],
            cycles: 0,
            misses: 0,
        }
    }

    /// Adds cycle `seq`: its stamps, its stages (`None`: not measured, an empty column)
    /// and whether it missed its deadline (`misses` is the caller's to count).
    pub(super) fn push(&mut self, seq: u64, stamps: &[u64], stages: &[Option<u64>], missed: bool) {
        self.cycles += 1;
        let _ = write!(self.csv, "{seq}");
        for s in stamps {
            let _ = write!(self.csv, ",{s}");
        }
        for (all, v) in self.stage_ns.iter_mut().zip(stages) {
            match v {
                Some(v) => {
                    all.push(*v);
                    let _ = write!(self.csv, ",{v}");
                }
                None => self.csv.push(','),
            }
        }
        let _ = writeln!(self.csv, ",{}", u8::from(missed));
    }
}

/// The recording's messages of the topics `rig latency` reads, per topic.
pub(super) type Messages = BTreeMap<String, Vec<Vec<u8>>>;

/// The messages of `topic`, parsed.
pub(super) fn json(msgs: &Messages, topic: &str) -> Result<Vec<serde_json::Value>, LatencyError> {
    msgs.get(topic)
        .ok_or_else(|| LatencyError::NoTopic(topic.to_owned()))?
        .iter()
        .map(|d| {
            serde_json::from_slice(d).map_err(|error| LatencyError::Json {
                topic: topic.to_owned(),
                error,
            })
        })
        .collect()
}

/// Field `key` of a message of `topic`, an unsigned integer.
pub(super) fn int(v: &serde_json::Value, key: &str, topic: &str) -> Result<u64, LatencyError> {
    v[key].as_u64().ok_or_else(|| LatencyError::NoKey {
        topic: topic.to_owned(),
        key: key.to_owned(),
    })
}

/// Per-sequence-number stamps of a `/timing/...` channel (0 where a key is missing).
pub(super) fn timing(
    msgs: &Messages,
    topic: &str,
    keys: &[&str],
) -> Result<BTreeMap<u64, Vec<u64>>, LatencyError> {
    json(msgs, topic)?
        .iter()
        .map(|v| {
            let stamps = keys.iter().map(|k| v[*k].as_u64().unwrap_or(0)).collect();
            Ok((int(v, "seq", topic)?, stamps))
        })
        .collect()
}

/// The `/timing/...` and `/driver/...` messages of `DIR/run.mcap`, per topic.
pub(super) fn messages(run_dir: &Path) -> Result<Messages, LatencyError> {
    let path = run_dir.join(NAME);
    let file = RunFile::read(&path).at("cannot read", &path)?;
    let mut msgs = Messages::new();
    for m in file.messages()? {
        let m = m?;
        let topic = &m.channel.topic;
        if TIMING.contains(&topic.as_str()) || topic.starts_with(DRIVER_PREFIX) {
            msgs.entry(topic.clone())
                .or_default()
                .push(m.data.into_owned());
        }
    }
    Ok(msgs)
}

/// The cycles of the run recorded in `run_dir`, whose plant wrote `cycles_path`, at
/// period `period_ns`.
pub(super) fn read(
    run_dir: &Path,
    cycles_path: &Path,
    period_ns: u64,
) -> Result<Cycles, LatencyError> {
    let msgs = messages(run_dir)?;
    let meas = timing(&msgs, TIMING[0], &["t_publish_ns"])?;
    let est = timing(&msgs, TIMING[1], &["t_received_ns", "t_publish_ns"])?;
    let act = timing(&msgs, TIMING[2], &["t_received_ns", "t_publish_ns"])?;
    let text = std::fs::read_to_string(cycles_path).at("cannot read", cycles_path)?;
    let mut c = Cycles::new(&STAMPS, &STAGES);
    for line in text.lines().skip(1) {
        let v: Vec<u64> = line
            .split(',')
            .map(|v| v.parse())
            .collect::<Result<_, _>>()
            .map_err(|e| bad_line(cycles_path, line, Some(e)))?;
        let [seq, t_k, woke, t_action] = v[..] else {
            return Err(bad_line(cycles_path, line, None));
        };
        let get = |m: &BTreeMap<u64, Vec<u64>>, i: usize| m.get(&seq).map_or(0, |v| v[i]);
        let stamps = [
            t_k,
            woke,
            get(&meas, 0),
            get(&est, 0),
            get(&est, 1),
            get(&act, 0),
            get(&act, 1),
            t_action,
            t_k + period_ns,
        ];
        c.add(seq, stamps);
    }
    if c.cycles == 0 {
        return Err(LatencyError::NoCycles(cycles_path.to_owned()));
    }
    Ok(c)
}

impl Cycles {
    /// Adds cycle `seq` of a simulated plant with its [`STAMPS`].
    fn add(&mut self, seq: u64, stamps: [u64; 9]) {
        let [t_k, woke, .., t_action, deadline] = stamps;
        let missed = t_action == 0 || stamps[2..7].contains(&0);
        self.misses += usize::from(t_action == 0);
        let jitter = Some(woke.saturating_sub(t_k));
        let stages = if missed {
            [jitter, None, None, None, None, None, None, None, None]
        } else {
            [
                jitter,
                Some(stamps[2].saturating_sub(t_k)),
                Some(stamps[3].saturating_sub(stamps[2])),
                Some(stamps[4].saturating_sub(stamps[3])),
                Some(stamps[5].saturating_sub(stamps[4])),
                Some(stamps[6].saturating_sub(stamps[5])),
                Some(t_action.saturating_sub(stamps[6])),
                Some(t_action.saturating_sub(t_k)),
                Some(deadline.saturating_sub(t_action)),
            ]
        };
        self.push(seq, &stamps, &stages, missed);
    }
}

/// A line of the cycles' file at `path` that is not four integers.
fn bad_line(path: &Path, line: &str, source: Option<std::num::ParseIntError>) -> LatencyError {
    LatencyError::BadLine {
        path: path.to_owned(),
        line: line.to_owned(),
        source,
    }
}
