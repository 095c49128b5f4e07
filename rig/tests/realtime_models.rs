//! A model driver on the realtime clock (`rigkit.model_driver`'s `--clock realtime`,
//! served by `rigkit.clocked`): the Furuta pendulum's driver passes `rig check-driver`'s
//! realtime checks (sample rate, watchdog, clamping, rejection) and the rig's default
//! learner runs against it in real time.
//!
//! The test needs `iceoryx2==0.10.0` importable by `$RIG_PYTHON` (default `python3`);
//! without it it prints why and passes — CI installs it, so it runs there.

use std::path::Path;
use std::time::Instant;

mod common;
use common::drivers::{Driver, python};
use common::{ok, rig};

/// The Furuta pendulum's driver with `--clock realtime`: `rig check-driver` passes with
/// the realtime clock's checks (the rate measured over 3 s, with the jitter bound of a
/// CI machine shared with other tests, as rig/tests/driver.rs's; the default, 10 %, is
/// for hardware), and two trials and a greedy one of the rig's default
/// learner (no `--algo`, no `--config`) run against it at the task's own sampling time:
/// the recorded driver samples are 20 ms apart on the monotonic clock (the median of
/// consecutive ones within 1 %), and the run took at least that long per sample.
#[test]
fn a_model_driver_on_the_realtime_clock_passes_its_checks_and_learns_in_real_time() {
    let Some(python) = python() else {
        return;
    };
    let dir = common::tmp("realtime-models", "furuta").join("run");
    let task = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/furuta/furuta.toml");
    let task = task.to_str().unwrap();
    let d = Driver::script(
        &python,
        "examples/furuta/driver.py",
        "furuta-rt",
        &["--clock", "realtime", "--task", task],
    );
    let out = rig()
        .args(["check-driver", "--driver", &d.id, "--driver-timeout", "20"])
        .args(["--task", task, "--rate-seconds", "3", "--max-jitter", "0.5"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{text}");
    assert!(text.contains("realtime clock"), "{text}");
    for check in ["sample rate", "watchdog", "out-of-range actions", "reset"] {
        assert!(text.contains(&format!("PASS  {check}")), "{text}");
    }

    let t0 = Instant::now();
    let out = ok(rig()
        .arg("run")
        .args(common::external(&d.id))
        .args([
            "--task",
            task,
            "--trials",
            "2",
            "--eval-every",
            "2",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap());
    let wall = t0.elapsed().as_secs_f64();
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(summary.contains("realtime clock"), "{summary}");
    let returns = std::fs::read_to_string(dir.join("returns.csv")).unwrap();
    assert_eq!(returns.lines().count(), 3, "{returns}");

    let msgs = common::messages(&dir.join("run.mcap"));
    let t_sample = common::field(&msgs, "/driver/sample", "t_sample_ns");
    let mut periods: Vec<f64> = t_sample
        .iter()
        .zip(t_sample.iter().skip(1))
        .filter(|((a, _), (b, _))| **b == **a + 1)
        .map(|((_, ta), (_, tb))| (tb - ta) * 1e-9)
        .collect();
    assert!(periods.len() >= 20, "{} consecutive samples", periods.len());
    periods.sort_by(f64::total_cmp);
    let median = periods[periods.len() / 2];
    assert!((median - 0.020).abs() < 0.0002, "median period {median} s");
    assert!(
        wall >= 0.02 * periods.len() as f64,
        "{wall} s for {} periods",
        periods.len()
    );
}
