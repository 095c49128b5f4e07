//! The supervision loop: drains every topic into the recording and `returns.csv`,
//! checks sequence continuity, watches the child processes and names the cause of an
//! early stop.

use std::path::{Path, PathBuf};
use std::process::Child;
use std::time::Duration;

use driver::link::DriverWatch;
use indicatif::ProgressBar;
use wire::{Action, Bus, Estimate, Measurement, Monotonic, Truth, flags, topic};

use crate::experiment::TrialRecord;

use super::command::Role;
use super::error::{Result, RunError};
use super::gaps::GapLog;
use super::logs::Logs;
use super::recording::RecordingWriter;
use super::retention::{DrainMark, Retention};
use super::returns::Returns;

/// How long the supervisor watches after a process exits early, to see which process
/// caused the stop (the others follow within milliseconds).
pub(super) const CAUSE_WINDOW: Duration = Duration::from_millis(100);

/// How long the observer and the agent are given, after Ctrl-C, to answer the samples
/// the stopped plant sent.
const ANSWER_WINDOW: Duration = Duration::from_secs(1);

/// How long the processes are given to exit after the end of the run.
const EXIT_WINDOW: Duration = Duration::from_secs(10);

/// How often the wait for the processes' exit looks again.
const LOOK_AGAIN: Duration = Duration::from_millis(5);

/// Checks that a topic's sequence numbers arrive without gaps.
#[derive(Default)]
pub(super) struct Continuity {
    pub(super) next: u64,
}

impl Continuity {
    pub(super) fn check(&mut self, topic: &'static str, seq: u64) -> Result<()> {
        if seq != self.next {
            return Err(RunError::Lost {
                topic,
                expected: self.next,
                got: seq,
            });
        }
        self.next = seq + 1;
        Ok(())
    }
}

/// The child processes; killed when dropped.
pub(super) struct Children(pub(super) Vec<(Role, Child)>);

impl Children {
    /// Stops every process where it is (SIGSTOP): nothing more is sent, and what they
    /// sent stays readable (it would be gone with a process that exits).
    pub(super) fn freeze(&self) {
        self.freeze_where(|_| true);
    }

    /// Stops the processes of the roles `which` picks (SIGSTOP).
    fn freeze_where(&self, which: impl Fn(Role) -> bool) {
        for (_, c) in self.0.iter().filter(|(role, _)| which(*role)) {
            // SAFETY: `kill` sends a signal to the child's pid; it touches no memory.
            unsafe {
                libc::kill(c.id() as libc::pid_t, libc::SIGSTOP);
            }
        }
    }
}

impl Drop for Children {
    fn drop(&mut self) {
        for (_, c) in &mut self.0 {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// Everything the supervision loop works on.
pub(super) struct Supervisor {
    pub(super) bus: Bus,
    pub(super) measurements: wire::Rx<Measurement>,
    pub(super) estimates: wire::Rx<Estimate>,
    pub(super) actions: wire::Rx<Action>,
    /// The plant's ground truth, with a sensor that does not measure the full state.
    pub(super) truths: Option<wire::Rx<Truth>>,
    /// Measurements drained, waiting for their ground truth to be drained too.
    pub(super) batch: Vec<Measurement>,
    /// Ground truth drained ahead of its measurement.
    pub(super) truth_queue: std::collections::VecDeque<Truth>,
    pub(super) recording: RecordingWriter,
    pub(super) returns: Returns,
    /// The trial attempts cut short by gaps.
    pub(super) gaps: GapLog,
    pub(super) children: Children,
    /// Their output.
    pub(super) logs: Logs,
    pub(super) out: PathBuf,
    pub(super) messages: u64,
    pub(super) continuity: [Continuity; 3],
    pub(super) deadline_misses: u64,
    /// The external driver's traffic, recorded.
    pub(super) driver: Option<DriverWatch>,
    /// The announcement that everything is recorded, which the processes wait for.
    pub(super) recorded: wire::RecordedSignal,
    /// Realtime and external driver: how long to go on recording after a process died,
    /// so that the recording shows the plant's reaction (its watchdog, or the driver's,
    /// applying the safe action within two periods).
    pub(super) grace: Option<Duration>,
    /// Removes the checkpoints no resume can need.
    pub(super) retention: Retention,
    /// The flags beside `--resume DIR` that continue this run (an external driver's).
    pub(super) resume_flags: String,
    /// The rows of `returns.csv` recorded on `/returns` so far (those kept by a resumed
    /// run, copied).
    pub(super) rows_recorded: usize,
    /// The time the supervisor's windows are measured on.
    pub(super) time: Monotonic,
}

impl Supervisor {
    /// Subscribes to every topic of the run on `bus` (before its processes start, so
    /// that no message is missed); the processes come later ([`Self::children`]).
    pub(super) fn new(
        bus: Bus,
        recording: RecordingWriter,
        (returns, gaps): (Returns, GapLog),
        out: &Path,
        first_seq: u64,
        driver: Option<DriverWatch>,
        grace: Option<Duration>,
    ) -> Result<Self> {
        let truths = if recording.truth.is_some() {
            Some(bus.rx::<Truth>(topic::TRUTH)?)
        } else {
            None
        };
        Ok(Self {
            recorded: bus.recorded()?,
            measurements: bus.rx::<Measurement>(topic::MEASUREMENT)?,
            estimates: bus.rx::<Estimate>(topic::ESTIMATE)?,
            actions: bus.rx::<Action>(topic::ACTION)?,
            truths,
            bus,
            batch: Vec::new(),
            truth_queue: std::collections::VecDeque::new(),
            recording,
            returns,
            gaps,
            children: Children(Vec::new()),
            logs: Logs::default(),
            out: out.to_owned(),
            messages: 0,
            continuity: std::array::from_fn(|_| Continuity { next: first_seq }),
            deadline_misses: 0,
            driver,
            grace,
            retention: Retention::new(crate::resume::checkpoint_dir(out)),
            resume_flags: String::new(),
            rows_recorded: 0,
            time: Monotonic::host(),
        })
    }

    /// Records everything waiting, then removes the checkpoints no resume can need any
    /// more; returns whether the run's end came by.
    pub(super) fn drain(&mut self, bar: &ProgressBar) -> Result<bool> {
        let before = DrainMark {
            recorded: self.continuity.iter().map(|c| c.next).min().unwrap_or(0),
            rows: self.returns.ends.len(),
        };
        let done = self.record_waiting(bar)?;
        self.retention
            .after_drain(before, self.recording.rec.flushes(), &self.returns.ends);
        Ok(done)
    }

    /// Records everything waiting; returns whether the run's end came by.
    fn record_waiting(&mut self, bar: &ProgressBar) -> Result<bool> {
        let mut done = false;
        if let Some(a) = self.actions.recv_timeout(Duration::from_millis(2))? {
            done |= self.action(a)?;
        }
        while let Some(a) = self.actions.try_recv()? {
            done |= self.action(a)?;
        }
        // The plant publishes a sample's ground truth before its measurement: drained
        // after the measurements, the truth of each of them is in.
        self.batch.clear();
        while let Some(m) = self.measurements.try_recv()? {
            self.batch.push(m);
        }
        if let Some(t) = &self.truths {
            while let Some(x) = t.try_recv()? {
                self.truth_queue.push_back(x);
            }
        }
        let batch = std::mem::take(&mut self.batch);
        for m in &batch {
            self.continuity[0].check(topic::MEASUREMENT, m.header.seq)?;
            self.deadline_misses = self.deadline_misses.max(m.deadline_misses);
            self.recording.measurement(m)?;
            self.gaps.measurement(m)?;
            self.messages += 1;
            if m.header.flags & (flags::END | flags::GAP) == flags::END {
                bar.inc(1);
            }
            let n = m.n_x as usize;
            // The rewards are the observer's: the estimates feed returns.csv.
            let estimated = m.header.flags & flags::ESTIMATED_REWARD != 0;
            if self.truths.is_some() && m.header.flags & flags::SHUTDOWN == 0 {
                let t = self
                    .truth_queue
                    .pop_front()
                    .filter(|t| t.header == m.header);
                let Some(t) = t else {
                    return Err(RunError::NoTruth {
                        topic: topic::TRUTH,
                        seq: m.header.seq,
                    });
                };
                self.recording.truth(&t)?;
                if !estimated {
                    self.sample(&m.header, m.reward, &t.x[..n])?;
                }
            } else if !estimated {
                self.sample(&m.header, m.reward, &m.y[..n])?;
            }
        }
        self.batch = batch;
        while let Some(e) = self.estimates.try_recv()? {
            self.continuity[1].check(topic::ESTIMATE, e.header.seq)?;
            self.recording.estimate(&e)?;
            self.messages += 1;
            if e.header.flags & flags::ESTIMATED_REWARD != 0 {
                self.sample(&e.header, e.reward, &e.x[..e.n_x as usize])?;
            }
        }
        if let Some(d) = &self.driver {
            while d.info.try_recv()?.is_some() {}
            while let Some(s) = d.samples.try_recv()? {
                self.recording.driver_sample(&s)?;
            }
            while let Some(c) = d.commands.try_recv()? {
                self.recording.driver_command(&c)?;
            }
            while let Some(l) = d.link.try_recv()? {
                self.recording.driver_link(&l)?;
            }
        }
        Ok(done)
    }

    /// Accounts for a sample in `returns.csv` (the message just recorded), and records
    /// the rows it completed.
    fn sample(&mut self, h: &wire::Header, reward: f64, x: &[f64]) -> Result<()> {
        self.returns
            .sample(h, reward, x, self.recording.log_time_ns)?;
        self.record_rows()
    }

    /// Records on `/returns` the rows of `returns.csv` not recorded yet, each at the log
    /// time of its trial's end; a row kept by a resumed run from a recording without
    /// `/returns`, at the current one.
    fn record_rows(&mut self) -> Result<()> {
        let records = &self.returns.records;
        let kept = records.len() - self.returns.log_times.len();
        for (i, r) in records.iter().enumerate().skip(self.rows_recorded) {
            let t = i
                .checked_sub(kept)
                .map_or(self.recording.log_time_ns, |j| self.returns.log_times[j]);
            self.recording.trial(r, t)?;
        }
        self.rows_recorded = records.len();
        Ok(())
    }

    pub(super) fn action(&mut self, a: Action) -> Result<bool> {
        self.continuity[2].check(topic::ACTION, a.header.seq)?;
        self.recording.action(&a)?;
        self.messages += 1;
        Ok(a.header.flags & flags::SHUTDOWN != 0)
    }

    /// A process that has exited, if any: its role and exit status.
    pub(super) fn exited(&mut self) -> Result<Option<(Role, std::process::ExitStatus)>> {
        for (role, child) in &mut self.children.0 {
            if let Some(status) = child.try_wait()? {
                return Ok(Some((*role, status)));
            }
        }
        Ok(None)
    }

    /// Of the processes that have exited, the one that caused the others to: killed by a
    /// signal rather than stopped by an error (a process whose peer dies stops with one).
    pub(super) fn cause(&mut self) -> Result<(Role, std::process::ExitStatus)> {
        use std::os::unix::process::ExitStatusExt;
        let mut first = None;
        for (role, child) in &mut self.children.0 {
            if let Some(status) = child.try_wait()? {
                let found = (*role, status);
                if status.signal().is_some() {
                    return Ok(found);
                }
                first.get_or_insert(found);
            }
        }
        first.ok_or(RunError::Vanished)
    }

    /// Waits for every process to exit after the end of the run.
    pub(super) fn reap(&mut self) -> Result<()> {
        reap(&mut self.children, &self.logs, &self.time)
    }

    /// How far the run got — its complete trials written to `returns.csv` first —, and
    /// how to continue it.
    pub(super) fn resume_hint(&mut self) -> String {
        let _ = self.returns.flush_complete();
        format!(
            "{} completed trials are in returns.csv; continue with `rig run --resume {}{}`",
            self.returns.records.len(),
            self.out.display(),
            self.resume_flags
        )
    }

    /// Ends the run whatever its `outcome`: stops the processes (on failure), writes
    /// the complete trials, and finishes the recording, so that `run.mcap` is readable
    /// after any outcome. Returns the trials, the messages received and the deadline
    /// misses.
    pub(super) fn finish(mut self, outcome: Result<()>) -> Result<(Vec<TrialRecord>, u64, u64)> {
        drop(std::mem::replace(&mut self.children, Children(Vec::new())));
        let _ = self.returns.flush_complete();
        let rows = self.record_rows();
        let counted = self.recording.rec.metadata("gaps", &self.gaps.metadata());
        let finished = self.recording.rec.finish();
        outcome?;
        rows?;
        counted?;
        finished?;
        Ok((self.returns.records, self.messages, self.deadline_misses))
    }

    /// After Ctrl-C: stops the processes and records what they sent, so that every
    /// trial in `returns.csv` is complete in the recording too. The plant stops first;
    /// the observer and the agent answer the samples it sent (a trial's last sample
    /// without its action would leave that trial incomplete), then stop.
    fn record_the_rest(&mut self, bar: &ProgressBar) {
        self.children.freeze_where(|role| role == Role::Plant);
        let time = self.time.clone();
        for_a_while(&time, ANSWER_WINDOW, || {
            !self.answered() && matches!(self.drain(bar), Ok(false))
        });
        self.children.freeze();
        loop {
            let before = self.messages;
            // An error here is a consequence of the interrupt, which is reported.
            if !matches!(self.drain(bar), Ok(false)) || self.messages == before {
                break;
            }
        }
    }

    /// Whether every measurement recorded has its estimate and its action recorded.
    fn answered(&self) -> bool {
        let [m, e, a] = &self.continuity;
        e.next == m.next && a.next == m.next
    }

    pub(super) fn supervise(&mut self, bar: &ProgressBar) -> Result<()> {
        loop {
            match self.drain(bar) {
                Ok(true) => break,
                Ok(false) => {}
                Err(e) => {
                    return Err(RunError::Stopped {
                        cause: Box::new(e),
                        hint: self.resume_hint(),
                    });
                }
            }
            if self.bus.interrupted() {
                self.record_the_rest(bar);
                return Err(RunError::Interrupted {
                    hint: self.resume_hint(),
                });
            }
            if let Some((_, status)) = self.exited()? {
                // A process that ends cleanly after its last message can be seen to exit
                // before that message is read: look once more.
                if status.success() && self.drain(bar)? {
                    break;
                }
                // Go on recording for a while: the plant's reaction (realtime), and the
                // peers' exits, to tell the cause from its consequences.
                let (time, window) = (self.time.clone(), self.grace.unwrap_or_default());
                let mut done = false;
                for_a_while(&time, window.max(CAUSE_WINDOW), || {
                    // Errors here are consequences of the death reported below.
                    let drained = self.drain(bar);
                    done = matches!(drained, Ok(true));
                    matches!(drained, Ok(false))
                });
                if done && self.cause().is_ok_and(|(_, s)| s.success()) {
                    // The run's end came after all: processes exit as it passes.
                    break;
                }
                let (role, status) = self.cause()?;
                return Err(RunError::Exited {
                    role: role.name(),
                    status,
                    hint: self.resume_hint(),
                    log: self.logs.last_lines(role),
                });
            }
            if let Some(e) = self.logs.error() {
                return Err(RunError::Log {
                    hint: self.resume_hint(),
                    log: e,
                });
            }
        }
        // Everything is read: the processes, waiting for this, may exit.
        self.recorded.announce()?;
        self.reap()?;
        self.returns.flush()
    }
}

/// Calls `go_on` until it says to stop or `window` of `time` has passed.
fn for_a_while(time: &Monotonic, window: Duration, mut go_on: impl FnMut() -> bool) {
    let end = time.now_ns() + window.as_nanos() as u64;
    while time.now_ns() < end && go_on() {}
}

/// Waits for every one of `children` to exit, [`EXIT_WINDOW`] of `time` at most; a
/// failed one is reported with its last lines in `logs`.
fn reap(children: &mut Children, logs: &Logs, time: &Monotonic) -> Result<()> {
    let deadline = time.now_ns() + EXIT_WINDOW.as_nanos() as u64;
    for (role, child) in &mut children.0 {
        let status = time
            .poll_until(deadline, LOOK_AGAIN, || child.try_wait().transpose())
            .ok_or(RunError::Lingered { role: role.name() })??;
        if !status.success() {
            return Err(RunError::Failed {
                role: role.name(),
                status,
                log: logs.last_lines(*role),
            });
        }
    }
    children.0.clear();
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::process::Command;

    use wire::MS;

    /// A window lasts its length of the time it is measured on, and no longer; it ends
    /// early when told to.
    #[test]
    fn a_window_lasts_its_length_of_mock_time() {
        let (clock, time) = Monotonic::mock();
        time.step_each_reading(Duration::from_millis(10));
        let mut calls = 0;
        for_a_while(&clock, ANSWER_WINDOW, || {
            calls += 1;
            true
        });
        // Readings at 0 (the start), 10, …, 1000 ms: calls at 10 … 990 ms.
        assert_eq!((calls, time.now_ns()), (99, 1000 * MS + 10 * MS));
        let mut calls = 0;
        for_a_while(&clock, ANSWER_WINDOW, || {
            calls += 1;
            calls < 3
        });
        assert_eq!(calls, 3);
    }

    /// A process that does not exit within ten seconds of the run's end is named; one
    /// that does is reaped.
    #[test]
    fn a_process_lingering_ten_seconds_is_named() {
        let (clock, time) = Monotonic::mock();
        time.step_each_reading(Duration::from_millis(500));
        let child = Command::new("sleep").arg("60").spawn().unwrap();
        let mut children = Children(vec![(Role::Observer, child)]);
        let lingered = reap(&mut children, &Logs::default(), &clock);
        assert!(
            matches!(lingered, Err(RunError::Lingered { role: "observer" })),
            "{lingered:?}"
        );
        // The deadline at 10 s, reached at the reading at 10 s (each moving the time on).
        assert_eq!(time.now_ns(), 10_000 * MS + 500 * MS);
        drop(children);

        let (clock, time) = Monotonic::mock();
        let mut done = Command::new("true").spawn().unwrap();
        done.wait().unwrap();
        let mut children = Children(vec![(Role::Plant, done)]);
        reap(&mut children, &Logs::default(), &clock).unwrap();
        assert!(children.0.is_empty() && time.now_ns() == 0);
    }
}
