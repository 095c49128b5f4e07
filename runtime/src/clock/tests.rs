use std::time::Duration;

use driver::contract::DriverInfo;
use wire::{FOREVER, Waiting};

use super::{Clock, ClockError, DriverFlags, ExternalDriver, Timing};
use crate::config::{ExperimentConfig, Overrides, resolve};

fn driver() -> ExternalDriver {
    ExternalDriver {
        id: "pendulum".into(),
        timeout: Duration::from_secs(60),
        reset_timeout: Duration::from_millis(2500),
    }
}

fn config(o: Overrides) -> ExperimentConfig {
    resolve(None, &o).unwrap()
}

#[test]
fn a_speed_is_turned_into_the_period_once() {
    let clock = Clock::realtime(0.03, 10.0).unwrap();
    assert_eq!(clock.period(), Some(Duration::from_millis(3)));
    assert!((Clock::speed(0.03, Duration::from_millis(3)) - 10.0).abs() < 1e-12);
    assert_eq!(clock.describe(0.03, None), "realtime, speed 10");
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY, 1000.5] {
        let e = Clock::realtime(0.03, bad).unwrap_err();
        assert!(matches!(e, ClockError::Speed(_)), "{e}");
        assert!(
            e.to_string()
                .starts_with(&format!("`--speed` {bad} is out of range")),
            "{e}"
        );
    }
}

#[test]
fn the_clock_says_which_it_is() {
    let realtime = Clock::realtime(0.03, 10.0).unwrap();
    let external = Clock::External(driver());
    let kinds = |c: &Clock| (c.is_lockstep(), c.is_realtime(), c.is_external());
    assert_eq!(kinds(&Clock::Lockstep), (true, false, false));
    assert_eq!(kinds(&realtime), (false, true, false));
    assert_eq!(kinds(&external), (false, false, true));
}

#[test]
fn the_flags_choose_one_clock_and_refuse_what_does_not_combine() {
    let flags = DriverFlags {
        id: None,
        timeouts: (60.0, 2.5),
    };
    let of = |t, speed, d: Option<DriverFlags>| Clock::of_flags((t, speed), (0.03, "pendulum"), d);
    assert_eq!(of(Timing::Lockstep, 1.0, None).unwrap(), Clock::Lockstep);
    // The speed is checked in lockstep too, and otherwise ignored there.
    assert!(of(Timing::Lockstep, 0.0, None).is_err());
    assert_eq!(of(Timing::Lockstep, 2.0, None).unwrap(), Clock::Lockstep);
    assert_eq!(
        of(Timing::Realtime, 2.0, None).unwrap(),
        Clock::Realtime {
            period: Duration::from_millis(15)
        }
    );
    assert_eq!(
        of(Timing::Lockstep, 1.0, Some(flags)).unwrap(),
        Clock::External(driver())
    );
    for (timing, speed) in [(Timing::Realtime, 1.0), (Timing::Lockstep, 2.0)] {
        let e = of(timing, speed, Some(flags)).unwrap_err();
        assert!(matches!(e, ClockError::ExternalTiming), "{e}");
        assert_eq!(
            e.to_string(),
            "`--timing`/`--speed` do not apply with `--plant external`: the driver is the clock"
        );
    }
}

#[test]
fn delays_predictive_timing_and_endless_polling_are_refused_where_they_cannot_hold() {
    let realtime = Clock::realtime(0.03, 1.0).unwrap();
    let external = Clock::External(driver());
    let delayed = config(Overrides {
        delay_ms: Some(5.0),
        ..Default::default()
    });
    assert!(Clock::Lockstep.check(&delayed, Waiting::Block).is_ok());
    for clock in [&realtime, &external] {
        let e = clock.check(&delayed, Waiting::Block).unwrap_err();
        assert!(matches!(e, ClockError::Delayed), "{e}");
        assert!(
            e.to_string()
                .contains("apply in lockstep with the simulated plant only"),
            "{e}"
        );
    }
    let plain = config(Overrides::default());
    let polling = Waiting::Yield(FOREVER);
    assert!(Clock::Lockstep.check(&plain, polling).is_ok());
    let bounded = Waiting::Yield(Duration::from_micros(50));
    for clock in [&realtime, &external] {
        assert!(clock.check(&plain, Waiting::Block).is_ok());
        // Polling that ends wakes the plant.
        assert!(clock.check(&plain, bounded).is_ok());
    }
    let e = realtime.check(&plain, polling).unwrap_err();
    assert!(matches!(e, ClockError::Unwoken), "{e}");
    assert!(
        e.to_string()
            .starts_with("`--wait spin|yield` without `--wait-us`"),
        "{e}"
    );
    // An external driver's clock is known once its info is read: polling without end
    // only with a driver in lockstep.
    assert!(external.check(&plain, polling).is_ok());
    let driver = |clock| DriverInfo {
        clock,
        ..Default::default()
    };
    let lockstep = driver(driver::contract::clock::LOCKSTEP);
    let in_real_time = driver(driver::contract::clock::REALTIME);
    assert!(Clock::check_driver_waiting(&lockstep, polling).is_ok());
    assert!(Clock::check_driver_waiting(&in_real_time, bounded).is_ok());
    assert!(matches!(
        Clock::check_driver_waiting(&in_real_time, polling),
        Err(ClockError::Unwoken)
    ));
    let predictive = config(Overrides {
        sensor: Some(observer::config::SensorKind::Angle),
        observer: Some(observer::config::ObserverKind::Predictive),
        observer_mode: Some(observer::config::ObserverMode::Predictive),
        ..Default::default()
    });
    assert!(realtime.check(&predictive, Waiting::Block).is_ok());
    let e = external.check(&predictive, Waiting::Block).unwrap_err();
    assert!(matches!(e, ClockError::Predictive), "{e}");
    assert!(e.to_string().contains("needs the simulated plant"), "{e}");
    let zero = Clock::Realtime {
        period: Duration::ZERO,
    };
    assert!(matches!(
        zero.check(&plain, Waiting::Block),
        Err(ClockError::ZeroPeriod)
    ));
}

#[test]
fn a_clock_is_written_and_read_back_with_its_durations_in_seconds() {
    #[derive(serde::Serialize, serde::Deserialize)]
    struct File {
        clock: Clock,
    }
    let clocks = [
        Clock::Lockstep,
        Clock::realtime(0.03, 7.0).unwrap(),
        Clock::External(driver()),
    ];
    for clock in clocks {
        let text = toml::to_string(&File {
            clock: clock.clone(),
        })
        .unwrap();
        let back: File = toml::from_str(&text).unwrap();
        assert_eq!(back.clock, clock, "{text}");
    }
    let by_hand: File =
        toml::from_str("[clock.external]\nid = \"arm\"\ntimeout = 60\nreset_timeout = 2.5\n")
            .unwrap();
    assert_eq!(
        by_hand.clock.driver().map(|d| (d.timeout, d.reset_timeout)),
        Some((Duration::from_secs(60), Duration::from_millis(2500)))
    );
    for typo in [
        "[clock.realtime]\nperiod = 0.003\nspeed = 10\n",
        "[clock.external]\nid = \"arm\"\ntimeout = 60\nreset_timeout = 2.5\nspeed = 1\n",
    ] {
        let e = toml::from_str::<File>(typo).err().unwrap().to_string();
        let named =
            e.contains("unknown field `speed`") || e.contains("unexpected keys in table: speed");
        assert!(named, "{e}");
    }
    for bad in ["0", "-1", "nan", "inf"] {
        let text = format!("[clock.realtime]\nperiod = {bad}\n");
        let e = toml::from_str::<File>(&text).err().unwrap().to_string();
        assert!(e.contains("not a number of seconds"), "{bad}: {e}");
    }
}
