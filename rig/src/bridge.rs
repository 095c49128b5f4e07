//! `rig bridge driver|rig`: one driver's services across two hosts over Zenoh
//! (docs/across-hosts.md).

use crate::exit::{Fails, Outcome};
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use clap::{Args as Flags, Subcommand};

#[derive(Flags)]
pub struct Args {
    #[command(subcommand)]
    side: Side,
}

#[derive(Subcommand)]
enum Side {
    /// On the driver's host, beside the driver: listen at ENDPOINT, admit the users of
    /// the credentials file, pass their commands for this driver only to it — one rig
    /// session's at a time — and its info and samples to them. The driver's own watchdog
    /// keeps the actuator safe when the link goes; stale commands are dropped. Runs
    /// until Ctrl-C or SIGTERM.
    Driver {
        #[command(flatten)]
        common: Common,
        /// Drop an action answering a sample more than N periods older than the newest
        /// (a late burst after an outage); 1 or more.
        #[arg(long, value_name = "N", default_value_t = 2, value_parser = clap::value_parser!(u64).range(1..))]
        max_age_periods: u64,
        /// A rig session holds the driver until it lets go or N periods of the driver
        /// (and at least 250 ms) pass without a command or a hold from it; meanwhile
        /// every other session's commands are refused; 2 or more.
        #[arg(long, value_name = "N", default_value_t = bridge::claim::Lease::DEFAULT.periods, value_parser = clap::value_parser!(u64).range(2..=10_000))]
        lease_periods: u64,
        /// Write each action's sample-to-actuation delay across the link to FILE as CSV
        /// (`seq,t_sample_ns,t_arrived_ns,sample_to_actuation`: from the driver's sample
        /// instant to the action's arrival here, ns, on this host's clock alone) — for
        /// `rig learn --delay-from FILE`.
        #[arg(long, value_name = "FILE")]
        timing_out: Option<PathBuf>,
    },
    /// On the rig's host: connect to the driver's bridge at ENDPOINT and stand in for
    /// the driver here (its id's services), so `rig run --plant external` and `rig
    /// check-driver` work unchanged; measure the link (round trips; one-way hops with
    /// `--same-clock`). Runs until Ctrl-C or SIGTERM, then prints the link's timing.
    Rig {
        #[command(flatten)]
        common: Common,
        /// Both hosts read one monotonic clock (network namespaces of one machine, or
        /// clocks synchronised otherwise): the driver's stamps pass unchanged and one-way
        /// hops are measured. Without it the stamps are placed on this host's clock by
        /// the offset of the shortest recent round trip (± half of it) and only round
        /// trips are measured.
        #[arg(long)]
        same_clock: bool,
        /// Ping the link every MS milliseconds (round trips, the clocks' offset).
        #[arg(long, value_name = "MS", default_value_t = 100, value_parser = clap::value_parser!(u64).range(1..=10_000))]
        ping_ms: u64,
        /// Write every measurement of the link to FILE as CSV (`what,seq,ns`: what is
        /// ping_round_trip, command_round_trip, command_hop or sample_hop).
        #[arg(long, value_name = "FILE")]
        timing_out: Option<PathBuf>,
    },
    /// From any host: connect to the driver's bridge at ENDPOINT with the credentials
    /// (or none) for a while, listen to the driver's info and samples and, with
    /// `--zero-actions`, put zero actions (a rig session of its own: refused while
    /// another session holds the driver); prints what arrived. The driver's bridge
    /// prints how many commands it passed on. To check an access-control setup: a peer
    /// without listed credentials must see nothing and command nothing. Exits 1 when
    /// nothing arrived (saying why, where Zenoh tells: nothing listening, the user or
    /// password refused, a failed TLS handshake) or its zero actions were refused.
    Probe {
        #[command(flatten)]
        common: Common,
        /// Connect without credentials (`--credentials` is then not read).
        #[arg(long)]
        anonymous: bool,
        /// Put a zero action (the safe action) every 10 ms.
        #[arg(long)]
        zero_actions: bool,
        /// How long to probe [s].
        #[arg(long, value_name = "S", default_value_t = 3.0)]
        seconds: f64,
    },
}

#[derive(Flags)]
struct Common {
    /// The driver's id (the same on both hosts): letters, digits, '-' and '_'.
    #[arg(long, value_name = "ID")]
    driver: String,
    /// The Zenoh endpoint: where the driver's bridge listens (e.g. `tcp/0.0.0.0:7447`)
    /// and the rig's bridge connects (e.g. `tcp/192.168.1.20:7447`).
    #[arg(long, value_name = "ENDPOINT")]
    endpoint: String,
    /// A file of `user:password` lines: on the driver's host every user that may
    /// command the driver; on the rig's host its own (the first line). Keep it
    /// readable by its owner only.
    #[arg(long, value_name = "FILE")]
    credentials: PathBuf,
    /// A Zenoh configuration file (JSON5) to start from, e.g. for TLS endpoints and
    /// their certificates; the mode, endpoints, authentication, access control and
    /// scouting are set over it.
    #[arg(long, value_name = "FILE")]
    zenoh_config: Option<PathBuf>,
    /// Report the link lost after MS milliseconds without a word from the other side;
    /// Zenoh closes it after the same silence and reconnects when it can.
    #[arg(long, value_name = "MS", default_value_t = 500, value_parser = clap::value_parser!(u64).range(10..=60_000))]
    link_timeout_ms: u64,
}

impl Common {
    fn network(&self) -> bridge::Network {
        bridge::Network {
            endpoint: self.endpoint.clone(),
            credentials: self.credentials.clone(),
            zenoh_config: self.zenoh_config.clone(),
            lease_ms: self.link_timeout_ms.max(100),
        }
    }
}

/// Runs the command.
pub fn main(args: &Args) -> Outcome {
    let result: anyhow::Result<()> = match &args.side {
        Side::Driver {
            common,
            max_age_periods,
            lease_periods,
            timing_out,
        } => bridge::serve_driver(&bridge::DriverSide {
            timing_out: timing_out.clone(),
            id: common.driver.clone(),
            net: common.network(),
            max_age_periods: *max_age_periods,
            link_timeout: Duration::from_millis(common.link_timeout_ms),
            lease: bridge::claim::Lease {
                periods: *lease_periods,
                ..bridge::claim::Lease::DEFAULT
            },
        })
        .map(|counts| eprintln!("bridge for driver {:?}: {counts}", common.driver))
        .map_err(Into::into),
        Side::Rig {
            common,
            same_clock,
            ping_ms,
            timing_out,
        } => bridge::serve_rig(&bridge::RigSide {
            id: common.driver.clone(),
            net: common.network(),
            same_clock: *same_clock,
            ping_period: Duration::from_millis(*ping_ms),
            link_timeout: Duration::from_millis(common.link_timeout_ms),
            timing_out: timing_out.clone(),
        })
        .map(|(counts, timing)| {
            eprintln!("bridge for driver {:?}: {counts}", common.driver);
            eprintln!("the link:\n{}", timing.summary());
        })
        .map_err(Into::into),
        Side::Probe {
            common,
            anonymous,
            zero_actions,
            seconds,
        } => bridge::probe(
            &common.driver,
            &common.network(),
            *anonymous,
            *zero_actions,
            *seconds,
        )
        .map_err(anyhow::Error::from)
        .and_then(|p| {
            println!(
                "probe of driver {:?} at {}: {} infos and {} samples arrived; {} zero actions put",
                common.driver, common.endpoint, p.infos, p.samples, p.commands
            );
            if !p.received() {
                let why = p.unconnected.clone().unwrap_or_else(|| {
                    "Zenoh did not say why: check the endpoint, the driver's id, the credentials and `rig bridge driver` there".into()
                });
                return Err(anyhow::anyhow!("nothing arrived: {why}"));
            }
            match p.refused {
                Some(why) => Err(anyhow::anyhow!("the zero actions were refused: {why}")),
                None => Ok(()),
            }
        }),
    };
    result.failure()?;
    Ok(ExitCode::SUCCESS)
}
