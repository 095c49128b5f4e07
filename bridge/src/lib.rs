//! A driver on one host, the rig on another: two bridges carry one driver's services
//! across the network over Zenoh, each side staying iceoryx2 zero-copy on its host.
//!
//! ```text
//!  driver's host                                         rig's host
//!  driver ──info, sample──► bridge driver ══Zenoh══► bridge rig ──info, sample──► rig
//!  driver ◄──command─────── (watchdog,      ◄══════   (stand-in   ◄──command──────
//!                            stale drops)    ping/pong  driver)
//! ```
//!
//! - [`serve_driver`] (`rig bridge driver`): beside the driver, listening; admits only the
//!   users of its credentials file, lets them reach this driver's keys only
//!   ([`session`]); answers pings; drops stale commands; says when the driver's watchdog
//!   engaged.
//! - [`serve_rig`] (`rig bridge rig`): beside the rig, connecting; publishes the driver's
//!   info and samples under the driver's id on this host, so `rig run --plant external`
//!   and `rig check-driver` work unchanged; carries the commands back; measures the
//!   link's round trips ([`timing`]) and places the driver's stamps on this host's clock
//!   ([`clock`]).
//! - [`probe`] (`rig bridge probe`): what a peer with given credentials, or none, can
//!   reach.
//! - [`message`]: what crosses, as bytes, under which keys.

pub mod claim;
pub mod clock;
mod driver_side;
pub mod error;
pub mod message;
mod outbox;
mod probe;
pub mod refusal;
mod rig_side;
pub mod session;
pub mod timing;

pub use driver_side::{serve_driver, settings::DriverSide};
pub use error::{Error, Result};
pub use probe::{Probed, probe};
pub use rig_side::{RigSide, serve_rig};
pub use session::Network;
pub use timing::LinkTiming;

use zenoh::Wait;
use zenoh::pubsub::Publisher;
use zenoh::qos::{CongestionControl, Priority};

/// What a bridge forwarded and dropped.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Counts {
    /// Commands passed on.
    pub commands: u64,
    /// Samples passed on.
    pub samples: u64,
    /// Info messages passed on.
    pub infos: u64,
    /// Commands dropped as stale (answering a sample too old).
    pub stale: u64,
    /// Commands dropped for not being after the last one of their session.
    pub out_of_order: u64,
    /// Messages of the wrong length.
    pub malformed: u64,
    /// RESETs dropped for having been passed on already (driver side), or sent again
    /// for want of an acknowledgement (rig side).
    pub repeated: u64,
    /// Commands of the holding session that never arrived (gaps in its numbers).
    pub lost: u64,
    /// Commands refused: another session held the driver.
    pub refused: u64,
    /// Times the driver's watchdog engaged (driver side), or the link was lost (rig
    /// side).
    pub watchdog: u64,
}

impl std::fmt::Display for Counts {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} commands, {} samples, {} infos passed on; dropped {} stale, {} out of order, {} malformed, {} repeated; {} lost; {} refused",
            self.commands,
            self.samples,
            self.infos,
            self.stale,
            self.out_of_order,
            self.malformed,
            self.repeated,
            self.lost,
            self.refused
        )
    }
}

/// A publisher for the loop's messages: real-time priority, sent at once (no
/// batching), dropped rather than queued when the link cannot take them.
fn publisher(session: &zenoh::Session, key: &str) -> Result<Publisher<'static>> {
    declare(session, key, CongestionControl::Drop)
}

/// A publisher for what must not be lost (resets, claims): as [`publisher`], but a put
/// waits for room on the link instead of being dropped. Of the same priority as the
/// loop's, so that the driver receives both in the order they were put.
fn reliable_publisher(session: &zenoh::Session, key: &str) -> Result<Publisher<'static>> {
    declare(session, key, CongestionControl::Block)
}

fn declare(
    session: &zenoh::Session,
    key: &str,
    congestion: CongestionControl,
) -> Result<Publisher<'static>> {
    session
        .declare_publisher(key.to_string())
        .priority(Priority::RealTime)
        .express(true)
        .congestion_control(congestion)
        .wait()
        .map_err(error::zenoh(|| format!("publisher on {key}")))
}
