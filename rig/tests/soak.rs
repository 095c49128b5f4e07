//! The soak benchmark's short version (`bench/scripts/soak.py`, docs/results/soak.md):
//! 20 s of link cuts, loss bursts, probes and second rigs against a run across two
//! hosts, resumed until done. Needs root, iproute2, nftables and Python with `mcap`
//! (RIG_PYTHON); without them it prints why and passes.

mod common;

use std::process::Command;

/// `$RIG_PYTHON` (default `python3`) if it imports rigkit and mcap; else says why not.
fn python_with_mcap() -> Option<String> {
    common::python::with("rigkit, mcap")
}

#[test]
fn a_short_soak_finishes_with_no_foreign_command_and_no_gap_learned() {
    let Some(python) = python_with_mcap() else {
        return;
    };
    // The scratch hosts of common::hosts check root and the tools; the script makes its
    // own.
    let Some(hosts) = common::hosts::Hosts::new(1) else {
        return;
    };
    drop(hosts);
    if Command::new("nft").arg("--version").output().is_err() {
        println!("skipped: no `nft` (nftables) to cut the link with");
        return;
    }
    let out = common::tmp("soak", "short");
    let run = common::python::script(&python, "bench/scripts/soak.py")
        .args([
            "--seconds",
            "20",
            "--speed",
            "2",
            "--seed",
            "1",
            "--trials",
            "8",
        ])
        .args(["--rig", env!("CARGO_BIN_EXE_rig"), "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let said = format!(
        "{}{}",
        String::from_utf8_lossy(&run.stdout),
        String::from_utf8_lossy(&run.stderr)
    );
    let figures: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("figures.json")).unwrap())
            .unwrap_or_else(|e| panic!("{e}: {said}"));
    let n = |key: &str| {
        figures[key]
            .as_u64()
            .unwrap_or_else(|| panic!("{key}: {said}"))
    };
    assert_eq!(figures["done"], true, "{said}");
    assert_eq!(
        n("second_session_commands_reaching_the_driver"),
        0,
        "{said}"
    );
    assert_eq!(n("trials_in_returns_with_a_gap"), 0, "{said}");
    assert_eq!(n("trials_checked_in_recording"), n("trials"), "{said}");
    // The seed's faults: at least one cut, survived, and a second session refused.
    assert!(n("cuts") >= 1 && n("cuts_survived") == n("cuts"), "{said}");
    assert!(
        n("probes_told_who_holds") + n("second_rigs_told_who_holds") >= 1,
        "{said}"
    );
    assert!(run.status.success(), "{said}");
}

/// The soak's must-be-0 count of a second session's commands, on made-up samples
/// (bench/scripts/test_soak_figures.py): it counts a command of another session applied
/// while the run held the driver, and none applied after the run's lease lapsed, at a
/// resumed run's start, or of the run's own that a resume dropped from the recording.
#[test]
fn the_soak_counts_a_second_sessions_command_only_while_the_run_held_the_driver() {
    let Some(python) = python_with_mcap() else {
        return;
    };
    let out = common::python::script(&python, "bench/scripts/test_soak_figures.py")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}
