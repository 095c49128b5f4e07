//! What a run's outputs say of gaps in the loop's timing (docs/run.md, "Gaps: cut and
//! redone"): the samples flagged, the transitions that were learned, the count in the
//! summary and in `gaps.csv`.

use std::path::Path;

/// The flag of a sample after a gap (`wire::flags::GAP`).
pub const GAP: u64 = 512;
const START: u64 = 1;
const END: u64 = 2;
const SHUTDOWN: u64 = 8;

/// One recorded measurement: its flags, sampling instant and publication (ns).
#[derive(Clone, Copy, Debug)]
pub struct Sampled {
    pub seq: u64,
    pub flags: u64,
    pub t_sample_ns: u64,
    pub t_publish_ns: u64,
}

/// Every measurement of the recording at `path`, in order.
pub fn sampled(path: &Path) -> Vec<Sampled> {
    let msgs = super::messages(path);
    let flags = super::field(&msgs, "/plant/measurement", "flags");
    let sampled = super::field(&msgs, "/timing/plant/measurement", "t_sample_ns");
    let published = super::field(&msgs, "/timing/plant/measurement", "t_publish_ns");
    flags
        .iter()
        .map(|(&seq, &f)| Sampled {
            seq,
            flags: f as u64,
            t_sample_ns: sampled[&seq] as u64,
            t_publish_ns: published[&seq] as u64,
        })
        .collect()
}

/// Asserts that the recording at `path` flags at least one gap and that no transition
/// learned (its later sample neither a start nor flagged) spans more than 1.5 periods of
/// `period_ns` between the samples' instants, or more than 2.5 between their
/// publications; returns how many samples are flagged.
pub fn flagged_and_never_learned(path: &Path, period_ns: u64) -> usize {
    let samples = sampled(path);
    let flagged = samples.iter().filter(|s| s.flags & GAP != 0).count();
    assert!(flagged >= 1, "no sample flagged");
    for w in samples.windows(2) {
        let (a, b) = (w[0], w[1]);
        let learned = b.flags & (START | SHUTDOWN | GAP) == 0 && a.flags & (END | SHUTDOWN) == 0;
        if !learned {
            continue;
        }
        let (instants, publications) = (
            b.t_sample_ns - a.t_sample_ns,
            b.t_publish_ns - a.t_publish_ns,
        );
        assert!(
            instants <= period_ns * 3 / 2 && publications <= period_ns * 5 / 2,
            "a transition learned spans {} ms between instants, {} ms between publications: {a:?} → {b:?}",
            instants / 1_000_000,
            publications / 1_000_000
        );
    }
    flagged
}

/// Asserts that the summary `said` and `dir/gaps.csv` count `cut` attempts cut short.
pub fn counted(said: &str, dir: &Path, cut: usize) {
    let n: usize = said
        .split("trials cut by gaps and redone: ")
        .nth(1)
        .and_then(|r| r.split_whitespace().next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no count of trials cut: {said}"));
    assert_eq!(n, cut, "{said}");
    let rows = std::fs::read_to_string(dir.join("gaps.csv")).unwrap();
    assert_eq!(rows.lines().count(), cut + 1, "{rows}");
}
