//! `responses.csv` — `run,t,x_0,...,u_0,...,reward`: each run's final greedy time
//! response — and `observer.csv` — `run,x_0,...`: each run's acted-on error per state
//! component. Numbers in Rust's shortest round-trip form.

use std::path::Path;

use super::write_atomic;
use crate::error::FileError;
use crate::response::ResponseSample;

/// Writes each run's acted-on error as `run,x_0,...` (shortest round-trip numbers).
pub fn write_acted_on(path: &Path, rmse: &[Vec<f64>]) -> Result<(), FileError> {
    let n = rmse.first().map_or(0, Vec::len);
    let mut text = String::from("run");
    for i in 0..n {
        text += &format!(",x_{i}");
    }
    for (run, r) in rmse.iter().enumerate() {
        text += &format!("\n{run}");
        for v in r {
            text += &format!(",{v}");
        }
    }
    text.push('\n');
    write_atomic(path, &text)
}

/// Writes each run's time response as `run,t,x_0,...,u_0,...,reward` (shortest
/// round-trip numbers).
pub fn write_responses(path: &Path, responses: &[Vec<ResponseSample>]) -> Result<(), FileError> {
    let mut s = String::new();
    if let Some(first) = responses.iter().flatten().next() {
        let cols: Vec<String> = (0..first.x.len())
            .map(|i| format!("x_{i}"))
            .chain((0..first.u.len()).map(|i| format!("u_{i}")))
            .collect();
        s.push_str(&format!("run,t,{},reward\n", cols.join(",")));
    }
    for (run, samples) in responses.iter().enumerate() {
        for p in samples {
            let v: Vec<String> = std::iter::once(p.t)
                .chain(p.x.iter().copied())
                .chain(p.u.iter().copied())
                .chain(std::iter::once(p.reward))
                .map(|v| v.to_string())
                .collect();
            s.push_str(&format!("{run},{}\n", v.join(",")));
        }
    }
    write_atomic(path, &s)
}

/// Reads what `write_responses` wrote for `runs` runs; `None` if the file is missing,
/// malformed or incomplete.
pub fn read_responses(path: &Path, runs: usize) -> Option<Vec<Vec<ResponseSample>>> {
    let mut reader = csv::Reader::from_path(path).ok()?;
    let n = reader
        .headers()
        .ok()?
        .iter()
        .filter(|h| h.starts_with("x_"))
        .count();
    let mut out = vec![Vec::new(); runs];
    for row in reader.records() {
        let row = row.ok()?;
        let run: usize = row.get(0)?.parse().ok()?;
        let v: Vec<f64> = row
            .iter()
            .skip(1)
            .map(|f| f.parse().ok())
            .collect::<Option<_>>()?;
        let last = v.len().checked_sub(1)?;
        out.get_mut(run)?.push(ResponseSample {
            t: v[0],
            x: v.get(1..1 + n)?.to_vec(),
            u: v.get(1 + n..last)?.to_vec(),
            reward: v[last],
        });
    }
    out.iter().all(|r| !r.is_empty()).then_some(out)
}
