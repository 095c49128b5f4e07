//! What can go wrong in a bridge, one variant per cause, each a line that names what it
//! was doing: Zenoh's errors and the loop's transport's (iceoryx2) kept as they are.

use std::path::PathBuf;

/// A bridge's error.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// Zenoh refused or failed an operation.
    #[error("{doing}: {error}")]
    Zenoh {
        /// What the bridge was doing (`publishing on rig/…`, `cannot connect to tcp/…`).
        doing: String,
        /// Zenoh's error.
        error: zenoh::Error,
    },
    /// The loop's transport on this host (iceoryx2).
    #[error(transparent)]
    Wire(#[from] wire::Error),
    /// The driver's services on this host taken by another process.
    #[error("{doing} on this host: {error} ({hint})")]
    Taken {
        /// What the bridge was doing (`commanding driver "pend"`).
        doing: String,
        /// The transport's error.
        error: wire::Error,
        /// What probably holds them.
        hint: &'static str,
    },
    /// The driver contract.
    #[error(transparent)]
    Driver(#[from] driver::Error),
    /// A file the bridge reads or writes (credentials, a key, a configuration, timing).
    #[error("{what} {}: {error}", path.display())]
    File {
        /// What the file is (`credentials file`, `--timing-out`).
        what: String,
        /// The file.
        path: PathBuf,
        /// Why.
        error: std::io::Error,
    },
    /// Writing what the bridge measured.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// A secret file others than its owner may read.
    #[error(
        "{what} {} is open to others than its owner (mode {mode:04o}); refused: `chmod 600 {}`",
        path.display(), path.display()
    )]
    OpenSecret {
        /// What the file is.
        what: String,
        /// The file.
        path: PathBuf,
        /// Its permission bits.
        mode: u32,
    },
    /// A credentials file that is not `user:password` lines.
    #[error("credentials file {}{problem}", path.display())]
    Credentials {
        /// The file.
        path: PathBuf,
        /// What is wrong in it.
        problem: Credentials,
    },
    /// A Zenoh configuration the bridge cannot read or set.
    #[error("Zenoh configuration {key}: {error}")]
    Config {
        /// The key (with its value) or the file.
        key: String,
        /// Zenoh's or the JSON reader's error.
        error: String,
    },
    /// A message of another length than its type's.
    #[error(
        "a {name} of {found} bytes arrived, {want} expected: is the other bridge of another version?"
    )]
    Length {
        /// The message type.
        name: &'static str,
        /// Its length.
        found: usize,
        /// The type's.
        want: usize,
    },
    /// A command without the claim that says whose it is.
    #[error("a command without its claim")]
    Unclaimed,
    /// A thread of the bridge panicked.
    #[error("the {0} thread panicked")]
    Panicked(&'static str),
}

/// What is wrong in a credentials file (said after its name).
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum Credentials {
    /// A line that is not `user:password`.
    #[error(
        " line {0}: expected `user:password` (a user without spaces, neither empty; no comments)"
    )]
    Line(usize),
    /// No line at all.
    #[error(": no `user:password` line")]
    Empty,
    /// A user that cannot name a key.
    #[error(
        ": user {0:?}: a user's name may hold letters, digits, '.', '-' and '_' only (it names the keys it commands on)"
    )]
    User(String),
}

/// The result of a bridge's operation.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Zenoh's error while doing what `doing` says (said only when it failed).
pub(crate) fn zenoh(doing: impl FnOnce() -> String) -> impl FnOnce(zenoh::Error) -> Error {
    move |error| Error::Zenoh {
        doing: doing(),
        error,
    }
}
