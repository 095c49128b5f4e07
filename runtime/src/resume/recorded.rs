//! What a run left behind: its `returns.csv` and its recording, read back, and where
//! each trial ends in the recording.

use std::collections::BTreeSet;
use std::path::Path;

use super::error::PrepareError;
use wire::flags;

use crate::experiment::TrialRecord;
use crate::record::channels::{DRIVER_PREFIX, Head, Keep, LOOP, MEASUREMENT, row_trial};
use crate::record::reader::{NAME, PART, RecordedMessage, RunFile};

/// Reads the rows of a `returns.csv`, but a last line cut short (a row being written when
/// the disk filled up), which `notes` then mentions.
pub(super) fn read_returns(
    path: &Path,
    notes: &mut Vec<String>,
) -> Result<Vec<TrialRecord>, PrepareError> {
    let text = std::fs::read_to_string(path).map_err(|source| PrepareError::NoReturns {
        path: path.to_path_buf(),
        source,
    })?;
    let lines = text.rfind('\n').map_or("", |end| &text[..=end]);
    if lines.len() < text.len() {
        notes.push(format!(
            "{}: left out its last line, which was cut short: {:?}",
            path.display(),
            &text[lines.len()..]
        ));
    }
    let mut reader = csv::Reader::from_reader(lines.as_bytes());
    let mut rows = Vec::new();
    for (i, rec) in reader.records().enumerate() {
        let line = i + 2;
        let bad = |why: String| PrepareError::Row {
            path: path.to_path_buf(),
            line,
            why,
        };
        let rec = rec.map_err(|e| bad(format!("unreadable row: {e}")))?;
        let field = |j: usize| rec.get(j).unwrap_or("");
        let num = |j: usize| -> Result<f64, PrepareError> {
            field(j)
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| bad(format!("column {} is not a number: {:?}", j + 1, field(j))))
        };
        let trial: u32 = field(1)
            .parse()
            .map_err(|_| bad(format!("trial {:?} is not a trial number", field(1))))?;
        if trial as usize != rows.len() + 1 {
            let want = rows.len() + 1;
            return Err(bad(format!(
                "trial {trial} where trial {want} was expected: the file was edited"
            )));
        }
        rows.push(TrialRecord {
            run: 0,
            trial,
            sim_time_s: num(2)?,
            ret: num(3)?,
            greedy: if field(4).is_empty() {
                None
            } else {
                Some(num(4)?)
            },
        });
    }
    Ok(rows)
}

/// Reads every message of the recording in `out` that can be read: `run.mcap`, or the
/// `run.mcap.part` a killed supervisor leaves (its completed chunks).
pub(super) fn read_recording(
    out: &Path,
    notes: &mut Vec<String>,
) -> Result<Vec<RecordedMessage>, PrepareError> {
    let full = out.join(NAME);
    let part = out.join(PART);
    let path = if full.exists() { full } else { part };
    let file = RunFile::read(&path).map_err(|source| PrepareError::NoRecording {
        path: path.clone(),
        source,
    })?;
    let (messages, cut) = file.readable().map_err(|source| PrepareError::NotMcap {
        path: path.clone(),
        source,
    })?;
    if let Some(e) = cut {
        notes.push(format!(
            "{} ends in an unfinished chunk ({e}); kept the {} messages before it",
            path.display(),
            messages.len()
        ));
    }
    Ok(messages)
}

/// Refuses to continue a run on another plant than it was made on: a hardware run
/// finished in the simulator (or the reverse) would mix two systems in one learning
/// curve.
pub(super) fn same_plant(
    out: &Path,
    messages: &[RecordedMessage],
    external: bool,
) -> Result<(), PrepareError> {
    let recorded = messages.iter().any(|m| m.topic.starts_with(DRIVER_PREFIX));
    if recorded == external {
        return Ok(());
    }
    Err(PrepareError::OtherPlant {
        dir: out.to_path_buf(),
        external: recorded,
    })
}

/// What the recording holds, per learning trial.
pub(super) struct RecordingIndex {
    /// Per main topic, the sequence numbers present.
    seqs: [BTreeSet<u64>; 3],
    /// `(seq, trial, flags)` of every measurement, in file order.
    measurements: Vec<(u64, u64, u64)>,
}

pub(super) fn index(messages: &[RecordedMessage]) -> Result<RecordingIndex, PrepareError> {
    let mut r = RecordingIndex {
        seqs: Default::default(),
        measurements: Vec::new(),
    };
    for m in messages {
        let Some(i) = LOOP.iter().position(|t| *t == m.topic) else {
            continue;
        };
        let h = Head::of(&m.data).map_err(|source| PrepareError::Message {
            topic: m.topic.clone(),
            source,
        })?;
        r.seqs[i].insert(h.seq);
        if i == 0 {
            r.measurements.push((h.seq, h.trial, h.flags));
        }
    }
    Ok(r)
}

impl RecordingIndex {
    /// The first sequence number after trial `c` and its evaluations, if the recording
    /// holds all of them: every sample up to there on all three topics, and the ends of
    /// the learning trial and of its `evals` greedy trials.
    pub(super) fn end_of(&self, c: u32, evals: usize) -> Option<u64> {
        let c = u64::from(c);
        let inside = |&&(_, t, f): &&(u64, u64, u64)| t <= c && f & flags::SHUTDOWN == 0;
        let q = self
            .measurements
            .iter()
            .filter(inside)
            .map(|m| m.0 + 1)
            .max()
            .unwrap_or(0);
        let ends = self
            .measurements
            .iter()
            .filter(|&&(_, t, f)| {
                t == c && f & (flags::END | flags::GAP | flags::SHUTDOWN) == flags::END
            })
            .count();
        let complete = self.seqs.iter().all(|s| s.range(..q).count() as u64 == q);
        (c == 0 || ends == 1 + evals)
            .then_some(q)
            .filter(|_| complete)
    }
}

/// The recorded messages before sample `first_seq`, after trial `c`, which the resumed
/// run keeps: the loop's topics, their timing and latency by sequence number (without the
/// shutdown), the rows of `returns.csv` of trials up to `c`, a picture per kept
/// measurement, the other channels (an external driver's traffic, the ground truth) up
/// to the last kept measurement's log time.
pub(super) fn kept(messages: Vec<RecordedMessage>, first_seq: u64, c: u32) -> Vec<RecordedMessage> {
    let last_log_time = messages
        .iter()
        .filter(|m| m.topic == MEASUREMENT)
        .filter_map(|m| {
            let h = Head::of(&m.data).ok()?;
            (h.seq < first_seq).then_some(m.log_time)
        })
        .max()
        .unwrap_or(0);
    let loop_kept = |h: Head| h.seq < first_seq && h.flags & flags::SHUTDOWN == 0;
    let measurements = messages
        .iter()
        .filter(|m| m.topic == MEASUREMENT)
        .filter(|m| Head::of(&m.data).is_ok_and(loop_kept))
        .count();
    let mut pictures = 0;
    let keep = |m: &RecordedMessage| -> bool {
        let head = || Head::of(&m.data).ok();
        match Keep::of(&m.topic) {
            Keep::Loop => head().is_some_and(loop_kept),
            Keep::Sample => head().is_some_and(|h| h.seq < first_seq),
            Keep::Row => row_trial(&m.data).is_some_and(|t| t <= u64::from(c)),
            Keep::Picture => {
                pictures += 1;
                pictures <= measurements
            }
            Keep::Logged => first_seq > 0 && m.log_time <= last_log_time,
        }
    };
    messages.into_iter().filter(keep).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_last_row_cut_short_is_left_out_with_a_note() {
        let dir = std::env::temp_dir().join(format!("rig-returns-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("returns.csv");
        let whole =
            "run,trial,sim_time_s,return,greedy_return\n0,1,3,-4000.5,\n0,2,6,-3900,-3000\n";
        std::fs::write(&path, whole).unwrap();
        let mut notes = Vec::new();
        assert_eq!(read_returns(&path, &mut notes).unwrap().len(), 2);
        assert!(notes.is_empty());
        std::fs::write(&path, format!("{whole}0,3,9,-38")).unwrap();
        let rows = read_returns(&path, &mut notes).unwrap();
        assert_eq!(rows.len(), 2);
        assert!(
            notes[0].contains("cut short") && notes[0].contains("0,3,9,-38"),
            "{notes:?}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn message(topic: &str, log_time: u64, data: &str) -> RecordedMessage {
        RecordedMessage {
            topic: topic.into(),
            log_time,
            publish_time: log_time,
            data: data.as_bytes().to_vec(),
        }
    }

    #[test]
    fn a_resumed_run_keeps_the_rows_of_its_trials_a_picture_per_kept_sample_and_their_latency() {
        use crate::record::channels::{LATENCY, RETURNS, SCENE};
        let sample = |seq: u64, trial: u64| {
            let data = format!(r#"{{"seq":{seq},"trial":{trial},"flags":0}}"#);
            [
                message(MEASUREMENT, 10 * seq, &data),
                message(SCENE, 10 * seq, "picture"),
                message(LATENCY, 10 * seq, &format!(r#"{{"seq":{seq}}}"#)),
            ]
        };
        let mut messages: Vec<RecordedMessage> =
            (0..4).flat_map(|s| sample(s, 1 + s / 2)).collect();
        messages.push(message(RETURNS, 15, r#"{"trial":1,"return":-3.5}"#));
        messages.push(message(RETURNS, 35, r#"{"trial":2,"return":-2.5}"#));
        // Resumed after trial 1: its two samples, their pictures and latency, its row.
        let kept = kept(messages, 2, 1);
        let topics: Vec<(&str, u64)> = kept.iter().map(|m| (&m.topic[..], m.log_time)).collect();
        assert_eq!(
            topics,
            [
                (MEASUREMENT, 0),
                (SCENE, 0),
                (LATENCY, 0),
                (MEASUREMENT, 10),
                (SCENE, 10),
                (LATENCY, 10),
                (RETURNS, 15)
            ]
        );
    }
}
