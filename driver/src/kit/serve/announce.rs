//! When a driver publishes its info: at start, at least once a second, and at once when
//! its readers change (a rig that starts need not wait for the next second).

use std::time::Duration;

use super::Services;
use crate::contract::DriverInfo;
use crate::error::Error;

/// How often the info is published while nothing else prompts it.
pub const INFO_EVERY: Duration = Duration::from_secs(1);

/// The driver's info and when it is next due.
pub struct Announcer {
    advertised: DriverInfo,
    next_ns: u64,
    readers: usize,
}

impl Announcer {
    /// Announces `advertised`, published once already (at start), on `io`'s time.
    pub fn new(advertised: DriverInfo, io: &Services) -> Self {
        Self {
            advertised,
            next_ns: io.time.now_ns() + INFO_EVERY.as_nanos() as u64,
            readers: io.infos.receivers(),
        }
    }

    /// When the info is next due by the clock (monotonic \[ns\]).
    pub fn next_ns(&self) -> u64 {
        self.next_ns
    }

    /// Publishes the info if a second has passed since it last went out or the number
    /// of its readers changed since the last call (a rig joined, or one left and may be
    /// followed by another).
    pub fn publish_if_due(&mut self, io: &Services) -> Result<(), Error> {
        let readers = io.infos.receivers();
        let changed = readers != self.readers;
        self.readers = readers;
        if changed || io.time.now_ns() >= self.next_ns {
            io.publish_info(self.advertised)?;
            self.next_ns = io.time.now_ns() + INFO_EVERY.as_nanos() as u64;
        }
        Ok(())
    }
}
