//! `run.mcap`: every message of a rig run, recorded for Foxglove and for replay.
//!
//! The supervising process (`rig run`) owns one [`Recorder`]; it declares one channel per
//! topic with [`Recorder::channel`] and hands every message it sees to [`Recorder::write`].
//!
//! File layout (MCAP, written with the official `mcap` crate):
//! - messages are JSON objects (`message_encoding = "json"`) with flat numeric fields, in
//!   the order the channel declared them; array fields of the wire structs are flattened to
//!   `x_0, x_1, ...` ([`Field::array`]);
//! - each channel has a schema with `encoding = "jsonschema"` whose data is
//!   `{"type":"object","properties":{"seq":{"type":"integer"},"x_0":{"type":"number"},...}}`:
//!   flat `integer` / `number` properties only, no `$ref`, so Foxglove plots every field;
//! - chunked, uncompressed, with chunk, data-section and summary CRCs, message indexes and
//!   a summary section (statistics, chunk, attachment and metadata indexes);
//! - the resolved configuration as an attachment ([`Recorder::attach`]) and the seed,
//!   versions and run id as metadata ([`Recorder::metadata`]).
//!
//! Numbers: integers are written in decimal; finite `f64` in shortest round-trip form
//! (`0.1`, `1.0`, `1e300`), so parsing the JSON gives back exactly the same `f64` and two
//! identical runs give byte-identical messages. NaN and ±∞ are not JSON numbers: they are
//! written as `null`.
//!
//! Determinism: the writer reads no clock and no environment. The header's `library`
//! field is the `mcap` crate's constant `mcap-rust/<version>`, attachment times are 0, and
//! the summary is written in id order; the same sequence of calls gives the same bytes.
//!
//! Crash behaviour: the file is written as `PATH.part` and renamed to `PATH` by
//! [`Recorder::finish`], so `PATH` exists only when complete. A recorder dropped without
//! `finish` (an error returned with `?`, a panic that unwinds) still gets its summary
//! written by the `mcap` writer's `Drop`, but keeps the `.part` name. A process killed
//! mid-run (SIGKILL, abort, power loss) leaves a `.part` file holding the chunks completed
//! so far, then the start of an unfinished chunk whose header still has its placeholder
//! length (2⁶⁴ − 1), and no summary or footer; up to one chunk (1 MiB of messages) plus
//! 64 KiB of write buffer is lost. What readers make of such a file (measured with mcap
//! 0.26 and Python mcap 1.6.0 on a run aborted after 120 000 messages, 118 532 readable):
//! - anything that starts from the footer fails at once: Rust `mcap::Summary::read`
//!   (`BadMagic`), Python `make_reader(f).get_summary()` / `.iter_messages()`
//!   (`RecordLengthLimitExceeded`), and so Foxglove's indexed loading;
//! - streaming readers return every message of the completed chunks, in file order, then
//!   fail at the unfinished chunk: Rust `mcap::MessageStream` ("Chunk ended in the middle
//!   of a record") and Python `NonSeekingReader(f).iter_messages(log_time_order=False)`
//!   (`RecordLengthLimitExceeded`). With the default `log_time_order=True` the Python
//!   reader sorts all messages before yielding any, so it yields none.
//!
//! [`Recorder::flush`] closes the current chunk and writes it out, which bounds what a
//! crash can lose; without it a chunk closes every 1 MiB of messages.

use std::collections::{BTreeMap, HashSet};
use std::ffi::OsString;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail, ensure};
use mcap::records::MessageHeader;
use serde_json::ser::{CompactFormatter, Formatter};

/// Message encoding of every channel.
const MESSAGE_ENCODING: &str = "json";
/// Schema encoding of every channel.
const SCHEMA_ENCODING: &str = "jsonschema";
/// Target uncompressed size of a chunk, in bytes.
const CHUNK_SIZE: u64 = 1024 * 1024;

/// The JSON type of one message field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldKind {
    /// JSON Schema `integer`: a [`Value::Int`].
    Integer,
    /// JSON Schema `number`: a [`Value::Num`] (or a [`Value::Int`]); NaN and ±∞ become `null`.
    Number,
}

/// One flat field of a channel's messages.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Field {
    /// The JSON key, e.g. `seq` or `x_0`.
    pub name: String,
    /// The JSON type.
    pub kind: FieldKind,
}

impl Field {
    /// An `integer` field called `name`.
    pub fn integer(name: &str) -> Field {
        Field {
            name: name.to_owned(),
            kind: FieldKind::Integer,
        }
    }

    /// A `number` field called `name`.
    pub fn number(name: &str) -> Field {
        Field {
            name: name.to_owned(),
            kind: FieldKind::Number,
        }
    }

    /// An array field flattened: `Field::array("x", 3, FieldKind::Number)` is the fields
    /// `x_0, x_1, x_2`, in that order.
    pub fn array(name: &str, len: usize, kind: FieldKind) -> Vec<Field> {
        (0..len)
            .map(|i| Field {
                name: format!("{name}_{i}"),
                kind,
            })
            .collect()
    }
}

/// One field value of a message, in the order of the channel's fields.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Value {
    /// An integer (counters, flags, trial numbers).
    Int(u64),
    /// A real number; NaN and ±∞ are written as `null`.
    Num(f64),
}

/// A channel of a [`Recorder`], returned by [`Recorder::channel`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ChannelId(usize);

/// What the recorder keeps per channel to encode its messages.
struct Channel {
    /// The MCAP channel id.
    id: u16,
    /// The topic, for error messages.
    topic: String,
    /// Per field, its kind and its JSON key with separators: `"seq":`, `,"x_0":`, ...
    fields: Vec<(FieldKind, Box<[u8]>)>,
    /// The MCAP sequence number of the next message.
    sequence: u32,
}

/// Records a run's messages into an MCAP file; see the module documentation.
pub struct Recorder {
    writer: mcap::Writer<BufWriter<File>>,
    channels: Vec<Channel>,
    /// Schema name → schema data, to refuse one name with two different field lists.
    schemas: BTreeMap<String, Vec<u8>>,
    /// Where the file is written until `finish`.
    part: PathBuf,
    /// Where `finish` moves it.
    path: PathBuf,
    /// The message being encoded (reused: no allocation per message).
    buf: Vec<u8>,
}

impl Recorder {
    /// Starts an MCAP file that [`finish`](Self::finish) will move to `path`; until then
    /// it is written as `path` with `.part` appended (replacing any file of that name).
    pub fn create(path: &Path) -> Result<Recorder> {
        let mut part = OsString::from(path.as_os_str());
        part.push(".part");
        let part = PathBuf::from(part);
        let file =
            File::create(&part).with_context(|| format!("cannot create {}", part.display()))?;
        // Set every option that shapes the bytes explicitly, so the file does not change if
        // another crate in the build enables the `mcap` crate's compression features.
        let options = mcap::WriteOptions::new()
            .compression(None)
            .profile("")
            .chunk_size(Some(CHUNK_SIZE))
            .use_chunks(true);
        let writer = options
            .create(BufWriter::with_capacity(1 << 16, file))
            .with_context(|| format!("cannot write {}", part.display()))?;
        Ok(Recorder {
            writer,
            channels: Vec::new(),
            schemas: BTreeMap::new(),
            part,
            path: path.to_owned(),
            buf: Vec::with_capacity(1024),
        })
    }

    /// Declares a topic whose messages have `fields`, in this order, under a
    /// `jsonschema` schema called `schema_name` (channels may share a schema). Topics must
    /// be unique, field names non-empty and unique within a channel.
    pub fn channel(
        &mut self,
        topic: &str,
        schema_name: &str,
        fields: &[Field],
    ) -> Result<ChannelId> {
        ensure!(
            self.channels.iter().all(|c| c.topic != topic),
            "topic {topic} is declared twice"
        );
        let mut seen = HashSet::new();
        for f in fields {
            ensure!(!f.name.is_empty(), "topic {topic}: empty field name");
            ensure!(
                seen.insert(f.name.as_str()),
                "topic {topic}: field {} appears twice",
                f.name
            );
        }
        let schema = json_schema(fields);
        match self.schemas.get(schema_name) {
            Some(existing) if *existing != schema => {
                bail!("schema {schema_name} is declared twice with different fields")
            }
            Some(_) => {}
            None => {
                self.schemas.insert(schema_name.to_owned(), schema.clone());
            }
        }
        let schema_id = self
            .writer
            .add_schema(schema_name, SCHEMA_ENCODING, &schema)?;
        let id = self
            .writer
            .add_channel(schema_id, topic, MESSAGE_ENCODING, &BTreeMap::new())?;
        let fields = fields
            .iter()
            .enumerate()
            .map(|(i, f)| {
                let mut key = Vec::with_capacity(f.name.len() + 4);
                if i > 0 {
                    key.push(b',');
                }
                key.extend_from_slice(json_string(&f.name).as_bytes());
                key.push(b':');
                (f.kind, key.into_boxed_slice())
            })
            .collect();
        self.channels.push(Channel {
            id,
            topic: topic.to_owned(),
            fields,
            sequence: 0,
        });
        Ok(ChannelId(self.channels.len() - 1))
    }

    /// Records one message on `channel`: `values` are the channel's fields, in order (a
    /// [`Value::Int`] may fill a `Number` field, not the other way round). Its MCAP
    /// sequence number is the count of messages recorded on the channel before it (0, 1,
    /// 2, ...; wrapping after 2³²). Times are nanoseconds, as the caller defines them.
    pub fn write(
        &mut self,
        channel: ChannelId,
        log_time_ns: u64,
        publish_time_ns: u64,
        values: &[Value],
    ) -> Result<()> {
        let ch = self
            .channels
            .get_mut(channel.0)
            .ok_or_else(|| anyhow!("unknown channel {channel:?}"))?;
        if values.len() != ch.fields.len() {
            bail!(
                "topic {}: {} values for {} fields",
                ch.topic,
                values.len(),
                ch.fields.len()
            );
        }
        let buf = &mut self.buf;
        buf.clear();
        buf.push(b'{');
        for ((kind, key), value) in ch.fields.iter().zip(values) {
            buf.extend_from_slice(key);
            match (kind, *value) {
                (_, Value::Int(i)) => CompactFormatter.write_u64(buf, i)?,
                (FieldKind::Number, Value::Num(x)) if x.is_finite() => {
                    CompactFormatter.write_f64(buf, x)?
                }
                (FieldKind::Number, Value::Num(_)) => buf.extend_from_slice(b"null"),
                (FieldKind::Integer, Value::Num(x)) => {
                    let name = String::from_utf8_lossy(&key[usize::from(key[0] == b',')..]);
                    bail!(
                        "topic {}: integer field {name} given the number {x}",
                        ch.topic
                    )
                }
            }
        }
        buf.push(b'}');
        let buf = std::mem::take(&mut self.buf);
        let written = self.put(channel.0, log_time_ns, publish_time_ns, &buf);
        self.buf = buf;
        written
    }

    /// Writes an encoded message on channel `index`, with the channel's next sequence
    /// number.
    fn put(
        &mut self,
        index: usize,
        log_time_ns: u64,
        publish_time_ns: u64,
        data: &[u8],
    ) -> Result<()> {
        let ch = &mut self.channels[index];
        let header = MessageHeader {
            channel_id: ch.id,
            sequence: ch.sequence,
            log_time: log_time_ns,
            publish_time: publish_time_ns,
        };
        self.writer
            .write_to_known_channel(&header, data)
            .with_context(|| format!("cannot write {}", self.part.display()))?;
        ch.sequence = ch.sequence.wrapping_add(1);
        Ok(())
    }

    /// Whether a channel of `topic` is declared.
    pub fn has_topic(&self, topic: &str) -> bool {
        self.channels.iter().any(|c| c.topic == topic)
    }

    /// Records a message already encoded for the channel of `topic` — one copied from an
    /// earlier recording with the same channel layout (`rig run --resume`).
    pub fn write_encoded(
        &mut self,
        topic: &str,
        log_time_ns: u64,
        publish_time_ns: u64,
        data: &[u8],
    ) -> Result<()> {
        let index = self
            .channels
            .iter()
            .position(|c| c.topic == topic)
            .ok_or_else(|| anyhow!("the recording has no topic {topic}"))?;
        self.put(index, log_time_ns, publish_time_ns, data)
    }

    /// Stores a file in the recording (e.g. the resolved `config.toml`, `text/x-toml`), with
    /// log and create times 0. Closes the current chunk.
    pub fn attach(&mut self, name: &str, media_type: &str, data: &[u8]) -> Result<()> {
        // The low-level calls avoid copying `data` into an `mcap::Attachment`.
        let header = mcap::records::AttachmentHeader {
            log_time: 0,
            create_time: 0,
            name: name.to_owned(),
            media_type: media_type.to_owned(),
        };
        self.writer.start_attachment(data.len() as u64, header)?;
        self.writer.put_attachment_bytes(data)?;
        self.writer.finish_attachment()?;
        Ok(())
    }

    /// Stores a named set of key–value strings (seed, versions, run id) as an MCAP metadata
    /// record. Closes the current chunk.
    pub fn metadata(&mut self, name: &str, entries: &BTreeMap<String, String>) -> Result<()> {
        let metadata = mcap::records::Metadata {
            name: name.to_owned(),
            metadata: entries.clone(),
        };
        self.writer.write_metadata(&metadata)?;
        Ok(())
    }

    /// Closes the current chunk and hands everything written so far to the operating
    /// system, so that a crash after this point loses nothing before it (see the module
    /// documentation). Calling it often makes smaller chunks; the summary is still written
    /// only by [`finish`](Self::finish).
    pub fn flush(&mut self) -> Result<()> {
        self.writer.flush()?;
        Ok(())
    }

    /// Writes the summary section and footer, syncs the file to disk and renames it to the
    /// path given to [`create`](Self::create).
    pub fn finish(self) -> Result<()> {
        let Recorder {
            mut writer,
            part,
            path,
            ..
        } = self;
        writer
            .finish()
            .with_context(|| format!("cannot finish {}", part.display()))?;
        let file = writer
            .into_inner()
            .into_inner()
            .map_err(|e| e.into_error())
            .with_context(|| format!("cannot write {}", part.display()))?;
        file.sync_all()
            .with_context(|| format!("cannot sync {}", part.display()))?;
        drop(file);
        std::fs::rename(&part, &path)
            .with_context(|| format!("cannot rename {} to {}", part.display(), path.display()))
    }
}

/// The JSON Schema of a channel: an object with flat `integer`/`number` properties, in
/// field order.
fn json_schema(fields: &[Field]) -> Vec<u8> {
    let mut s = String::from(r#"{"type":"object","properties":{"#);
    for (i, f) in fields.iter().enumerate() {
        if i > 0 {
            s.push(',');
        }
        let kind = match f.kind {
            FieldKind::Integer => "integer",
            FieldKind::Number => "number",
        };
        s.push_str(&json_string(&f.name));
        s.push_str(r#":{"type":""#);
        s.push_str(kind);
        s.push_str(r#""}"#);
    }
    s.push_str("}}");
    s.into_bytes()
}

/// `s` as a JSON string literal, quoted and escaped.
fn json_string(s: &str) -> String {
    serde_json::to_string(s).expect("a string always serialises")
}

#[cfg(test)]
mod tests {
    use super::*;
    use mcap::{MessageStream, Summary};
    use serde_json::json;

    fn tmpdir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("rig-record-test-{}-{name}", std::process::id()));
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
        let mut r = Recorder::create(path).unwrap();
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
        let mut per_topic: BTreeMap<String, Vec<(u32, u64, u64, serde_json::Value)>> =
            BTreeMap::new();
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
        r.finish().unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let summary = Summary::read(&bytes).unwrap().unwrap();
        assert!(
            summary.chunk_indexes.len() > 2,
            "{} chunks",
            summary.chunk_indexes.len()
        );
        let mut k = 0u32;
        for m in MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            assert_eq!((m.sequence, m.log_time), (k, k as u64));
            k += 1;
        }
        assert_eq!(k as u64, n);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
