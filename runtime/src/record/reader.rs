//! The one reader of `run.mcap` ([`RunFile`]): its metadata and attachments by the
//! summary (a finished file), and its messages streamed in file order — of a finished
//! file, or of the `run.mcap.part` a killed supervisor leaves, up to its unfinished chunk.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use mcap::McapError;

/// The recording's name in a run folder.
pub const NAME: &str = "run.mcap";
/// Its name until the recorder has finished it.
pub const PART: &str = "run.mcap.part";

/// One message of a recording, as stored.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RecordedMessage {
    /// Its topic.
    pub topic: String,
    /// Log time \[ns\].
    pub log_time: u64,
    /// Publish time \[ns\].
    pub publish_time: u64,
    /// The message (JSON for every channel but `/scene`).
    pub data: Vec<u8>,
}

/// A recording read into memory.
pub struct RunFile {
    /// Where it was read from.
    pub path: PathBuf,
    bytes: Vec<u8>,
}

impl RunFile {
    /// Reads the file at `path`.
    pub fn read(path: &Path) -> std::io::Result<RunFile> {
        Ok(RunFile {
            path: path.to_owned(),
            bytes: std::fs::read(path)?,
        })
    }

    /// Its summary: `None` for a file without one (unfinished files fail to read).
    pub fn summary(&self) -> Result<Option<mcap::Summary>, McapError> {
        mcap::Summary::read(&self.bytes)
    }

    /// The metadata record `name`, through `summary`.
    pub fn metadata(
        &self,
        summary: &mcap::Summary,
        name: &str,
    ) -> Option<BTreeMap<String, String>> {
        summary
            .metadata_indexes
            .iter()
            .filter(|i| i.name == name)
            .find_map(|i| mcap::read::metadata(&self.bytes, i).ok())
            .map(|m| m.metadata)
    }

    /// The attachment `name`'s data, through `summary`.
    pub fn attachment(&self, summary: &mcap::Summary, name: &str) -> Option<Vec<u8>> {
        summary
            .attachment_indexes
            .iter()
            .filter(|i| i.name == name)
            .find_map(|i| mcap::read::attachment(&self.bytes, i).ok())
            .map(|a| a.data.into_owned())
    }

    /// Every message in file order; an unfinished chunk ends the stream with an error.
    pub fn messages(&self) -> Result<mcap::MessageStream<'_>, McapError> {
        mcap::MessageStream::new(&self.bytes)
    }

    /// Every message that can be read, in file order, copied; and the error that ended
    /// the stream early (an unfinished chunk), if one did.
    pub fn readable(&self) -> Result<(Vec<RecordedMessage>, Option<McapError>), McapError> {
        let mut messages = Vec::new();
        for m in self.messages()? {
            match m {
                Ok(m) => messages.push(RecordedMessage {
                    topic: m.channel.topic.clone(),
                    log_time: m.log_time,
                    publish_time: m.publish_time,
                    data: m.data.into_owned(),
                }),
                Err(e) => return Ok((messages, Some(e))),
            }
        }
        Ok((messages, None))
    }
}
