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

use wire::{MAX_U, MAX_X, now_ns};

use super::state::Driver;
use super::{Served, Serving, Start};
use crate::contract::{DriverCommand, clock, kind, status};
use crate::device::Device;
use crate::error::Error;

/// A simulation that can run in lockstep: its state can be set, and it integrates exactly
/// one sample period at a time (hardware cannot: it keeps the real-time clock).
pub trait Lockstep: Device {
    /// Puts the system at rest at `x0` (angles wrapped).
    fn place(&mut self, x0: &[f64]);
    /// Integrates one sample period with the action in effect.
    fn step(&mut self);
}

/// How often the info is published while no command arrives.
const INFO_EVERY: Duration = Duration::from_secs(1);

/// Serves `device` as driver `driver_id` in lockstep until Ctrl-C or SIGTERM (or
/// [`Serving::stop_after`] samples): each command is answered as the module
/// documentation says; the info goes out at start and every second.
pub fn serve_lockstep(
    device: &mut impl Lockstep,
    driver_id: &str,
    how: &Serving,
) -> Result<Served, Error> {
    let (n_x, n_u) = (device.task().state_dim(), device.task().action_dim());
    let Start {
        io,
        mut d,
        advertised,
        ..
    } = Start::of(device, driver_id, clock::LOCKSTEP, how.verbose)?;
    let mut next_info = now_ns() + INFO_EVERY.as_nanos() as u64;
    let mut served = Served::default();
    let mut x = [0.0; MAX_X];
    // The newest sample published (none yet).
    let mut newest: Option<u64> = None;
    while !io.bus.interrupted() && how.stop_after.is_none_or(|n| served.samples < n) {
        let Some(c) = io.commands.try_recv().map_err(|e| io.err(e))? else {
            io.commands.wait_until(next_info).map_err(|e| io.err(e))?;
            if now_ns() >= next_info {
                io.publish_info(advertised)?;
                next_info = now_ns() + INFO_EVERY.as_nanos() as u64;
            }
            continue;
        };
        let answered = match c.kind {
            kind::RESET => reset(&mut d, device, &c),
            kind::ACTION if d.status & status::READY != 0 && newest == Some(c.sample_seq) => {
                d.command(device, now_ns(), &c);
                device.step();
                true
            }
            // An action before a reset or for an older sample: counted, nothing else.
            kind::ACTION => {
                d.other_rejected += 1;
                false
            }
            _ => {
                d.command(device, now_ns(), &c);
                false
            }
        };
        if answered {
            let seq = newest.map_or(0, |k| k + 1);
            let t = now_ns();
            device.sample(t, &mut x[..n_x]);
            let mut s = d.sample(seq, t, &x[..n_x]);
            s.t_publish_ns = now_ns();
            io.samples.send(s).map_err(|e| io.err(e))?;
            newest = Some(seq);
            served.samples += 1;
        }
    }
    device.apply(now_ns(), &[0.0; MAX_U][..n_u]);
    Ok(served)
}

/// A RESET: the device placed at `x0` at once and READY there, zero in effect; false if
/// the driver rejected it (malformed).
fn reset(d: &mut Driver, device: &mut impl Lockstep, c: &DriverCommand) -> bool {
    d.command(device, now_ns(), c);
    if d.status != status::RESETTING || d.reset_id != c.seq {
        return false;
    }
    let x0 = &c.x0[..d.n_x];
    device.place(x0);
    d.ready(x0);
    d.set(device, now_ns(), &[0.0; MAX_U][..d.n_u]);
    true
}
