//! The cycles of a realtime run: each sample's stamps, from the plant's cycle file
//! (`rig plant --cycles-out`) and the recording's `/timing/...` channels, and the
//! stages between them ([`super::STAGES`]).

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result, anyhow, bail};

use super::{STAGES, STAMPS};

/// Every cycle of a run.
pub(super) struct Cycles {
    /// `latency.csv`: per cycle its stamps, its stages and whether it missed.
    pub(super) csv: String,
    /// Per stage, its duration in every cycle that met its deadline (the jitter in
    /// every cycle) \[ns\].
    pub(super) stage_ns: Vec<Vec<u64>>,
    /// Cycles timed.
    pub(super) cycles: usize,
    /// Cycles whose action did not arrive within the period.
    pub(super) misses: usize,
}

/// Per-sequence-number stamps of a `/timing/...` channel.
fn timing(
    msgs: &BTreeMap<String, Vec<Vec<u8>>>,
    topic: &str,
    keys: &[&str],
) -> Result<BTreeMap<u64, Vec<u64>>> {
    let list = msgs
        .get(topic)
        .ok_or_else(|| anyhow!("the recording has no {topic}"))?;
    let mut out = BTreeMap::new();
    for data in list {
        let v: serde_json::Value = serde_json::from_slice(data)?;
        let seq = v["seq"]
            .as_u64()
            .ok_or_else(|| anyhow!("{topic}: a message without seq"))?;
        out.insert(
            seq,
            keys.iter().map(|k| v[*k].as_u64().unwrap_or(0)).collect(),
        );
    }
    Ok(out)
}

/// The `/timing/...` messages of `DIR/run.mcap`, per topic.
fn timing_messages(run_dir: &Path) -> Result<BTreeMap<String, Vec<Vec<u8>>>> {
    let bytes = std::fs::read(run_dir.join("run.mcap"))?;
    let mut msgs: BTreeMap<String, Vec<Vec<u8>>> = BTreeMap::new();
    for m in mcap::MessageStream::new(&bytes)? {
        let m = m?;
        if m.channel.topic.starts_with("/timing/") {
            msgs.entry(m.channel.topic.clone())
                .or_default()
                .push(m.data.into_owned());
        }
    }
    Ok(msgs)
}

/// The cycles of the run recorded in `run_dir`, whose plant wrote `cycles_path`, at
/// period `period_ns`.
pub(super) fn read(run_dir: &Path, cycles_path: &Path, period_ns: u64) -> Result<Cycles> {
    let msgs = timing_messages(run_dir)?;
    let meas = timing(&msgs, "/timing/plant/measurement", &["t_publish_ns"])?;
    let est = timing(
        &msgs,
        "/timing/observer/estimate",
        &["t_received_ns", "t_publish_ns"],
    )?;
    let act = timing(
        &msgs,
        "/timing/agent/action",
        &["t_received_ns", "t_publish_ns"],
    )?;
    let text = std::fs::read_to_string(cycles_path)
        .with_context(|| format!("cannot read {}", cycles_path.display()))?;
    let mut c = Cycles {
        csv: format!(
            "seq,{},{},deadline_miss\n",
            STAMPS.join(","),
            STAGES.join(",")
        ),
        stage_ns: vec![Vec::new(); STAGES.len()],
        cycles: 0,
        misses: 0,
    };
    for line in text.lines().skip(1) {
        let v: Vec<u64> = line
            .split(',')
            .map(|v| v.parse())
            .collect::<Result<_, _>>()
            .with_context(|| format!("{}: bad line {line:?}", cycles_path.display()))?;
        let [seq, t_k, woke, t_action] = v[..] else {
            bail!("{}: bad line {line:?}", cycles_path.display());
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
        bail!("{}: no cycles were recorded", cycles_path.display());
    }
    Ok(c)
}

impl Cycles {
    /// Adds cycle `seq` with its [`STAMPS`].
    fn add(&mut self, seq: u64, stamps: [u64; 9]) {
        let [t_k, woke, .., t_action, deadline] = stamps;
        self.cycles += 1;
        let missed = t_action == 0 || stamps[2..7].contains(&0);
        let _ = write!(
            self.csv,
            "{seq},{}",
            stamps.map(|s| s.to_string()).join(",")
        );
        let jitter = woke.saturating_sub(t_k);
        if missed {
            self.misses += usize::from(t_action == 0);
            self.stage_ns[0].push(jitter);
            let _ = writeln!(self.csv, ",{jitter}{},1", ",".repeat(STAGES.len() - 1));
            return;
        }
        let stage = [
            jitter,
            stamps[2].saturating_sub(t_k),
            stamps[3].saturating_sub(stamps[2]),
            stamps[4].saturating_sub(stamps[3]),
            stamps[5].saturating_sub(stamps[4]),
            stamps[6].saturating_sub(stamps[5]),
            t_action.saturating_sub(stamps[6]),
            t_action.saturating_sub(t_k),
            deadline.saturating_sub(t_action),
        ];
        for (all, v) in self.stage_ns.iter_mut().zip(&stage) {
            all.push(*v);
        }
        let _ = writeln!(self.csv, ",{},0", stage.map(|s| s.to_string()).join(","));
    }
}
