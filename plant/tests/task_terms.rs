//! Task files' reward terms beyond the quadratic form, goals, trial endings and start
//! distributions: read, hashed, and refused in one line when bad.

use std::f64::consts::PI;
use std::path::PathBuf;

use plant::region::Region;
use plant::reward::Term;
use plant::start::StartDistribution;
mod common;

use plant::task::builtin;
use plant::{SystemName, Task, TaskFile};

/// The example task with every new key.
fn reach_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../examples/tasks/pendulum-reach.toml")
}

fn reach_text() -> String {
    std::fs::read_to_string(reach_path()).unwrap()
}

fn write(name: &str, text: &str) -> PathBuf {
    common::write("task-terms", name, text)
}

/// The thesis's task files hash as they did before the new keys existed (the values a
/// driver built then advertises).
#[test]
fn the_thesis_tasks_keep_their_hashes() {
    let want = [
        (SystemName::Pendulum, 0x25e0_c961_796d_7a9f),
        (SystemName::ArmVertical, 0x0cd7_b529_9470_b689),
        (SystemName::ArmHorizontal, 0xfdc7_9d49_9299_0a50),
        (SystemName::Arm64, 0x5637_b3a7_0c2d_4a5d),
        (SystemName::DoubleIntegrator, 0x0550_6ca4_876f_698a),
    ];
    for (system, hash) in want {
        assert_eq!(Task::new(system).hash(), hash, "{system}");
    }
}

#[test]
fn every_term_ending_and_start_distribution_is_read() {
    let task = Task::from_file(&reach_path()).unwrap();
    let r = &task.reward;
    assert_eq!(r.terms.len(), 3);
    assert!(matches!(&r.terms[0], Term::Cosine { weights, .. } if weights == &[4.0, 0.0]));
    assert!(matches!(&r.terms[1], Term::AbsAction { weights } if weights == &[0.2]));
    assert!(matches!(&r.terms[2], Term::Goal { bonus, .. } if *bonus == 1.0));
    // ρ by hand: hanging, inside the bonus ball, and of a negative action.
    let rho = |x: [f64; 2], u: f64| r.reward(&x, &[u]);
    assert!((rho([PI, 0.0], 0.0) - (-8.0)).abs() < 1e-12);
    let want = -0.1 * 4.0 - 0.1 * 4.0 - 4.0 * (1.0 - 0.3f64.cos()) - 0.2 * 2.0 + 1.0;
    assert!((rho([0.3, 2.0], -2.0) - want).abs() < 1e-12);
    let goal = task.goal.as_ref().unwrap();
    assert_eq!(goal.reward, 10.0);
    assert!(goal.region.contains(&[0.05, 0.4], &task.angle_mask));
    assert!(!goal.region.contains(&[0.05, 0.6], &task.angle_mask));
    assert_eq!(
        task.start_distribution,
        Some(StartDistribution::Uniform {
            low: vec![0.9 * PI, -0.5],
            high: vec![1.1 * PI, 0.5]
        })
    );
    assert_eq!(task.operating_range.as_ref().unwrap().penalty, -200.0);
    // Written out and read back, the file is the same.
    let file = TaskFile::parse(&reach_text(), None).unwrap();
    assert_eq!(TaskFile::parse(&file.to_toml(), None).unwrap(), file);
}

/// Each new key enters the hash: the file without it hashes otherwise; and the
/// pendulum's file with the keys of no effect (zero weights) is another task.
#[test]
fn each_new_key_enters_the_hash() {
    let text = reach_text();
    let base = Task::from_file(&write("reach.toml", &text)).unwrap().hash();
    let cuts = [
        ("cosine_weights = [4.0, 0.0]\n", ""),
        ("action_abs_weights = [0.2]\n", ""),
        ("bonus = 1.0", "bonus = 1.5"),
        ("reward = 10.0", "reward = 11.0"),
        ("low = [-0.1, -0.5]", "low = [-0.2, -0.5]"),
        ("radius = [0.5, inf]", "radius = [0.4, inf]"),
        (
            "kind = \"uniform\"\nlow = [\"0.9pi\", -0.5]\nhigh = [\"1.1pi\", 0.5]",
            "kind = \"normal\"\nmean = [\"0.9pi\", -0.5]\nstd = [\"1.1pi\", 0.5]",
        ),
    ];
    let mut seen = vec![base];
    for (from, to) in cuts {
        assert!(text.contains(from), "{from}");
        let h = Task::from_file(&write("cut.toml", &text.replacen(from, to, 1)))
            .unwrap()
            .hash();
        assert!(
            !seen.contains(&h),
            "{from:?} → {to:?} does not change the hash"
        );
        seen.push(h);
    }
    let pendulum = builtin::text(SystemName::Pendulum);
    let zero = pendulum.replace(
        "action_weights = [1.0]",
        "action_weights = [1.0]\ncosine_weights = [0.0, 0.0]",
    );
    let t = Task::from_file(&write("zero.toml", &zero)).unwrap();
    assert_ne!(t.hash(), Task::pendulum().hash());
    assert_eq!(
        t.reward.reward(&[1.0, 2.0], &[0.5]),
        Task::pendulum().reward.reward(&[1.0, 2.0], &[0.5])
    );
}

/// A box around an angle is taken on the circle; a ball by its radii.
#[test]
fn goals_are_boxes_or_balls() {
    let task = Task::from_file(&reach_path()).unwrap();
    let Term::Goal { region, .. } = &task.reward.terms[2] else {
        panic!("a goal term")
    };
    assert_eq!(
        region,
        &Region::Ball {
            centre: vec![0.0, 0.0],
            radius: vec![0.5, f64::INFINITY]
        }
    );
    assert!(region.contains(&[-0.4, 100.0], &task.angle_mask));
}

#[test]
fn bad_terms_endings_and_starts_are_one_line_errors() {
    let text = reach_text();
    let edited = |from: &str, to: &str| {
        assert!(text.contains(from), "{from:?}");
        text.replacen(from, to, 1)
    };
    let cases: &[(&str, String, &str)] = &[
        (
            "a cosine weight on a state that is not an angle",
            edited("cosine_weights = [4.0, 0.0]", "cosine_weights = [4.0, 1.0]"),
            "`reward.cosine_weights[1]`: 1 weighs a state that is not an angle",
        ),
        (
            "cosine weights of the wrong size",
            edited("cosine_weights = [4.0, 0.0]", "cosine_weights = [4.0]"),
            "`reward.cosine_weights`: has 1 entries; must have 2, one per state",
        ),
        (
            "a negative absolute action weight",
            edited("action_abs_weights = [0.2]", "action_abs_weights = [-0.2]"),
            "`reward.action_abs_weights[0]`: -0.2 must be a finite number ≥ 0",
        ),
        (
            "a goal bonus that is no bonus",
            edited("bonus = 1.0", "bonus = -1.0"),
            "`reward.goal.bonus`: -1 must be a finite number > 0",
        ),
        (
            "a bonus region with a terminal reward",
            edited("bonus = 1.0", "reward = 1.0"),
            "`reward.goal.reward`: a bonus region takes `bonus`",
        ),
        (
            "a terminal goal with a bonus",
            edited("reward = 10.0", "bonus = 10.0"),
            "`goal.bonus`: [goal] ends the trial and takes `reward`",
        ),
        (
            "a terminal goal without its reward",
            edited("reward = 10.0\n", ""),
            "`goal.reward`: is missing",
        ),
        (
            "a box and a ball at once",
            edited(
                "low = [-0.1, -0.5]",
                "centre = [0.0, 0.0]\nlow = [-0.1, -0.5]",
            ),
            "`goal`: give a box (`low` and `high`) or a ball (`centre` and `radius`)",
        ),
        (
            "a ball of no radius",
            edited("radius = [0.5, inf]", "radius = [0.0, inf]"),
            "`reward.goal.radius[0]`: 0 must be a number > 0, or inf",
        ),
        (
            "a box of the wrong order",
            edited("high = [0.1, 0.5]", "high = [0.1, -0.6]"),
            "`goal[1]`: [-0.5, -0.6]: the lower bound must be below the upper",
        ),
        (
            "an unknown goal key",
            edited("reward = 10.0", "reward = 10.0\nradious = 1"),
            "unknown field `radious`, expected one of `low`, `high`, `centre`, `radius`, `bonus`, `reward`",
        ),
        (
            "a positive operating-range penalty",
            edited("penalty = -200.0", "penalty = 200.0"),
            "`operating_range.penalty`: 200 must be a finite number ≤ 0: it is the reward of leaving the range, a failure; reward a region with [goal]'s `reward`",
        ),
        (
            "an unknown distribution",
            edited("kind = \"uniform\"", "kind = \"gauss\""),
            "unknown variant `gauss`, expected `uniform` or `normal`",
        ),
        (
            "a uniform distribution given a mean",
            edited(
                "kind = \"uniform\"",
                "kind = \"uniform\"\nmean = [0.0, 0.0]",
            ),
            "`start_distribution.mean`: a uniform distribution takes `low` and `high`, not `mean`",
        ),
        (
            "a normal distribution without its std",
            edited("kind = \"uniform\"\nlow", "kind = \"normal\"\nmean")
                .replace("high = [\"1.1pi\", 0.5]\n", ""),
            "`start_distribution.std`: is missing: a normal distribution needs `mean` and `std`",
        ),
        (
            "a uniform box outside the operating range",
            edited("high = [\"1.1pi\", 0.5]", "high = [\"1.1pi\", 20.0]"),
            "`start_distribution.high[1]`: 20 lies outside the operating range [-18.84955592153876, 18.84955592153876]",
        ),
        (
            "a uniform box upside down",
            edited("high = [\"1.1pi\", 0.5]", "high = [\"0.8pi\", 0.5]"),
            "`start_distribution.low[0]`: [2.827433388230814, 2.5132741228718345]: the lower bound must not exceed the upper",
        ),
        (
            "a uniform box too wide to draw from",
            edited("low = [\"0.9pi\", -0.5]", "low = [\"0.9pi\", -1e308]")
                .replace("high = [\"1.1pi\", 0.5]", "high = [\"1.1pi\", 1e308]")
                .replace("low = [-inf, \"-6pi\"]", "low = [-inf, -inf]")
                .replace("high = [inf, \"6pi\"]", "high = [inf, inf]"),
            "`start_distribution.low[1]`: [-100000000",
        ),
    ];
    common::assert_refused("task-terms", cases);
}
