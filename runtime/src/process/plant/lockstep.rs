//! The simulated plant in lockstep: simulated time advances only when the action for
//! the sample has arrived, exactly as in process ([`crate::experiment::Experiment`]).

use crate::process::Result;
use ::plant::episode::Episode;
use ::plant::safety::SafetyCounts;
use ::plant::schedule::Trial;
use wire::{Header, flags};

use super::super::SILENCE;
use super::link::{Link, TrialHeader, end_flags};
use super::{Ended, Trials};

/// The simulated system in lockstep.
pub(super) struct LockstepPlant {
    episode: Episode,
    link: Link,
}

impl LockstepPlant {
    /// Trials of `episode`, published on `link`.
    pub(super) fn new(link: Link, episode: Episode) -> Self {
        Self { episode, link }
    }
}

impl Trials for LockstepPlant {
    fn trial(&mut self, trial: &Trial) -> Result<Ended> {
        let header = TrialHeader::new(trial, self.link.task.ts);
        let mut u = vec![0.0; self.link.task.action_dim()];
        let link = &mut self.link;
        self.episode.start(&trial.x0, &mut u, |e, primed, u| {
            let f = if primed { flags::PRIMED } else { flags::START };
            exchange(link, e, header.at(link.seq, 0, f), 0.0, u)
        })?;
        loop {
            let step = self.episode.step(&u);
            let h = header.at(self.link.seq, step.sample, end_flags(&step));
            exchange(&mut self.link, &self.episode, h, step.reward, &mut u)?;
            if step.ended() {
                return Ok(Ended::Done(self.episode.skipped()));
            }
        }
    }

    fn link(&mut self) -> &mut Link {
        &mut self.link
    }

    fn safety(&mut self) -> SafetyCounts {
        self.episode.plant_mut().safety().counts()
    }
}

/// Publishes the episode's current sample (`header`, `reward`) and waits for the action
/// that answers it, into `u`.
fn exchange(
    link: &mut Link,
    e: &Episode,
    header: Header,
    reward: f64,
    u: &mut [f64],
) -> Result<()> {
    let (plant, actuator) = (e.plant(), e.actuator());
    match actuator.next_action() {
        Some(next) => link.u_next.copy_from_slice(next),
        None => link.u_next.fill(f64::NAN),
    }
    link.delay_s = if header.flags & (flags::START | flags::PRIMED) != 0 {
        0.0
    } else {
        actuator.last_delay()
    };
    let t_publish_ns = link.publish(
        header,
        reward,
        plant.state(),
        plant.applied_action(),
        link.time.now_ns(),
    )?;
    let a = link.actions.recv(&link.bus, SILENCE)?;
    link.t_action_ns = link.time.now_ns();
    link.latencies.push(link.t_action_ns - t_publish_ns);
    Link::check_answer(&a, header.seq)?;
    u.copy_from_slice(&a.u[..u.len()]);
    Ok(())
}
