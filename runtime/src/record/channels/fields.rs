//! The fields of each channel of `run.mcap`, in the order its messages hold them, for a
//! task of `n` state and `m` action components. The recorder writes values in this
//! order; [`super::decode`] reads them back by these names.

use crate::record::{Field, FieldKind};

/// The header's fields, which every message of the loop begins with.
pub const HEADER: [&str; 4] = ["seq", "trial", "step", "flags"];
/// The header's simulated time, after [`HEADER`].
pub const T_SIM: &str = "t_sim";
/// The stamps of `/timing/plant/measurement`, after `seq`.
pub const MEASUREMENT_STAMPS: [&str; 3] = ["t_sample_ns", "t_publish_ns", "t_action_ns"];
/// The stamps of `/timing/observer/estimate` and `/timing/agent/action`, after `seq`.
pub const STAMPS: [&str; 3] = ["t_sample_ns", "t_received_ns", "t_publish_ns"];
/// The integer fields of `/driver/link`, in `LinkSample`'s order (the offset, signed,
/// follows as a number: [`LINK_OFFSET`]).
pub const LINK_INTS: [&str; 7] = [
    "seq",
    "t_received_ns",
    "sample_hop_ns",
    "command_round_trip_ns",
    "command_hop_ns",
    "ping_round_trip_ns",
    "clock_uncertainty_ns",
];
/// The last field of `/driver/link`.
pub const LINK_OFFSET: &str = "clock_offset_ns";

/// The header's fields, then `extra`'s.
fn header(extra: Vec<Vec<Field>>) -> Vec<Field> {
    let mut f: Vec<Field> = HEADER.iter().map(|n| Field::integer(n)).collect();
    f.push(Field::number(T_SIM));
    f.extend(extra.into_iter().flatten());
    f
}

/// The reward, the state `x` as `name_0..`, and the action applied.
fn state(name: &str, n: usize, m: usize) -> Vec<Vec<Field>> {
    vec![
        vec![Field::number("reward")],
        Field::array(name, n, FieldKind::Number),
        Field::array("u_applied", m, FieldKind::Number),
    ]
}

fn integers(names: &[&str]) -> Vec<Field> {
    names.iter().map(|f| Field::integer(f)).collect()
}

/// `/plant/measurement`.
pub fn measurement(n: usize, m: usize) -> Vec<Field> {
    let mut measured = state("y", n, m);
    measured.push(Field::array("u_next", m, FieldKind::Number));
    measured.push(vec![Field::number("delay_s")]);
    header(measured)
}

/// `/observer/estimate`.
pub fn estimate(n: usize, m: usize) -> Vec<Field> {
    header(state("x", n, m))
}

/// `/agent/action`.
pub fn action(m: usize) -> Vec<Field> {
    header(vec![Field::array("u", m, FieldKind::Number)])
}

/// `/plant/truth`.
pub fn truth(n: usize) -> Vec<Field> {
    header(vec![Field::array("x", n, FieldKind::Number)])
}

/// A `/timing/...` channel: `seq`, then the stamps.
pub fn timing(stamps: &[&str]) -> Vec<Field> {
    std::iter::once(Field::integer("seq"))
        .chain(stamps.iter().map(|n| Field::integer(n)))
        .collect()
}

/// `/driver/sample`.
pub fn driver_sample(n: usize, m: usize) -> Vec<Field> {
    let mut sample = integers(&["seq", "t_sample_ns", "status", "reset_id", "last_command"]);
    sample.extend(Field::array("x", n, FieldKind::Number));
    sample.extend(Field::array("u_applied", m, FieldKind::Number));
    sample.extend(integers(&["clamped", "rejected", "watchdog_trips"]));
    sample
}

/// `/driver/command`.
pub fn driver_command(n: usize, m: usize) -> Vec<Field> {
    let mut command = integers(&["seq", "kind", "sample_seq", "t_publish_ns"]);
    command.extend(Field::array("u", m, FieldKind::Number));
    command.extend(Field::array("x0", n, FieldKind::Number));
    command
}

/// `/driver/link`.
pub fn driver_link() -> Vec<Field> {
    let mut link = integers(&LINK_INTS);
    link.push(Field::number(LINK_OFFSET));
    link
}

/// `/returns`: a trial, its return, its greedy return (`null` without an evaluation) and
/// the simulated time at its end.
pub fn returns() -> Vec<Field> {
    vec![
        Field::integer("trial"),
        Field::number("return"),
        Field::number("greedy"),
        Field::number("sim_time_s"),
    ]
}

/// `/latency`: an action's sample, the time from the sample to the action and the
/// agent's share of it, in µs.
pub fn latency() -> Vec<Field> {
    vec![
        Field::integer("seq"),
        Field::number("sample_to_action_us"),
        Field::number("agent_us"),
    ]
}
