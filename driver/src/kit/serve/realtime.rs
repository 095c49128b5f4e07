//! The real-time clock of [`serve`]: a sample every period on `CLOCK_MONOTONIC`,
//! whether or not actions arrive; commands applied as they arrive in between.

use wire::{MAX_U, MAX_X, now_ns};

use super::{Served, Serving, Start};
use crate::contract::clock;
use crate::error::Error;
use crate::kit::device::Device;

/// Serves `device` as driver `driver_id` until Ctrl-C or SIGTERM (or
/// [`Serving::stop_after`] samples): opens the three services of `docs/driver.md`,
/// publishes the info at start and every second, and at each sample instant
/// `t_start + k · period` samples the device, decides (reset progress, watchdog) and
/// publishes the sample; between sample instants it applies each command as it arrives.
pub fn serve(device: &mut impl Device, driver_id: &str, how: &Serving) -> Result<Served, Error> {
    let (n_x, n_u) = (device.task().state_dim(), device.task().action_dim());
    let Start {
        io,
        mut d,
        advertised,
        t_start,
        period_ns,
    } = Start::of(device, driver_id, clock::REALTIME, how.verbose)?;
    let (bus, samples, commands) = (&io.bus, &io.samples, &io.commands);
    let mut next_info = t_start + 1_000_000_000;
    let mut served = Served::default();
    let mut x = [0.0; MAX_X];
    let mut seq = 0;
    while !bus.interrupted() && how.stop_after.is_none_or(|n| served.samples < n) {
        let t_k = t_start + seq * period_ns;
        // Until the sample instant: each command at its arrival.
        loop {
            while let Some(c) = commands.try_recv().map_err(|e| io.err(e))? {
                d.command(device, now_ns(), &c);
            }
            let now = now_ns();
            if now >= t_k {
                break;
            }
            if t_k - now > how.spin_ns {
                commands
                    .wait_until(t_k - how.spin_ns)
                    .map_err(|e| io.err(e))?;
            } else {
                std::hint::spin_loop();
            }
        }
        // Woken a whole period late or more: those periods were missed.
        let late = (now_ns() - t_k) / period_ns;
        if late > 0 {
            seq += late;
            served.missed += late;
            d.log(|| format!("missed {late} period(s)"));
        }
        let t_sample = now_ns();
        device.sample(t_sample, &mut x[..n_x]);
        let mut s = d.sample(seq, t_sample, &x[..n_x]);
        d.outcome(device, &mut s, d.in_trial());
        d.decide(device, t_sample, &x[..n_x]);
        s.status = d.status;
        s.t_publish_ns = now_ns();
        samples.send(s).map_err(|e| io.err(e))?;
        served.samples += 1;
        if t_sample >= next_info {
            io.publish_info(advertised)?;
            next_info = t_sample + 1_000_000_000;
        }
        seq += 1;
    }
    // Stopping: the safe action.
    device.apply(now_ns(), &[0.0; MAX_U][..n_u]);
    Ok(served)
}
