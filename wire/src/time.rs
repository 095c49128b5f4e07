//! The time all processes of a host share: `CLOCK_MONOTONIC` ([`now_ns`]), and
//! [`Monotonic`], the time source a component that keeps real time reads — the host's
//! clock, or in a test a mock that the test moves ([`Monotonic::mock`]), so that a rule of
//! real time is tested in microseconds instead of by waiting.

use std::cell::RefCell;
use std::collections::VecDeque;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering::SeqCst};
use std::time::Duration;

use crate::Error;

/// A millisecond in the nanoseconds a [`Monotonic`] counts (a mock's times read in ms).
pub const MS: u64 = 1_000_000;

/// `CLOCK_MONOTONIC` now, in nanoseconds.
pub fn now_ns() -> u64 {
    let mut ts = libc_timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes a timespec; CLOCK_MONOTONIC = 1 on Linux.
    unsafe { clock_gettime(1, &mut ts) };
    ts.tv_sec as u64 * 1_000_000_000 + ts.tv_nsec as u64
}

#[repr(C)]
struct libc_timespec {
    tv_sec: i64,
    tv_nsec: i64,
}

unsafe extern "C" {
    fn clock_gettime(clock: i32, ts: *mut libc_timespec) -> i32;
}

/// A monotonic time source in nanoseconds: the host's `CLOCK_MONOTONIC`
/// ([`Monotonic::host`], the default), or a mock that only [`MockTime`] moves. Cheap to
/// clone; clones of a mock share its time.
#[derive(Clone, Debug, Default)]
pub struct Monotonic {
    mock: Option<Arc<Mock>>,
}

#[derive(Debug, Default)]
struct Mock {
    now_ns: AtomicU64,
    /// How far each reading moves the time (time passing while a loop polls).
    step_ns: AtomicU64,
}

/// The hand that moves a mock [`Monotonic`].
#[derive(Clone, Debug)]
pub struct MockTime(Arc<Mock>);

impl Monotonic {
    /// The host's `CLOCK_MONOTONIC`, which all processes of a host share.
    pub fn host() -> Self {
        Self::default()
    }

    /// A mock at time 0 that stands still until its [`MockTime`] moves it.
    pub fn mock() -> (Self, MockTime) {
        let m = Arc::new(Mock::default());
        (
            Self {
                mock: Some(m.clone()),
            },
            MockTime(m),
        )
    }

    /// Now \[ns\] (a mock: then moved on by its step, [`MockTime::step_each_reading`]).
    pub fn now_ns(&self) -> u64 {
        match &self.mock {
            None => now_ns(),
            Some(m) => m.now_ns.fetch_add(m.step_ns.load(SeqCst), SeqCst),
        }
    }

    /// Sleeps until `t_ns` (a mock: moves on to it, if it is earlier).
    pub fn sleep_until(&self, t_ns: u64) {
        match &self.mock {
            None => std::thread::sleep(Duration::from_nanos(t_ns.saturating_sub(now_ns()))),
            Some(m) => {
                m.now_ns.fetch_max(t_ns, SeqCst);
            }
        }
    }

    /// Asks `ready` until it gives a value or the time reaches `end_ns`, asking again every
    /// `every`: the value, or `None` if the time ran out first. It is asked at least once.
    pub fn poll_until<T>(
        &self,
        end_ns: u64,
        every: Duration,
        mut ready: impl FnMut() -> Option<T>,
    ) -> Option<T> {
        loop {
            if let Some(v) = ready() {
                return Some(v);
            }
            let now = self.now_ns();
            if now >= end_ns {
                return None;
            }
            self.sleep_until(now + every.as_nanos() as u64);
        }
    }

    /// Whether this is a mock.
    pub fn is_mock(&self) -> bool {
        self.mock.is_some()
    }
}

impl MockTime {
    /// Moves the time on by `d`.
    pub fn advance(&self, d: Duration) {
        self.0.now_ns.fetch_add(d.as_nanos() as u64, SeqCst);
    }

    /// Moves the time on to `t_ns`, if it is earlier.
    pub fn advance_to(&self, t_ns: u64) {
        self.0.now_ns.fetch_max(t_ns, SeqCst);
    }

    /// Time passing while a loop polls: every reading moves the time on by `d` after it.
    pub fn step_each_reading(&self, d: Duration) {
        self.0.step_ns.store(d.as_nanos() as u64, SeqCst);
    }

    /// The time now \[ns\], without moving it.
    pub fn now_ns(&self) -> u64 {
        self.0.now_ns.load(SeqCst)
    }
}

/// Where a process's messages of one kind come from, as a loop that keeps time waits
/// for them: an [`crate::Rx`], or in a test a [`Scripted`] inbox on a mock clock.
pub trait Inbox<T> {
    /// The next message, if one is waiting.
    fn try_recv(&self) -> Result<Option<T>, Error>;
    /// Waits until a message may have arrived or until monotonic time `t_ns`.
    fn wait_until(&self, t_ns: u64) -> Result<(), Error>;
}

/// Messages that arrive at set times of a mock clock, for tests of loops that keep time.
#[derive(Debug)]
pub struct Scripted<T> {
    time: MockTime,
    /// `(arrival, message, how long its receipt takes)`, in order of arrival.
    script: RefCell<VecDeque<(u64, T, Duration)>>,
}

impl<T> Scripted<T> {
    /// An empty inbox on the mock clock `time`.
    pub fn new(time: &MockTime) -> Self {
        Self {
            time: time.clone(),
            script: RefCell::default(),
        }
    }

    /// Message `m` arrives at `t_ns`; receiving it takes `held` of the mock's time (a
    /// receipt held up).
    pub fn arrives(self, t_ns: u64, m: T, held: Duration) -> Self {
        self.script.borrow_mut().push_back((t_ns, m, held));
        self
    }
}

impl<T> Inbox<T> for Scripted<T> {
    fn try_recv(&self) -> Result<Option<T>, Error> {
        let mut script = self.script.borrow_mut();
        if script.front().is_none_or(|(t, ..)| *t > self.time.now_ns()) {
            return Ok(None);
        }
        let (_, m, held) = script.pop_front().expect("one is due");
        self.time.advance(held);
        Ok(Some(m))
    }

    /// Moves the mock on to `t_ns`, or to the next arrival before it.
    fn wait_until(&self, t_ns: u64) -> Result<(), Error> {
        let next = self.script.borrow().front().map_or(t_ns, |(t, ..)| *t);
        self.time.advance_to(next.min(t_ns));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn monotonic_clock_advances() {
        let a = now_ns();
        std::thread::sleep(Duration::from_millis(2));
        assert!(now_ns() >= a + 1_000_000);
        let host = Monotonic::host();
        assert!(!host.is_mock() && host.now_ns() >= a + 1_000_000);
        let b = host.now_ns();
        host.sleep_until(b + 2_000_000);
        assert!(now_ns() >= b + 2_000_000);
    }

    /// A mock stands still until moved; its clones share its time; a step moves it on
    /// after each reading.
    /// A poll asks until it is answered or its end is reached, sleeping its interval
    /// between questions; answered at once, it takes no time.
    #[test]
    fn a_poll_asks_until_answered_or_out_of_time() {
        let (time, _) = Monotonic::mock();
        let every = Duration::from_millis(10);
        let mut asked = 0;
        let answer = time.poll_until(35_000_000, every, || {
            asked += 1;
            (asked == 3).then_some(asked)
        });
        assert_eq!((answer, time.now_ns()), (Some(3), 20_000_000));
        let never = time.poll_until(50_000_000, every, || None::<()>);
        assert_eq!((never, time.now_ns()), (None, 50_000_000));
        let at_once = time.poll_until(0, every, || Some(()));
        assert_eq!((at_once, time.now_ns()), (Some(()), 50_000_000));
    }

    #[test]
    fn a_mock_moves_only_when_moved() {
        let (clock, time) = Monotonic::mock();
        let clone = clock.clone();
        assert_eq!((clock.now_ns(), clock.now_ns()), (0, 0));
        time.advance(Duration::from_millis(3));
        assert_eq!(clone.now_ns(), 3_000_000);
        time.advance_to(1_000);
        assert_eq!(clock.now_ns(), 3_000_000);
        time.step_each_reading(Duration::from_micros(1));
        assert_eq!((clock.now_ns(), clone.now_ns()), (3_000_000, 3_001_000));
        assert_eq!(time.now_ns(), 3_002_000);
        time.step_each_reading(Duration::ZERO);
        clone.sleep_until(9_000_000);
        clock.sleep_until(4_000_000);
        assert_eq!(clock.now_ns(), 9_000_000);
    }

    /// A scripted message is received only from its arrival on; waiting stops at the
    /// next arrival; a held receipt takes the mock's time.
    #[test]
    fn a_scripted_inbox_delivers_on_time() {
        let (clock, time) = Monotonic::mock();
        let inbox = Scripted::new(&time)
            .arrives(5_000, 'a', Duration::ZERO)
            .arrives(9_000, 'b', Duration::from_micros(4));
        assert_eq!(inbox.try_recv().unwrap(), None);
        inbox.wait_until(100_000).unwrap();
        assert_eq!(clock.now_ns(), 5_000);
        assert_eq!(inbox.try_recv().unwrap(), Some('a'));
        inbox.wait_until(7_000).unwrap();
        assert_eq!((clock.now_ns(), inbox.try_recv().unwrap()), (7_000, None));
        inbox.wait_until(100_000).unwrap();
        assert_eq!(inbox.try_recv().unwrap(), Some('b'));
        assert_eq!(clock.now_ns(), 13_000);
    }
}
