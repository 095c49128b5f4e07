//! A time response: the samples of a greedy trial from one start state
//! ([`crate::experiment::Experiment::greedy_trajectory`]), as `responses.csv` holds them.

/// One sample of a time response.
#[derive(Clone, Debug, PartialEq)]
pub struct ResponseSample {
    /// Time since the trial start \[s\].
    pub t: f64,
    /// The state the agent acted on at this sample: direct timing `x̂_k`, from which the
    /// applied action was computed; predictive timing `x̂_{k+1|k}`, for the next interval's
    /// action (the applied one was computed a sample earlier).
    pub x: Vec<f64>,
    /// Applied action.
    pub u: Vec<f64>,
    /// `ρ(x_k, u_k)`.
    pub reward: f64,
}
