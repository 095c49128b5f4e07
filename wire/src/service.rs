//! Publish-subscribe settings of a service, and what an existing service carries.

use std::time::Duration;

use iceoryx2::prelude::*;

/// Subscriber buffer of every run topic: the recorder may lag this many samples behind
/// (about a quarter of a second of the default lockstep experiment) before it holds the
/// loop back ([`RUN_QOS`]).
pub const BUFFER: usize = 16384;

/// How long a publisher on a run topic waits for a subscriber whose buffer is full
/// before it drops the message for that subscriber (and `rig run` stops with an error
/// naming the topic): a process that stopped reading, not one that is merely slow.
pub const PATIENCE: Duration = Duration::from_secs(10);

/// Publish-subscribe settings of a service. Both ends must use the same values:
/// iceoryx2 refuses to open a service whose settings cannot serve the opener's.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Qos {
    /// Publishers at most.
    pub max_publishers: usize,
    /// Subscribers at most.
    pub max_subscribers: usize,
    /// Samples a subscriber may have waiting.
    pub buffer: usize,
    /// When a subscriber's buffer is full: `true` overwrites its oldest sample (the
    /// publisher never waits); `false` makes the publisher wait until the subscriber has
    /// read one, for up to [`PATIENCE`].
    pub safe_overflow: bool,
}

/// Settings of the run topics (`rig/<run id>/...`). A publisher waits for a subscriber
/// that lags a whole buffer behind — in practice the recorder on a machine busy with
/// other work — rather than lose its messages: in lockstep the run slows down; in real
/// time, where the recorder lagging [`BUFFER`] samples behind is minutes of samples, late
/// actions are counted as deadline misses. Nothing is lost either way.
pub const RUN_QOS: Qos = Qos {
    max_publishers: 1,
    max_subscribers: 4,
    buffer: BUFFER,
    safe_overflow: false,
};

/// The `#[type_name]` of a payload type: its identity across processes and languages.
pub fn type_name_of<T: ZeroCopySend>() -> &'static str {
    // SAFETY: only reads the name; the layout guarantee the trait asks for is the
    // implementer's (every payload here is `#[repr(C)]` and derives it).
    unsafe { <T as ZeroCopySend>::type_name() }
}

/// The payload type name of existing publish-subscribe service `service` (e.g.
/// `rig.DriverInfo.v3`), if there is one and its settings can be read.
pub fn payload_type_name(service: &str, config: &iceoryx2::config::Config) -> Option<String> {
    let name = ServiceName::new(service).ok()?;
    let d = ipc::Service::details(&name, config, MessagingPattern::PublishSubscribe).ok()??;
    let ps = d.static_details.publish_subscribe();
    Some(ps.message_type_details().payload.type_name().to_string())
}

/// What an existing publish-subscribe service carries, in words, e.g. "the existing
/// service carries payload `X` (16 bytes, alignment 8), max 1 publisher(s), 8
/// subscribers, buffer 2" — for error messages about incompatible peers.
pub fn describe_service(name: &ServiceName, config: &iceoryx2::config::Config) -> String {
    match ipc::Service::details(name, config, MessagingPattern::PublishSubscribe) {
        Ok(Some(d)) => {
            let ps = d.static_details.publish_subscribe();
            let p = &ps.message_type_details().payload;
            format!(
                "the existing service carries payload {} ({} bytes, alignment {}), max {} publisher(s), {} subscribers, buffer {}",
                p.type_name(),
                p.size(),
                p.alignment(),
                ps.max_publishers(),
                ps.max_subscribers(),
                ps.subscriber_max_buffer_size()
            )
        }
        Ok(None) => "no such service exists yet".to_string(),
        Err(e) => format!("its settings cannot be read ({e:?})"),
    }
}
