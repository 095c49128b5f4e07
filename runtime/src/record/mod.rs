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
//! - chunked, each chunk compressed with zstd (level 5, one thread),
//!   with chunk, data-section and summary CRCs, message indexes and
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
//! A channel of messages encoded elsewhere ([`Recorder::encoded_channel`]: the system's
//! picture, a protobuf `foxglove.SceneUpdate`, [`scene`]) takes its schema as given and
//! its messages as they are ([`Recorder::write_bytes`]).
//!
//! A [`Tap`] given to [`Recorder::set_tap`] receives every channel and every message as
//! it is written, in the same encoding; channels declared with [`Recorder::live_channel`]
//! go to the tap only, and leave the file's bytes as they are.
//!
//! [`Recorder::flush`] closes the current chunk and writes it out, which bounds what a
//! crash can lose; without it a chunk closes every 1 MiB of messages, written out the
//! same way. [`Recorder::flushes`] counts them: what was recorded before the last one
//! survives a crash.

use std::collections::{BTreeMap, HashSet};
use std::ffi::OsString;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use mcap::records::MessageHeader;
use serde_json::ser::{CompactFormatter, Formatter};

use crate::error::AtFile;

/// Message encoding of every channel.
const MESSAGE_ENCODING: &str = "json";
/// Schema encoding of every channel.
const SCHEMA_ENCODING: &str = "jsonschema";
/// zstd level of the chunks: the default run's `run.mcap` at 24 % of its JSON size
/// (levels 1 and 3: 26 %, 9: 23 %, at more CPU; `docs/results/speed.md`).
const COMPRESSION_LEVEL: u32 = 5;
/// Target uncompressed size of a chunk, in bytes.
const CHUNK_SIZE: u64 = 1024 * 1024;
/// The bytes of a message record beside its data: opcode, length, channel id, sequence,
/// log and publish time.
const MESSAGE_RECORD: u64 = 1 + 8 + 2 + 4 + 8 + 8;

pub mod channels;
mod error;
pub mod reader;
pub mod scene;
mod schema;
mod tap;
#[cfg(test)]
mod tests;

pub use error::RecordError;
use scene::Encoding;
pub use schema::{Field, FieldKind, Value};
use schema::{json_schema, json_string};
pub use tap::Tap;
/// A channel of a [`Recorder`], returned by [`Recorder::channel`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ChannelId(usize);

/// What the recorder keeps per channel to encode its messages.
struct Channel {
    /// The MCAP channel id; `None` for a channel of the tap only.
    id: Option<u16>,
    /// The topic, for error messages.
    topic: String,
    /// The schema and the messages' encoding, for a tap set later.
    encoding: Encoding,
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
    /// Uncompressed bytes of the message records in the open chunk.
    chunk_bytes: u64,
    /// How often everything recorded was written out ([`Recorder::flushes`]).
    flushes: u64,
    /// Where every channel and message goes besides the file ([`Recorder::set_tap`]).
    tap: Option<Box<dyn Tap>>,
}

impl Recorder {
    /// Starts an MCAP file that [`finish`](Self::finish) will move to `path`; until then
    /// it is written as `path` with `.part` appended (replacing any file of that name).
    pub fn create(path: &Path) -> Result<Recorder, RecordError> {
        let mut part = OsString::from(path.as_os_str());
        part.push(".part");
        let part = PathBuf::from(part);
        let file = File::create(&part).at("cannot create", &part)?;
        // Set every option that shapes the bytes explicitly: one compression thread (the
        // same bytes whatever the machine; no thread beside the loop's processes).
        let options = mcap::WriteOptions::new()
            .compression(Some(mcap::Compression::Zstd))
            .compression_level(COMPRESSION_LEVEL)
            .compression_threads(0)
            .profile("")
            // Chunks close in `put`, where the recorder knows it: `flushes`.
            .chunk_size(None)
            .use_chunks(true);
        let writer = options
            .create(BufWriter::with_capacity(1 << 16, file))
            .at("cannot write", &part)?;
        Ok(Recorder {
            writer,
            channels: Vec::new(),
            schemas: BTreeMap::new(),
            part,
            path: path.to_owned(),
            buf: Vec::with_capacity(1024),
            chunk_bytes: 0,
            flushes: 0,
            tap: None,
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
    ) -> Result<ChannelId, RecordError> {
        self.declare(topic, schema_name, fields, true)
    }

    /// Declares a channel as [`channel`](Self::channel) does, but for the [`Tap`] only:
    /// its messages are encoded the same way and handed to the tap, never written to the
    /// file (without a tap they go nowhere).
    pub fn live_channel(
        &mut self,
        topic: &str,
        schema_name: &str,
        fields: &[Field],
    ) -> Result<ChannelId, RecordError> {
        self.declare(topic, schema_name, fields, false)
    }

    /// Hands every channel declared so far, and from now on every channel and message, to
    /// `tap` too.
    pub fn set_tap(&mut self, mut tap: Box<dyn Tap>) {
        for c in &self.channels {
            tap.channel(&c.topic, &c.encoding);
        }
        self.tap = Some(tap);
    }

    /// Declares a channel, in the file or for the tap only.
    fn declare(
        &mut self,
        topic: &str,
        schema_name: &str,
        fields: &[Field],
        in_file: bool,
    ) -> Result<ChannelId, RecordError> {
        let mut seen = HashSet::new();
        for f in fields {
            if f.name.is_empty() {
                return Err(RecordError::EmptyField(topic.to_owned()));
            }
            if !seen.insert(f.name.as_str()) {
                return Err(RecordError::FieldTwice {
                    topic: topic.to_owned(),
                    field: f.name.clone(),
                });
            }
        }
        let encoding = Encoding {
            schema_name: schema_name.to_owned(),
            schema_encoding: SCHEMA_ENCODING.to_owned(),
            schema: json_schema(fields),
            message_encoding: MESSAGE_ENCODING.to_owned(),
        };
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
        self.add(topic, encoding, fields, in_file)
    }

    /// Declares a channel whose messages come encoded ([`write_bytes`](Self::write_bytes)),
    /// with the schema and encodings of `encoding` (the system's picture:
    /// [`scene::Scene`]). Topics must be unique.
    pub fn encoded_channel(
        &mut self,
        topic: &str,
        encoding: &Encoding,
    ) -> Result<ChannelId, RecordError> {
        self.add(topic, encoding.clone(), Vec::new(), true)
    }

    /// Adds a channel: its schema once per name, in the file or for the tap only.
    fn add(
        &mut self,
        topic: &str,
        encoding: Encoding,
        fields: Vec<(FieldKind, Box<[u8]>)>,
        in_file: bool,
    ) -> Result<ChannelId, RecordError> {
        if self.channels.iter().any(|c| c.topic == topic) {
            return Err(RecordError::TopicTwice(topic.to_owned()));
        }
        let name = &encoding.schema_name;
        match self.schemas.get(name) {
            Some(existing) if *existing != encoding.schema => {
                return Err(RecordError::SchemaTwice(name.clone()));
            }
            Some(_) => {}
            None => {
                self.schemas.insert(name.clone(), encoding.schema.clone());
            }
        }
        let id = match in_file {
            true => {
                let schema_id =
                    self.writer
                        .add_schema(name, &encoding.schema_encoding, &encoding.schema)?;
                Some(self.writer.add_channel(
                    schema_id,
                    topic,
                    &encoding.message_encoding,
                    &BTreeMap::new(),
                )?)
            }
            false => None,
        };
        if let Some(tap) = &mut self.tap {
            tap.channel(topic, &encoding);
        }
        self.channels.push(Channel {
            id,
            topic: topic.to_owned(),
            encoding,
            fields,
            sequence: 0,
        });
        Ok(ChannelId(self.channels.len() - 1))
    }

    /// Records one message already encoded on `channel` (one of
    /// [`encoded_channel`](Self::encoded_channel)), with its next sequence number.
    pub fn write_bytes(
        &mut self,
        channel: ChannelId,
        log_time_ns: u64,
        publish_time_ns: u64,
        data: &[u8],
    ) -> Result<(), RecordError> {
        if channel.0 >= self.channels.len() {
            return Err(RecordError::UnknownChannel(channel));
        }
        self.put(channel.0, log_time_ns, publish_time_ns, data)
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
    ) -> Result<(), RecordError> {
        let ch = self
            .channels
            .get_mut(channel.0)
            .ok_or(RecordError::UnknownChannel(channel))?;
        if values.len() != ch.fields.len() {
            return Err(RecordError::Values {
                topic: ch.topic.clone(),
                values: values.len(),
                fields: ch.fields.len(),
            });
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
                    let field = String::from_utf8_lossy(&key[usize::from(key[0] == b',')..]);
                    return Err(RecordError::NotInteger {
                        topic: ch.topic.clone(),
                        field: field.into_owned(),
                        x,
                    });
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
    /// number, and hands it to the tap.
    fn put(
        &mut self,
        index: usize,
        log_time_ns: u64,
        publish_time_ns: u64,
        data: &[u8],
    ) -> Result<(), RecordError> {
        if let Some(tap) = &mut self.tap {
            tap.message(index, log_time_ns, data);
        }
        let Some(channel_id) = self.channels[index].id else {
            return Ok(());
        };
        // As the `mcap` writer closes a chunk grown past its target size, but written
        // out at once and counted.
        if self.chunk_bytes > CHUNK_SIZE {
            self.flush()?;
        }
        self.chunk_bytes += MESSAGE_RECORD + data.len() as u64;
        let ch = &mut self.channels[index];
        let header = MessageHeader {
            channel_id,
            sequence: ch.sequence,
            log_time: log_time_ns,
            publish_time: publish_time_ns,
        };
        self.writer
            .write_to_known_channel(&header, data)
            .at("cannot write", &self.part)?;
        ch.sequence = ch.sequence.wrapping_add(1);
        Ok(())
    }

    /// Whether a channel of `topic` is declared in the file.
    pub fn has_topic(&self, topic: &str) -> bool {
        self.channels
            .iter()
            .any(|c| c.id.is_some() && c.topic == topic)
    }

    /// Records a message already encoded for the channel of `topic` — one copied from an
    /// earlier recording with the same channel layout (`rig run --resume`).
    pub fn write_encoded(
        &mut self,
        topic: &str,
        log_time_ns: u64,
        publish_time_ns: u64,
        data: &[u8],
    ) -> Result<(), RecordError> {
        let index = self
            .channels
            .iter()
            .position(|c| c.id.is_some() && c.topic == topic)
            .ok_or_else(|| RecordError::NoTopic(topic.to_owned()))?;
        self.put(index, log_time_ns, publish_time_ns, data)
    }

    /// Stores a file in the recording (e.g. the resolved `config.toml`, `text/x-toml`), with
    /// log and create times 0. Closes the current chunk.
    pub fn attach(&mut self, name: &str, media_type: &str, data: &[u8]) -> Result<(), RecordError> {
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
        self.chunk_bytes = 0;
        Ok(())
    }

    /// Stores a named set of key–value strings (seed, versions, run id) as an MCAP metadata
    /// record. Closes the current chunk.
    pub fn metadata(
        &mut self,
        name: &str,
        entries: &BTreeMap<String, String>,
    ) -> Result<(), RecordError> {
        let metadata = mcap::records::Metadata {
            name: name.to_owned(),
            metadata: entries.clone(),
        };
        self.writer.write_metadata(&metadata)?;
        self.chunk_bytes = 0;
        Ok(())
    }

    /// Closes the current chunk and hands everything written so far to the operating
    /// system, so that a crash after this point loses nothing before it (see the module
    /// documentation). Calling it often makes smaller chunks; the summary is still written
    /// only by [`finish`](Self::finish).
    pub fn flush(&mut self) -> Result<(), RecordError> {
        self.writer.flush().at("cannot write", &self.part)?;
        self.chunk_bytes = 0;
        self.flushes += 1;
        Ok(())
    }

    /// How many times everything recorded so far was written out to the operating system
    /// ([`flush`](Self::flush), also when a chunk reaches its size): a crash loses nothing
    /// recorded before the last of them.
    pub fn flushes(&self) -> u64 {
        self.flushes
    }

    /// Writes the summary section and footer, syncs the file to disk and renames it to the
    /// path given to [`create`](Self::create).
    pub fn finish(self) -> Result<(), RecordError> {
        let Recorder {
            mut writer,
            part,
            path,
            ..
        } = self;
        writer.finish().at("cannot finish", &part)?;
        let file = writer
            .into_inner()
            .into_inner()
            .map_err(|e| e.into_error())
            .at("cannot write", &part)?;
        file.sync_all().at("cannot sync", &part)?;
        drop(file);
        std::fs::rename(&part, &path).map_err(|source| RecordError::Rename {
            from: part,
            to: path,
            source,
        })
    }
}
