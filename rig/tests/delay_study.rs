//! `rig delay-study` with small runs: its outputs exist and agree with each other (not the
//! acceptance numbers, which need the full study).

mod common;

use common::{ok, rig, tmp};

#[test]
fn a_small_delay_study_writes_consistent_outputs() {
    let dir = tmp("delay-study", "small");
    ok(rig()
        .args([
            "delay-study",
            "--runs",
            "2",
            "--trials",
            "10",
            "--delays",
            "0,10",
            "--quiet",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap());
    for f in [
        "cells.csv",
        "summary.txt",
        "final_return.png",
        "final_return.svg",
        "curves-vgbp-lstd.png",
        "curves-mlac-llr.svg",
        "mlac-llr/predictive/runs.csv",
        "mlac-llr/predictive/observer.csv",
        "vgbp-lstd/direct-0ms/config.toml",
    ] {
        assert!(dir.join(f).is_file(), "{f}");
    }
    assert!(!dir.join("mlac-llr/predictive-10ms").exists());
    let csv = std::fs::read_to_string(dir.join("cells.csv")).unwrap();
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    // 2 learners × 2 timings × 2 delays, each of 2 runs, its mean inside its CI.
    assert_eq!(rows.len(), 8, "{csv}");
    for r in &rows {
        assert_eq!(r[4], "2");
        let v: Vec<f64> = r[5..].iter().map(|x| x.parse().unwrap()).collect();
        assert!(v[2] <= v[0] && v[0] <= v[3], "{r:?}");
        // The velocity the agent acted on is estimated, not measured: it has an error.
        assert!(v[4] > 0.0 && v[4].is_finite(), "{r:?}");
    }
    // A delay below Ts does not reach the plant in predictive timing: one run stands for
    // every delay; in direct timing it changes the run.
    let cell = |learner: &str, mode: &str, d: &str| {
        rows.iter()
            .find(|r| r[0] == learner && r[2] == mode && r[3] == d)
            .unwrap()[5..]
            .to_vec()
    };
    for learner in ["vgbp", "mlac"] {
        assert_eq!(
            cell(learner, "predictive", "0"),
            cell(learner, "predictive", "10")
        );
        assert_ne!(cell(learner, "direct", "0"), cell(learner, "direct", "10"));
    }
    // The mean of run finals in cells.csv is that of the cell's runs.csv greedy column.
    let runs = std::fs::read_to_string(dir.join("mlac-llr/direct-10ms/runs.csv")).unwrap();
    let mut finals = Vec::new();
    for run in ["0", "1"] {
        let g: Vec<f64> = runs
            .lines()
            .skip(1)
            .filter(|l| l.starts_with(&format!("{run},")))
            .filter_map(|l| l.rsplit(',').next().unwrap().parse().ok())
            .collect();
        let last = &g[g.len().saturating_sub(3)..];
        finals.push(last.iter().sum::<f64>() / last.len() as f64);
    }
    let mean: f64 = cell("mlac", "direct", "10")[0].parse().unwrap();
    assert!((mean - (finals[0] + finals[1]) / 2.0).abs() < 1e-9 * mean.abs());
    let summary = std::fs::read_to_string(dir.join("summary.txt")).unwrap();
    assert!(summary.contains("Acceptance 1") && summary.contains("Welch"));
    assert!(summary.contains("Acceptance 2"));
}
