//! Recorded against replayed, field by field and bit for bit: the first difference.

use std::fmt;

use wire::{Action, Estimate, Header};

use crate::record::Value;

/// The first field in which a replayed message differs from the recorded one.
#[derive(Clone, Debug, PartialEq)]
pub struct Difference {
    /// The message's topic.
    pub topic: &'static str,
    /// The sample: sequence number, trial and step (the recorded message's).
    pub seq: u64,
    /// Its trial.
    pub trial: u64,
    /// Its step within the trial.
    pub step: u64,
    /// The field, as the recording names it (`x_1`, `flags`); `message` when one side
    /// has no message for the sample.
    pub field: String,
    /// The recorded value, `f64` in full precision (shortest round trip).
    pub recorded: String,
    /// The replayed value.
    pub replayed: String,
}

impl fmt::Display for Difference {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} at sample seq {} (trial {}, step {}), field {}: recorded {}, replayed {}",
            self.topic, self.seq, self.trial, self.step, self.field, self.recorded, self.replayed
        )
    }
}

impl Difference {
    /// A sample for which one side has a message and the other none.
    pub fn missing(topic: &'static str, h: &Header, recorded: bool) -> Self {
        let (present, absent) = ("present".to_string(), "none".to_string());
        let (recorded, replayed) = if recorded {
            (present, absent)
        } else {
            (absent, present)
        };
        Difference {
            topic,
            seq: h.seq,
            trial: h.trial,
            step: h.step,
            field: "message".into(),
            recorded,
            replayed,
        }
    }
}

/// A field's name: `name`, or `name_i` for component `i` of an array.
type Name = (&'static str, Option<usize>);

/// The recorded fields of a header, in the recording's order.
fn header(h: &Header, out: &mut Vec<(Name, Value)>) {
    out.extend([
        (("seq", None), Value::Int(h.seq)),
        (("trial", None), Value::Int(h.trial)),
        (("step", None), Value::Int(h.step)),
        (("flags", None), Value::Int(h.flags)),
        (("t_sim", None), Value::Num(h.t_sim)),
    ]);
}

fn array(name: &'static str, v: &[f64], out: &mut Vec<(Name, Value)>) {
    out.extend(
        v.iter()
            .enumerate()
            .map(|(i, &x)| ((name, Some(i)), Value::Num(x))),
    );
}

/// The recorded fields of an estimate of `n` states and `m` actions.
fn estimate_fields(e: &Estimate, n: usize, m: usize) -> Vec<(Name, Value)> {
    let mut out = Vec::with_capacity(6 + n + m);
    header(&e.header, &mut out);
    out.push((("reward", None), Value::Num(e.reward)));
    array("x", &e.x[..n], &mut out);
    array("u_applied", &e.u_applied[..m], &mut out);
    out
}

/// The recorded fields of an action of `m` components.
fn action_fields(a: &Action, m: usize) -> Vec<(Name, Value)> {
    let mut out = Vec::with_capacity(5 + m);
    header(&a.header, &mut out);
    array("u", &a.u[..m], &mut out);
    out
}

/// Whether two values are the same bits — any NaN the same as any other, since the
/// recording writes NaN as `null`.
fn same(a: Value, b: Value) -> bool {
    match (a, b) {
        (Value::Int(a), Value::Int(b)) => a == b,
        (Value::Num(a), Value::Num(b)) => a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
        _ => false,
    }
}

fn show(v: Value) -> String {
    match v {
        Value::Int(i) => i.to_string(),
        Value::Num(x) => format!("{x:?}"),
    }
}

/// The first field of `recorded` that `replayed` differs in.
fn first(
    topic: &'static str,
    h: &Header,
    recorded: Vec<(Name, Value)>,
    replayed: Vec<(Name, Value)>,
) -> Option<Difference> {
    let ((name, i), a, b) = recorded
        .into_iter()
        .zip(replayed)
        .map(|((name, a), (_, b))| (name, a, b))
        .find(|&(_, a, b)| !same(a, b))?;
    Some(Difference {
        topic,
        seq: h.seq,
        trial: h.trial,
        step: h.step,
        field: i.map_or(name.to_string(), |i| format!("{name}_{i}")),
        recorded: show(a),
        replayed: show(b),
    })
}

/// The first difference of a replayed estimate from the recorded one.
pub fn estimate(
    topic: &'static str,
    recorded: &Estimate,
    replayed: &Estimate,
    n: usize,
    m: usize,
) -> Option<Difference> {
    first(
        topic,
        &recorded.header,
        estimate_fields(recorded, n, m),
        estimate_fields(replayed, n, m),
    )
}

/// The first difference of a replayed action from the recorded one.
pub fn action(
    topic: &'static str,
    recorded: &Action,
    replayed: &Action,
    m: usize,
) -> Option<Difference> {
    first(
        topic,
        &recorded.header,
        action_fields(recorded, m),
        action_fields(replayed, m),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_differing_field_is_named_with_both_values_in_full() {
        let mut a = Estimate::default();
        a.x[1] = 0.1 + 0.2;
        let mut b = a;
        assert_eq!(estimate("/e", &a, &b, 2, 1), None);
        b.x[1] = 0.3;
        b.reward = -0.0;
        let d = estimate("/e", &a, &b, 2, 1).unwrap();
        assert_eq!(d.field, "reward", "-0.0 is not 0.0, bit for bit");
        b.reward = 0.0;
        let d = estimate("/e", &a, &b, 2, 1).unwrap();
        assert_eq!(
            (d.field.as_str(), d.recorded.as_str(), d.replayed.as_str()),
            ("x_1", "0.30000000000000004", "0.3")
        );
        a.x[1] = f64::NAN;
        b.x[1] = -f64::NAN;
        assert_eq!(estimate("/e", &a, &b, 2, 1), None, "null is any NaN");
    }
}
