//! Benchmarks and studies on top of the rig's runtime: the realtime loop's latency
//! budget ([`latency`]), the lockstep loop against a raw ping-pong ([`loop_bench`]), the
//! thesis's figures ([`reproduce`]), the delay study ([`delay_study`]), the sensitivity
//! analysis ([`sensitivity`]), time responses of learned policies ([`response`]) and the
//! pendulum's optimal-control reference ([`optimal`]).

pub mod delay_study;
pub mod latency;
pub mod loop_bench;
pub mod optimal;
pub mod reproduce;
pub mod response;
pub mod sensitivity;
