//! Which channels a viewer watches: the feed copies a message only for those, so that a
//! run with `--live` and no viewer (or a viewer of a few panels) pays for what is shown.
//!
//! The view's thread sets the flags from the server's subscriptions at least every
//! [`REFRESH`]; the feed reads them without waiting. A channel subscribed to starts to
//! receive within that time.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

/// How often at most the flags lag behind the server's subscriptions.
pub const REFRESH: Duration = Duration::from_millis(20);

/// Channels numbered beyond this are always copied (a run declares far fewer).
const FLAGGED: usize = 64;

/// One flag per channel index: whether a viewer subscribes to it.
pub struct Watched([AtomicBool; FLAGGED]);

impl Default for Watched {
    fn default() -> Self {
        Watched(std::array::from_fn(|_| AtomicBool::new(false)))
    }
}

impl Watched {
    /// Whether channel `index`'s messages are wanted.
    pub fn wants(&self, index: usize) -> bool {
        self.0
            .get(index)
            .is_none_or(|flag| flag.load(Ordering::Relaxed))
    }

    /// Says whether channel `index` is wanted.
    pub fn set(&self, index: usize, wanted: bool) {
        if let Some(flag) = self.0.get(index) {
            flag.store(wanted, Ordering::Relaxed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_channel_is_wanted_once_set_and_one_beyond_the_flags_always() {
        let w = Watched::default();
        assert!(!w.wants(3));
        w.set(3, true);
        assert!(w.wants(3) && !w.wants(2));
        w.set(3, false);
        assert!(!w.wants(3));
        assert!(w.wants(FLAGGED));
        w.set(FLAGGED, false);
        assert!(w.wants(FLAGGED));
    }
}
