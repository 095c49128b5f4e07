//! A pace on a [`Monotonic`]: at most one of a thing every period (the system's
//! pictures, the subscriptions' refresh), on the host's clock or, in a test, a mock.

use std::time::Duration;

use wire::Monotonic;

/// At most one every `period` of `time`.
pub struct Pace {
    time: Monotonic,
    period_ns: u64,
    /// When the last one went.
    last: Option<u64>,
}

impl Pace {
    /// One every `period` of `time`; the first is due at once.
    pub fn every(period: Duration, time: Monotonic) -> Self {
        Self {
            time,
            period_ns: period.as_nanos() as u64,
            last: None,
        }
    }

    /// Whether the next is due: a period has passed since the last went.
    pub fn due(&self) -> bool {
        self.last
            .is_none_or(|t| self.time.now_ns().saturating_sub(t) >= self.period_ns)
    }

    /// One went now.
    pub fn went(&mut self) {
        self.last = Some(self.time.now_ns());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Thirty a second: one at once, the next 33.3 ms after it went, not before.
    #[test]
    fn one_a_period_of_mock_time() {
        let (clock, time) = Monotonic::mock();
        let mut pace = Pace::every(Duration::from_secs(1) / 30, clock);
        assert!(pace.due());
        time.advance(Duration::from_millis(5));
        pace.went();
        time.advance(Duration::from_nanos(33_333_332));
        assert!(!pace.due());
        time.advance(Duration::from_nanos(1));
        assert!(pace.due());
        pace.went();
        assert!(!pace.due());
    }
}
