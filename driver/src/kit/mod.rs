//! The driver kit: what a process that owns a motor (or a simulation of it) links to
//! serve the rig over the driver contract — the [`Device`] it implements, [`serve`] and
//! [`serve_lockstep`] that run the contract for it, [`Simulated`] (any built-in system
//! as a device) and the actuator's [`safety`] layer. It knows nothing of the rig's end
//! ([`crate::link`]).

mod device;
mod serve;
mod simulated;

pub use device::{Device, Outcome, REST_SAMPLES};
pub use plant::safety;
pub use serve::{Lockstep, Served, Serving, serve, serve_lockstep};
pub use simulated::Simulated;
