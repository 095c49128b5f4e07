//! `rig run --live`: the official Foxglove WebSocket client (`@foxglove/ws-protocol`, run
//! by Node: `tests/live/client.mjs`) subscribes to a run's live view and receives every
//! channel of the recording, the trials' returns, the loop's latency and the system's
//! picture; each message it decodes equals the run's own `run.mcap` and `returns.csv`,
//! byte for byte and value for value. A viewer that stops reading holds the loop back in
//! nothing: the run's results are those of a run without the live view. A rig built
//! without the `live` feature refuses `--live` in one line naming the command that builds
//! it.

use std::path::PathBuf;

mod common;
use common::rig;

fn tmp(name: &str) -> PathBuf {
    common::tmp("live", name)
}

#[test]
fn a_bad_address_is_refused_naming_the_flag() {
    let out = rig()
        .args(["run", "--live", "nowhere", "--trials", "1"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--live") && err.contains("nowhere"), "{err}");
}

#[cfg(not(feature = "live"))]
#[test]
fn without_the_feature_the_live_view_is_refused_naming_the_build() {
    let dir = tmp("absent");
    let out = rig()
        .args(["run", "--live", "--trials", "1", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--features live"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
}

/// The tests with the view: a rig built with the `live` feature.
#[cfg(feature = "live")]
mod with_the_view {
    use std::collections::{BTreeMap, HashMap, HashSet};
    use std::net::TcpListener;
    use std::path::{Path, PathBuf};
    use std::process::{Child, Command, Stdio};
    use std::time::{Duration, Instant};

    use serde_json::Value;

    use super::common::{messages, ok, rig};
    use super::tmp;

    /// Node with the client's packages (`npm ci` in `tests/live` if they are missing), or
    /// `None`, said, when there is no Node (`$RIG_NODE`, default `node`).
    fn node() -> Option<String> {
        let node = std::env::var("RIG_NODE").unwrap_or_else(|_| "node".into());
        if Command::new(&node).arg("--version").output().is_err() {
            eprintln!("skipped: no Node.js ({node}); install it or set RIG_NODE");
            return None;
        }
        let dir = client_dir();
        if !dir.join("node_modules/@foxglove/ws-protocol").exists() {
            let npm = Command::new("npm")
                .args(["ci", "--no-audit", "--no-fund"])
                .current_dir(&dir)
                .status()
                .expect("npm, to install the client's packages (tests/live)");
            assert!(npm.success(), "npm ci in {} failed", dir.display());
        }
        Some(node)
    }

    fn client_dir() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../tests/live")
    }

    /// A port free on this host now.
    fn free_port() -> u16 {
        TcpListener::bind("127.0.0.1:0")
            .unwrap()
            .local_addr()
            .unwrap()
            .port()
    }

    /// The Node client viewing `port`, writing what it received to `out`.
    fn viewer(node: &str, port: u16, out: &Path, stall: bool) -> Child {
        let mut c = Command::new(node);
        c.arg(client_dir().join("client.mjs"))
            .arg("--url")
            .arg(format!("ws://127.0.0.1:{port}"))
            .arg("--out")
            .arg(out);
        if stall {
            c.arg("--stall");
        }
        c.stdout(Stdio::null()).spawn().unwrap()
    }

    /// Waits at most 60 s for `child`; asserts it succeeded.
    fn finish(mut child: Child, what: &str) {
        let t0 = Instant::now();
        loop {
            if let Some(status) = child.try_wait().unwrap() {
                assert!(status.success(), "{what}: {status}");
                return;
            }
            if t0.elapsed() > Duration::from_secs(60) {
                let _ = child.kill();
                panic!("{what} did not finish");
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// What the client received: its count of messages of other encodings per
    /// `topic encoding schema`, and per JSON message its topic, log time, text and value.
    struct Received {
        others: BTreeMap<String, u64>,
        messages: Vec<(String, u64, String, Value)>,
    }

    fn received(path: &Path) -> Received {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        let head: Value = serde_json::from_str(lines.next().unwrap()).unwrap();
        let others = head["others"]
            .as_object()
            .unwrap()
            .iter()
            .map(|(k, v)| (k.clone(), v.as_u64().unwrap()))
            .collect();
        let messages = lines
            .map(|l| {
                let v: Value = serde_json::from_str(l).unwrap();
                (
                    v["topic"].as_str().unwrap().to_string(),
                    v["log_time"].as_str().unwrap().parse().unwrap(),
                    v["raw"].as_str().unwrap().to_string(),
                    v["value"].clone(),
                )
            })
            .collect();
        Received { others, messages }
    }

    /// The fields of a JSON object as numbers (`null`: `None`).
    fn numbers(v: &Value) -> BTreeMap<String, Option<f64>> {
        v.as_object()
            .unwrap()
            .iter()
            .map(|(k, x)| (k.clone(), x.as_f64()))
            .collect()
    }

    /// `returns.csv`: per trial, its simulated time, return and greedy return.
    fn returns_csv(dir: &Path) -> HashMap<u64, (f64, f64, Option<f64>)> {
        let text = std::fs::read_to_string(dir.join("returns.csv")).unwrap();
        text.lines()
            .skip(1)
            .map(|l| {
                let f: Vec<&str> = l.split(',').collect();
                let greedy = (!f[4].is_empty()).then(|| f[4].parse().unwrap());
                (
                    f[1].parse().unwrap(),
                    (f[2].parse().unwrap(), f[3].parse().unwrap(), greedy),
                )
            })
            .collect()
    }

    #[test]
    fn the_foxglove_client_receives_every_channel_equal_to_the_recording() {
        let Some(node) = node() else { return };
        let dir = tmp("client");
        let port = free_port();
        let run = rig()
            .args(["run", "--cpus", "shared", "--quiet", "--timing", "realtime"])
            .args([
                "--speed",
                "10",
                "--gaps",
                "learn",
                "--trials",
                "8",
                "--eval-every",
                "2",
            ])
            .arg("--live")
            .arg(format!("127.0.0.1:{port}"))
            .arg("--out")
            .arg(&dir)
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let client = viewer(&node, port, &dir.join("received.jsonl"), false);
        let run = run.wait_with_output().unwrap();
        ok(run);
        finish(client, "the client");

        let got = received(&dir.join("received.jsonl"));
        let recorded = messages(&dir.join("run.mcap"));
        let in_file: HashSet<(&str, u64, &[u8])> = recorded
            .iter()
            .flat_map(|(topic, ms)| ms.iter().map(move |(t, d)| (topic.as_str(), *t, &d[..])))
            .collect();
        let action_stamps: HashMap<u64, (u64, u64, u64)> = recorded["/timing/agent/action"]
            .iter()
            .map(|(_, d)| {
                let v = numbers(&serde_json::from_slice(d).unwrap());
                let int = |k: &str| v[k].unwrap() as u64;
                let stamps = (
                    int("t_sample_ns"),
                    int("t_received_ns"),
                    int("t_publish_ns"),
                );
                (int("seq"), stamps)
            })
            .collect();
        let trials = returns_csv(&dir);
        let mut per_topic: BTreeMap<&str, usize> = BTreeMap::new();
        for (topic, log_time, raw, value) in &got.messages {
            *per_topic.entry(topic.as_str()).or_default() += 1;
            // Decoded, the value is the text's; the text is the recording's, or derived
            // from it exactly.
            assert_eq!(numbers(value), numbers(&serde_json::from_str(raw).unwrap()));
            let v = numbers(value);
            match topic.as_str() {
                "/returns" => {
                    let trial = v["trial"].unwrap() as u64;
                    let (sim_time, ret, greedy) = trials[&trial];
                    assert_eq!(v["sim_time_s"], Some(sim_time), "trial {trial}");
                    assert_eq!(v["return"], Some(ret), "trial {trial}");
                    assert_eq!(v["greedy"], greedy, "trial {trial}");
                }
                "/latency" => {
                    let (sample, received, publish) = action_stamps[&(v["seq"].unwrap() as u64)];
                    let us = |from: u64, to: u64| (to as f64 - from as f64) / 1e3;
                    assert_eq!(v["sample_to_action_us"], Some(us(sample, publish)));
                    assert_eq!(v["agent_us"], Some(us(received, publish)));
                }
                _ => assert!(
                    in_file.contains(&(topic.as_str(), *log_time, raw.as_bytes())),
                    "{topic} at {log_time}: {raw} is not in the recording"
                ),
            }
        }
        eprintln!("received {per_topic:?}, others {:?}", got.others);
        for topic in recorded.keys() {
            assert!(per_topic.contains_key(topic.as_str()), "nothing on {topic}");
        }
        assert!(per_topic["/plant/measurement"] > 100, "{per_topic:?}");
        assert!(per_topic.contains_key("/latency"), "{per_topic:?}");
        let rows = per_topic.get("/returns").copied().unwrap_or(0);
        assert!(rows >= 2, "{rows} rows of returns for 8 trials");
        let pictures = got.others.get("/scene protobuf foxglove.SceneUpdate");
        assert!(pictures.is_some_and(|&n| n > 0), "{:?}", got.others);
    }

    #[test]
    fn a_viewer_that_stops_reading_changes_nothing_of_the_run() {
        let Some(node) = node() else { return };
        // Long enough (about 150 000 messages) for the viewer to connect, subscribe and stop
        // reading while the run goes on, and to fill the server's queue for it.
        let flags = ["run", "--cpus", "shared", "--quiet", "--trials", "200"];
        let plain = tmp("plain");
        ok(rig().args(flags).arg("--out").arg(&plain).output().unwrap());
        let dir = tmp("stalled");
        let port = free_port();
        // The viewer first (it retries until the view serves): a lockstep run would end
        // before a viewer started after it had connected.
        let client = viewer(&node, port, &dir.join("received.jsonl"), true);
        let run = rig()
            .args(flags)
            .arg("--live")
            .arg(format!("127.0.0.1:{port}"))
            .arg("--out")
            .arg(&dir)
            .spawn()
            .unwrap();
        finish(run, "the run with a stalled viewer");
        finish(client, "the stalled client");
        let read = |d: &Path| std::fs::read(d.join("returns.csv")).unwrap();
        assert_eq!(read(&dir), read(&plain));
        let (with, without) = (
            messages(&dir.join("run.mcap")),
            messages(&plain.join("run.mcap")),
        );
        assert_eq!(
            with.keys().collect::<Vec<_>>(),
            without.keys().collect::<Vec<_>>()
        );
        for topic in ["/plant/measurement", "/observer/estimate", "/agent/action"] {
            assert_eq!(with[topic], without[topic], "{topic}");
        }
    }
}
