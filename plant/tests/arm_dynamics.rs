//! The two-link arm's equation of motion (Appendix A.2),
//! `M(φ) φ̈ + C(φ, φ̇) φ̇ + G(φ) = u`, against computations that do not use the plant's
//! `M`, `C` or `G`:
//!
//! * the kinetic energy of the two rigid links from their geometry — each link's centre
//!   of mass moving as the joints turn it, and its rotation about that centre — and the
//!   potential whose gradient is the `G` of Appendix A.2;
//! * with no input and no friction, that energy is conserved along a trajectory of the
//!   plant's dynamics (integrated here by a classical RK4 step of this file), up to an
//!   error that shrinks with the step as RK4's does;
//! * at any state and input, the plant's `φ̈` satisfies the Euler–Lagrange equations of
//!   that Lagrangian, `d/dt ∂L/∂φ̇ − ∂L/∂φ = u − b φ̇` (`b` the viscous friction), all
//!   derivatives of `L` taken by central differences.
//!
//! `G` as Appendix A.2 prints it (and the plant implements it),
//! `[g l₁ (m₁ + m₂) sin φ₁, g l₂ m₂ sin φ₂]`, is the gradient of
//! `V(φ) = −g l₁ (m₁ + m₂) cos φ₁ − g l₂ m₂ cos φ₂` — not of the potential of the links'
//! centres of mass, which the thesis's `G` does not follow. `M` is the geometry's (with
//! `φ₂` the angle of link 2 relative to link 1 and `I₁`, `I₂` about the centres of mass),
//! and `C` must be the Coriolis and centrifugal terms of that `M`. With the sign of `C`'s
//! lower-left entry `P₃ φ̇₁ sin φ₂` flipped in `plant/src/two_link.rs` both tests fail
//! (an energy drift of 1.6 J, an Euler–Lagrange residual of 2.5 N m); with that of its
//! upper-left entry `−P₃ φ̇₂ sin φ₂`, too (5.2 J, 1.7 N m).

use plant::Dynamics;
use plant::two_link::TwoLink;

/// Table A.2 of the thesis (vertical plane, gravity 9.81 m/s²).
const TABLE_A2: Params = Params {
    l: [0.3825, 0.1],
    m: [0.809, 0.852],
    c: [0.07, 0.2450],
    i: [0.1449, 0.1635],
    g: 9.81,
    b: [0.0, 0.0],
};

/// Link lengths, masses, centres of mass, inertias about the centres of mass, gravity,
/// viscous friction: the thesis's symbols.
#[derive(Clone, Copy)]
struct Params {
    l: [f64; 2],
    m: [f64; 2],
    c: [f64; 2],
    i: [f64; 2],
    g: f64,
    b: [f64; 2],
}

impl Params {
    fn of(arm: &TwoLink) -> Self {
        Self {
            l: arm.length,
            m: arm.mass,
            c: arm.centre_of_mass,
            i: arm.inertia,
            g: arm.gravity,
            b: arm.friction,
        }
    }

    /// Kinetic energy at `(q, q̇)` from the links' geometry (link 1 turning about the
    /// fixed joint, link 2 about the end of link 1 at the absolute angle `q₁ + q₂`):
    /// `½ mₖ |vₖ|²` of each centre of mass, `v₁ = c₁ q̇₁ e(q₁)`,
    /// `v₂ = l₁ q̇₁ e(q₁) + c₂ (q̇₁ + q̇₂) e(q₁ + q₂)` with the unit vector
    /// `e(a) = (cos a, sin a)`, plus `½ Iₖ ωₖ²` of the rotations `ω₁ = q̇₁`,
    /// `ω₂ = q̇₁ + q̇₂` about the centres of mass.
    fn kinetic(&self, q: [f64; 2], qd: [f64; 2]) -> f64 {
        let e = |a: f64| [a.cos(), a.sin()];
        let (w1, w2) = (qd[0], qd[0] + qd[1]);
        let (e1, e12) = (e(q[0]), e(q[0] + q[1]));
        let v1 = [self.c[0] * w1 * e1[0], self.c[0] * w1 * e1[1]];
        let v2 = [
            self.l[0] * w1 * e1[0] + self.c[1] * w2 * e12[0],
            self.l[0] * w1 * e1[1] + self.c[1] * w2 * e12[1],
        ];
        let sq = |v: [f64; 2]| v[0] * v[0] + v[1] * v[1];
        0.5 * (self.m[0] * sq(v1) + self.m[1] * sq(v2) + self.i[0] * w1 * w1 + self.i[1] * w2 * w2)
    }

    /// The potential whose gradient is Appendix A.2's `G`.
    fn potential(&self, q: [f64; 2]) -> f64 {
        -self.g * self.l[0] * (self.m[0] + self.m[1]) * q[0].cos()
            - self.g * self.l[1] * self.m[1] * q[1].cos()
    }

    fn lagrangian(&self, q: [f64; 2], qd: [f64; 2]) -> f64 {
        self.kinetic(q, qd) - self.potential(q)
    }

    fn energy(&self, x: &[f64; 4]) -> f64 {
        self.kinetic([x[0], x[1]], [x[2], x[3]]) + self.potential([x[0], x[1]])
    }
}

/// The plant's state derivative `[φ̇, φ̈]` at `x` under input `u`.
fn f(arm: &dyn Dynamics, x: &[f64; 4], u: [f64; 2]) -> [f64; 4] {
    let mut dx = [0.0; 4];
    arm.derivative(x, &u, &mut dx);
    dx
}

/// One classical Runge–Kutta step of `h` with no input.
fn rk4(arm: &dyn Dynamics, x: &[f64; 4], h: f64) -> [f64; 4] {
    let add = |x: &[f64; 4], k: &[f64; 4], s: f64| std::array::from_fn(|i| x[i] + s * k[i]);
    let k1 = f(arm, x, [0.0; 2]);
    let k2 = f(arm, &add(x, &k1, h / 2.0), [0.0; 2]);
    let k3 = f(arm, &add(x, &k2, h / 2.0), [0.0; 2]);
    let k4 = f(arm, &add(x, &k3, h), [0.0; 2]);
    std::array::from_fn(|i| x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
}

/// The largest deviation of the energy from its initial value over `seconds` of
/// motion from `x0`, integrated with steps of `h`.
fn energy_drift(arm: &dyn Dynamics, p: &Params, x0: [f64; 4], seconds: f64, h: f64) -> f64 {
    let e0 = p.energy(&x0);
    let mut x = x0;
    let mut worst: f64 = 0.0;
    for _ in 0..(seconds / h).round() as usize {
        x = rk4(arm, &x, h);
        worst = worst.max((p.energy(&x) - e0).abs());
    }
    worst
}

#[test]
fn the_plant_has_the_parameters_of_table_a2() {
    let p = Params::of(&TwoLink::vertical());
    assert_eq!(
        (p.l, p.m, p.c, p.i, p.g, p.b),
        (
            TABLE_A2.l, TABLE_A2.m, TABLE_A2.c, TABLE_A2.i, TABLE_A2.g, TABLE_A2.b
        )
    );
}

/// The vertical arm (Case I, with gravity), swinging freely for 2 s from a state with
/// both links moving (2.2 J of kinetic energy, 4.7 J above the lowest point): the energy
/// stays within 1e-8 J of its initial value with steps of 1 ms (measured: 9e-11 J). RK4's
/// error per unit time is `O(h⁴)`, so with steps of 2 ms the drift must be about 16
/// times larger (measured 1.4e-9 J; more than 8 times is asserted): what remains is the
/// integrator's, not the model's. With a sign of `C` flipped the energy drifts by 1.6 J
/// (lower-left entry) or 5.2 J (upper-left), whatever the step.
#[test]
fn the_vertical_arm_conserves_its_energy_without_input_and_friction() {
    let task = plant::Task::new(plant::SystemName::ArmVertical);
    let p = Params::of(&TwoLink::vertical());
    let x0 = [0.8, -1.3, 4.0, -5.0];
    let swing = p.energy(&x0) - p.energy(&[0.0; 4]);
    let moving = p.kinetic([x0[0], x0[1]], [x0[2], x0[3]]);
    assert!(swing > 4.0 && moving > 2.0, "{swing} J, {moving} J moving");
    let coarse = energy_drift(task.simulation().dynamics.as_ref(), &p, x0, 2.0, 2e-3);
    let fine = energy_drift(task.simulation().dynamics.as_ref(), &p, x0, 2.0, 1e-3);
    assert!(fine < 1e-8, "energy drift {fine} J with 1 ms steps");
    assert!(
        coarse / fine > 8.0,
        "drift {coarse} J with 2 ms steps, {fine} J with 1 ms: not RK4's error"
    );
}

/// The derivative of `g` at 0 by the fourth-order central difference of step `e`
/// (truncation `e⁴/30` of the fifth derivative).
fn d(g: impl Fn(f64) -> f64, e: f64) -> f64 {
    (8.0 * (g(e) - g(-e)) - (g(2.0 * e) - g(-2.0 * e))) / (12.0 * e)
}

/// `d/dt ∂L/∂φ̇ − ∂L/∂φ = u − b φ̇` at the plant's `φ̈`, with every derivative of `L` a
/// difference quotient: `∂L/∂φ̇ᵢ` a central difference of step 1 (exact up to rounding,
/// `L` being quadratic in `φ̇`), its derivative along the motion `(φ̇, φ̈)` and `∂L/∂φᵢ`
/// fourth-order differences of step 1e-3 (truncation about 1e-12 times the fifth
/// derivative, rounding about 1e-13 times `L`): residuals of 1e-10 N m or less, 1e-8
/// asserted. At 50 states and inputs drawn from a fixed sequence, for the arm in the
/// vertical plane (Table A.2), in the horizontal plane (`G = 0`) and the §6.4.2
/// manipulator (Table 6.3, with its friction).
#[test]
fn the_arms_accelerations_satisfy_the_euler_lagrange_equations() {
    let mut seed = 0x2545_f491_4f6c_dd1d_u64;
    let mut draw = |scale: f64| {
        // xorshift64*: a fixed sequence in [−scale, scale).
        seed ^= seed >> 12;
        seed ^= seed << 25;
        seed ^= seed >> 27;
        let r = seed.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        scale * (2.0 * r as f64 / (1u64 << 53) as f64 - 1.0)
    };
    for arm in [
        TwoLink::vertical(),
        TwoLink::horizontal(),
        TwoLink::manipulator_6_4(),
    ] {
        let p = Params::of(&arm);
        let torque = if p.g > 0.0 { 5.0 } else { 0.5 };
        let mut worst: f64 = 0.0;
        for _ in 0..50 {
            let x = [draw(3.0), draw(3.0), draw(4.0), draw(4.0)];
            let u = [draw(torque), draw(torque)];
            let dx = f(&arm, &x, u);
            let (q, qd, qdd) = ([x[0], x[1]], [x[2], x[3]], [dx[2], dx[3]]);
            let shift = |v: [f64; 2], i: usize, s: f64| {
                let mut v = v;
                v[i] += s;
                v
            };
            // ∂L/∂φ̇ᵢ at (q, q̇)
            let momentum = |q: [f64; 2], qd: [f64; 2], i: usize| {
                (p.lagrangian(q, shift(qd, i, 1.0)) - p.lagrangian(q, shift(qd, i, -1.0))) / 2.0
            };
            for i in 0..2 {
                let along = |s: f64| {
                    momentum(
                        [q[0] + s * qd[0], q[1] + s * qd[1]],
                        [qd[0] + s * qdd[0], qd[1] + s * qdd[1]],
                        i,
                    )
                };
                let d_momentum = d(along, 1e-3);
                let d_q = d(|s| p.lagrangian(shift(q, i, s), qd), 1e-3);
                let residual = d_momentum - d_q - (u[i] - p.b[i] * qd[i]);
                worst = worst.max(residual.abs());
            }
        }
        eprintln!(
            "gravity {}, friction {:?}: worst residual {worst:e}",
            p.g, p.b
        );
        assert!(
            worst < 1e-8,
            "Euler–Lagrange residual {worst} N m (gravity {}, friction {:?})",
            p.g,
            p.b
        );
    }
}
