//! Why a recording could not be declared or written.

use crate::error::FileError;

use super::ChannelId;

/// Why the recorder refused a channel or a message, or could not write its file.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// The file could not be created, written, synced or renamed.
    #[error(transparent)]
    File(#[from] FileError),
    /// The MCAP writer refused a record.
    #[error(transparent)]
    Mcap(#[from] mcap::McapError),
    /// A message could not be encoded.
    #[error(transparent)]
    Encode(#[from] std::io::Error),
    /// Two channels of one topic.
    #[error("topic {0} is declared twice")]
    TopicTwice(String),
    /// A field without a name.
    #[error("topic {0}: empty field name")]
    EmptyField(String),
    /// Two fields of one name in a channel.
    #[error("topic {topic}: field {field} appears twice")]
    FieldTwice {
        /// The channel's topic.
        topic: String,
        /// The field.
        field: String,
    },
    /// One schema name for two field lists.
    #[error("schema {0} is declared twice with different fields")]
    SchemaTwice(String),
    /// A channel this recorder did not declare.
    #[error("unknown channel {0:?}")]
    UnknownChannel(ChannelId),
    /// A message with more or fewer values than its channel has fields.
    #[error("topic {topic}: {values} values for {fields} fields")]
    Values {
        /// The channel's topic.
        topic: String,
        /// Values given.
        values: usize,
        /// Fields declared.
        fields: usize,
    },
    /// A number given for an integer field.
    #[error("topic {topic}: integer field {field} given the number {x}")]
    NotInteger {
        /// The channel's topic.
        topic: String,
        /// The field (its JSON key).
        field: String,
        /// The number.
        x: f64,
    },
    /// An encoded message for a topic the file has no channel of.
    #[error("the recording has no topic {0}")]
    NoTopic(String),
    /// The finished file could not be moved to its name.
    #[error("cannot rename {} to {}", from.display(), to.display())]
    Rename {
        /// The file written.
        from: std::path::PathBuf,
        /// Its name.
        to: std::path::PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
}
