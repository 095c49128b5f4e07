//! What crosses the network: the driver contract's messages as their bytes, under one
//! key per topic, with the bridges' own stamps beside them.
//!
//! ```text
//! rig/driver/<id>/info             DriverInfo     driver's host → rig's host
//! rig/driver/<id>/sample           DriverSample   driver's host → rig's host   (+ Stamps)
//! rig/driver/<id>/command/<user>   DriverCommand  rig's host → driver's host   (+ Claim)
//! rig/driver/<id>/claim/<user>     Claim          rig's host → driver's host   (hold, release)
//! rig/driver/<id>/ping             Ping           rig's host → driver's host
//! rig/driver/<id>/pong             Ping           driver's host → rig's host
//! rig/driver/<id>/refused          text           driver's host → rig's host   (+ Claim)
//! ```
//!
//! Commands and claims go under the user who puts them: the driver's side lets each user
//! put on its own keys only, so the key names the commanding user ([`crate::claim`]).
//!
//! A message is its `#[repr(C)]` layout's bytes (both hosts little-endian, as every
//! platform iceoryx2 supports); the receiver checks the length, so a bridge of another
//! contract version is refused by name, not misread.

use crate::error::{Credentials, Error, Result};
use driver::contract::{DriverCommand, DriverInfo, DriverSample, service};

use crate::claim::Claim;

/// A message the bridges carry: a `#[repr(C)]` struct of `u64`, `f64` and `u8` arrays,
/// without padding, for which every bit pattern is a value.
///
/// # Safety
/// Implement only for such types: [`to_bytes`] reads and [`from_bytes`] writes every
/// byte of the value.
pub unsafe trait Message: Copy + 'static {
    /// The type's name in errors: the contract's iceoryx2 type name where it has one, so
    /// that a new version of a contract message is named by its own version.
    fn name() -> &'static str;
}

// SAFETY: u64, f64 and [u8; 32] fields only, sizes pinned by the driver contract's tests
// (184, 200, 144 bytes: the sums of their fields).
unsafe impl Message for DriverInfo {
    fn name() -> &'static str {
        wire::type_name_of::<Self>()
    }
}
// SAFETY: as above.
unsafe impl Message for DriverSample {
    fn name() -> &'static str {
        wire::type_name_of::<Self>()
    }
}
// SAFETY: as above.
unsafe impl Message for DriverCommand {
    fn name() -> &'static str {
        wire::type_name_of::<Self>()
    }
}
// SAFETY: three u64.
unsafe impl Message for Ping {
    fn name() -> &'static str {
        "rig.BridgePing.v1"
    }
}
// SAFETY: three u64.
unsafe impl Message for Stamps {
    fn name() -> &'static str {
        "rig.BridgeStamps.v1"
    }
}
// SAFETY: [u8; 16] and three u64 (40 bytes).
unsafe impl Message for Claim {
    fn name() -> &'static str {
        "rig.BridgeClaim.v1"
    }
}

/// The bytes of `m`.
pub fn to_bytes<T: Message>(m: &T) -> Vec<u8> {
    // SAFETY: `Message` types have no padding: every byte is initialised.
    unsafe { std::slice::from_raw_parts((m as *const T).cast::<u8>(), size_of::<T>()) }.to_vec()
}

/// The message whose bytes are `b`; an error naming the type if the length differs.
pub fn from_bytes<T: Message>(b: &[u8]) -> Result<T> {
    if b.len() != size_of::<T>() {
        return Err(Error::Length {
            name: T::name(),
            found: b.len(),
            want: size_of::<T>(),
        });
    }
    // SAFETY: the length is the type's, and every bit pattern is a value (`Message`).
    Ok(unsafe { std::ptr::read_unaligned(b.as_ptr().cast::<T>()) })
}

/// A round trip of the link, on the rig's host's clock (`sent`, and the arrival of the
/// answer) and the driver's (`arrived`, `answered`): the clocks' offset and the network's
/// share of the round trip follow without the clocks agreeing ([`crate::clock`]).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Ping {
    /// When the rig's bridge sent the ping (its monotonic clock, ns).
    pub sent: u64,
    /// When the driver's bridge received it (its monotonic clock, ns).
    pub arrived: u64,
    /// When the driver's bridge answered (its monotonic clock, ns).
    pub answered: u64,
}

/// The driver's bridge's stamps on a sample it forwards (the sample's attachment).
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stamps {
    /// `seq` of the last command it passed to the driver (0: none yet).
    pub command: u64,
    /// When that command arrived (the driver's host's clock, ns).
    pub command_arrived: u64,
    /// When the sample left for the network (the driver's host's clock, ns).
    pub forwarded: u64,
}

/// The topics the bridges carry for one driver.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Topic {
    /// [`DriverInfo`], driver → rig.
    Info,
    /// [`DriverSample`] with [`Stamps`], driver → rig.
    Sample,
    /// [`DriverCommand`] with its [`Claim`], rig → driver, per user.
    Command,
    /// A [`Claim`] held on to or let go, rig → driver, per user.
    Claim,
    /// [`Ping`], rig → driver.
    Ping,
    /// [`Ping`] answered, driver → rig.
    Pong,
    /// Who holds the driver, in words, to a session refused (its [`Claim`] attached),
    /// driver → rig.
    Refused,
}

impl Topic {
    /// Every topic.
    pub const ALL: [Topic; 7] = [
        Topic::Info,
        Topic::Sample,
        Topic::Command,
        Topic::Claim,
        Topic::Ping,
        Topic::Pong,
        Topic::Refused,
    ];

    /// The topic's chunk of the key.
    pub fn name(self) -> &'static str {
        match self {
            Topic::Info => driver::contract::topic::INFO,
            Topic::Sample => driver::contract::topic::SAMPLE,
            Topic::Command => driver::contract::topic::COMMAND,
            Topic::Claim => "claim",
            Topic::Ping => "ping",
            Topic::Pong => "pong",
            Topic::Refused => "refused",
        }
    }

    /// Whether the rig's host sends it (else the driver's host does).
    pub fn from_rig(self) -> bool {
        matches!(self, Topic::Command | Topic::Claim | Topic::Ping)
    }

    /// Whether it goes under the user who puts it (`<topic>/<user>`).
    pub fn per_user(self) -> bool {
        matches!(self, Topic::Command | Topic::Claim)
    }

    /// The Zenoh key of driver `id`'s topic: `rig/driver/<id>/<topic>` (its iceoryx2
    /// service name), and for a topic [`per_user`](Self::per_user) every user's
    /// (`…/<topic>/*`).
    pub fn key(self, id: &str) -> String {
        match self.per_user() {
            true => format!("{}/*", service(id, self.name())),
            false => service(id, self.name()),
        }
    }

    /// The Zenoh key of `user`'s puts on driver `id`'s topic.
    pub fn key_of(self, id: &str, user: &str) -> String {
        format!("{}/{user}", service(id, self.name()))
    }
}

/// The user a key of a topic [`per_user`](Topic::per_user) names (its last chunk).
pub fn user_of(key: &str) -> &str {
    key.rsplit('/').next().unwrap_or_default()
}

/// Checks that `user` can name a key: letters, digits, `.`, `-` and `_`.
pub fn check_user(user: &str) -> Result<(), Credentials> {
    let fits = |c: char| c.is_ascii_alphanumeric() || matches!(c, '.' | '-' | '_');
    if user.is_empty() || !user.chars().all(fits) {
        return Err(Credentials::User(user.to_string()));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_cross_as_their_bytes() {
        let mut s = DriverSample {
            seq: 41,
            n_x: 2,
            n_u: 1,
            ..Default::default()
        };
        s.x[..2].copy_from_slice(&[0.5, f64::NAN]);
        let back: DriverSample = from_bytes(&to_bytes(&s)).unwrap();
        assert_eq!((back.seq, back.x[0]), (41, 0.5));
        assert!(back.x[1].is_nan());
        assert_eq!(to_bytes(&back), to_bytes(&s));
        let short = from_bytes::<DriverCommand>(&[0; 136])
            .unwrap_err()
            .to_string();
        assert!(
            short.contains("rig.DriverCommand.v1 of 136 bytes"),
            "{short}"
        );
        assert_eq!(size_of::<Ping>(), 24);
        assert_eq!(size_of::<Stamps>(), 24);
    }

    #[test]
    fn keys_are_the_driver_services() {
        assert_eq!(Topic::Sample.key("qube"), "rig/driver/qube/sample");
        assert_eq!(Topic::Pong.key("qube"), "rig/driver/qube/pong");
        assert_eq!(Topic::ALL.iter().filter(|t| t.from_rig()).count(), 3);
        assert_eq!(Topic::Command.key("qube"), "rig/driver/qube/command/*");
        let mine = Topic::Command.key_of("qube", "lab-1");
        assert_eq!(
            (mine.as_str(), user_of(&mine)),
            ("rig/driver/qube/command/lab-1", "lab-1")
        );
        assert!(check_user("lab_1.b").is_ok());
        for bad in ["", "a/b", "*", "a b", "$x"] {
            assert!(check_user(bad).is_err(), "{bad:?}");
        }
    }
}
