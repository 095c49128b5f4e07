//! The transport alone: a ping-pong of `Measurement`s between two `rig pong` processes,
//! started the way the loop's processes are, waiting the way they are told.

use std::path::Path;
use std::time::Duration;

use runtime::error::AtFile;
use runtime::process::{CpuSet, Wait};
use wire::{Bus, Measurement, Waiting, now_ns};

use super::{Kill, LoopError, spawn};

/// Round trips before the timed ones.
const WARM_UP: usize = 1000;

/// One side of the ping-pong (`rig pong`). The echo returns every message on `pong`
/// until a message with `seq == u64::MAX`; with `ping = Some((n, file))` this side sends
/// instead, times `n` round trips after 1000 of warm-up and writes them to `file` \[ns, one
/// per line\]. With `pin_cpus` the echo is pinned to the plant's CPU, the pinger to the
/// others.
pub fn pong(
    run_id: &str,
    pin_cpus: bool,
    waiting: Waiting,
    ping: Option<(usize, &Path)>,
) -> Result<(), LoopError> {
    if pin_cpus {
        runtime::process::cpus::pin(if ping.is_some() {
            CpuSet::Others
        } else {
            CpuSet::Last
        })?;
    }
    let role = if ping.is_some() { "ping" } else { "pong" };
    let bus = Bus::join(run_id, role)?.with_waiting(waiting);
    let (inbox, outbox) = if ping.is_some() {
        ("pong", "ping")
    } else {
        ("ping", "pong")
    };
    let rx = bus.rx::<Measurement>(inbox)?;
    let tx = bus.tx::<Measurement>(outbox)?;
    tx.wait_for_receivers(1, Duration::from_secs(30), &bus)?;
    let Some((samples, file)) = ping else {
        loop {
            let m = rx.recv(&bus, Duration::from_secs(30))?;
            tx.send(m)?;
            if m.header.seq == u64::MAX {
                return Ok(());
            }
        }
    };
    let mut rtt = Vec::with_capacity(samples);
    let mut m = Measurement::default();
    for i in 0..samples + WARM_UP {
        m.header.seq = i as u64;
        let t0 = now_ns();
        tx.send(m)?;
        let back = rx.recv(&bus, Duration::from_secs(10))?;
        let dt = now_ns() - t0;
        if back.header.seq != i as u64 {
            return Err(LoopError::OutOfStep {
                sent: i,
                got: back.header.seq,
            });
        }
        if i >= WARM_UP {
            rtt.push(dt.to_string());
        }
    }
    m.header.seq = u64::MAX;
    tx.send(m)?;
    let _ = rx.recv(&bus, Duration::from_secs(10));
    Ok(std::fs::write(file, rtt.join("\n")).at("cannot write", file)?)
}

/// `samples` round trips \[ns\] between two `rig pong` processes waiting as `waiting`
/// says, pinned as the loop's processes are with `pin_cpus`; their output in
/// `out/pong-<tag>.log`.
pub fn raw_round_trips(
    exe: &Path,
    out: &Path,
    samples: usize,
    pin_cpus: bool,
    waiting: Waiting,
) -> Result<Vec<u64>, LoopError> {
    let run_id = format!("raw{}-{}", std::process::id(), now_ns() % 1_000_000);
    let tag = Wait::process_args(waiting).join("").replace("--", "-");
    let file = out.join(format!("pong{tag}.txt"));
    let samples_s = samples.to_string();
    let mut common = vec!["pong".to_string(), "--run-id".into(), run_id];
    common.extend(Wait::process_args(waiting));
    if pin_cpus {
        common.push("--pin-cpus".into());
    }
    let echo: Vec<&str> = common.iter().map(String::as_str).collect();
    let mut ping = echo.clone();
    ping.extend(["--ping", &samples_s, "--rtt-out"]);
    let file_s = file.to_string_lossy().to_string();
    ping.push(&file_s);
    let mut kids = Kill(vec![spawn(
        exe,
        &echo,
        &out.join(format!("pong{tag}.log")),
    )?]);
    kids.0
        .push(spawn(exe, &ping, &out.join(format!("ping{tag}.log")))?);
    for (c, name) in kids.0.iter_mut().zip(["echo", "ping"]) {
        let status = c.wait()?;
        if !status.success() {
            return Err(LoopError::PingPong {
                name,
                status,
                dir: out.to_owned(),
            });
        }
    }
    kids.0.clear();
    let text = std::fs::read_to_string(&file).at("cannot read", &file)?;
    text.lines()
        .map(|l| {
            l.parse().map_err(|source| LoopError::BadLine {
                path: file.clone(),
                line: l.to_owned(),
                source,
            })
        })
        .collect()
}
