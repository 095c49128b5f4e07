//! What `rig bridge driver` serves: the driver, the network, and the rules its commands
//! are judged by.

use std::time::Duration;

use crate::claim::Lease;
use crate::session::Network;

/// What `rig bridge driver` serves.
#[derive(Clone, Debug)]
pub struct DriverSide {
    /// The driver's id on this host.
    pub id: String,
    /// Where the rig's bridge connects, and who may.
    pub net: Network,
    /// Commands answering a sample more than this many periods older than the newest
    /// are dropped.
    pub max_age_periods: u64,
    /// Silence of the rig's pings after which the link is reported lost.
    pub link_timeout: Duration,
    /// How long a rig session holds the driver without a word from it.
    pub lease: Lease,
    /// Each action's sample-to-actuation delay across the link as CSV, if given
    /// (`seq,t_sample_ns,t_arrived_ns,sample_to_actuation`, ns on this host's clock: a
    /// file `rig learn --delay-from` takes).
    pub timing_out: Option<std::path::PathBuf>,
}
