//! Why a connection did not become a session, as far as Zenoh's own log tells: the
//! bridges capture Zenoh's `tracing` events about opening and accepting links.
//!
//! - The connecting side tells nothing listening at the endpoint (the connection
//!   refused), its user or password refused (the listener closed the link at Zenoh's
//!   authentication: an unknown user and a wrong password look alike from here), a
//!   failed TLS handshake (with rustls's reason), and a link closed during the handshake
//!   for another reason ([`Refusal`]).
//! - The listening side logs each connection it refuses: an unknown user or a wrong
//!   password with the address the connection came from (the link Zenoh accepted last),
//!   a failed TLS handshake with its reason (Zenoh does not log the address of those).

use std::sync::{Arc, Mutex};
use std::time::Duration;

use wire::Monotonic;

use tracing::field::{Field, Visit};
use tracing::{Event, Level, Subscriber};
use tracing_subscriber::Layer;
use tracing_subscriber::filter::Targets;
use tracing_subscriber::layer::{Context, SubscriberExt};

/// Why the connecting side's link did not become a session.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Refusal {
    /// The connection was refused: nothing listens at the endpoint.
    NoListener,
    /// The listener closed the link at Zenoh's authentication.
    Credentials,
    /// The TLS handshake failed, for this reason.
    Tls(String),
    /// The link closed during Zenoh's handshake, as said.
    Closed(String),
}

impl Refusal {
    /// What Zenoh said when a connection failed, if it tells why.
    pub fn of(said: &str) -> Option<Self> {
        let said = &unlocated(said);
        let lower = said.to_lowercase();
        let tls = ["certificate", "fatal alert", "handshake", "unknownissuer"];
        Some(if lower.contains("connection refused") {
            Refusal::NoListener
        } else if said.contains("in response to an OpenSyn") {
            Refusal::Credentials
        } else if tls.iter().any(|w| lower.contains(w)) {
            Refusal::Tls(reason(said))
        } else if said.contains("in response to an InitSyn")
            || lower.contains("connection reset")
            || lower.contains("read error")
            || lower.contains("end of file")
        {
            Refusal::Closed(reason(said))
        } else {
            return None;
        })
    }

    /// One line, for the connecting side at `endpoint`.
    pub fn explain(&self, endpoint: &str) -> String {
        match self {
            Refusal::NoListener => format!(
                "nothing listens at {endpoint} (the connection was refused): is `rig bridge driver` running there, on that port?"
            ),
            Refusal::Credentials => format!(
                "the driver's bridge at {endpoint} refused this user or password (it closed the link at Zenoh's authentication): check the credentials file"
            ),
            Refusal::Tls(why) => format!(
                "the TLS handshake with {endpoint} failed: {why} (the certificates of the Zenoh configuration files)"
            ),
            Refusal::Closed(why) => format!(
                "{endpoint} closed the link during Zenoh's handshake: {why} (does it speak TLS where this side does not, or the other way round?)"
            ),
        }
    }
}

/// Zenoh's message without the retry's tail.
fn reason(said: &str) -> String {
    said.split(". Retry in")
        .next()
        .unwrap_or(said)
        .trim()
        .to_string()
}

/// Zenoh's message without the source locations its errors carry (` at /…/x.rs:105`).
fn unlocated(said: &str) -> String {
    let mut out = String::with_capacity(said.len());
    let mut rest = said;
    while let Some(at) = rest.find(" at /") {
        out.push_str(&rest[..at]);
        let tail = &rest[at..];
        let end = tail.find(".rs:").map_or(tail.len(), |i| {
            let digits = tail[i + 4..].find(|c: char| !c.is_ascii_digit());
            i + 4 + digits.unwrap_or(tail.len() - i - 4)
        });
        rest = &tail[end..];
    }
    out.push_str(rest);
    out
}

/// Why the listening side refused a connection, in words, if Zenoh said.
fn refused(said: &str) -> Option<&'static str> {
    if said.contains("UsrPwd") && said.contains("Invalid password") {
        Some("wrong password for its user")
    } else if said.contains("UsrPwd") && said.contains("Invalid user") {
        Some("a user not in the credentials file")
    } else if said.contains("Can not accept TLS connection") || said.contains("fatal alert") {
        Some("TLS handshake failed")
    } else {
        None
    }
}

/// What the bridge has heard of refusals.
#[derive(Default)]
pub struct Heard {
    /// The connecting side's latest refusal.
    latest: Mutex<Option<Refusal>>,
}

impl Heard {
    /// The latest refusal of this side's connection, if any.
    pub fn latest(&self) -> Option<Refusal> {
        self.latest
            .lock()
            .expect("no panics while holding it")
            .clone()
    }
}

/// The layer that listens to Zenoh's events.
struct Listening {
    heard: Arc<Heard>,
    /// Print every event listened to (`RIG_ZENOH_EVENTS=1`).
    echo: bool,
    /// The listening side: prefix of its log lines, and the address of the link Zenoh
    /// accepted last; refusals said, to say each once a minute.
    listener: Option<(String, Said)>,
    /// The time refusals are said on.
    time: Monotonic,
}

/// The address of the link Zenoh accepted last, and each refusal said with when.
type Said = Mutex<(String, Vec<(String, u64)>)>;

/// A refusal is said again after this long at the earliest.
const SAY_AGAIN_AFTER: Duration = Duration::from_secs(60);

/// Whether `line` is to be said at `now`: not said within [`SAY_AGAIN_AFTER`] before
/// (`said`: the lines said, with when, which this keeps).
fn to_say(said: &mut Vec<(String, u64)>, line: &str, now: u64) -> bool {
    said.retain(|(_, t)| now.saturating_sub(*t) < SAY_AGAIN_AFTER.as_nanos() as u64);
    if said.iter().any(|(l, _)| l == line) {
        return false;
    }
    said.push((line.to_string(), now));
    true
}

/// The message of an event.
#[derive(Default)]
struct Message(String);

impl Visit for Message {
    fn record_debug(&mut self, field: &Field, value: &dyn std::fmt::Debug) {
        if field.name() == "message" {
            self.0 = format!("{value:?}");
        }
    }
}

impl<S: Subscriber> Layer<S> for Listening {
    fn on_event(&self, event: &Event<'_>, _: Context<'_, S>) {
        let mut m = Message::default();
        event.record(&mut m);
        if self.echo {
            let meta = event.metadata();
            eprintln!("zenoh {} {}: {}", meta.level(), meta.target(), m.0);
        }
        if let Some(r) = Refusal::of(&m.0).filter(|_| self.listener.is_none()) {
            *self
                .heard
                .latest
                .lock()
                .expect("no panics while holding it") = Some(r);
        }
        let Some((prefix, state)) = &self.listener else {
            return;
        };
        let mut state = state.lock().expect("no panics while holding it");
        if let Some(link) = m.0.strip_prefix("Accepting link... ") {
            state.0 = link.rsplit(" => ").next().unwrap_or(link).to_string();
            return;
        }
        let Some(why) = refused(&m.0) else {
            return;
        };
        let line = match why {
            "TLS handshake failed" => {
                let said = m.0.split(". Hint:").next().unwrap_or(&m.0);
                format!("refused a TLS connection: {said}")
            }
            _ => format!("refused a connection from {}: {why}", state.0),
        };
        if to_say(&mut state.1, &line, self.time.now_ns()) {
            eprintln!("{prefix}: {line}");
        }
    }
}

/// Starts listening to Zenoh's events about links, for this process (the first call
/// decides): on the listening side (`listener`: its log lines' prefix), logs each
/// refused connection; on the connecting side, keeps why its connection failed. With
/// the environment variable `RIG_ZENOH_EVENTS=1`, every such event is printed too.
pub fn listen(listener: Option<String>) -> Arc<Heard> {
    let heard = Arc::new(Heard::default());
    let layer = Listening {
        heard: heard.clone(),
        echo: std::env::var_os("RIG_ZENOH_EVENTS").is_some_and(|v| v == "1"),
        listener: listener.map(|p| {
            (
                p,
                Mutex::new((String::from("an unknown address"), Vec::new())),
            )
        }),
        time: Monotonic::host(),
    };
    let targets = Targets::new()
        .with_target("zenoh_transport::unicast::manager", Level::TRACE)
        .with_target("zenoh_transport", Level::DEBUG)
        .with_target("zenoh_link_tls", Level::DEBUG)
        .with_target("zenoh::net::runtime::orchestrator", Level::DEBUG);
    let subscriber = tracing_subscriber::registry().with(layer.with_filter(targets));
    let _ = tracing::subscriber::set_global_default(subscriber);
    heard
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn what_zenoh_says_tells_why() {
        let refused = "Unable to connect to configured peer tcp/10.0.0.1:7447! Can not create a new TCP link bound to 10.0.0.1:7447: Connection refused (os error 111). Retry in 100ms.";
        assert_eq!(Refusal::of(refused), Some(Refusal::NoListener));
        let closed = "Received a close message (reason GENERIC) in response to an OpenSyn on: Link { src: tcp/10.0.0.2:5 }";
        assert_eq!(Refusal::of(closed), Some(Refusal::Credentials));
        let tls = "Unable to connect to configured peer tls/10.0.0.1:7447! invalid peer certificate: UnknownIssuer. Retry in 100ms.";
        assert_eq!(
            Refusal::of(tls),
            Some(Refusal::Tls(
                "Unable to connect to configured peer tls/10.0.0.1:7447! invalid peer certificate: UnknownIssuer".into()
            ))
        );
        assert_eq!(Refusal::of("Try to connect: tcp/10.0.0.1:7447"), None);
        let located =
            "Read error on TLS link x at /r/zenoh-link-tls-1.10.2/src/unicast.rs:213. Retry in 1s.";
        assert_eq!(unlocated(located), "Read error on TLS link x. Retry in 1s.");
        assert_eq!(
            Refusal::of(located),
            Some(Refusal::Closed("Read error on TLS link x".into()))
        );
        assert!(
            Refusal::NoListener
                .explain("tcp/x:1")
                .contains("nothing listens at tcp/x:1")
        );
        assert!(
            Refusal::Credentials
                .explain("tcp/x:1")
                .contains("refused this user or password")
        );
        assert_eq!(
            super::refused("UsrPwd extension - Recv OpenSyn. Invalid password."),
            Some("wrong password for its user")
        );
        assert_eq!(super::refused("Listener added"), None);
        assert_eq!(
            super::refused(
                "received fatal alert: UnknownCA. Hint: increase the system open file limit."
            ),
            Some("TLS handshake failed")
        );
    }

    /// A refusal is said once a minute at most, each of its kind.
    #[test]
    fn a_refusal_is_said_once_a_minute() {
        let (clock, time) = Monotonic::mock();
        let mut said = Vec::new();
        assert!(to_say(&mut said, "refused a", clock.now_ns()));
        assert!(to_say(&mut said, "refused b", clock.now_ns()));
        time.advance(Duration::from_millis(59_999));
        assert!(!to_say(&mut said, "refused a", clock.now_ns()));
        time.advance(Duration::from_millis(1));
        assert!(to_say(&mut said, "refused a", clock.now_ns()));
        assert_eq!(said.len(), 1);
    }
}
