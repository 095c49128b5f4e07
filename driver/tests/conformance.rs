//! The conformance check as a driver author runs it from their own tests: the kit's
//! simulated pendulum, served in lockstep on a thread of the test, passes every check of
//! `rig check-driver`.

use std::sync::Arc;
use std::time::Duration;

use driver::link::conformance::{CheckOptions, check};
use driver::{Serving, Simulated, serve_lockstep};
use plant::{SystemName, Task};

#[test]
fn the_kits_simulated_pendulum_in_lockstep_passes_the_conformance_check() {
    let id = format!("conformance-{}", std::process::id());
    let mut device = Simulated::new(SystemName::Pendulum, 1.0)
        .unwrap()
        .in_lockstep();
    let served = id.clone();
    // Served until the test's process ends.
    std::thread::spawn(move || {
        let how = Serving {
            stop_after: None,
            spin_ns: 0,
            verbose: false,
        };
        serve_lockstep(&mut device, &served, &how)
    });
    let opts = CheckOptions {
        driver: id,
        task: Arc::new(Task::new(SystemName::Pendulum)),
        timeout: Duration::from_secs(20),
        serve: String::new(),
        reset_timeout: Duration::from_secs(5),
        rate_seconds: 1.0,
        max_jitter: 0.5,
        max_missed: 0.01,
        step: 0.25,
    };
    let mut seen = Vec::new();
    let outcomes = check(&opts, &mut |o| seen.push(o.name)).unwrap();
    assert_eq!(
        seen.len(),
        outcomes.len(),
        "each outcome reported as it came"
    );
    let failed: Vec<_> = outcomes.iter().filter(|o| !o.pass).collect();
    assert!(failed.is_empty(), "{failed:#?}");
    for name in ["payload types", "info", "reset", "lockstep", "determinism"] {
        assert!(outcomes.iter().any(|o| o.name == name), "{name} checked");
    }
}
