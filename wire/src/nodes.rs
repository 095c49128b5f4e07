//! Node names: each process of a run is the iceoryx2 node `rig-<run id>-<role>`, and the
//! driver kit's drivers are run `driver` with their id as role (`rig-driver-<id>`). The
//! rig lists these nodes to tell which processes of a run are alive and which drivers
//! are running.

use iceoryx2::node::NodeView;
use iceoryx2::prelude::*;

/// The run id under which the driver kit's drivers name their nodes.
pub const DRIVER_RUN: &str = "driver";

/// The iceoryx2 node name of process `role` of run `run_id`: `rig-<run id>-<role>`.
pub fn node_name(run_id: &str, role: &str) -> String {
    format!("rig-{run_id}-{role}")
}

/// A node of a run, as this host's iceoryx2 lists it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Peer {
    /// Its role: `plant`, `observer`, … (a driver's id for run [`DRIVER_RUN`]).
    pub role: String,
    /// Its process id.
    pub pid: u32,
    /// Alive; otherwise dead (killed without cleaning up).
    pub alive: bool,
}

/// The nodes of run `run_id` on this host with iceoryx2 configuration `config`, alive or
/// dead, in listing order.
pub fn peers(config: &iceoryx2::config::Config, run_id: &str) -> Vec<Peer> {
    let prefix = node_name(run_id, "");
    let mut found = Vec::new();
    let _ = Node::<ipc::Service>::list(config, |state| {
        let (details, alive) = match &state {
            NodeState::Alive(v) => (v.details().as_ref(), true),
            NodeState::Dead(v) => (v.details().as_ref(), false),
            _ => (None, false),
        };
        if let Some(d) = details
            && let Some(role) = d.name().to_string().strip_prefix(&prefix)
        {
            found.push(Peer {
                role: role.to_string(),
                pid: d.process_id().value() as u32,
                alive,
            });
        }
        CallbackProgression::Continue
    });
    found
}
