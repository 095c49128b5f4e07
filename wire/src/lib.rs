//! The wire contract between plant, observer and agent processes, and the transport
//! over iceoryx2 0.10 zero-copy shared memory.
//!
//! ```text
//! plant ──Measurement──► observer ──Estimate──► agent ──Action──► plant
//!           (rig/<run>/measurement)   (rig/<run>/estimate)   (rig/<run>/action)
//! plant ──Truth──► supervisor only (rig/<run>/truth; angle-only sensing: ground truth)
//! ```
//!
//! Every payload is `#[repr(C)]`, made of `u64`, `f64` and fixed-size arrays of them,
//! sized for the largest system ([`MAX_X`] state and [`MAX_U`] action components), with a
//! versioned `#[type_name]` — iceoryx2 checks only name, size and alignment, so a layout
//! change must change the name. Each publish-subscribe service has an event service of
//! the same name: receivers may block on it instead of polling ([`Waiting`]). Service
//! names live under
//! `rig/<run id>/`, so runs on one host never see each other.
//!
//! Timestamps are `CLOCK_MONOTONIC` nanoseconds ([`now_ns`]), shared by all processes on
//! one host; a component that keeps real time reads them from a [`Monotonic`], which a
//! test replaces with a mock.

mod bus;
mod error;
mod messages;
mod nodes;
mod ports;
mod service;
mod time;
mod waiting;

pub use bus::Bus;
pub use error::Error;
pub use messages::{Action, Estimate, Header, MAX_U, MAX_X, Measurement, Truth, flags, topic};
pub use nodes::{DRIVER_RUN, Peer, node_name, peers};
pub use ports::{RecordedSignal, Rx, Tx};
pub use service::{
    BUFFER, PATIENCE, Qos, RUN_QOS, describe_service, payload_type_name, type_name_of,
};
pub use time::{Inbox, MS, MockTime, Monotonic, Scripted, now_ns};
pub use waiting::{FOREVER, Waiting};
