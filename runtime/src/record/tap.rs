//! A recording's messages handed on as they are written — to a live view (`rig run
//! --live`) — in the recording's own encoding: one schema source for the file and the view.

/// Receives what a [`Recorder`](super::Recorder) declares and writes, encoded as in the
/// file. Its calls must return at once: the recorder drains the loop's topics, and a tap
/// that waits would hold the loop back. A slow consumer drops messages instead.
pub trait Tap: Send {
    /// A channel was declared: its topic, its schema and its messages' encoding (JSON
    /// with a JSON Schema, but for messages encoded elsewhere: the system's picture).
    /// Channels are numbered 0, 1, 2, … in the order declared (those of the file and those
    /// only for the tap alike, [`Recorder::live_channel`](super::Recorder::live_channel)).
    fn channel(&mut self, topic: &str, encoding: &super::scene::Encoding);
    /// A message on channel `index`: the message the file holds, and its log time.
    fn message(&mut self, index: usize, log_time_ns: u64, data: &[u8]);
}
