//! An output folder belongs to one command: a second `rig run`, `rig learn` or agent
//! process into a folder in use is refused with one line naming the holder, the first
//! one's outputs stay intact, and a folder whose run was killed can be resumed at once.

use std::path::{Path, PathBuf};
use std::process::{Output, Stdio};
use std::time::Duration;

mod common;
use common::{ok, rig};

fn tmp(name: &str) -> PathBuf {
    common::tmp("folder", name)
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Asserts that `out` failed with one line naming process `pid`, a `rig` command.
fn refused_naming(out: &Output, pid: u32, folder: &Path) {
    let err = stderr(out);
    assert!(!out.status.success(), "must be refused: {err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(
        err.contains(&format!(
            "{} is in use by process {pid} (rig ",
            folder.display()
        )),
        "{err}"
    );
}

/// Two `rig run --out same`, the second started 0.3 s after the first: the second is
/// refused, naming the first; the first's recording is whole (the official reader reads
/// it and its returns are those of returns.csv) and its returns.csv complete.
#[test]
fn a_second_run_into_a_folder_in_use_is_refused_and_the_first_stays_readable() {
    let dir = tmp("two-runs");
    let out = dir.join("run");
    let first = rig()
        .args(["run", "--trials", "400", "--quiet", "--out"])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let second = rig()
        .args(["run", "--trials", "400", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    let first_pid = first.id();
    let first = first.wait_with_output().unwrap();
    assert!(first.status.success(), "the first run: {}", stderr(&first));
    refused_naming(&second, first_pid, &out);
    assert!(
        stderr(&second).contains("rig run --trials 400"),
        "{}",
        stderr(&second)
    );
    let returns = std::fs::read_to_string(out.join("returns.csv")).unwrap();
    assert_eq!(returns.lines().count(), 401);
    common::check_mcap(&out);
}

/// `rig learn` into a folder `rig run` writes to, and an agent process started by hand
/// with that run's checkpoint folder, are refused naming the run's processes.
#[test]
fn learn_and_a_hand_started_agent_are_refused_a_folder_in_use() {
    let dir = tmp("others");
    let out = dir.join("run");
    let run = rig()
        .args(["run", "--trials", "3000", "--quiet", "--out"])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    common::wait_for_lines(&out.join("returns.csv"), 3);
    let learn = rig()
        .args(["learn", "--trials", "2", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    refused_naming(&learn, run.id(), &out);
    assert!(
        stderr(&learn).contains("rig run --trials 3000"),
        "{}",
        stderr(&learn)
    );
    let agent = common::child_running(run.id(), "agent");
    let checkpoints = out.join("checkpoints");
    let settings = out.with_extension("agent.toml");
    std::fs::write(
        &settings,
        format!(
            "checkpoints = {checkpoints:?}\n[node]\nrun_id = \"by-hand\"\nconfig = {:?}\n",
            out.join("config.toml")
        ),
    )
    .unwrap();
    let by_hand = rig()
        .args(["agent", "--node"])
        .arg(&settings)
        .output()
        .unwrap();
    refused_naming(&by_hand, agent, &checkpoints);
    assert!(
        stderr(&by_hand).contains("rig agent"),
        "{}",
        stderr(&by_hand)
    );
    common::signal(run.id(), "-INT");
    let run = run.wait_with_output().unwrap();
    assert!(stderr(&run).contains("interrupted"), "{}", stderr(&run));
    // Once the run has ended, the folder is free.
    ok(rig()
        .args(["learn", "--trials", "2", "--quiet", "--out"])
        .arg(&out)
        .output()
        .unwrap());
}

/// `kill -9` of a run's every process leaves the lock file behind, but not the lock:
/// `--resume` continues at once, to the uninterrupted run's returns.
#[test]
fn a_folder_whose_run_was_killed_resumes() {
    let dir = tmp("killed");
    let args = ["--trials", "150", "--eval-every", "5", "--quiet", "--out"];
    ok(rig()
        .arg("run")
        .args(args)
        .arg(dir.join("whole"))
        .output()
        .unwrap());
    let out = dir.join("killed");
    let mut run = rig().arg("run").args(args).arg(&out).spawn().unwrap();
    common::wait_for_lines(&out.join("returns.csv"), 10);
    common::kill_run(run.id());
    run.wait().unwrap();
    assert!(out.join(".lock").exists());
    ok(rig()
        .args(["run", "--quiet", "--resume"])
        .arg(&out)
        .output()
        .unwrap());
    assert_eq!(
        std::fs::read_to_string(out.join("returns.csv")).unwrap(),
        std::fs::read_to_string(dir.join("whole/returns.csv")).unwrap()
    );
}
