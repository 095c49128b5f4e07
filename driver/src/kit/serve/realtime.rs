//! The real-time clock of [`serve`]: a sample every period on `CLOCK_MONOTONIC`,
//! whether or not actions arrive; commands applied as they arrive in between.

use wire::{Inbox, MAX_U, MAX_X, Monotonic};

use super::state::Driver;
use super::{Served, Serving, Start};
use crate::contract::{DriverCommand, clock};
use crate::error::Error;
use crate::kit::device::Device;

/// Serves `device` as driver `driver_id` until Ctrl-C or SIGTERM (or
/// [`Serving::stop_after`] samples): opens the three services of `docs/driver.md`,
/// publishes the info at start and every second, and at each sample instant
/// `t_start + k · period` samples the device, decides (reset progress, watchdog) and
/// publishes the sample; between sample instants it applies each command as it arrives.
pub fn serve(device: &mut impl Device, driver_id: &str, how: &Serving) -> Result<Served, Error> {
    let n_x = device.task().state_dim();
    let time = Monotonic::host();
    let Start {
        io,
        mut d,
        advertised,
        t_start,
        period_ns,
    } = Start::of(device, driver_id, clock::REALTIME, &time, how.verbose)?;
    let (bus, samples, commands) = (&io.bus, &io.samples, &io.commands);
    let mut instants = Instants {
        time,
        t_start,
        period_ns,
        seq: 0,
    };
    let mut next_info = t_start + 1_000_000_000;
    let mut served = Served::default();
    let mut x = [0.0; MAX_X];
    while !bus.interrupted() && how.stop_after.is_none_or(|n| served.samples < n) {
        let missed = instants
            .wait(commands, (&mut d, device), how.spin_ns)
            .map_err(|e| io.err(e))?;
        if missed > 0 {
            served.missed += missed;
            d.log(|| format!("missed {missed} period(s)"));
        }
        let t_sample = instants.time.now_ns();
        let mut s = instants.sample(&mut d, device, t_sample, &mut x[..n_x]);
        s.t_publish_ns = instants.time.now_ns();
        samples.send(s).map_err(|e| io.err(e))?;
        served.samples += 1;
        if t_sample >= next_info {
            io.publish_info(advertised)?;
            next_info = t_sample + 1_000_000_000;
        }
    }
    // Stopping: the safe action.
    device.apply(instants.time.now_ns(), &[0.0; MAX_U][..d.n_u]);
    Ok(served)
}

/// The sample instants `t_start + seq · period` on `time`.
struct Instants {
    time: Monotonic,
    t_start: u64,
    period_ns: u64,
    /// The next instant's sequence number.
    seq: u64,
}

impl Instants {
    /// Until the next instant, each command of `commands` applied by driver `d` to
    /// `device` at its arrival (from `spin_ns` before the instant polling, not
    /// sleeping); woken a whole period late or more, those periods were missed: skipped,
    /// and their count returned.
    fn wait(
        &mut self,
        commands: &impl Inbox<DriverCommand>,
        (d, device): (&mut Driver, &mut impl Device),
        spin_ns: u64,
    ) -> Result<u64, wire::Error> {
        let t_k = self.t_start + self.seq * self.period_ns;
        loop {
            while let Some(c) = commands.try_recv()? {
                d.command(device, self.time.now_ns(), &c);
            }
            let now = self.time.now_ns();
            if now >= t_k {
                break;
            }
            if t_k - now > spin_ns {
                commands.wait_until(t_k - spin_ns)?;
            } else {
                std::hint::spin_loop();
            }
        }
        let missed = (self.time.now_ns() - t_k) / self.period_ns;
        self.seq += missed;
        Ok(missed)
    }

    /// The sample at `t_sample` into `x`, after this instant's decisions (the reward of
    /// the period it closes, a reset's progress, the watchdog); the next instant is due.
    fn sample(
        &mut self,
        d: &mut Driver,
        device: &mut impl Device,
        t_sample: u64,
        x: &mut [f64],
    ) -> crate::contract::DriverSample {
        device.sample(t_sample, x);
        let mut s = d.sample(self.seq, t_sample, x);
        d.outcome(device, &mut s, d.in_trial());
        d.decide(device, t_sample, x);
        s.status = d.status;
        self.seq += 1;
        s
    }
}

#[cfg(test)]
mod tests {
    use super::super::state::tests::action;
    use super::*;
    use crate::Simulated;
    use crate::contract::status;
    use plant::SystemName;
    use std::time::Duration;
    use wire::Scripted;

    use wire::MS;

    /// On a mock clock, periods of 10 ms from 0, READY: an action at 5 ms is applied
    /// at its arrival and keeps the watchdog off at 10 ms; the period to 20 ms without
    /// one engages it (zero applied); woken at 45 ms for the instant of 30 ms, one
    /// period was missed and the sample is the instant of 40 ms's.
    #[test]
    fn a_period_without_an_action_engages_the_watchdog() {
        let (clock, time) = Monotonic::mock();
        time.step_each_reading(Duration::from_micros(1));
        let mut device = Simulated::new(SystemName::Pendulum, 1.0).unwrap();
        let mut d = Driver::new(device.task(), false);
        let mut x = [0.0; 2];
        d.ready(&x);
        let mut instants = Instants {
            time: clock.clone(),
            t_start: 0,
            period_ns: 10 * MS,
            seq: 1,
        };
        let inbox = Scripted::new(&time).arrives(5 * MS, action(1, 0.5), Duration::ZERO);
        let mut instant = |d: &mut Driver, device: &mut Simulated| {
            let missed = instants.wait(&inbox, (d, device), 50_000).unwrap();
            let s = instants.sample(d, device, clock.now_ns(), &mut x);
            (missed, s)
        };
        let (missed, s) = instant(&mut d, &mut device);
        assert_eq!(
            (missed, s.seq, s.last_command, s.u_applied[0]),
            (0, 1, 1, 0.5)
        );
        assert_eq!(s.status & status::WATCHDOG, 0);
        let (_, s) = instant(&mut d, &mut device);
        assert_eq!((s.seq, s.status & status::WATCHDOG), (2, status::WATCHDOG));
        assert_eq!((d.u[0], d.safety.counts().watchdog_trips), (0.0, 1));
        time.advance_to(45 * MS);
        let (missed, s) = instant(&mut d, &mut device);
        assert_eq!((missed, s.seq), (1, 4));
        assert!((45 * MS..46 * MS).contains(&s.t_sample_ns));
    }
}
