//! Experiments on a task file: `--task`, the `task` key (a path or a `[task]` table),
//! and the errors that name the task file.

use std::path::{Path, PathBuf};

use plant::SystemName;

use super::*;

/// The pendulum's shipped task with other reward weights, two start states and another
/// name, written to a folder of `test`'s own; returns the folder.
fn heavy_pendulum(test: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("cfg-task-{test}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = plant::task::builtin::text(SystemName::Pendulum)
        .replace("name = \"pendulum\"", "name = \"heavy\"")
        .replace("state_weights = [5.0, 0.1]", "state_weights = [8.0, 0.2]")
        .replace("[[\"pi\", 0.0]]", "[[\"pi\", 0.0], [3.0, 0.5]]");
    std::fs::write(dir.join("heavy.toml"), text).unwrap();
    dir
}

/// `heavy.toml` of `dir` without its `[simulation]`, written as `driven.toml`.
fn without_simulation(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(dir.join("heavy.toml")).unwrap();
    let driven = dir.join("driven.toml");
    std::fs::write(&driven, text.split("[simulation]").next().unwrap()).unwrap();
    driven
}

/// `--task PATH`, no learner named: the task chooses it.
fn with_task(path: &Path) -> Overrides {
    Overrides {
        task: Some(path.to_path_buf()),
        ..Default::default()
    }
}

/// `--task PATH --algo mlac --approx llr`: the learner named.
fn with_task_and_mlac(path: &Path) -> Overrides {
    Overrides {
        algo: Some(Algo::Mlac),
        approx: Some(ApproxKind::Llr),
        ..with_task(path)
    }
}

#[test]
fn a_task_file_gives_the_task_and_its_simulation_the_presets() {
    let dir = heavy_pendulum("gives");
    let cfg = resolve(None, &with_task_and_mlac(&dir.join("heavy.toml"))).unwrap();
    assert_eq!(
        cfg.system(),
        SystemName::Pendulum,
        "the system it simulates"
    );
    assert_eq!(cfg.task_name(), "heavy");
    let task = cfg.task();
    assert_eq!(task.reward.q, [8.0, 0.2]);
    assert_eq!(task.initial_states.len(), 2);
    // The learner named is the pendulum's preset.
    let preset = resolve(None, &Overrides::default()).unwrap();
    assert_eq!(cfg.agent(), &preset.agent);
    // config.toml carries the task: it resolves to itself wherever it is read.
    let text = cfg.to_toml();
    assert!(text.contains("[task]\nname = \"heavy\""), "{text}");
    let again = resolve(
        Some((Path::new("/elsewhere/config.toml"), &text)),
        &Overrides::default(),
    );
    assert_eq!(again.unwrap(), cfg);
    // A configuration file names it relative to its own folder.
    let file = dir.join("exp.toml");
    let from_key = resolve(
        Some((
            &file,
            "task = \"heavy.toml\"\nalgo = \"mlac\"\napprox = \"llr\"\n",
        )),
        &Overrides::default(),
    );
    assert_eq!(from_key.unwrap(), cfg);
    // And it is part of what a checkpoint belongs to.
    assert_eq!(cfg.origin(0).system, "heavy");
    assert_ne!(cfg.origin(0).fingerprint, preset.origin(0).fingerprint);
}

#[test]
fn task_errors_name_the_task_file_or_the_key() {
    let dir = heavy_pendulum("errors");
    let heavy = dir.join("heavy.toml");
    // Another system beside the task.
    let o = Overrides {
        system: Some(SystemName::ArmVertical),
        ..with_task(&heavy)
    };
    let e = resolve(None, &o).unwrap_err().to_string();
    assert!(
        e.contains("`system`: \"arm-vertical\" differs from the system task \"heavy\" simulates, \"pendulum\""),
        "{e}"
    );
    // The same system is no contradiction (config.toml has both).
    let o = Overrides {
        system: Some(SystemName::Pendulum),
        ..with_task(&heavy)
    };
    resolve(None, &o).unwrap();
    // A bad task file is named, not the configuration that points at it.
    let bad = dir.join("bad.toml");
    let text = std::fs::read_to_string(&heavy).unwrap();
    std::fs::write(&bad, text.replace("low = -3.0", "low = 3.0")).unwrap();
    let e = resolve(
        Some((&dir.join("exp.toml"), "task = \"bad.toml\"\n")),
        &Overrides::default(),
    )
    .unwrap_err();
    assert_eq!(e.file.as_deref(), Some(bad.as_path()));
    assert_eq!(e.key, "action[0].low");
    // An inline table's errors carry the `task.` prefix and the configuration's name.
    let inline = format!("{}\n", resolve(None, &with_task(&heavy)).unwrap().to_toml())
        .replace("sampling_time = 0.03", "sampling_time = -1.0");
    let e = resolve(Some((Path::new("c.toml"), &inline)), &Overrides::default()).unwrap_err();
    assert!(
        e.to_string()
            .starts_with("c.toml: `task.sampling_time`: -1 is out of range"),
        "{e}"
    );
    let e = resolve(
        Some((Path::new("c.toml"), "task = 3\n")),
        &Overrides::default(),
    );
    assert!(
        e.unwrap_err()
            .to_string()
            .contains("must be a task file's path or a [task] table")
    );
}

#[test]
fn a_task_without_a_simulation_takes_the_pendulum_presets_by_rules() {
    let dir = heavy_pendulum("driven");
    let driven = without_simulation(&dir);
    let cfg = resolve(None, &with_task_and_mlac(&driven)).unwrap();
    assert_eq!(cfg.system(), SystemName::Pendulum, "the presets' basis");
    let task = cfg.task();
    assert!(task.simulation.is_none());
    let rules = agent::preset::for_task(
        &task,
        cfg.agent().algo,
        cfg.agent().approx,
        cfg.agent().horizon,
    );
    assert_eq!(cfg.agent(), &rules.unwrap().agent);
    // Its config.toml resolves to itself.
    assert_eq!(
        resolve(
            Some((Path::new("c.toml"), &cfg.to_toml())),
            &Overrides::default()
        )
        .unwrap(),
        cfg
    );
    // The rig cannot simulate it: one line says to use its driver.
    let e = cfg.check_simulated().unwrap_err().to_string();
    assert!(
        e.contains(
            "\"heavy\" has no [simulation]: the rig cannot simulate it; learn it against its driver"
        ),
        "{e}"
    );
    assert!(
        resolve(None, &with_task(&dir.join("heavy.toml")))
            .unwrap()
            .check_simulated()
            .is_ok()
    );
    // Nor can the observer integrate its dynamics.
    let known = "[observer]\nsensor = \"angle\"\nobserver = \"predictive\"\nmodel = \"known\"\n";
    let e = resolve(Some((Path::new("k.toml"), known)), &with_task(&driven)).unwrap_err();
    assert_eq!(e.key, "observer.model");
    // Another system than the pendulum beside it is a contradiction.
    let o = Overrides {
        system: Some(SystemName::Arm64),
        ..with_task(&driven)
    };
    let e = resolve(None, &o).unwrap_err().to_string();
    assert!(
        e.contains("takes its presets from (by rules), \"pendulum\""),
        "{e}"
    );
}

/// The configuration of a task without a simulation does not claim a simulated system:
/// `rig config --task` says where its presets come from instead of `system =
/// "pendulum"`, and its TOML resolves to itself.
#[test]
fn a_driven_task_says_where_its_presets_come_from() {
    let dir = heavy_pendulum("presets");
    let driven = without_simulation(&dir);
    let cfg = resolve(None, &with_task(&driven)).unwrap();
    let toml = cfg.to_toml();
    assert!(!toml.contains("system ="), "{toml}");
    assert!(
        toml.starts_with("# Task \"heavy\" has no [simulation]: its learner's presets are the pendulum's, carried over by rules"),
        "{toml}"
    );
    let again = resolve(Some((Path::new("c.toml"), &toml)), &Overrides::default()).unwrap();
    assert_eq!(again, cfg);
    // A simulated task keeps its system.
    let simulated = resolve(None, &with_task(&dir.join("heavy.toml"))).unwrap();
    assert!(simulated.to_toml().starts_with("system = \"pendulum\""));
}

#[test]
fn a_configuration_with_a_bad_task_is_refused_when_read() {
    let dir = heavy_pendulum("bad-when-read");
    let cfg = resolve(None, &with_task(&dir.join("heavy.toml"))).unwrap();
    let text = cfg.to_toml();
    assert!(text.contains("state_weights = [8.0, 0.2]"), "{text}");
    // A settings file whose task has lost a weight: an error when the file is read,
    // naming the task's key, not a panic when the task is asked for.
    let bad = text.replace("state_weights = [8.0, 0.2]", "state_weights = [8.0]");
    let e = toml::from_str::<ExperimentConfig>(&bad).unwrap_err();
    assert!(e.message().contains("`task."), "{e}");
}

/// With no learner named, a task file that is not one of the thesis's chooses it — here a
/// swing-up (it starts hanging): planning by the iterative LQR — whether it simulates a
/// built-in system or not; a configuration file that names none keeps the choice and
/// changes its values; config.toml names the learner, so it resolves to itself.
#[test]
fn a_task_file_without_a_named_learner_gets_the_one_it_chooses() {
    let dir = heavy_pendulum("chooses");
    for path in [dir.join("heavy.toml"), without_simulation(&dir)] {
        let (cfg, choice) = resolve_with_choice(None, &with_task(&path)).unwrap();
        let choice = choice.expect("the task chose");
        assert_eq!(
            choice.kind,
            agent::preset::by_task::TaskKind::SwingUp,
            "{choice}"
        );
        let (preset, _) = agent::preset::by_task::learner(&cfg.task()).unwrap();
        assert_eq!(cfg.agent(), &preset.agent);
        assert!(cfg.agent().planning.is_some());
        let (again, said) = resolve_with_choice(
            Some((Path::new("c.toml"), &cfg.to_toml())),
            &Overrides::default(),
        )
        .unwrap();
        assert_eq!((again, said), (cfg.clone(), None));
        let file = "[learning]\ngamma = 0.99\n";
        let (tuned, kept) =
            resolve_with_choice(Some((Path::new("g.toml"), file)), &with_task(&path)).unwrap();
        assert!(kept.is_some() && tuned.agent().planning.is_some());
        assert_eq!(tuned.agent().learning.gamma, 0.99);
    }
    // The thesis's own task keeps the preset, silently.
    let shipped =
        std::env::temp_dir().join(format!("cfg-task-shipped-{}.toml", std::process::id()));
    std::fs::write(&shipped, plant::task::builtin::text(SystemName::Pendulum)).unwrap();
    let (cfg, choice) = resolve_with_choice(None, &with_task(&shipped)).unwrap();
    assert_eq!(choice, None);
    assert_eq!(
        cfg.agent(),
        resolve(None, &Overrides::default()).unwrap().agent()
    );
}
