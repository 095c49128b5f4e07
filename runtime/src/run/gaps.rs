//! `gaps.csv` of a run: the trial attempts cut short by a gap ([`flags::GAP`]), one row
//! each — the trial, whether greedy, the sample it was cut at, its sequence number, how
//! long after the previous sample's instant its own came and how long after its instant
//! the plant published it (ms). Cut attempts are run again, so `returns.csv` holds none
//! of them.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use super::error::Result;
use crate::error::AtFile;
use wire::{Measurement, flags};

use crate::record::channels::{Head, MEASUREMENT};
use crate::resume::ResumePoint;

/// The header of `gaps.csv`.
pub const GAPS_HEADER: &str = "trial,greedy,step,seq,span_ms,late_ms";

/// Streams `gaps.csv` from the plant's measurements.
pub(super) struct GapLog {
    out: BufWriter<File>,
    /// Where `out` writes.
    path: PathBuf,
    /// Attempts cut in the part of the run that is running now.
    pub(super) now: u64,
    /// Attempts cut in the trials a resumed run keeps.
    kept: u64,
    /// The previous measurement's instant (monotonic ns).
    previous_ns: u64,
}

impl GapLog {
    /// Creates `path` with its header — or, resuming at `point`, goes on after its rows
    /// (every attempt cut, also of trials that are now run again).
    pub(super) fn create(path: &Path, point: Option<&ResumePoint>) -> Result<Self> {
        let resumed = point.is_some() && path.exists();
        let file = File::options()
            .create(true)
            .append(resumed)
            .write(true)
            .truncate(!resumed)
            .open(path)
            .at("cannot create", path)?;
        let mut out = BufWriter::new(file);
        if !resumed {
            writeln!(out, "{GAPS_HEADER}")
                .and_then(|()| out.flush())
                .at("cannot write", path)?;
        }
        Ok(Self {
            out,
            path: path.to_owned(),
            now: 0,
            kept: point.map_or(0, kept_cuts),
            previous_ns: 0,
        })
    }

    /// Accounts for measurement `m`: a row if it comes after a gap.
    pub(super) fn measurement(&mut self, m: &Measurement) -> Result<()> {
        let h = &m.header;
        if h.flags & flags::GAP != 0 {
            let ms = |ns: u64| ns as f64 * 1e-6;
            writeln!(
                self.out,
                "{},{},{},{},{:.3},{:.3}",
                h.trial,
                u8::from(h.flags & flags::GREEDY != 0),
                h.step,
                h.seq,
                ms(m.t_sample_ns.saturating_sub(self.previous_ns)),
                ms(m.t_publish_ns.saturating_sub(m.t_sample_ns))
            )
            .and_then(|()| self.out.flush())
            .at("cannot write", &self.path)?;
            self.now += 1;
        }
        self.previous_ns = m.t_sample_ns;
        Ok(())
    }

    /// The recording's metadata `gaps`: the attempts cut in it, and in the part run now.
    pub(super) fn metadata(&self) -> BTreeMap<String, String> {
        [
            ("attempts_cut", self.kept + self.now),
            ("attempts_cut_now", self.now),
        ]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
    }
}

/// The attempts cut short among the measurements a resumed run keeps.
fn kept_cuts(p: &ResumePoint) -> u64 {
    p.messages
        .iter()
        .filter(|m| m.topic == MEASUREMENT)
        .filter_map(|m| Head::of(&m.data).ok())
        .filter(|h| h.flags & flags::GAP != 0)
        .count() as u64
}
