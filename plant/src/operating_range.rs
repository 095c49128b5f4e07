//! The operating range of a system with physical limits (§6.4.2): leaving it ends a
//! trial with a penalty.

/// The operating range of a system with physical limits, and the penalty for leaving it:
/// the failure region (its outside) of the trial's endings.
#[derive(Clone, Debug, PartialEq)]
pub struct OperatingRange {
    /// `(low, high)` per state component; infinite bounds for unlimited components.
    pub limits: Vec<(f64, f64)>,
    /// The reward of the transition that leaves the range, which is the trial's last.
    pub penalty: f64,
}

impl OperatingRange {
    /// Whether `x` lies outside the range (a non-finite component counts as outside).
    pub fn excludes(&self, x: &[f64]) -> bool {
        x.iter()
            .zip(&self.limits)
            .any(|(&xi, &(lo, hi))| !(lo..=hi).contains(&xi))
    }
}
