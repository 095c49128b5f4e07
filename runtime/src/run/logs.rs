//! Each process's output: through a pipe to the supervisor, which writes it to
//! `DIR/<process>.log` and keeps its last lines, so that it can say why a process
//! stopped even when the log cannot be written (a full disk): the process's own words
//! reach it without the disk.

use std::collections::VecDeque;
use std::fs::File;
use std::io::{BufRead, BufReader, PipeReader, PipeWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use wire::Monotonic;

use super::command::Role;
use super::error::Result;
use crate::error::AtFile;

/// The lines of a log kept in memory.
const TAIL: usize = 5;

/// How long [`Log::tail`] waits for the lines a process wrote before it exited.
const LAST_WORDS: Duration = Duration::from_secs(1);

/// How often the wait for the last words looks whether the pipe has closed.
const LOOK_AGAIN: Duration = Duration::from_millis(2);

/// The logs of the run's processes, by role.
#[derive(Default)]
pub(super) struct Logs(pub(super) Vec<(Role, Log)>);

impl Logs {
    /// The log of process `role`.
    pub(super) fn of(&self, role: Role) -> Option<&Log> {
        self.0.iter().find(|(r, _)| *r == role).map(|(_, l)| l)
    }

    /// `last lines of DIR/<role>.log:` and those lines.
    pub(super) fn last_lines(&self, role: Role) -> String {
        match self.of(role) {
            Some(log) => format!("last lines of {}:\n{}", log.path.display(), log.tail()),
            None => format!("no log of the {} process", role.name()),
        }
    }

    /// The first log that could not be written: why, and the last lines meant for it.
    pub(super) fn error(&self) -> Option<String> {
        let (role, e) = self
            .0
            .iter()
            .find_map(|(role, l)| Some((role, l.error()?)))?;
        Some(format!("{e}; {}", self.last_lines(*role)))
    }
}

/// One process's log.
pub(super) struct Log {
    /// The log file.
    pub(super) path: PathBuf,
    relayed: Arc<Mutex<Relayed>>,
    thread: Option<JoinHandle<()>>,
}

/// What the relay has seen.
#[derive(Default)]
struct Relayed {
    /// The last lines.
    tail: VecDeque<String>,
    /// Why the log file could not be written, if it could not.
    error: Option<String>,
}

impl Log {
    /// Creates the log file `path` and the pipe into it: returns the log and the pipe's
    /// writing end, for the process's standard output and error.
    pub(super) fn open(path: &Path) -> Result<(Self, PipeWriter)> {
        let file = File::create(path).at("cannot create", path)?;
        let (reader, writer) = std::io::pipe().at("cannot make a pipe for", path)?;
        let relayed = Arc::new(Mutex::new(Relayed::default()));
        let thread = {
            let (relayed, path) = (relayed.clone(), path.to_owned());
            std::thread::spawn(move || relay(reader, file, &path, &relayed))
        };
        let log = Self {
            path: path.to_owned(),
            relayed,
            thread: Some(thread),
        };
        Ok((log, writer))
    }

    /// The last lines the process wrote, once it has exited (waiting a moment for those
    /// still in the pipe), and why the log could not be written if it could not.
    pub(super) fn tail(&self) -> String {
        self.tail_on(&Monotonic::host())
    }

    /// [`Self::tail`], waiting at most [`LAST_WORDS`] of `time` for the pipe to close.
    fn tail_on(&self, time: &Monotonic) -> String {
        let end = time.now_ns() + LAST_WORDS.as_nanos() as u64;
        let closed = || {
            self.thread
                .as_ref()
                .is_none_or(|t| t.is_finished())
                .then_some(())
        };
        time.poll_until(end, LOOK_AGAIN, closed);
        let r = self.relayed.lock().unwrap_or_else(|e| e.into_inner());
        let mut lines: Vec<&str> = r.tail.iter().map(String::as_str).collect();
        lines.extend(r.error.as_deref());
        lines.join("\n")
    }

    /// Why the log file could not be written, if it could not.
    pub(super) fn error(&self) -> Option<String> {
        let r = self.relayed.lock().unwrap_or_else(|e| e.into_inner());
        r.error.clone()
    }
}

/// Copies the process's output from `reader` into `file` (at `path`) line by line,
/// keeping the last lines in `relayed`; after a failed write it goes on reading, and
/// keeping lines, without writing.
fn relay(reader: PipeReader, mut file: File, path: &Path, relayed: &Mutex<Relayed>) {
    let mut reader = BufReader::new(reader);
    let mut line = Vec::new();
    loop {
        line.clear();
        match reader.read_until(b'\n', &mut line) {
            Ok(0) | Err(_) => return,
            Ok(_) => {}
        }
        let mut r = relayed.lock().unwrap_or_else(|e| e.into_inner());
        if r.error.is_none()
            && let Err(e) = file.write_all(&line)
        {
            r.error = Some(format!("cannot write {}: {e}", path.display()));
        }
        if r.tail.len() == TAIL {
            r.tail.pop_front();
        }
        r.tail
            .push_back(String::from_utf8_lossy(&line).trim_end().to_string());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_last_lines_are_kept_and_written() {
        let dir = std::env::temp_dir().join(format!("rig-logs-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("agent.log");
        let (log, mut w) = Log::open(&path).unwrap();
        for i in 0..7 {
            writeln!(w, "line {i}").unwrap();
        }
        drop(w);
        assert_eq!(log.tail(), "line 2\nline 3\nline 4\nline 5\nline 6");
        assert_eq!(std::fs::read_to_string(&path).unwrap().lines().count(), 7);
        assert!(log.error().is_none());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_log_that_cannot_be_written_keeps_its_lines_and_says_why() {
        // /dev/full: every write fails with "No space left on device".
        let Ok(file) = std::fs::OpenOptions::new().write(true).open("/dev/full") else {
            return;
        };
        let (reader, mut w) = std::io::pipe().unwrap();
        let relayed = Arc::new(Mutex::new(Relayed::default()));
        let thread = {
            let relayed = relayed.clone();
            std::thread::spawn(move || relay(reader, file, Path::new("/dev/full"), &relayed))
        };
        writeln!(
            w,
            "error: cannot write checkpoint x: No space left on device"
        )
        .unwrap();
        drop(w);
        let log = Log {
            path: "/dev/full".into(),
            relayed,
            thread: Some(thread),
        };
        let tail = log.tail();
        assert!(
            tail.starts_with("error: cannot write checkpoint x"),
            "{tail}"
        );
        assert!(
            tail.ends_with("cannot write /dev/full: No space left on device (os error 28)"),
            "{tail}"
        );
        assert!(log.error().is_some());
    }

    #[test]
    fn the_last_words_are_waited_for_a_second_at_most() {
        let dir = std::env::temp_dir().join(format!("rig-logs-open-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        // A process that has not closed its output: the relay never finishes.
        let (log, writer) = Log::open(&dir.join("agent.log")).unwrap();
        let (time, _) = Monotonic::mock();
        log.tail_on(&time);
        let waited = time.now_ns();
        let most = LAST_WORDS.as_nanos() as u64;
        assert!(
            (most..most + LOOK_AGAIN.as_nanos() as u64).contains(&waited),
            "{waited} ns"
        );
        drop(writer);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
