//! The loop's recorded messages read back into the wire's layouts: each a flat JSON
//! object of the fields [`super::fields`] lists (`null` for NaN and ±∞), numbers parsed
//! back to the bits written (serde_json's `float_roundtrip`).

use serde_json::{Map, Value as Json};
use wire::{Action, Estimate, Header, MAX_U, MAX_X, Measurement, Truth};

use super::fields::{HEADER, T_SIM};

/// Why a message's field could not be decoded.
#[derive(Debug, thiserror::Error)]
pub enum FieldError {
    /// The message has no such field.
    #[error("no field {0}")]
    Missing(String),
    /// The field holds another type.
    #[error("field {0} is not {1}")]
    Type(String, &'static str),
    /// The message is no JSON object.
    #[error("not a JSON object: {0}")]
    Json(String),
}

/// One recorded message: a flat JSON object of numbers (`null` for NaN).
pub struct Flat(Map<String, Json>);

impl Flat {
    /// Parses the JSON message `data`.
    pub fn parse(data: &[u8]) -> Result<Self, FieldError> {
        serde_json::from_slice(data)
            .map(Flat)
            .map_err(|e| FieldError::Json(e.to_string()))
    }

    fn get(&self, key: &str) -> Result<&Json, FieldError> {
        self.0
            .get(key)
            .ok_or_else(|| FieldError::Missing(key.into()))
    }

    fn int(&self, key: &str) -> Result<u64, FieldError> {
        self.get(key)?
            .as_u64()
            .ok_or_else(|| FieldError::Type(key.into(), "an unsigned integer"))
    }

    /// A number; `null` is NaN (the recorder writes NaN and ±∞ so).
    fn num(&self, key: &str) -> Result<f64, FieldError> {
        match self.get(key)? {
            Json::Null => Ok(f64::NAN),
            v => v
                .as_f64()
                .ok_or_else(|| FieldError::Type(key.into(), "a number")),
        }
    }

    /// The fields `name_0 .. name_{len-1}`, the rest zero.
    fn array<const N: usize>(&self, name: &str, len: usize) -> Result<[f64; N], FieldError> {
        let mut a = [0.0; N];
        for (i, v) in a.iter_mut().enumerate().take(len) {
            *v = self.num(&format!("{name}_{i}"))?;
        }
        Ok(a)
    }

    fn header(&self) -> Result<Header, FieldError> {
        let [seq, trial, step, flags] = HEADER;
        Ok(Header {
            seq: self.int(seq)?,
            trial: self.int(trial)?,
            step: self.int(step)?,
            flags: self.int(flags)?,
            t_sim: self.num(T_SIM)?,
        })
    }

    /// A `/plant/measurement` of `n` state and `m` action components.
    pub fn measurement(&self, n: usize, m: usize) -> Result<Measurement, FieldError> {
        Ok(Measurement {
            header: self.header()?,
            n_x: n as u64,
            n_u: m as u64,
            reward: self.num("reward")?,
            y: self.array::<MAX_X>("y", n)?,
            u_applied: self.array::<MAX_U>("u_applied", m)?,
            u_next: self.array::<MAX_U>("u_next", m)?,
            delay_s: self.num("delay_s")?,
            ..Measurement::default()
        })
    }

    /// An `/observer/estimate`.
    pub fn estimate(&self, n: usize, m: usize) -> Result<Estimate, FieldError> {
        Ok(Estimate {
            header: self.header()?,
            n_x: n as u64,
            n_u: m as u64,
            reward: self.num("reward")?,
            x: self.array::<MAX_X>("x", n)?,
            u_applied: self.array::<MAX_U>("u_applied", m)?,
            ..Estimate::default()
        })
    }

    /// An `/agent/action`.
    pub fn action(&self, m: usize) -> Result<Action, FieldError> {
        Ok(Action {
            header: self.header()?,
            n_u: m as u64,
            u: self.array::<MAX_U>("u", m)?,
            ..Action::default()
        })
    }

    /// A `/plant/truth`.
    pub fn truth(&self, n: usize) -> Result<Truth, FieldError> {
        Ok(Truth {
            header: self.header()?,
            n_x: n as u64,
            x: self.array::<MAX_X>("x", n)?,
            ..Truth::default()
        })
    }
}
