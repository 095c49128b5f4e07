//! A full disk is an error, not a crash: `rig run` into a small file system (a tmpfs of
//! 4 MB) stops with a one-line cause naming the file and "no space left on device" —
//! no panic, the process that could not write named —, and once there is space again
//! `--resume` ends with the bytes of a run never interrupted.
//!
//! Mounting needs root: without it the tests print why and pass.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;
use common::{ok, rig};

/// A tmpfs mounted on a fresh folder; unmounted when dropped.
struct SmallDisk {
    dir: PathBuf,
}

impl SmallDisk {
    /// A `size` tmpfs on `rig-full-disk-<pid>-<name>/disk`, or `None` (and why) where it
    /// cannot be mounted.
    fn mount(name: &str, size: &str) -> Option<Self> {
        // SAFETY: `geteuid` reads this process's user id.
        if unsafe { libc::geteuid() } != 0 {
            println!("skipped: mounting a tmpfs needs root");
            return None;
        }
        let dir = common::tmp("full-disk", name).join("disk");
        std::fs::create_dir_all(&dir).unwrap();
        let out = Command::new("mount")
            .args(["-t", "tmpfs", "-o", &format!("size={size}"), "tmpfs"])
            .arg(&dir)
            .output();
        match out {
            Ok(o) if o.status.success() => Some(Self { dir }),
            Ok(o) => {
                println!(
                    "skipped: cannot mount a tmpfs: {}",
                    String::from_utf8_lossy(&o.stderr).trim()
                );
                None
            }
            Err(e) => {
                println!("skipped: cannot run mount: {e}");
                None
            }
        }
    }

    /// Makes the file system `size` large.
    fn grow(&self, size: &str) {
        let status = Command::new("mount")
            .args(["-o", &format!("remount,size={size}")])
            .arg(&self.dir)
            .status()
            .unwrap();
        assert!(status.success());
    }

    /// Fills the file system but for `free` bytes.
    fn fill_but(&self, free: u64) {
        use std::io::Write;
        let path = self.dir.join("filler");
        let mut f = std::fs::File::create(&path).unwrap();
        let block = vec![0xa5u8; 1 << 16];
        while f.write_all(&block).is_ok() {}
        // Whole pages, as the file system counts.
        let len = f.metadata().unwrap().len().saturating_sub(free) & !4095;
        f.set_len(len).unwrap();
    }
}

impl Drop for SmallDisk {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.dir).status();
    }
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Asserts that `out` failed with an error, not a panic, naming a file in `dir` and
/// the full disk; and that no process's log holds a panic.
fn stopped_by_the_full_disk(out: &Output, dir: &Path) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        !err.contains("panicked") && !err.contains("exit status: 101"),
        "{err}"
    );
    let cause = err
        .lines()
        .find(|l| l.contains("No space left on device"))
        .unwrap_or_else(|| panic!("no line says the disk is full: {err}"));
    assert!(cause.contains(&dir.display().to_string()), "{err}");
    for log in ["plant.log", "observer.log", "agent.log"] {
        let text = std::fs::read_to_string(dir.join(log)).unwrap_or_default();
        assert!(!text.contains("panicked"), "{log}: {text}");
    }
}

/// The uninterrupted run's `returns.csv` of `rig run` with `args`.
fn whole(name: &str, args: &[&str]) -> String {
    let dir = common::tmp("full-disk", name).join("whole");
    ok(run(args, &dir));
    std::fs::read_to_string(dir.join("returns.csv")).unwrap()
}

/// The whole run folder on 4 MB: whichever process meets the full disk first, the run
/// stops with its cause; on 256 MB the run resumes to the uninterrupted run's bytes.
/// `rig run ARGS --out DIR`.
fn run(args: &[&str], dir: &Path) -> Output {
    rig()
        .arg("run")
        .args(args)
        .arg("--out")
        .arg(dir)
        .output()
        .unwrap()
}

/// `rig run --resume DIR` succeeds, and `returns.csv` is then the uninterrupted run's.
fn resumed_to(dir: &Path, expected: &str) {
    ok(rig()
        .args(["run", "--quiet", "--resume"])
        .arg(dir)
        .output()
        .unwrap());
    assert_eq!(
        std::fs::read_to_string(dir.join("returns.csv")).unwrap(),
        expected
    );
}

#[test]
fn a_run_into_a_full_disk_stops_with_the_cause_and_resumes_once_there_is_space() {
    let args = ["--trials", "200", "--quiet"];
    let Some(disk) = SmallDisk::mount("whole-run", "4m") else {
        return;
    };
    let expected = whole("whole-run", &args);
    let dir = disk.dir.join("run");
    let out = run(&args, &dir);
    stopped_by_the_full_disk(&out, &dir);
    disk.grow("256m");
    resumed_to(&dir, &expected);
}

/// The disk full but for 36 kB when the run starts: the run's small files (its
/// configuration, the nodes' settings, logs, the recording's start) take most of that,
/// and the agent's checkpoint folder (its lock, its first checkpoint of 11 kB) does not
/// fit, nor does the agent's log. The agent stops with one line naming the file, and
/// the rig says so — in the agent's own words, which reach it without the disk.
#[test]
fn an_agent_whose_checkpoint_does_not_fit_says_so_through_the_rig() {
    let args = ["--trials", "3", "--quiet"];
    let Some(disk) = SmallDisk::mount("first-checkpoint", "4m") else {
        return;
    };
    let expected = whole("first-checkpoint", &args);
    disk.fill_but(36 * 1024);
    let dir = disk.dir.join("run");
    let out = run(&args, &dir);
    stopped_by_the_full_disk(&out, &dir);
    let err = stderr(&out);
    let agent = err
        .lines()
        .skip_while(|l| !l.contains("agent.log:"))
        .nth(1)
        .unwrap_or_else(|| panic!("no line of the agent's: {err}"));
    assert!(
        agent.starts_with("error: cannot ")
            && agent.contains(&dir.join("checkpoints").display().to_string())
            && agent.ends_with("No space left on device (os error 28)"),
        "{err}"
    );
    std::fs::remove_file(disk.dir.join("filler")).unwrap();
    resumed_to(&dir, &expected);
}
