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
    use std::io::{Read, Write};
    use std::net::{TcpListener, TcpStream};
    use std::path::{Path, PathBuf};
    use std::process::{Child, Command, Stdio};
    use std::time::{Duration, Instant};

    use serde_json::Value;

    use super::common::{messages, ok, rig, signal};
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

    /// The subprotocol names a client offers (`client.mjs --offer`), and the one the
    /// server must answer with: the protocol's own name, the Foxglove SDK's, or both.
    const OFFERS: [(&str, &str); 3] = [
        ("spec", "foxglove.websocket.v1"),
        ("sdk", "foxglove.sdk.v1"),
        ("both", "foxglove.sdk.v1"),
    ];

    /// The Node client viewing `port`, offering `offer`, writing what it received to `out`.
    fn viewer(node: &str, port: u16, out: &Path, offer: &str, stall: bool) -> Child {
        let mut c = Command::new(node);
        c.arg(client_dir().join("client.mjs"))
            .arg("--url")
            .arg(format!("ws://127.0.0.1:{port}"))
            .arg("--offer")
            .arg(offer)
            .arg("--out")
            .arg(out);
        if stall {
            c.arg("--stall");
        }
        c.stdout(Stdio::null()).spawn().unwrap()
    }

    /// Waits at most 60 s for `child`; asserts it succeeded.
    fn finish(child: Child, what: &str) {
        let status = wait(child, what);
        assert!(status.success(), "{what}: {status}");
    }

    /// Waits at most 60 s for `child` to end.
    fn wait(mut child: Child, what: &str) -> std::process::ExitStatus {
        let t0 = Instant::now();
        loop {
            if let Some(status) = child.try_wait().unwrap() {
                return status;
            }
            if t0.elapsed() > Duration::from_secs(60) {
                let _ = child.kill();
                panic!("{what} did not finish");
            }
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// What the client received: the subprotocol the server chose, its count of messages
    /// of other encodings per `topic encoding schema`, and per JSON message its topic, log
    /// time, text and value.
    struct Received {
        protocol: String,
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
        Received {
            protocol: head["protocol"].as_str().unwrap().to_string(),
            others,
            messages,
        }
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

    /// A run's own record of what it sent: every recorded message, the stamps of every
    /// action, and `returns.csv`.
    struct Recording {
        messages: BTreeMap<String, Vec<(u64, Vec<u8>)>>,
        action_stamps: HashMap<u64, (u64, u64, u64)>,
        trials: HashMap<u64, (f64, f64, Option<f64>)>,
    }

    impl Recording {
        fn of(dir: &Path) -> Recording {
            let messages = messages(&dir.join("run.mcap"));
            let action_stamps = messages["/timing/agent/action"]
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
            Recording {
                messages,
                action_stamps,
                trials: returns_csv(dir),
            }
        }

        /// Asserts that every message `got` holds is the recording's, or derived from it
        /// exactly, and that every channel arrived; returns the count per topic.
        fn check(&self, got: &Received) -> BTreeMap<String, usize> {
            let in_file: HashSet<(&str, u64, &[u8])> = self
                .messages
                .iter()
                .flat_map(|(topic, ms)| ms.iter().map(move |(t, d)| (topic.as_str(), *t, &d[..])))
                .collect();
            let mut per_topic: BTreeMap<String, usize> = BTreeMap::new();
            for (topic, log_time, raw, value) in &got.messages {
                *per_topic.entry(topic.clone()).or_default() += 1;
                // Decoded, the value is the text's; the text is the recording's, or derived
                // from it exactly.
                assert_eq!(numbers(value), numbers(&serde_json::from_str(raw).unwrap()));
                let v = numbers(value);
                match topic.as_str() {
                    "/returns" => {
                        let trial = v["trial"].unwrap() as u64;
                        let (sim_time, ret, greedy) = self.trials[&trial];
                        assert_eq!(v["sim_time_s"], Some(sim_time), "trial {trial}");
                        assert_eq!(v["return"], Some(ret), "trial {trial}");
                        assert_eq!(v["greedy"], greedy, "trial {trial}");
                    }
                    "/latency" => {
                        let seq = v["seq"].unwrap() as u64;
                        let (sample, received, publish) = self.action_stamps[&seq];
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
            // The pictures, protobuf, are counted below.
            for topic in self.messages.keys().filter(|t| *t != "/scene") {
                assert!(per_topic.contains_key(topic), "nothing on {topic}");
            }
            assert!(per_topic["/plant/measurement"] > 100, "{per_topic:?}");
            assert!(per_topic.contains_key("/latency"), "{per_topic:?}");
            let rows = per_topic.get("/returns").copied().unwrap_or(0);
            assert!(rows >= 2, "{rows} rows of returns for 8 trials");
            let pictures = got.others.get("/scene protobuf foxglove.SceneUpdate");
            assert!(pictures.is_some_and(|&n| n > 0), "{:?}", got.others);
            per_topic
        }
    }

    /// A WebSocket handshake with the view at `port` offering `protocols`: the answer's
    /// status line, the subprotocol it chose, and (if it switched) the text of its first
    /// message.
    fn handshake(port: u16, protocols: &str) -> (String, Option<String>, Option<String>) {
        let mut s = TcpStream::connect(("127.0.0.1", port)).unwrap();
        s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        write!(
            s,
            "GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n\
             Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n\
             Sec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: {protocols}\r\n\r\n"
        )
        .unwrap();
        let mut head = Vec::new();
        let mut byte = [0u8];
        while !head.ends_with(b"\r\n\r\n") {
            s.read_exact(&mut byte).unwrap();
            head.push(byte[0]);
        }
        let head = String::from_utf8(head).unwrap();
        let status = head.lines().next().unwrap().to_string();
        let chosen = head.lines().find_map(|l| {
            let (name, value) = l.split_once(':')?;
            name.eq_ignore_ascii_case("sec-websocket-protocol")
                .then(|| value.trim().to_string())
        });
        if !status.contains(" 101 ") {
            return (status, chosen, None);
        }
        // The server's first frame, unmasked text: its length in 7, 16 or 64 bits.
        let mut h = [0u8; 2];
        s.read_exact(&mut h).unwrap();
        assert_eq!(h[0], 0x81, "a whole text frame");
        let len = match h[1] {
            126 => {
                let mut l = [0u8; 2];
                s.read_exact(&mut l).unwrap();
                u16::from_be_bytes(l) as usize
            }
            127 => {
                let mut l = [0u8; 8];
                s.read_exact(&mut l).unwrap();
                u64::from_be_bytes(l) as usize
            }
            n => n as usize,
        };
        let mut text = vec![0u8; len];
        s.read_exact(&mut text).unwrap();
        (status, chosen, Some(String::from_utf8(text).unwrap()))
    }

    /// Each offer is answered with a name it made, and the protocol's first message
    /// follows; an offer of neither name is refused, as the server refuses it.
    #[test]
    fn a_client_offering_either_name_is_let_in() {
        let dir = tmp("names");
        let port = free_port();
        let run = rig()
            .args(["run", "--cpus", "shared", "--quiet", "--timing", "realtime"])
            .args(["--trials", "20", "--live"])
            .arg(format!("127.0.0.1:{port}"))
            .arg("--out")
            .arg(&dir)
            .spawn()
            .unwrap();
        let t0 = Instant::now();
        while TcpStream::connect(("127.0.0.1", port)).is_err() {
            assert!(t0.elapsed() < Duration::from_secs(20), "no view on {port}");
            std::thread::sleep(Duration::from_millis(20));
        }
        let offers = [
            ("foxglove.websocket.v1", Some("foxglove.websocket.v1")),
            ("foxglove.sdk.v1", Some("foxglove.sdk.v1")),
            (
                "foxglove.websocket.v1, foxglove.sdk.v1",
                Some("foxglove.sdk.v1"),
            ),
            (
                "foxglove.sdk.v1, foxglove.websocket.v1",
                Some("foxglove.sdk.v1"),
            ),
            (
                "other, foxglove.websocket.v1",
                Some("foxglove.websocket.v1"),
            ),
            ("foxglove.websocket.v2", None),
        ];
        for (offer, answer) in offers {
            let (status, chosen, first) = handshake(port, offer);
            assert_eq!(chosen.as_deref(), answer, "offering {offer}: {status}");
            match answer {
                Some(_) => {
                    assert!(status.contains(" 101 "), "offering {offer}: {status}");
                    let first = first.unwrap();
                    assert!(first.contains(r#""op":"serverInfo""#), "{first}");
                }
                None => assert!(status.contains(" 400 "), "offering {offer}: {status}"),
            }
        }
        signal(run.id(), "-TERM");
        wait(run, "the run, interrupted");
    }

    /// Three viewers at once, offering the protocol's own name, the Foxglove SDK's, and
    /// both: each is answered with a name it offered and receives every channel.
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
        let out = |offer: &str| dir.join(format!("received-{offer}.jsonl"));
        let clients: Vec<Child> = OFFERS
            .iter()
            .map(|(offer, _)| viewer(&node, port, &out(offer), offer, false))
            .collect();
        let run = run.wait_with_output().unwrap();
        ok(run);
        for (client, (offer, _)) in clients.into_iter().zip(OFFERS) {
            finish(client, &format!("the client offering {offer}"));
        }

        let recording = Recording::of(&dir);
        for (offer, answer) in OFFERS {
            let got = received(&out(offer));
            assert_eq!(got.protocol, answer, "offering {offer}");
            let per_topic = recording.check(&got);
            eprintln!(
                "offering {offer}: received {per_topic:?}, others {:?}",
                got.others
            );
        }
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
        let client = viewer(&node, port, &dir.join("received.jsonl"), "spec", true);
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
