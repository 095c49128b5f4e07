//! `rig run --live` in a rig built without the live view (the `live` feature): says how
//! to build one that has it.

use std::net::SocketAddr;

use anyhow::{Result, bail};
use runtime::record::Tap;

/// No live view can be made in this build.
pub enum LiveView {}

impl LiveView {
    /// Refuses with the command that builds the live view.
    pub fn start(_: SocketAddr, _: &plant::Task) -> Result<(LiveView, Box<dyn Tap>)> {
        bail!(
            "rig run --live: this rig was built without the live view; build it with the \
             `live` feature: cargo run --release -p rig --features live -- run --live \
             (docs/run.md)"
        )
    }

    /// Where it listens.
    pub fn addr(&self) -> SocketAddr {
        match *self {}
    }

    /// What it did.
    pub fn close(self) -> String {
        match self {}
    }
}
