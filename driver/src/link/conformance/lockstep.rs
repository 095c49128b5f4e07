//! The checks of a lockstep driver (`clock = lockstep`, `docs/driver.md` "Lockstep"), in
//! place of the sample rate and the watchdog, which need a clock: one sample per action,
//! none without, and the same samples for the same commands.

use std::time::Duration;

use crate::Error;
use crate::contract::DriverSample;

use super::{Probe, STEP_PERIODS, vector};

/// How long a lockstep driver must stay silent when no command comes.
const SILENCE_PROBE: Duration = Duration::from_millis(200);

impl Probe<'_> {
    /// Samples answered with zero, each followed by exactly the next; then silence
    /// without a command.
    pub(super) fn lockstep(&mut self) -> Result<(), Error> {
        let samples = self.zero_input_samples()?;
        let mut wrong = Vec::new();
        for w in samples.windows(2) {
            let ((a, cmd), (b, _)) = (w[0], w[1]);
            if b.seq != a.seq + 1 || b.last_command != cmd {
                wrong.push(format!(
                    "sample {} after the action (command {cmd}) answering {}: want sample {} showing command {cmd} applied, got last_command {}",
                    b.seq,
                    a.seq,
                    a.seq + 1,
                    b.last_command
                ));
            }
        }
        // The last action's answer, then nothing until the next command.
        let pending = self.sample()?;
        std::thread::sleep(SILENCE_PROBE);
        if let Some(s) = self.link.latest_sample()? {
            wrong.push(format!(
                "sample {} published {:.0} ms after sample {} without a command",
                s.seq,
                (s.t_sample_ns.saturating_sub(pending.t_sample_ns)) as f64 * 1e-6,
                pending.seq
            ));
        }
        wrong.truncate(3);
        self.record_problems(
            "lockstep",
            wrong,
            format!(
                "{} actions each answered by exactly the next sample, showing it applied; no sample for {} ms without a command",
                samples.len(),
                SILENCE_PROBE.as_millis()
            ),
        );
        self.pending = Some(pending);
        Ok(())
    }

    /// From the start state, a small step for [`STEP_PERIODS`] periods takes the state
    /// elsewhere than zero input does (compared exactly: both from the same reset, so an
    /// unstable start state, which zero input leaves fast, is no obstacle), and shows as
    /// applied.
    pub(super) fn step_against_zero(&mut self) -> Result<(), Error> {
        let u = self.action(self.opts.step);
        let zero = self.replay(&vec![0.0; u.len()])?;
        let step = self.replay(&u)?;
        let (z, s) = (zero[STEP_PERIODS].state(), step[STEP_PERIODS].state());
        let apart = self.change(z, s);
        let applied = step[1..]
            .iter()
            .filter(|s| super::same(s.applied(), &u))
            .count();
        self.record(
            "step response",
            apart > 1e-3 && applied == STEP_PERIODS,
            format!(
                "u = {} for {STEP_PERIODS} periods from the start state: x {} against zero input's {}, {:.2} % of the state range apart (bound: > 0.10 %); reported applied in {applied} of {STEP_PERIODS} samples",
                vector(&u),
                vector(s),
                vector(z),
                apart * 100.0
            ),
        );
        Ok(())
    }

    /// The same reset and actions twice give the same samples, bit for bit.
    pub(super) fn determinism(&mut self) -> Result<(), Error> {
        let u = self.action(self.opts.step);
        let first = self.replay(&u)?;
        let second = self.replay(&u)?;
        let differ = first
            .iter()
            .zip(&second)
            .position(|(a, b)| a.state() != b.state() || a.applied() != b.applied());
        self.record(
            "determinism",
            differ.is_none() && first.len() == second.len(),
            match differ {
                None => format!(
                    "reset and u = {} for {STEP_PERIODS} periods, twice: the same {} samples, bit for bit",
                    vector(&u),
                    first.len()
                ),
                Some(k) => format!(
                    "reset and u = {} for {STEP_PERIODS} periods, twice: sample {k} differs: x {} then {}",
                    vector(&u),
                    vector(first[k].state()),
                    vector(second[k].state())
                ),
            },
        );
        Ok(())
    }

    /// Resets to the start state and answers [`STEP_PERIODS`] samples with `u`: the
    /// READY sample and the ones after, the last left pending.
    fn replay(&mut self, u: &[f64]) -> Result<Vec<DriverSample>, Error> {
        // The reset answers the pending sample.
        self.pending = None;
        let x0 = self.task.initial_states[0].clone();
        let id = self.link.reset(&x0)?;
        let ready = self
            .link
            .wait_ready(&self.bus, &self.info, id, self.opts.reset_timeout)?;
        self.reset_id = id;
        let mut samples = vec![ready];
        for _ in 0..STEP_PERIODS {
            self.act(u, samples.last().expect("one sample at least"))?;
            samples.push(self.sample()?);
        }
        self.pending = samples.last().copied();
        Ok(samples)
    }
}
