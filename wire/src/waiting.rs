//! How a process waits for its next message: asleep on the topic's event, or polling.

use std::time::Duration;

/// How a receiver waits for the next message, and so whether its sender must wake it.
///
/// A blocked receiver costs no CPU while it waits, but every message then costs an
/// operating-system wake-up (tens of µs on a virtual machine). A polling receiver sees a
/// message within a fraction of a µs once it runs, at the price of a busy CPU.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Waiting {
    /// Sleep on the topic's event until the sender wakes it.
    #[default]
    Block,
    /// Poll with the CPU's spin hint for up to this long, then block: for a receiver
    /// with a core of its own. [`FOREVER`]: never block.
    Spin(Duration),
    /// Poll, handing the CPU to any other runnable process between polls, for up to this
    /// long, then block: for processes that share cores. [`FOREVER`]: never block.
    Yield(Duration),
}

/// A polling bound without end: the receiver never blocks, and its senders need not
/// wake it.
pub const FOREVER: Duration = Duration::MAX;

impl Waiting {
    /// Whether a sender to receivers waiting this way must wake them (an event per
    /// message and receiver): unless they poll [`FOREVER`].
    pub fn needs_wake_up(self) -> bool {
        match self {
            Waiting::Block => true,
            Waiting::Spin(bound) | Waiting::Yield(bound) => bound != FOREVER,
        }
    }
}
