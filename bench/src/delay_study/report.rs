//! The study's report in its folder: `cells.csv`, the plots against the delay and of
//! each learner's curves, and `summary.txt` (the table and the acceptance checks).

use std::fmt::Write as _;

use observer::config::{ObserverMode, ObserverModel};

use runtime::output::runs::LAST_EVALUATIONS;
use runtime::output::write_atomic;
use runtime::report::plot::{PointSeries, plot_points};
use runtime::report::{Series, SeriesStyle, plot_curves};

use super::study::{
    COMPARED_AT_MS, DelayStudyError, DelayStudyOptions, LEARNERS, SWING_UP, StudyCell, ms, welch,
};

/// `cells.csv`, the plots and `summary.txt`.
pub fn write(opts: &DelayStudyOptions, cells: &[StudyCell]) -> Result<(), DelayStudyError> {
    let mut csv =
        String::from("algo,approx,mode,delay_ms,runs,mean,sd,ci_low,ci_high,velocity_error\n");
    for c in cells {
        let s = &c.stats;
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{},{},{},{}",
            c.algo,
            c.approx,
            c.mode,
            ms(c.delay_ms),
            s.n,
            s.mean,
            s.sd,
            s.ci.0,
            s.ci.1,
            c.velocity_error
        );
    }
    write_atomic(&opts.out.join("cells.csv"), &csv)?;

    let of = |algo, mode| -> Vec<&StudyCell> {
        cells
            .iter()
            .filter(|c| c.algo == algo && c.mode == mode)
            .collect()
    };
    let mut labels = Vec::new();
    let mut points = Vec::new();
    for (algo, approx) in LEARNERS {
        for mode in ObserverMode::ALL {
            labels.push(format!(
                "{}/{} {mode}",
                algo.as_str().to_uppercase(),
                approx.as_str().to_uppercase()
            ));
            points.push(
                of(algo, mode)
                    .iter()
                    .map(|c| (c.delay_ms, c.stats.mean, c.stats.ci.0, c.stats.ci.1))
                    .collect::<Vec<_>>(),
            );
        }
    }
    let series: Vec<PointSeries> = labels
        .iter()
        .zip(&points)
        .enumerate()
        .map(|(i, (label, points))| PointSeries {
            label,
            points,
            dashed: i % 2 == 1,
            colour: i / 2,
        })
        .collect();
    plot_points(
        &opts.out.join("final_return.png"),
        &opts.out.join("final_return.svg"),
        &format!(
            "Pendulum, angle-only, {} observer model: final greedy return vs delay ({} runs, 95 % CI)",
            opts.model, opts.runs
        ),
        (
            "Injected sample-to-actuation delay [ms]",
            "Final greedy return",
        ),
        &series,
    )?;
    for (algo, approx) in LEARNERS {
        let mine: Vec<&StudyCell> = cells.iter().filter(|c| c.algo == algo).collect();
        let labels: Vec<String> = mine
            .iter()
            .map(|c| format!("{} {} ms", c.mode, ms(c.delay_ms)))
            .collect();
        let series: Vec<Series> = mine
            .iter()
            .zip(&labels)
            .filter(|(c, _)| !c.greedy_curve.is_empty())
            .map(|(c, label)| Series {
                label: label.clone(),
                points: &c.greedy_curve,
                style: SeriesStyle::Line,
            })
            .collect();
        if series.is_empty() {
            continue;
        }
        plot_curves(
            &opts.out.join(format!("curves-{algo}-{approx}.png")),
            &opts.out.join(format!("curves-{algo}-{approx}.svg")),
            &format!(
                "{}/{}, angle-only: greedy learning curves (mean of {} runs)",
                algo.as_str().to_uppercase(),
                approx.as_str().to_uppercase(),
                opts.runs
            ),
            &series,
            None,
        )?;
    }
    let summary = summary(opts.model, cells);
    write_atomic(&opts.out.join("summary.txt"), &summary)?;
    if opts.verbose {
        print!("{summary}");
    }
    Ok(())
}

/// The table and the acceptance checks.
pub fn summary(model: ObserverModel, cells: &[StudyCell]) -> String {
    let mut s = format!(
        "Final greedy return (per run: mean of its last {LAST_EVALUATIONS} greedy evaluations), pendulum, angle-only sensing, predictive estimator with the {model} model; v_err: RMSE of the velocity the agent acted on against the truth (x̂_k direct, x̂_(k+1|k) predictive), mean over runs; predictive timing is run once and stands for every delay < Ts\n\n",
    );
    let _ = writeln!(
        s,
        "{:<10} {:<10} {:>8} {:>5} {:>9} {:>8} {:>21} {:>13}",
        "learner", "timing", "delay_ms", "runs", "mean", "sd", "95% CI", "v_err [rad/s]"
    );
    for c in cells {
        let st = &c.stats;
        let _ = writeln!(
            s,
            "{:<10} {:<10} {:>8} {:>5} {:>9.1} {:>8.1} {:>21} {:>13.3}",
            format!("{}/{}", c.algo, c.approx),
            c.mode.as_str(),
            ms(c.delay_ms),
            st.n,
            st.mean,
            st.sd,
            format!("[{:.1}, {:.1}]", st.ci.0, st.ci.1),
            c.velocity_error
        );
    }
    let cell = |algo, mode, d: f64| {
        cells
            .iter()
            .find(|c| c.algo == algo && c.mode == mode && c.delay_ms == d)
    };
    let _ = writeln!(
        s,
        "\nAcceptance 1: at {COMPARED_AT_MS} ms, predictive timing better than direct (one-sided Welch t-test, p < 0.05):"
    );
    for (algo, approx) in LEARNERS {
        let (Some(p), Some(d)) = (
            cell(algo, ObserverMode::Predictive, COMPARED_AT_MS),
            cell(algo, ObserverMode::Direct, COMPARED_AT_MS),
        ) else {
            let _ = writeln!(
                s,
                "  {algo}/{approx}: not measured ({COMPARED_AT_MS} ms is not among the delays)"
            );
            continue;
        };
        let overlap = p.stats.ci.0 <= d.stats.ci.1 && d.stats.ci.0 <= p.stats.ci.1;
        let verdict = match welch(&p.stats, &d.stats) {
            Some((t, df, pv)) => format!(
                "t = {t:.2}, df = {df:.1}, p {} → {}",
                if pv < 0.001 {
                    "< 0.001".to_string()
                } else {
                    format!("= {pv:.3}")
                },
                if pv < 0.05 { "HOLDS" } else { "does NOT hold" }
            ),
            None => "no test (fewer than 2 runs or no spread)".into(),
        };
        let _ = writeln!(
            s,
            "  {algo}/{approx}: predictive {:.1} [{:.1}, {:.1}] vs direct {:.1} [{:.1}, {:.1}]; difference {:+.1}; CIs {}; {verdict}",
            p.stats.mean,
            p.stats.ci.0,
            p.stats.ci.1,
            d.stats.mean,
            d.stats.ci.0,
            d.stats.ci.1,
            p.stats.mean - d.stats.mean,
            if overlap { "overlap" } else { "do not overlap" },
        );
    }
    let _ = writeln!(
        s,
        "\nAcceptance 2: predictive timing learns the swing-up (mean final greedy return ≥ {SWING_UP}):"
    );
    for (algo, approx) in LEARNERS {
        for c in cells
            .iter()
            .filter(|c| c.algo == algo && c.mode == ObserverMode::Predictive)
        {
            let _ = writeln!(
                s,
                "  {algo}/{approx} at {} ms: {:.1} over {} runs → {}",
                ms(c.delay_ms),
                c.stats.mean,
                c.stats.n,
                if c.stats.mean >= SWING_UP {
                    "HOLDS"
                } else {
                    "does NOT hold"
                }
            );
        }
    }
    s
}
