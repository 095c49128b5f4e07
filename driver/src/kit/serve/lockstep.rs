//! The lockstep clock ([`clock::LOCKSTEP`]): a simulation that advances one sample period
//! per action, so that it runs as fast as the loop and the same commands give the same
//! samples (`docs/driver.md`, "Lockstep").
//!
//! A RESET puts the simulation at `x0` at once and is answered by a READY sample there.
//! An ACTION that answers the newest sample while READY moves the simulation one period —
//! with the action, clamped, or with zero if it is rejected — and is answered by the
//! sample that closes the period. Any other command (an action before a reset or for an
//! older sample) only counts as rejected and is answered by no sample. No time passes
//! without an action, so the watchdog never engages.

use std::time::Duration;

use wire::{Inbox, MAX_U, MAX_X, Monotonic};

use super::announce::Announcer;
use super::state::Driver;
use super::{Served, Serving, Start};
use crate::contract::{DriverCommand, clock, kind, status};
use crate::error::Error;
use crate::kit::device::Device;

/// A simulation that can run in lockstep: its state can be set, and it integrates exactly
/// one sample period at a time (hardware cannot: it keeps the real-time clock).
pub trait Lockstep: Device {
    /// Puts the system at rest at `x0` (angles wrapped).
    fn place(&mut self, x0: &[f64]);
    /// Integrates one sample period with the action in effect.
    fn step(&mut self);
}

/// How long after a command the driver polls for the next one (handing the CPU on
/// between polls, as a lockstep run's processes do) before it sleeps until the rig wakes
/// it: a loop that is running answers within microseconds; a rig that stopped or went
/// away costs a CPU for this long at most.
const POLL_AFTER_COMMAND: Duration = Duration::from_secs(1);

/// Serves `device` as driver `driver_id` in lockstep until Ctrl-C or SIGTERM (or
/// [`Serving::stop_after`] samples): each command is answered as the module
/// documentation says; the info goes out at start, every second and at once when its
/// readers change ([`Announcer`]).
pub fn serve_lockstep(
    device: &mut impl Lockstep,
    driver_id: &str,
    how: &Serving,
) -> Result<Served, Error> {
    let (n_x, n_u) = (device.task().state_dim(), device.task().action_dim());
    let time = Monotonic::host();
    let Start {
        io,
        mut d,
        advertised,
        ..
    } = Start::of(device, driver_id, clock::LOCKSTEP, &time, how.verbose)?;
    let mut info = Announcer::new(advertised, &io);
    let mut served = Served::default();
    let mut x = [0.0; MAX_X];
    // The newest sample published (none yet).
    let mut newest: Option<u64> = None;
    // Until when the driver polls for commands (not at all before the first).
    let mut poll_until = 0;
    while !io.bus.interrupted() && how.stop_after.is_none_or(|n| served.samples < n) {
        let wait = Wait {
            poll_until,
            next_info: info.next_ns(),
        };
        let Some(c) = next_command(&io.commands, &time, wait).map_err(|e| io.err(e))? else {
            info.publish_if_due(&io)?;
            continue;
        };
        poll_until = time.now_ns() + POLL_AFTER_COMMAND.as_nanos() as u64;
        let answered = match c.kind {
            kind::RESET => reset(&mut d, device, &c, time.now_ns()),
            kind::ACTION if d.status & status::READY != 0 && newest == Some(c.sample_seq) => {
                d.command(device, time.now_ns(), &c);
                device.step();
                true
            }
            // An action before a reset or for an older sample: counted, nothing else.
            kind::ACTION => {
                d.other_rejected += 1;
                false
            }
            _ => {
                d.command(device, time.now_ns(), &c);
                false
            }
        };
        if answered {
            let seq = newest.map_or(0, |k| k + 1);
            let t = time.now_ns();
            device.sample(t, &mut x[..n_x]);
            let mut s = d.sample(seq, t, &x[..n_x]);
            d.outcome(device, &mut s, c.kind == kind::ACTION);
            s.t_publish_ns = time.now_ns();
            io.samples.send(s).map_err(|e| io.err(e))?;
            newest = Some(seq);
            served.samples += 1;
        }
    }
    device.apply(time.now_ns(), &[0.0; MAX_U][..n_u]);
    Ok(served)
}

/// How often a polling driver looks up from polling (for Ctrl-C, the readers of its info
/// and the info's second).
const LOOK_UP_EVERY: Duration = Duration::from_millis(10);

/// How often a sleeping driver looks up (for the readers of its info).
const LOOK_UP_ASLEEP: Duration = Duration::from_millis(50);

/// How [`next_command`] waits, in monotonic time \[ns\].
#[derive(Clone, Copy, Debug)]
struct Wait {
    /// Polled for until then (not at all before the first command), asleep after.
    poll_until: u64,
    /// When the info is next due.
    next_info: u64,
}

/// The next of `commands`, on `time`: polled for until `wait.poll_until`, handing the CPU
/// on between polls; after that, waited for asleep until the rig wakes the driver. `None`
/// at `wait.next_info`, after [`LOOK_UP_EVERY`] of polling or [`LOOK_UP_ASLEEP`] asleep,
/// or after a signal or a wake-up without a command.
fn next_command(
    commands: &impl Inbox<DriverCommand>,
    time: &Monotonic,
    wait: Wait,
) -> Result<Option<DriverCommand>, wire::Error> {
    let Wait {
        poll_until,
        next_info,
    } = wait;
    let look_up = time.now_ns() + LOOK_UP_EVERY.as_nanos() as u64;
    loop {
        if let Some(c) = commands.try_recv()? {
            return Ok(Some(c));
        }
        let now = time.now_ns();
        if now >= next_info.min(look_up) {
            return Ok(None);
        }
        if now >= poll_until {
            let wake = next_info.min(now + LOOK_UP_ASLEEP.as_nanos() as u64);
            commands.wait_until(wake)?;
            return commands.try_recv();
        }
        std::thread::yield_now();
    }
}

/// A RESET at `now`: the device placed at `x0` at once and READY there, zero in effect;
/// false if the driver rejected it (malformed).
fn reset(d: &mut Driver, device: &mut impl Lockstep, c: &DriverCommand, now: u64) -> bool {
    d.command(device, now, c);
    if d.status != status::RESETTING || d.reset_id != c.seq {
        return false;
    }
    let x0 = &c.x0[..d.n_x];
    device.place(x0);
    d.ready(x0);
    d.set(device, now, &[0.0; MAX_U][..d.n_u]);
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use wire::Scripted;

    use wire::MS;

    fn action(seq: u64) -> DriverCommand {
        DriverCommand {
            seq,
            kind: kind::ACTION,
            ..Default::default()
        }
    }

    /// Within a second of a command the driver polls, looking up every 10 ms; after it,
    /// it sleeps until a command comes or 50 ms pass; the info's second wakes it either
    /// way.
    #[test]
    fn a_driver_polls_for_a_second_after_a_command_then_sleeps() {
        let (clock, time) = Monotonic::mock();
        time.step_each_reading(Duration::from_micros(100));
        let commands = Scripted::new(&time)
            .arrives(25 * MS, action(1), Duration::ZERO)
            .arrives(2_000 * MS, action(2), Duration::ZERO)
            .arrives(2_120 * MS, action(3), Duration::ZERO);
        let polling = Wait {
            poll_until: POLL_AFTER_COMMAND.as_nanos() as u64,
            next_info: 5_000 * MS,
        };
        // Polling: looks up after 10 ms, then again, then the command at 25 ms.
        assert_eq!(next_command(&commands, &clock, polling).unwrap(), None);
        assert!((10 * MS..11 * MS).contains(&time.now_ns()));
        assert_eq!(next_command(&commands, &clock, polling).unwrap(), None);
        let c = next_command(&commands, &clock, polling).unwrap();
        assert_eq!(c.map(|c| c.seq), Some(1));
        assert!((25 * MS..26 * MS).contains(&time.now_ns()));
        // Past its second of polling: asleep until the command at 2 s wakes it.
        time.advance_to(1_990 * MS);
        let asleep = Wait {
            poll_until: 0,
            next_info: 5_000 * MS,
        };
        let c = next_command(&commands, &clock, asleep).unwrap();
        assert_eq!(c.map(|c| c.seq), Some(2));
        assert!((2_000 * MS..2_001 * MS).contains(&time.now_ns()));
        // Asleep, it looks up after 50 ms without a command, or at the info's time.
        assert_eq!(next_command(&commands, &clock, asleep).unwrap(), None);
        assert!((2_050 * MS..2_051 * MS).contains(&time.now_ns()));
        let info_due = Wait {
            poll_until: 0,
            next_info: 2_060 * MS,
        };
        assert_eq!(next_command(&commands, &clock, info_due).unwrap(), None);
        assert!((2_060 * MS..2_061 * MS).contains(&time.now_ns()));
    }
}
