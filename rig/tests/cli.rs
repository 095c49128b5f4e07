//! The `rig` binary as a user runs it.

use std::path::PathBuf;

mod common;
use common::{ok, rig};

fn tmp(name: &str) -> PathBuf {
    common::tmp("cli", name)
}

#[test]
fn learn_writes_its_outputs_and_the_config_repeats_the_run() {
    let dir = tmp("learn");
    ok(rig()
        .args([
            "learn",
            "--runs",
            "2",
            "--trials",
            "4",
            "--eval-every",
            "2",
            "--quiet",
            "--out",
        ])
        .arg(dir.join("a"))
        .output()
        .unwrap());
    let again = rig()
        .args(["learn", "--quiet", "--config"])
        .arg(dir.join("a/config.toml"))
        .arg("--out")
        .arg(dir.join("b"))
        .output()
        .unwrap();
    assert!(
        again.status.success(),
        "{}",
        String::from_utf8_lossy(&again.stderr)
    );
    let a = std::fs::read(dir.join("a/runs.csv")).unwrap();
    assert_eq!(a, std::fs::read(dir.join("b/runs.csv")).unwrap());
    assert_eq!(String::from_utf8(a).unwrap().lines().count(), 1 + 2 * 4);
}

#[test]
fn bad_config_is_a_one_line_error_naming_file_and_key() {
    let dir = tmp("bad");
    let file = dir.join("exp.toml");
    for (text, key, fragment) in [
        (
            "[critic]\nneighbors = 10\n",
            "critic.neighbors",
            "unknown key",
        ),
        ("[learning]\ngamma = 1.2\n", "learning.gamma", "(0, 1)"),
        ("[run]\nruns = 0\n", "run.runs", "1..=100000"),
        ("algo = \"ppo\"\n", "algo", "sac, mlac, rmac"),
        ("horizon = \"finit\"\n", "horizon", "infinite, finite"),
        ("[actor\n", "", "not valid TOML"),
    ] {
        std::fs::write(&file, text).unwrap();
        let out = rig()
            .args(["learn", "--quiet", "--config"])
            .arg(&file)
            .arg("--out")
            .arg(dir.join("o"))
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{text}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.lines().count(), 1, "one line: {err}");
        assert!(
            err.starts_with("error: ")
                && err.contains("exp.toml")
                && err.contains(key)
                && err.contains(fragment),
            "{err}"
        );
    }
    let out = rig()
        .args(["learn", "--algo", "mlac", "--approx", "tiles", "--out"])
        .arg(dir.join("o"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("tile coding has no gradient"));
    let missing = rig()
        .args(["learn", "--config", "/nonexistent/x.toml"])
        .output()
        .unwrap();
    assert_eq!(missing.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&missing.stderr).contains("/nonexistent/x.toml"));
}

#[test]
fn config_prints_a_resolvable_preset_and_help_explains_every_flag() {
    let out = rig()
        .args(["config", "--algo", "sac", "--approx", "rbf"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("algo = \"sac\"") && text.contains("intersection = 0.5"),
        "{text}"
    );
    let help = String::from_utf8(rig().args(["learn", "--help"]).output().unwrap().stdout).unwrap();
    for flag in [
        "--system",
        "--algo",
        "--approx",
        "--horizon",
        "--trials",
        "--runs",
        "--seed",
        "--eval-every",
        "--config",
        "--out",
        "--threads",
        "--quiet",
    ] {
        assert!(help.contains(flag), "--help lacks {flag}");
    }
    let help = |cmd: &str| {
        String::from_utf8(rig().args([cmd, "--help"]).output().unwrap().stdout).unwrap()
    };
    let run = help("run");
    for flag in [
        "--plant",
        "--driver",
        "--driver-timeout",
        "--reset-timeout",
        "--timing",
        "--speed",
    ] {
        assert!(run.contains(flag), "run --help lacks {flag}");
    }
    let check = help("check-driver");
    for flag in [
        "--driver",
        "--driver-timeout",
        "--reset-timeout",
        "--system",
        "--rate-seconds",
        "--max-jitter",
        "--max-missed",
        "--step",
    ] {
        assert!(check.contains(flag), "check-driver --help lacks {flag}");
    }
}

#[test]
fn sensor_and_observer_flags_are_validated_and_written_to_the_config() {
    let dir = tmp("observer");
    let out = rig()
        .args(["config", "--sensor", "angle"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("`observer.observer`") && err.lines().count() == 1,
        "{err}"
    );
    ok(rig()
        .args([
            "learn",
            "--sensor",
            "angle",
            "--observer",
            "predictive",
            "--runs",
            "1",
            "--trials",
            "2",
            "--quiet",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap());
    let toml = std::fs::read_to_string(dir.join("config.toml")).unwrap();
    assert!(
        toml.contains("[observer]") && toml.contains("\"predictive\""),
        "{toml}"
    );
    // rig latency's default timing is predictive: a finite-difference observer is told
    // which flags fit, before anything runs.
    let out = rig()
        .args(["latency", "--observer", "finite-difference", "--out"])
        .arg(dir.join("latency"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("--observer-mode direct") && err.lines().count() == 1,
        "{err}"
    );
}

/// The final greedy return (mean, sample sd) per curve of a figure's `summary.csv`
/// (`curve,runs,trials,final_greedy_mean,final_greedy_sd,` and six more columns; a curve
/// label may contain commas).
fn summary_finals(csv: &str) -> Vec<(String, f64, f64)> {
    csv.lines()
        .skip(1)
        .map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            let k = f.len() - 10;
            let label = f[..k].join(",");
            (label, f[k + 2].parse().unwrap(), f[k + 3].parse().unwrap())
        })
        .collect()
}

/// The verdict one part of a claim's explanation implies, from its numbers (as printed,
/// to 0.1): `Some(true)` if it confirms, `Some(false)` if not, `None` if the printed
/// numbers tie. Checks what the numbers must satisfy besides: the final greedy returns
/// and their sds are those of `summary.csv` (`finals`), and a difference and its 95 %
/// margin (Welch, 1.96 standard errors of `runs` runs each) are those of the returns.
///
/// The parts (`bench/src/reproduce/claims.rs`):
/// * `to the common level L: A t_A min, B t_B min` — A faster: `t_A < t_B`;
/// * `final greedy return A x ± s, B y ± r` — A better: `x > y`;
/// * the same with ` (difference d, 95 % margin e)` — A clearly better: `d > e`.
fn claim_part(part: &str, finals: &[(String, f64, f64)], runs: f64) -> Option<bool> {
    let num = |s: &str| -> f64 {
        s.trim()
            .parse()
            .unwrap_or_else(|_| panic!("{s:?} in {part:?}"))
    };
    let order = |a: f64, b: f64| (a != b).then_some(a > b);
    if let Some(rest) = part.strip_prefix("to the common level ") {
        let (level, times) = rest.split_once(": ").expect(part);
        assert!(num(level).is_finite(), "{part}");
        let (a, b) = times.split_once(" min, ").expect(part);
        let b = b.strip_suffix(" min").expect(part);
        let t = |s: &str| num(s.rsplit_once(' ').expect(part).1);
        return order(t(b), t(a));
    }
    let rest = part.strip_prefix("final greedy return ").expect(part);
    let (pair, margin) = match rest.split_once(" (difference ") {
        Some((pair, tail)) => {
            let (d, e) = tail
                .strip_suffix(')')
                .expect(part)
                .split_once(", 95 % margin ")
                .expect(part);
            (pair, Some((num(d), num(e))))
        }
        None => (rest, None),
    };
    // `A x ± s, B y ± r`; the labels hold no ` ± `.
    let (ax, s_by) = pair.split_once(" ± ").expect(part);
    let (s, by) = s_by.split_once(", ").expect(part);
    let (by, r) = by.split_once(" ± ").expect(part);
    let mut curves = Vec::new();
    for (label_value, sd) in [(ax, s), (by, r)] {
        let (label, value) = label_value.rsplit_once(' ').expect(part);
        let (_, mean, s) = finals
            .iter()
            .find(|c| c.0 == label)
            .unwrap_or_else(|| panic!("{label} of {part} not in summary.csv"));
        assert_eq!(
            format!("{mean:.1} ± {s:.1}"),
            format!("{value} ± {sd}"),
            "{part}"
        );
        curves.push((*mean, *s));
    }
    let [(x, sx), (y, sy)] = [curves[0], curves[1]];
    match margin {
        None => order(
            num(ax.rsplit_once(' ').unwrap().1),
            num(by.rsplit_once(' ').unwrap().1),
        ),
        Some((d, e)) => {
            let se = ((sx * sx + sy * sy) / runs).sqrt();
            assert_eq!(
                format!("{d:.1} {e:.1}"),
                format!("{:.1} {:.1}", x - y, 1.96 * se),
                "{part}"
            );
            order(d, e)
        }
    }
}

/// Every claim line of `report` (`- what the thesis says — **confirmed**: why.` or
/// `**not confirmed**`) has an explanation whose numbers are the measured ones and
/// imply its verdict: confirmed when every part confirms, not confirmed when one does
/// not. Returns how many claims were checked. (With `better`'s comparison inverted, or
/// the margin computed from twice the runs, the reproduce test fails here.)
fn check_claims(report: &str, finals: &[(String, f64, f64)], runs: f64) -> usize {
    let mut checked = 0;
    for line in report.lines() {
        let (says, verdict, why) = if let Some((says, why)) = line.split_once(" — **confirmed**: ")
        {
            (says, true, why)
        } else if let Some((says, why)) = line.split_once(" — **not confirmed**: ") {
            (says, false, why)
        } else {
            continue;
        };
        assert!(says.starts_with("- ") && says.len() > 10, "{line}");
        let why = why.strip_suffix('.').expect(line);
        let parts: Vec<Option<bool>> = why
            .split("; ")
            .map(|p| claim_part(p, finals, runs))
            .collect();
        if parts.contains(&Some(false)) {
            assert!(!verdict, "confirmed, but a part is not: {line}");
        } else if parts.iter().all(|p| *p == Some(true)) {
            assert!(verdict, "not confirmed, but every part is: {line}");
        }
        checked += 1;
    }
    checked
}

#[test]
fn reproduce_writes_figures_a_report_and_checks_claims() {
    let dir = tmp("reproduce");
    let out = ok(rig()
        .args([
            "reproduce",
            "--only",
            "3.17,3.22",
            "--runs",
            "2",
            "--trials",
            "30",
            "--quiet",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap());
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        stdout.contains("Figure 3.17:") && stdout.contains("Figure 3.22:"),
        "{stdout}"
    );
    for id in ["3.17", "3.22"] {
        for f in [
            "figure.png",
            "figure.svg",
            "summary.csv",
            "response.png",
            "response.svg",
        ] {
            assert!(dir.join(id).join(f).is_file(), "{id}/{f}");
        }
    }
    let summary = std::fs::read_to_string(dir.join("3.17/summary.csv")).unwrap();
    // MLAC/RBF, MLAC/LLR and both with the input saturation ignored (§3.7).
    assert_eq!(summary.lines().count(), 5, "{summary}");
    assert!(
        summary
            .lines()
            .nth(1)
            .unwrap()
            .starts_with("MLAC/RBF,2,30,"),
        "{summary}"
    );
    let report = std::fs::read_to_string(dir.join("REPORT.md")).unwrap();
    assert!(report.contains("![3.17](3.17/figure.png)"), "{report}");
    assert!(report.contains("| MLAC/LLR | 2 × 30 |"), "{report}");
    // Every claim is marked one way or the other, with the measured numbers behind it,
    // and the verdict is the one they imply.
    let marked =
        report.matches("**confirmed**").count() + report.matches("**not confirmed**").count();
    assert_eq!(marked, 4, "{report}");
    let mut finals = summary_finals(&summary);
    finals.extend(summary_finals(
        &std::fs::read_to_string(dir.join("3.22/summary.csv")).unwrap(),
    ));
    assert_eq!(finals.len(), 6, "{finals:?}");
    assert_eq!(check_claims(&report, &finals, 2.0), 4, "{report}");
    assert!(report.contains("| t₉₀ [min] |"), "{report}");
    // Each experiment's own outputs are there, with every run's final time response.
    assert!(dir.join("3.17/mlac-llr/runs.csv").is_file());
    let responses = std::fs::read_to_string(dir.join("3.17/mlac-llr/responses.csv")).unwrap();
    for run in ["0,", "1,"] {
        assert_eq!(
            responses.lines().filter(|l| l.starts_with(run)).count(),
            100,
            "one 3 s trial of run {run}"
        );
    }

    // Run again into the same directory: the finished experiments of this build are
    // reused; one whose `build.txt` names another build of rig is run again.
    std::fs::write(dir.join("3.17/mlac-llr/build.txt"), "another build\n").unwrap();
    let again = ok(rig()
        .args([
            "reproduce",
            "--only",
            "3.17",
            "--runs",
            "2",
            "--trials",
            "30",
            "--out",
        ])
        .arg(&dir)
        .output()
        .unwrap());
    let log = String::from_utf8_lossy(&again.stderr);
    assert!(log.contains("3.17 MLAC/RBF: reusing"), "{log}");
    assert!(
        log.contains("3.17 MLAC/LLR: 2 runs × 30 trials") && !log.contains("MLAC/LLR: reusing"),
        "{log}"
    );

    // The sensitivity analysis: every parameter at every factor, for both algorithms.
    let sens = dir.join("sens");
    ok(rig()
        .args([
            "reproduce",
            "--only",
            "sensitivity",
            "--runs",
            "2",
            "--trials",
            "20",
            "--quiet",
            "--out",
        ])
        .arg(&sens)
        .output()
        .unwrap());
    let csv = std::fs::read_to_string(sens.join("sensitivity/sensitivity.csv")).unwrap();
    assert_eq!(csv.lines().count(), 1 + 2 * (1 + 5 * 4), "{csv}");
    assert!(sens.join("sensitivity/sensitivity.png").is_file());
    assert!(sens.join("sensitivity/sensitivity.svg").is_file());
    let report = std::fs::read_to_string(sens.join("REPORT.md")).unwrap();
    assert!(
        report.contains("| σ (exploration) |") && report.contains("Most robust"),
        "{report}"
    );

    let bad = rig()
        .args(["reproduce", "--only", "9.9", "--out"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(!bad.status.success());
    let err = String::from_utf8_lossy(&bad.stderr);
    assert!(err.contains("9.9") && err.contains("3.12"), "{err}");
}
