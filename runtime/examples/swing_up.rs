//! Learn the pendulum swing-up with MLAC/LLR for 60 trials (3 simulated minutes), then
//! print the greedy policy's time response, like the thesis's Figure 6.2.
//!
//! `cargo run --release -p runtime --example swing_up`

use runtime::config::{Overrides, resolve};
use runtime::experiment::Experiment;

fn main() {
    let cfg = resolve(
        None,
        &Overrides {
            trials: Some(60),
            runs: Some(1),
            eval_every: Some(20),
            ..Default::default()
        },
    )
    .expect("the default preset resolves");
    let mut exp = Experiment::new(&cfg, 0);
    while let Some(r) = exp.next_trial() {
        if let Some(g) = r.greedy {
            println!(
                "trial {:3} ({:.1} min): learning return {:8.1}, greedy return {:8.1}",
                r.trial,
                r.sim_time_s / 60.0,
                r.ret,
                g
            );
        }
    }
    let response = exp.greedy_trajectory(&[std::f64::consts::PI, 0.0]);
    println!("\n   t [s]   phi [rad]  phi_dot [rad/s]   u [V]");
    for s in response.iter().step_by(3) {
        println!("{:8.2} {:10.3} {:14.3} {:9.3}", s.t, s.x[0], s.x[1], s.u[0]);
    }
    let ret: f64 = response.iter().map(|s| s.reward).sum();
    println!("return of this trial: {ret:.1}");
}
