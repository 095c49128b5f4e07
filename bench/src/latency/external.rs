//! The cycles of a run against an external driver (`rig latency --driver ID`): each
//! driver sample answered by an action, its stamps from the recording's `/driver/...`
//! and `/timing/...` channels, and the stages between them ([`DRIVER_STAGES`]).
//!
//! The driver is the clock and may sit on another host behind the rig's bridge
//! (`rig bridge rig`, docs/across-hosts.md). Its stamps (`t_k`) reach the recording on
//! the rig's clock only as well as the bridge could map them, so a stage that spans both
//! hosts is reported only where they read one clock (`rig bridge … --same-clock`, or a
//! driver on this host). The link's round trip needs no common clock: each host's share
//! is measured on its own and subtracted.

use std::collections::BTreeMap;
use std::fmt::Write as _;

use super::error::LatencyError;
use driver::contract::kind;
use runtime::record::channels::{DRIVER_COMMAND, DRIVER_LINK, DRIVER_SAMPLE, TIMING};

use super::cycles::{Cycles, Messages, int, json, timing};

/// Stage names, in cycle order, as `latency.csv` columns (ns) and summary rows. A stage
/// not measured in a run (no bridge, or two clocks) is left out of its summary.
pub const DRIVER_STAGES: [&str; 13] = [
    "driver_to_rig",
    "rig_to_measurement",
    "plant_to_observer",
    "observer",
    "observer_to_agent",
    "agent",
    "agent_to_command",
    "rig_to_driver",
    "link_round_trip",
    "rig_turnaround",
    "sample_to_command",
    "sample_to_actuation",
    "slack",
];

/// Timestamp and duration columns of `latency.csv` (ns; 0: not recorded).
pub const DRIVER_STAMPS: [&str; 11] = [
    "t_sample_ns",
    "t_rig_received_ns",
    "t_measurement_publish_ns",
    "t_observer_received_ns",
    "t_observer_publish_ns",
    "t_agent_received_ns",
    "t_agent_publish_ns",
    "t_command_publish_ns",
    "sample_hop_ns",
    "command_hop_ns",
    "link_round_trip_ns",
];

/// How the driver's samples reached the rig.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reach {
    /// The driver runs on this host: its stamps are on the rig's clock.
    Local,
    /// Across hosts whose clocks are one (the bridges' `--same-clock`).
    AcrossOneClock,
    /// Across hosts with clocks of their own: the bridge mapped the driver's stamps with
    /// an offset known to within the given uncertainty (median over the run) \[ns\].
    AcrossTwoClocks {
        /// The median of the offset's uncertainty (half the round trip it was taken
        /// from) \[ns\].
        uncertainty_ns: u64,
    },
}

impl Reach {
    /// Whether stamps of both hosts may be subtracted.
    fn one_clock(self) -> bool {
        !matches!(self, Reach::AcrossTwoClocks { .. })
    }
}

/// A driver sample as recorded: when it was taken and the last command applied by then.
#[derive(Clone, Copy)]
struct Sample {
    t_sample: u64,
    last_command: u64,
}

/// The link's timing of a sample (`/driver/link`).
#[derive(Clone, Copy)]
struct LinkTiming {
    t_received: u64,
    sample_hop: u64,
    command_round_trip: u64,
    command_hop: u64,
}

/// Reads the cycles of the run recorded in `msgs`, with the driver's period
/// `period_ns`; returns them and how the samples reached the rig.
pub(super) fn read(msgs: &Messages, period_ns: u64) -> Result<(Cycles, Reach), LatencyError> {
    let samples = samples(msgs)?;
    let (link, reach) = link(msgs)?;
    // The measurement built from a driver sample carries its t_k.
    let meas: BTreeMap<u64, Vec<u64>> = timing(msgs, TIMING[0], &["t_sample_ns", "t_publish_ns"])?
        .into_iter()
        .map(|(seq, v)| (v[0], vec![seq, v[1]]))
        .collect();
    let est = timing(msgs, TIMING[1], &["t_received_ns", "t_publish_ns"])?;
    let act = timing(msgs, TIMING[2], &["t_received_ns", "t_publish_ns"])?;
    let acknowledged = acknowledging(&samples, &link);
    let mut c = Cycles::new(&DRIVER_STAMPS, &DRIVER_STAGES);
    for cmd in commands(msgs)? {
        let Some(s) = samples.get(&cmd.sample_seq) else {
            continue;
        };
        let t_k = s.t_sample;
        let [m, t_meas] = meas.get(&t_k).map_or([0, 0], |v| [v[0], v[1]]);
        let get = |map: &BTreeMap<u64, Vec<u64>>, i: usize| map.get(&m).map_or(0, |v| v[i]);
        let here = link.get(&cmd.sample_seq);
        let back = acknowledged.get(&cmd.seq);
        let stamps = [
            t_k,
            here.map_or(0, |l| l.t_received),
            t_meas,
            get(&est, 0),
            get(&est, 1),
            get(&act, 0),
            get(&act, 1),
            cmd.t_publish,
            here.map_or(0, |l| l.sample_hop),
            back.map_or(0, |l| l.command_hop),
            back.map_or(0, |l| l.command_round_trip),
        ];
        // Applied by the next sample, as the plant counts it.
        let applied = samples
            .get(&(cmd.sample_seq + 1))
            .is_some_and(|n| n.last_command == cmd.seq);
        c.push(
            cmd.sample_seq,
            &stamps,
            &stages(&stamps, reach, period_ns),
            !applied,
        );
        c.misses += usize::from(!applied);
    }
    if c.cycles == 0 {
        return Err(LatencyError::NoCommands);
    }
    Ok((c, reach))
}

/// The stages of one cycle from its [`DRIVER_STAMPS`]; `None` where not measured.
fn stages(s: &[u64; 11], reach: Reach, period_ns: u64) -> [Option<u64>; 13] {
    let [
        t_k,
        rig,
        meas,
        est_in,
        est_out,
        act_in,
        act_out,
        cmd,
        hop,
        cmd_hop,
        rtt,
    ] = *s;
    let diff = |later: u64, earlier: u64| {
        (later != 0 && earlier != 0).then(|| later.saturating_sub(earlier))
    };
    let nonzero = |v: u64| (v != 0).then_some(v);
    // Where the sample entered this host: the rig's bridge, or the driver itself.
    let arrived = if reach == Reach::Local { t_k } else { rig };
    let one_clock = reach.one_clock();
    [
        nonzero(hop),
        diff(meas, arrived),
        diff(est_in, meas),
        diff(est_out, est_in),
        diff(act_in, est_out),
        diff(act_out, act_in),
        diff(cmd, act_out),
        nonzero(cmd_hop),
        nonzero(rtt),
        if reach == Reach::Local {
            None
        } else {
            diff(cmd, rig)
        },
        one_clock.then(|| diff(cmd, t_k)).flatten(),
        // Across hosts on one clock: until the command reached the driver's bridge (as
        // the bridge's `--timing-out` file has it).
        (one_clock && cmd_hop != 0)
            .then(|| diff(cmd, t_k).map(|d| d + cmd_hop))
            .flatten(),
        // The deadline is the driver's: across hosts on one clock, the command's hop
        // to the driver's bridge counts against it.
        one_clock
            .then(|| (cmd != 0).then(|| (t_k + period_ns).saturating_sub(cmd + cmd_hop)))
            .flatten(),
    ]
}

/// An action command as recorded.
struct Command {
    seq: u64,
    sample_seq: u64,
    t_publish: u64,
}

/// The ACTION commands of `/driver/command`, in order.
fn commands(msgs: &Messages) -> Result<Vec<Command>, LatencyError> {
    let mut out = Vec::new();
    for v in json(msgs, DRIVER_COMMAND)? {
        if v["kind"].as_u64() == Some(kind::ACTION) {
            out.push(Command {
                seq: int(&v, "seq", DRIVER_COMMAND)?,
                sample_seq: int(&v, "sample_seq", DRIVER_COMMAND)?,
                t_publish: int(&v, "t_publish_ns", DRIVER_COMMAND)?,
            });
        }
    }
    Ok(out)
}

/// The driver samples of `/driver/sample`, by sequence number.
fn samples(msgs: &Messages) -> Result<BTreeMap<u64, Sample>, LatencyError> {
    json(msgs, DRIVER_SAMPLE)?
        .iter()
        .map(|v| {
            let t = DRIVER_SAMPLE;
            Ok((
                int(v, "seq", t)?,
                Sample {
                    t_sample: int(v, "t_sample_ns", t)?,
                    last_command: int(v, "last_command", t)?,
                },
            ))
        })
        .collect()
}

/// The link's timing per sample (`/driver/link`; none with a driver on this host) and
/// how the samples reached the rig.
fn link(msgs: &Messages) -> Result<(BTreeMap<u64, LinkTiming>, Reach), LatencyError> {
    if !msgs.contains_key(DRIVER_LINK) {
        return Ok((BTreeMap::new(), Reach::Local));
    }
    let t = DRIVER_LINK;
    let mut out = BTreeMap::new();
    let mut uncertainty = Vec::new();
    let mut one_clock = false;
    for v in json(msgs, t)? {
        let l = LinkTiming {
            t_received: int(&v, "t_received_ns", t)?,
            sample_hop: int(&v, "sample_hop_ns", t)?,
            command_round_trip: int(&v, "command_round_trip_ns", t)?,
            command_hop: int(&v, "command_hop_ns", t)?,
        };
        one_clock |= l.sample_hop != 0;
        uncertainty.push(int(&v, "clock_uncertainty_ns", t)?);
        out.insert(int(&v, "seq", t)?, l);
    }
    if out.is_empty() {
        return Ok((out, Reach::Local));
    }
    let reach = if one_clock {
        Reach::AcrossOneClock
    } else {
        uncertainty.sort_unstable();
        Reach::AcrossTwoClocks {
            uncertainty_ns: uncertainty[uncertainty.len() / 2],
        }
    };
    Ok((out, reach))
}

/// Per command sequence number, the link timing of the first sample that reports it
/// applied: its round trip is that command's.
fn acknowledging(
    samples: &BTreeMap<u64, Sample>,
    link: &BTreeMap<u64, LinkTiming>,
) -> BTreeMap<u64, LinkTiming> {
    let mut out = BTreeMap::new();
    for (seq, s) in samples {
        if let Some(l) = link.get(seq) {
            out.entry(s.last_command).or_insert(*l);
        }
    }
    out
}

/// A line for the summary: how the samples reached the rig and what that allows.
pub(super) fn describe(reach: Reach) -> String {
    let mut s = String::new();
    let _ = match reach {
        Reach::Local => write!(s, "driver on this host (one clock)"),
        Reach::AcrossOneClock => write!(
            s,
            "driver on another host, through the bridges, on one clock: one-way hops shown"
        ),
        Reach::AcrossTwoClocks { uncertainty_ns } => write!(
            s,
            "driver on another host, through the bridges, on two clocks (offset known to ±{:.1} µs): round trips only, no one-way hop",
            uncertainty_ns as f64 * 1e-3
        ),
    };
    s
}
