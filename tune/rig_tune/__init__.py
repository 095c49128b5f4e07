"""`rig tune`: a hyperparameter study over a task's learner configuration, with Optuna.

The modules, in the order a study uses them:

* `cli` — the command line;
* `config` — the learner configuration, read from `rig config`, keys by dotted path;
* `space` — the search space file (TOML) and the starting space a preset suggests;
* `runner` — one learning run of `rig learn` or `rig run --plant external`, followed
  evaluation by evaluation;
* `objective` — one trial: a configuration, its runs on the study's seeds, pruning;
* `study` — storage, sampler, pruner, the worker processes and their progress;
* `check` — the best configuration and the preset re-run on fresh seeds;
* `report` — report.md and its plots.
"""
