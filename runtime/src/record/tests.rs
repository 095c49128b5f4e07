//! The recorder against the official readers: layout, CRCs, determinism, crash.

use super::*;
use mcap::{MessageStream, Summary};
use serde_json::json;

fn tmpdir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("rig-record-test-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn entries() -> BTreeMap<String, String> {
    BTreeMap::from([
        ("seed".to_owned(), "42".to_owned()),
        ("run_id".to_owned(), "r-0001".to_owned()),
    ])
}

/// A small fixed recording: two channels, an attachment, metadata.
fn record(path: &Path) {
    record_to(path, None);
}

/// [`record`]'s recording; with a tap, a channel of the tap's only written between.
fn record_to(path: &Path, tap: Option<Kept>) {
    let mut r = Recorder::create(path).unwrap();
    let tapped = tap.is_some();
    if let Some(tap) = tap {
        r.set_tap(Box::new(tap));
    }
    let live = r
        .live_channel("/live", "Live", &[Field::number("v")])
        .unwrap();
    let mut meas = vec![Field::integer("seq"), Field::number("reward")];
    meas.extend(Field::array("x", 2, FieldKind::Number));
    let m = r
        .channel("/plant/measurement", "Measurement", &meas)
        .unwrap();
    let mut act = vec![Field::integer("seq")];
    act.extend(Field::array("u", 1, FieldKind::Number));
    let a = r.channel("/agent/action", "Action", &act).unwrap();
    r.metadata("run", &entries()).unwrap();
    r.attach("config.toml", "text/x-toml", b"seed = 42\n")
        .unwrap();
    for k in 0..5u64 {
        let t = 30_000_000 * k;
        let x = [0.1 * k as f64, -(k as f64) / 3.0];
        let reward = if k == 3 { f64::NAN } else { -1.5 * k as f64 };
        r.write(
            m,
            t,
            t + 1,
            &[
                Value::Int(k),
                Value::Num(reward),
                Value::Num(x[0]),
                Value::Num(x[1]),
            ],
        )
        .unwrap();
        if tapped {
            r.write(live, t, t, &[Value::Num(1.0)]).unwrap();
        }
        r.write(
            a,
            t + 5,
            t + 6,
            &[
                Value::Int(k),
                Value::Num(if k == 4 { f64::INFINITY } else { 2.0 }),
            ],
        )
        .unwrap();
    }
    r.finish().unwrap();
}

#[test]
fn field_array_flattens() {
    let f = Field::array("x", 3, FieldKind::Number);
    let names: Vec<_> = f.iter().map(|f| f.name.as_str()).collect();
    assert_eq!(names, ["x_0", "x_1", "x_2"]);
    assert!(f.iter().all(|f| f.kind == FieldKind::Number));
}

#[test]
fn reads_back() {
    let dir = tmpdir("reads-back");
    let path = dir.join("run.mcap");
    record(&path);
    assert!(!dir.join("run.mcap.part").exists());
    let bytes = std::fs::read(&path).unwrap();

    // Summary: channels, schemas, statistics, CRC-checked attachment and metadata.
    let summary = Summary::read(&bytes).unwrap().expect("summary present");
    let stats = summary.stats.as_ref().unwrap();
    assert_eq!(stats.message_count, 10);
    assert_eq!((stats.channel_count, stats.schema_count), (2, 2));
    assert_eq!((stats.attachment_count, stats.metadata_count), (1, 1));
    // Every chunk compressed with zstd, and smaller than its messages.
    assert!(!summary.chunk_indexes.is_empty());
    for c in &summary.chunk_indexes {
        assert_eq!(c.compression, "zstd");
        assert!(c.compressed_size < c.uncompressed_size, "{c:?}");
    }
    let mut topics: Vec<_> = summary.channels.values().map(|c| c.topic.clone()).collect();
    topics.sort();
    assert_eq!(topics, ["/agent/action", "/plant/measurement"]);
    for c in summary.channels.values() {
        assert_eq!(c.message_encoding, "json");
        let s = c.schema.as_ref().unwrap();
        assert_eq!(s.encoding, "jsonschema");
        let schema: serde_json::Value = serde_json::from_slice(&s.data).unwrap();
        let expected = if c.topic == "/plant/measurement" {
            assert_eq!(s.name, "Measurement");
            json!({"type": "object", "properties": {
                "seq": {"type": "integer"}, "reward": {"type": "number"},
                "x_0": {"type": "number"}, "x_1": {"type": "number"}}})
        } else {
            assert_eq!(s.name, "Action");
            json!({"type": "object", "properties": {
                "seq": {"type": "integer"}, "u_0": {"type": "number"}}})
        };
        assert_eq!(schema, expected);
        // Field order is kept in the schema text.
        let text = std::str::from_utf8(&s.data).unwrap();
        assert!(
            text.starts_with(r#"{"type":"object","properties":{"seq":"#),
            "{text}"
        );
    }
    let [ai] = &summary.attachment_indexes[..] else {
        panic!("one attachment")
    };
    let att = mcap::read::attachment(&bytes, ai).unwrap();
    assert_eq!(
        (att.name.as_str(), att.media_type.as_str()),
        ("config.toml", "text/x-toml")
    );
    assert_eq!(&att.data[..], b"seed = 42\n");
    let [mi] = &summary.metadata_indexes[..] else {
        panic!("one metadata record")
    };
    let meta = mcap::read::metadata(&bytes, mi).unwrap();
    assert_eq!(meta.name, "run");
    assert_eq!(meta.metadata, entries());

    // Messages (the stream checks chunk CRCs).
    let mut per_topic: BTreeMap<String, Vec<(u32, u64, u64, serde_json::Value)>> = BTreeMap::new();
    for msg in MessageStream::new(&bytes).unwrap() {
        let msg = msg.unwrap();
        let v: serde_json::Value = serde_json::from_slice(&msg.data).unwrap();
        per_topic
            .entry(msg.channel.topic.clone())
            .or_default()
            .push((msg.sequence, msg.log_time, msg.publish_time, v));
    }
    let meas = &per_topic["/plant/measurement"];
    let act = &per_topic["/agent/action"];
    assert_eq!((meas.len(), act.len()), (5, 5));
    for k in 0..5usize {
        let t = 30_000_000 * k as u64;
        let (seq, log, publ, v) = &meas[k];
        assert_eq!((*seq, *log, *publ), (k as u32, t, t + 1));
        assert_eq!(v["seq"], json!(k));
        assert!(v["seq"].is_u64());
        if k == 3 {
            assert!(v["reward"].is_null(), "NaN is written as null");
        } else {
            assert_eq!(v["reward"].as_f64().unwrap(), -1.5 * k as f64);
        }
        // Exact round trip of the f64 values.
        assert_eq!(
            v["x_0"].as_f64().unwrap().to_bits(),
            (0.1 * k as f64).to_bits()
        );
        assert_eq!(
            v["x_1"].as_f64().unwrap().to_bits(),
            (-(k as f64) / 3.0).to_bits()
        );
        let (seq, log, publ, v) = &act[k];
        assert_eq!((*seq, *log, *publ), (k as u32, t + 5, t + 6));
        if k == 4 {
            assert!(v["u_0"].is_null(), "inf is written as null");
        } else {
            assert_eq!(v["u_0"], json!(2.0));
        }
    }
    // Message text: fields in declared order, compact.
    let first = MessageStream::new(&bytes).unwrap().next().unwrap().unwrap();
    assert_eq!(
        std::str::from_utf8(&first.data).unwrap(),
        r#"{"seq":0,"reward":-0.0,"x_0":0.0,"x_1":-0.0}"#
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn same_calls_same_bytes() {
    let dir = tmpdir("same-bytes");
    let (a, b) = (dir.join("a.mcap"), dir.join("b.mcap"));
    record(&a);
    record(&b);
    let (a, b) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(!a.is_empty());
    assert!(a == b, "two identical recordings differ");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn rejects_bad_calls() {
    let dir = tmpdir("bad-calls");
    let mut r = Recorder::create(&dir.join("run.mcap")).unwrap();
    let c = r
        .channel("/a", "A", &[Field::integer("seq"), Field::number("v")])
        .unwrap();
    assert!(
        r.channel("/a", "A", &[Field::integer("seq")]).is_err(),
        "duplicate topic"
    );
    assert!(
        r.channel("/b", "A", &[Field::integer("seq")]).is_err(),
        "schema redefined"
    );
    assert!(
        r.channel("/b", "B", &[Field::number("v"), Field::number("v")])
            .is_err()
    );
    assert!(
        r.write(c, 0, 0, &[Value::Int(1)]).is_err(),
        "too few values"
    );
    assert!(
        r.write(c, 0, 0, &[Value::Num(1.0), Value::Num(1.0)])
            .is_err(),
        "number as integer"
    );
    // An integer in a number field is fine; the sequence counts only written messages.
    r.write(c, 7, 7, &[Value::Int(1), Value::Int(2)]).unwrap();
    let shared = r
        .channel("/b", "A", &[Field::integer("seq"), Field::number("v")])
        .unwrap();
    r.write(shared, 8, 8, &[Value::Int(1), Value::Num(0.5)])
        .unwrap();
    r.finish().unwrap();
    let bytes = std::fs::read(dir.join("run.mcap")).unwrap();
    let summary = Summary::read(&bytes).unwrap().unwrap();
    assert_eq!(
        summary.schemas.len(),
        1,
        "channels with equal schemas share one"
    );
    let msgs: Vec<_> = MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap())
        .collect();
    assert_eq!(msgs.len(), 2);
    assert_eq!(
        (msgs[0].sequence, &msgs[0].data[..]),
        (0, &br#"{"seq":1,"v":2}"#[..])
    );
    assert_eq!(
        (msgs[1].sequence, &msgs[1].data[..]),
        (0, &br#"{"seq":1,"v":0.5}"#[..])
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn recorder_is_send() {
    fn send<T: Send>() {}
    send::<Recorder>();
}

#[test]
fn crash_leaves_readable_prefix() {
    // A killed process runs no destructors: `forget` the recorder after more writes.
    let dir = tmpdir("crash");
    let path = dir.join("run.mcap");
    let mut r = Recorder::create(&path).unwrap();
    let c = r
        .channel("/x", "X", &[Field::integer("seq"), Field::number("v")])
        .unwrap();
    for k in 0..100u64 {
        r.write(c, k, k, &[Value::Int(k), Value::Num(k as f64)])
            .unwrap();
    }
    r.flush().unwrap();
    for k in 100..110u64 {
        r.write(c, k, k, &[Value::Int(k), Value::Num(k as f64)])
            .unwrap();
    }
    std::mem::forget(r);
    assert!(
        !path.exists(),
        "an unfinished recording keeps its .part name"
    );
    let bytes = std::fs::read(dir.join("run.mcap.part")).unwrap();
    assert!(Summary::read(&bytes).is_err(), "no footer");
    let mut k = 0u32;
    for m in MessageStream::new(&bytes).unwrap() {
        let Ok(m) = m else { break };
        assert_eq!((m.sequence, m.log_time), (k, u64::from(k)));
        k += 1;
    }
    assert!(k >= 100, "the flushed messages are readable, got {k}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn drop_without_finish_keeps_part_name() {
    let dir = tmpdir("drop");
    let path = dir.join("run.mcap");
    let mut r = Recorder::create(&path).unwrap();
    let c = r.channel("/x", "X", &[Field::integer("seq")]).unwrap();
    r.write(c, 1, 1, &[Value::Int(0)]).unwrap();
    drop(r);
    assert!(!path.exists());
    let bytes = std::fs::read(dir.join("run.mcap.part")).unwrap();
    let summary = Summary::read(&bytes)
        .unwrap()
        .expect("the mcap writer's Drop finishes");
    assert_eq!(summary.stats.unwrap().message_count, 1);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn many_chunks() {
    // Enough messages for several 1 MiB chunks; all read back in order.
    let dir = tmpdir("many-chunks");
    let path = dir.join("run.mcap");
    let mut r = Recorder::create(&path).unwrap();
    let mut fields = vec![Field::integer("seq")];
    fields.extend(Field::array("x", 8, FieldKind::Number));
    let c = r.channel("/x", "X", &fields).unwrap();
    let n = 30_000u64;
    let mut values = vec![Value::Int(0); 9];
    for k in 0..n {
        values[0] = Value::Int(k);
        for i in 0..8 {
            values[1 + i] = Value::Num((k as f64 + 1.0) / (i as f64 + 3.0));
        }
        r.write(c, k, k, &values).unwrap();
    }
    let flushed = r.flushes();
    r.finish().unwrap();
    let bytes = std::fs::read(&path).unwrap();
    let summary = Summary::read(&bytes).unwrap().unwrap();
    assert!(
        summary.chunk_indexes.len() > 2,
        "{} chunks",
        summary.chunk_indexes.len()
    );
    // Every chunk but the last (closed by `finish`) was counted when written out.
    assert_eq!(summary.chunk_indexes.len() as u64, flushed + 1);
    let mut k = 0u32;
    for m in MessageStream::new(&bytes).unwrap() {
        let m = m.unwrap();
        assert_eq!((m.sequence, m.log_time), (k, k as u64));
        k += 1;
    }
    assert_eq!(k as u64, n);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_crash_keeps_every_message_recorded_before_the_last_flush() {
    let dir = tmpdir("crash-after-flush");
    let path = dir.join("run.mcap");
    let mut r = Recorder::create(&path).unwrap();
    let mut fields = vec![Field::integer("seq")];
    fields.extend(Field::array("x", 8, FieldKind::Number));
    let c = r.channel("/x", "X", &fields).unwrap();
    let mut values = vec![Value::Int(0); 9];
    let mut before_flush = 0;
    for k in 0..20_000u64 {
        let flushes = r.flushes();
        values[0] = Value::Int(k);
        for i in 0..8 {
            values[1 + i] = Value::Num(k as f64 / (i as f64 + 3.0));
        }
        r.write(c, k, k, &values).unwrap();
        if r.flushes() > flushes {
            before_flush = k;
        }
    }
    assert!(r.flushes() >= 2);
    // As a process killed now: no summary, no buffered bytes written.
    std::mem::forget(r);
    let bytes = std::fs::read(dir.join("run.mcap.part")).unwrap();
    let read = MessageStream::new(&bytes)
        .unwrap()
        .take_while(Result::is_ok)
        .count();
    assert_eq!(read as u64, before_flush);
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A tap that keeps what it is handed.
#[derive(Clone, Default)]
struct Kept(std::sync::Arc<std::sync::Mutex<(Vec<Declared>, Vec<Tapped>)>>);

/// A channel declared to a tap: topic, schema name, schema.
type Declared = (String, String, Vec<u8>);

/// A message handed to a tap: channel index, log time, data.
type Tapped = (usize, u64, Vec<u8>);

impl Tap for Kept {
    fn channel(&mut self, topic: &str, encoding: &scene::Encoding) {
        let mut k = self.0.lock().unwrap();
        let (name, schema) = (&encoding.schema_name, &encoding.schema);
        k.0.push((topic.into(), name.clone(), schema.clone()));
    }

    fn message(&mut self, index: usize, log_time_ns: u64, data: &[u8]) {
        self.0
            .lock()
            .unwrap()
            .1
            .push((index, log_time_ns, data.to_vec()));
    }
}

#[test]
fn a_tap_gets_the_files_channels_and_messages_and_its_own_and_the_file_stays_the_same() {
    let dir = tmpdir("tap");
    let (plain, tapped) = (dir.join("plain.mcap"), dir.join("tapped.mcap"));
    record(&plain);
    let kept = Kept::default();
    let mut r = Recorder::create(&tapped).unwrap();
    let seq = [Field::integer("seq")];
    // Declared before the tap: handed on when it is set.
    let before = r.channel("/before", "Seq", &seq).unwrap();
    r.set_tap(Box::new(kept.clone()));
    let live = r
        .live_channel("/live", "Live", &[Field::number("v")])
        .unwrap();
    assert!(r.has_topic("/before") && !r.has_topic("/live"));
    r.write(before, 5, 5, &[Value::Int(7)]).unwrap();
    r.write(live, 6, 6, &[Value::Num(f64::NAN)]).unwrap();
    r.finish().unwrap();
    let (channels, messages) = kept.0.lock().unwrap().clone();
    let names: Vec<_> = channels.iter().map(|c| (&c.0[..], &c.1[..])).collect();
    assert_eq!(names, [("/before", "Seq"), ("/live", "Live")]);
    assert_eq!(channels[0].2, json_schema(&seq));
    assert_eq!(
        messages,
        [
            (0, 5, br#"{"seq":7}"#.to_vec()),
            (1, 6, br#"{"v":null}"#.to_vec())
        ]
    );
    // The file has the file's channel and message only.
    let bytes = std::fs::read(&tapped).unwrap();
    let in_file: Vec<_> = MessageStream::new(&bytes)
        .unwrap()
        .map(|m| m.unwrap().channel.topic.clone())
        .collect();
    assert_eq!(in_file, ["/before"]);

    // A tap, and messages on a channel of its own between the file's, leave the bytes of
    // a recording as they are.
    let again = dir.join("again.mcap");
    let kept = Kept::default();
    record_to(&again, Some(kept.clone()));
    assert_eq!(kept.0.lock().unwrap().1.len(), 15);
    assert_eq!(
        std::fs::read(&again).unwrap(),
        std::fs::read(&plain).unwrap()
    );
}
