//! The agent process: state estimates in, actions out; learns as it goes.

use std::path::Path;

use ::agent::Agent;
use ::agent::checkpoint::{Checkpoint, Origin, Snapshot};
use ::observer::config::ObserverMode;
use ::observer::timing::{Call, ToAgent, act};

use wire::{Action, Estimate, Monotonic, flags, topic};

use super::{AgentSettings, NodeError, Result, SILENCE, STARTUP, pack};
use crate::config::ExperimentConfig;
use crate::resume::CheckpointWriter;

/// Runs the agent side of a run until the plant announces its end.
pub fn run(args: &AgentSettings) -> Result<()> {
    let node = &args.node;
    super::set_rt_priority(node.scheduling.rt_priority)?;
    node.scheduling.place(super::Part::Node)?;
    let cfg = node.experiment()?;
    let checkpoints = args
        .checkpoints
        .as_deref()
        .map(|dir| CheckpointWriter::new(dir, node.scheduling.layout(), args.keep_checkpoints))
        .transpose()?;
    let mut learner = AgentNode::new(&cfg, node.run_index, args.resume.as_deref(), checkpoints)?;
    let bus = node.join("agent")?;
    let estimates = bus.rx::<Estimate>(topic::ESTIMATE)?;
    let out = bus.tx::<Action>(topic::ACTION)?;
    let linger = super::Linger::open(&bus, node.receivers)?;
    out.wait_for_receivers(node.receivers, STARTUP, &bus)?;
    // The time the actions are stamped on.
    let time = Monotonic::host();
    loop {
        let e = estimates.recv(&bus, STARTUP.max(SILENCE))?;
        let t_received_ns = time.now_ns();
        let f = e.header.flags;
        let mut a = learner.action(&e, args.trivial)?;
        a.t_received_ns = t_received_ns;
        a.t_publish_ns = time.now_ns();
        out.send(a)?;
        if f & flags::SHUTDOWN != 0 {
            if let Some(w) = &mut learner.checkpoints {
                w.finish()?;
            }
            return linger.wait(&bus);
        }
    }
}

/// The agent of the run, its checkpoints, and which learning trial is due.
pub struct AgentNode {
    agent: Box<dyn Agent>,
    /// Which experiment and run this is (for checkpoints).
    origin: Origin,
    /// Where a checkpoint of every learning trial goes (`checkpoints`).
    checkpoints: Option<CheckpointWriter>,
    /// The next learning trial.
    expect_trial: u64,
    /// Whether the last learning trial's attempt was cut short by a gap: it is run again.
    cut: bool,
    /// Predictive timing (`observer.mode`).
    predictive: bool,
    /// Action dimension.
    m: usize,
}

impl AgentNode {
    /// The agent of run `run` of `cfg`, from the checkpoint `resume` if given, writing
    /// a checkpoint of every learning trial to `checkpoints` if given.
    pub fn new(
        cfg: &ExperimentConfig,
        run: u32,
        resume: Option<&Path>,
        checkpoints: Option<CheckpointWriter>,
    ) -> Result<Self> {
        let task = cfg.task();
        let mut agent = ::agent::build(
            &task,
            cfg.learner(),
            ::agent::seed::run_seed(cfg.run().seed, run),
        );
        let origin = cfg.origin(run);
        // The first learning trial this process runs.
        let mut expect_trial = 1;
        if let Some(path) = resume {
            let c = Checkpoint::read(path)?;
            c.restore(&origin, agent.as_mut())
                .map_err(|why| NodeError::Restore {
                    path: path.to_path_buf(),
                    why,
                })?;
            expect_trial = u64::from(c.trial) + 1;
        }
        Ok(Self {
            agent,
            origin,
            checkpoints,
            expect_trial,
            cut: false,
            predictive: cfg.observer().mode == ObserverMode::Predictive,
            m: task.action_dim(),
        })
    }

    /// The action the agent sends for estimate `e` (zero for the run's end, or always
    /// when `trivial`); its wall-clock stamps (`t_received_ns`, `t_publish_ns`) are left 0
    /// for the caller. `rig replay` takes the same step over a recording.
    pub fn action(&mut self, e: &Estimate, trivial: bool) -> Result<Action> {
        let mut u = vec![0.0; self.m];
        if e.header.flags & flags::SHUTDOWN == 0 && !trivial {
            self.answer(e, &mut u)?;
        }
        Ok(Action {
            header: e.header,
            n_u: self.m as u64,
            u: pack(&u),
            t_sample_ns: e.t_sample_ns,
            ..Action::default()
        })
    }

    /// The agent's answer to estimate `e` into `u` (it learns, unless `e` is of a greedy
    /// trial); at the end of a learning trial, its checkpoint.
    fn answer(&mut self, e: &Estimate, u: &mut [f64]) -> Result<()> {
        let f = e.header.flags;
        let call = super::observer::call_of(f);
        let greedy = f & flags::GREEDY != 0;
        if !greedy && call == Call::Start {
            // A trial cut short by a gap is run again.
            let again = std::mem::take(&mut self.cut) && e.header.trial + 1 == self.expect_trial;
            if !again && e.header.trial != self.expect_trial {
                return Err(NodeError::TrialOutOfTurn {
                    started: e.header.trial,
                    due: self.expect_trial,
                });
            }
            self.expect_trial += u64::from(!again);
        }
        if !greedy && f & flags::GAP != 0 {
            self.cut = true;
        }
        let t = ToAgent {
            call,
            reward: e.reward,
            x: &e.x[..e.n_x as usize],
            u_prev: &e.u_applied[..self.m],
            // The sample the action applies at: the next in predictive timing (but the
            // answer to the start state, u_0, applies at the start).
            step: e.header.step as usize + usize::from(self.predictive && call != Call::Start),
        };
        act(self.agent.as_mut(), greedy, &t, u);
        if !greedy && f & flags::END != 0 && f & flags::GAP == 0 {
            // The trial's learning is complete: checkpoint it before acknowledging.
            self.checkpoint(e)?;
        }
        Ok(())
    }

    /// Checkpoints the agent at the end of the learning trial of estimate `e`.
    fn checkpoint(&mut self, e: &Estimate) -> Result<()> {
        let Some(w) = &mut self.checkpoints else {
            return Ok(());
        };
        let mut state = Snapshot::default();
        self.agent.save(&mut state);
        w.save(Checkpoint {
            origin: self.origin.clone(),
            trial: e.header.trial as u32,
            sim_time_s: e.header.t_sim,
            state,
        })?;
        Ok(())
    }
}
