//! Learning-curve statistics across independent runs, and their CSV form.
//!
//! A learning curve is the sum of rewards per trial plotted over simulated time
//! (thesis §3.6). Every learning experiment is repeated R times; [`curve`] reduces
//! the R values at each point to the statistics the thesis plots: mean, min, max
//! and the 95 % confidence interval of the mean.

use std::fs;
use std::path::Path;

use super::error::{CurveError, PointError};
use crate::error::AtFile;
use statrs::distribution::{ContinuousCDF, StudentsT};

/// Statistics across runs at one point of a learning curve.
#[derive(Clone, Debug, PartialEq)]
pub struct CurvePoint {
    /// Trial index of this point.
    pub trial: u32,
    /// Simulated time at this point, in seconds.
    pub sim_time_s: f64,
    /// Sample mean across runs.
    pub mean: f64,
    /// Smallest value across runs.
    pub min: f64,
    /// Largest value across runs.
    pub max: f64,
    /// Lower end of the 95 % confidence interval of the mean.
    pub ci_low: f64,
    /// Upper end of the 95 % confidence interval of the mean.
    pub ci_high: f64,
    /// Number of runs the statistics are computed from.
    pub n: usize,
}

/// The header row of the CSV written by [`write_curve_csv`].
pub const CSV_HEADER: [&str; 7] = [
    "trial",
    "sim_time_s",
    "mean",
    "min",
    "max",
    "ci_low",
    "ci_high",
];

/// Computes learning-curve statistics across runs.
///
/// `values[i]` holds the value of every run at point `i` (for example the sum of
/// rewards of trial `trials[i]`, at simulated time `sim_time_s[i]`, in each of
/// R runs). For each point this returns the mean, min and max across runs
/// and the 95 % confidence interval of the mean, `mean ± t · s / √n`, where `s` is
/// the sample standard deviation and `t` the 0.975 quantile of Student's t
/// distribution with `n − 1` degrees of freedom. With a single run (`n = 1`) the
/// interval collapses to the mean. The number of runs may differ between points.
///
/// The mean is clamped into `[min, max]`, so that floating-point rounding cannot
/// put it outside the range of its own data (e.g. for identical values).
///
/// # Errors
///
/// Non-finite input is never averaged: the function fails if any value or time
/// is NaN or infinite, if a point has no values, if the three slices differ in
/// length, or if the statistics overflow `f64`.
pub fn curve(
    trials: &[u32],
    sim_time_s: &[f64],
    values: &[Vec<f64>],
) -> Result<Vec<CurvePoint>, CurveError> {
    if !(trials.len() == sim_time_s.len() && trials.len() == values.len()) {
        return Err(CurveError::Lengths {
            trials: trials.len(),
            times: sim_time_s.len(),
            rows: values.len(),
        });
    }
    let mut quantile = TQuantileCache::default();
    trials
        .iter()
        .zip(sim_time_s)
        .zip(values)
        .map(|((&trial, &time), runs)| {
            if !time.is_finite() {
                return Err(CurveError::Time { trial, time });
            }
            point(trial, time, runs, &mut quantile).map_err(|why| CurveError::Point {
                trial,
                time,
                why,
            })
        })
        .collect()
}

/// Statistics of one point; `runs` holds one value per run.
fn point(
    trial: u32,
    sim_time_s: f64,
    runs: &[f64],
    quantile: &mut TQuantileCache,
) -> Result<CurvePoint, PointError> {
    if runs.is_empty() {
        return Err(PointError::NoValues);
    }
    if let Some(run) = runs.iter().position(|v| !v.is_finite()) {
        let value = runs[run];
        return Err(PointError::NonFinite { run, value });
    }
    let n = runs.len();
    let min = runs.iter().copied().fold(f64::INFINITY, f64::min);
    let max = runs.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let sum: f64 = runs.iter().sum();
    if !sum.is_finite() {
        return Err(PointError::SumOverflow);
    }
    let mean = (sum / n as f64).clamp(min, max);
    let half_width = if n == 1 {
        0.0
    } else {
        let var = runs.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        quantile.get(n - 1)? * (var / n as f64).sqrt()
    };
    let (ci_low, ci_high) = (mean - half_width, mean + half_width);
    if !(ci_low.is_finite() && ci_high.is_finite()) {
        return Err(PointError::IntervalOverflow);
    }
    Ok(CurvePoint {
        trial,
        sim_time_s,
        mean,
        min,
        max,
        ci_low,
        ci_high,
        n,
    })
}

/// Remembers the last 0.975 quantile of Student's t, as almost every point of a
/// curve has the same number of runs.
#[derive(Default)]
struct TQuantileCache {
    last: Option<(usize, f64)>,
}

impl TQuantileCache {
    /// The 0.975 quantile of Student's t with `dof` degrees of freedom.
    fn get(&mut self, dof: usize) -> Result<f64, PointError> {
        match self.last {
            Some((d, t)) if d == dof => Ok(t),
            _ => {
                let t = StudentsT::new(0.0, 1.0, dof as f64)
                    .map_err(|e| PointError::StudentsT {
                        dof,
                        why: e.to_string(),
                    })?
                    .inverse_cdf(0.975);
                self.last = Some((dof, t));
                Ok(t)
            }
        }
    }
}

/// The median of `values` (the mean of the middle two for an even count; NaN when
/// empty): of the runs' final returns, where one run that never swings up moves the
/// mean by hundreds.
pub fn median(values: &[f64]) -> f64 {
    if values.is_empty() {
        return f64::NAN;
    }
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let n = sorted.len();
    (sorted[(n - 1) / 2] + sorted[n / 2]) / 2.0
}

/// Writes a learning curve as CSV.
///
/// The header is `trial,sim_time_s,mean,min,max,ci_low,ci_high` ([`CSV_HEADER`];
/// `n` is not written). Numbers use Rust's default `{}` formatting, which is the
/// shortest string that parses back to the same `f64`, so equal curves give
/// byte-identical files. The file is written to `path.with_extension("csv.tmp")`
/// first and then renamed over `path`, so readers never see a partial file.
///
/// # Errors
///
/// Fails if the file cannot be written, synced or renamed; the temporary file
/// is then removed.
pub fn write_curve_csv(path: &Path, points: &[CurvePoint]) -> Result<(), CurveError> {
    let tmp = path.with_extension("csv.tmp");
    let result = write_csv_to(&tmp, points)
        .and_then(|()| fs::rename(&tmp, path).at("renaming the temporary file onto", path));
    if result.is_err() {
        // Best effort: do not leave a half-written temporary file behind.
        let _ = fs::remove_file(&tmp);
    }
    Ok(result?)
}

/// Writes and syncs the CSV file at `path`.
fn write_csv_to(path: &Path, points: &[CurvePoint]) -> Result<(), crate::error::FileError> {
    let mut w = csv::Writer::from_path(path).at("creating", path)?;
    w.write_record(CSV_HEADER).at("writing", path)?;
    for p in points {
        w.write_record([
            p.trial.to_string(),
            p.sim_time_s.to_string(),
            p.mean.to_string(),
            p.min.to_string(),
            p.max.to_string(),
            p.ci_low.to_string(),
            p.ci_high.to_string(),
        ])
        .at("writing", path)?;
    }
    let file = w
        .into_inner()
        .map_err(|e| e.into_error())
        .at("flushing", path)?;
    file.sync_all().at("syncing", path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_even_and_empty() {
        assert_eq!(median(&[3.0, -1.0, 2.0]), 2.0);
        assert_eq!(median(&[4.0, -6000.0, 1.0, 2.0]), 1.5);
        assert!(median(&[]).is_nan());
    }

    /// A fresh, empty directory under the system temp dir.
    fn temp_dir(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("rig-report-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn known_small_data_set() {
        let pts = curve(&[7], &[21.0], &[vec![4.0, 1.0, 3.0, 2.0]]).unwrap();
        assert_eq!(pts.len(), 1);
        let p = &pts[0];
        // Mean 2.5; squared deviations 2.25 + 0.25 + 0.25 + 2.25 = 5; s² = 5/3.
        let sd = (5.0_f64 / 3.0).sqrt();
        // t_{0.975} with 3 degrees of freedom, from a statistics table.
        let t3 = 3.182_446_305_284_263;
        let half = t3 * sd / 2.0; // √n = 2
        assert!((half - 2.054_3).abs() < 1e-4);
        assert_eq!((p.trial, p.sim_time_s, p.n), (7, 21.0, 4));
        assert_eq!((p.mean, p.min, p.max), (2.5, 1.0, 4.0));
        assert!((p.ci_low - (2.5 - half)).abs() < 1e-9, "{p:?}");
        assert!((p.ci_high - (2.5 + half)).abs() < 1e-9, "{p:?}");
    }

    #[test]
    fn t_quantile_matches_table() {
        // Two-sided 95 % critical values from a t table.
        for (dof, t) in [(1, 12.706_204_736), (9, 2.262_157_163), (29, 2.045_229_642)] {
            let got = TQuantileCache::default().get(dof).unwrap();
            assert!((got - t).abs() < 1e-6, "dof {dof}: {got} vs {t}");
        }
    }

    #[test]
    fn single_run_collapses_ci() {
        let pts = curve(&[1, 2], &[3.0, 6.0], &[vec![-5.5], vec![0.25]]).unwrap();
        for (p, v) in pts.iter().zip([-5.5, 0.25]) {
            assert_eq!(p.n, 1);
            for x in [p.mean, p.min, p.max, p.ci_low, p.ci_high] {
                assert_eq!(x, v);
            }
        }
    }

    #[test]
    fn identical_values_give_zero_width() {
        let p = &curve(&[1], &[3.0], &[vec![0.1; 30]]).unwrap()[0];
        assert_eq!((p.mean, p.min, p.max), (0.1, 0.1, 0.1));
        assert!(p.ci_high - p.ci_low < 1e-15);
    }

    #[test]
    fn non_finite_and_malformed_input_rejected() {
        let err = curve(&[1, 2], &[3.0, 6.0], &[vec![1.0, 2.0], vec![1.0, f64::NAN]]).unwrap_err();
        // As the commands print it: the error and its sources.
        let msg = crate::error::chain(&err);
        assert!(msg.contains("trial 2") && msg.contains("run 1"), "{msg}");
        assert!(curve(&[1], &[3.0], &[vec![f64::INFINITY]]).is_err());
        assert!(curve(&[1], &[f64::NAN], &[vec![1.0]]).is_err());
        assert!(curve(&[1], &[3.0], &[vec![]]).is_err());
        assert!(curve(&[1, 2], &[3.0], &[vec![1.0]]).is_err());
        assert!(curve(&[1], &[3.0], &[vec![f64::MAX, f64::MAX / 2.0]]).is_err());
        assert!(curve(&[1], &[3.0], &[vec![f64::MAX, -f64::MAX]]).is_err());
        assert!(curve(&[], &[], &[]).unwrap().is_empty());
    }

    #[test]
    fn csv_header_and_round_trip() {
        let values = [
            vec![-1.5, -2.25, 0.1],
            vec![1.0 / 3.0, 2.0, 1e-7],
            vec![42.0],
        ];
        let pts = curve(&[0, 1, 2], &[3.0, 6.0, 9.0], &values).unwrap();
        let dir = temp_dir("csv");
        let path = dir.join("curve.csv");
        write_curve_csv(&path, &pts).unwrap();
        assert!(!dir.join("curve.csv.tmp").exists());

        let text = fs::read_to_string(&path).unwrap();
        assert_eq!(
            text.lines().next(),
            Some("trial,sim_time_s,mean,min,max,ci_low,ci_high")
        );
        assert!(
            text.lines()
                .nth(3)
                .unwrap()
                .starts_with("2,9,42,42,42,42,42"),
            "{text}"
        );

        let mut reader = csv::Reader::from_path(&path).unwrap();
        let rows: Vec<Vec<f64>> = reader
            .records()
            .map(|r| r.unwrap().iter().map(|f| f.parse().unwrap()).collect())
            .collect();
        assert_eq!(rows.len(), pts.len());
        for (row, p) in rows.iter().zip(&pts) {
            let expected = [
                f64::from(p.trial),
                p.sim_time_s,
                p.mean,
                p.min,
                p.max,
                p.ci_low,
                p.ci_high,
            ];
            assert_eq!(row.as_slice(), expected.as_slice());
        }

        // Deterministic: writing again gives the same bytes.
        write_curve_csv(&path, &pts).unwrap();
        assert_eq!(fs::read_to_string(&path).unwrap(), text);
        fs::remove_dir_all(dir).unwrap();
    }
}
