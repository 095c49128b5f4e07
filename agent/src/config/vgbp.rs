//! `[vgbp]`: VGBP's action selection.

use plant::config::{ConfigError, check_int};
use serde::{Deserialize, Serialize};

/// VGBP's action selection (§6.3, [`crate::vgbp`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct VgbpConfig {
    /// Re-evaluations of the value gradient at the predicted next state (0: Eq. 6.21 as
    /// the thesis has it).
    pub lookahead: u32,
    /// Action levels per component at which the right-hand side of Eq. 6.6 is searched
    /// (with the model affine in `u`, Eq. 6.9, and `V` not linearised); 0: no search,
    /// the action of Eq. 6.21 and the look-ahead.
    #[serde(default)]
    pub grid: u32,
    /// Fit Eq. 6.21's process model at `(x, u = 0)` rather than at the state `x`
    /// (Algorithm 7 line 12, the default `false`).
    #[serde(default)]
    pub fit_at_zero_action: bool,
}

impl VgbpConfig {
    /// Checks every value against its allowed range.
    pub fn validate(&self) -> Result<(), ConfigError> {
        check_int("vgbp.lookahead", self.lookahead.into(), 0, 100)?;
        if self.grid == 1 || self.grid > 1001 {
            return Err(ConfigError::new(
                "vgbp.grid",
                format!(
                    "{} is out of range: must be 0 (no search) or an integer in 2..=1001",
                    self.grid
                ),
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_one_level_search_is_out_of_range() {
        let v = VgbpConfig {
            lookahead: 2,
            grid: 0,
            fit_at_zero_action: false,
        };
        v.validate().unwrap();
        let e = VgbpConfig { grid: 1, ..v }.validate().unwrap_err();
        assert_eq!(e.key, "vgbp.grid");
    }
}
