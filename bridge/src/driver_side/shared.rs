//! What the driver's side's two halves share: the commands passed to the driver, the
//! newest samples, the driver's period and the last ping, each with when it came.

use std::collections::VecDeque;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64};

/// What the two halves share.
#[derive(Default)]
pub(crate) struct Shared {
    pub(crate) stop: AtomicBool,
    /// `seq` of the last command passed to the driver, and when it arrived.
    pub(crate) command: AtomicU64,
    pub(crate) command_arrived: AtomicU64,
    /// When the last ACTION passed to the driver arrived; 0 once a RESET or another
    /// control command followed it.
    pub(crate) action_arrived: AtomicU64,
    /// The newest sample's `seq`.
    pub(crate) newest: AtomicU64,
    /// The driver's period (0 until its info came) \[ns\].
    pub(crate) period_ns: AtomicU64,
    /// When the last ping arrived.
    pub(super) pinged: AtomicU64,
    /// The recent samples' `(seq, t_sample_ns)`, the newest last.
    pub(crate) sampled: Mutex<VecDeque<(u64, u64)>>,
}
