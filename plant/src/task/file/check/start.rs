//! `[start_distribution]` checked: a uniform box or a normal distribution, inside the
//! operating range.

use super::vector;
use crate::config::ConfigError;
use crate::start::StartDistribution;
use crate::task::file::{StartKind, StartSpec};

/// The distribution of `s` over `n` states; `range`: the operating range's limits, which
/// a uniform box and a normal mean must lie in.
pub(super) fn distribution(
    s: &StartSpec,
    n: usize,
    range: Option<&(Vec<(f64, f64)>, f64)>,
) -> Result<StartDistribution, ConfigError> {
    let key = "start_distribution";
    let (first, second, names) = match s.kind {
        StartKind::Uniform => (&s.low, &s.high, ["low", "high", "mean", "std"]),
        StartKind::Normal => (&s.mean, &s.std, ["mean", "std", "low", "high"]),
    };
    let given = |name: &str| match name {
        "low" => s.low.is_some(),
        "high" => s.high.is_some(),
        "mean" => s.mean.is_some(),
        _ => s.std.is_some(),
    };
    let kind = format!("{:?}", s.kind).to_lowercase();
    if let Some(other) = names[2..].iter().find(|k| given(k)) {
        return Err(ConfigError::new(
            &format!("{key}.{other}"),
            format!(
                "a {kind} distribution takes `{}` and `{}`, not `{other}`",
                names[0], names[1]
            ),
        ));
    }
    let (Some(a), Some(b)) = (first, second) else {
        let missing = if first.is_none() { names[0] } else { names[1] };
        return Err(ConfigError::new(
            &format!("{key}.{missing}"),
            format!(
                "is missing: a {kind} distribution needs `{}` and `{}`, one number per state each",
                names[0], names[1]
            ),
        ));
    };
    let a = vector(&format!("{key}.{}", names[0]), a, n, "state", false)?;
    let b = vector(
        &format!("{key}.{}", names[1]),
        b,
        n,
        "state",
        s.kind == StartKind::Normal,
    )?;
    for i in 0..n {
        // A width beyond the largest f64 cannot be drawn from.
        let width = b[i] - a[i];
        if s.kind == StartKind::Uniform && !(width >= 0.0 && width.is_finite()) {
            return Err(ConfigError::new(
                &format!("{key}.low[{i}]"),
                format!(
                    "[{}, {}]: the lower bound must not exceed the upper, nor lie more than 1.7e308 below it",
                    a[i], b[i]
                ),
            ));
        }
        let Some(&(lo, hi)) = range.map(|r| &r.0[i]) else {
            continue;
        };
        // A uniform box lies inside the operating range; a normal mean does.
        let ends = match s.kind {
            StartKind::Uniform => [(names[0], a[i]), (names[1], b[i])],
            StartKind::Normal => [(names[0], a[i]), (names[0], a[i])],
        };
        if let Some((name, v)) = ends.into_iter().find(|&(_, v)| !(lo..=hi).contains(&v)) {
            return Err(ConfigError::new(
                &format!("{key}.{name}[{i}]"),
                format!("{v} lies outside the operating range [{lo}, {hi}]"),
            ));
        }
    }
    Ok(match s.kind {
        StartKind::Uniform => StartDistribution::Uniform { low: a, high: b },
        StartKind::Normal => StartDistribution::Normal { mean: a, std: b },
    })
}
