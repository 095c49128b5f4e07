//! The two-link manipulator of Appendix A.2 (Table A.2), state `x = [φ₁, φ₂, φ̇₁, φ̇₂]`
//! as in Chapter 5.
//!
//! `M(φ) φ̈ + C(φ, φ̇) φ̇ + G(φ) = u` with
//! `P₁ = m₁c₁² + m₂l₁² + I₁`, `P₂ = m₂c₂² + I₂`, `P₃ = m₂l₁c₂`.
//! `G` is implemented exactly as Appendix A.2 prints it,
//! `G = [g l₁ (m₁ + m₂) sin φ₁, g l₂ m₂ sin φ₂]`; Case II (§5.4, horizontal plane) sets
//! `G = 0`.

use crate::Dynamics;

/// Viscous joint friction assumed for the §6.4.2 manipulator \[N m s/rad\]
/// (see [`TwoLink::manipulator_6_4`]).
pub const MANIPULATOR_6_4_FRICTION: f64 = 0.125;

/// Parameters of Table A.2 and whether gravity acts (vertical plane, Case I).
#[derive(Clone, Debug, PartialEq)]
pub struct TwoLink {
    /// Link lengths `l₁, l₂` \[m\].
    pub length: [f64; 2],
    /// Link masses `m₁, m₂` \[kg\].
    pub mass: [f64; 2],
    /// Centres of mass `c₁, c₂` \[m\].
    pub centre_of_mass: [f64; 2],
    /// Link inertias `I₁, I₂` \[kg m²\].
    pub inertia: [f64; 2],
    /// Gravity \[m/s²\]; zero in the horizontal plane.
    pub gravity: f64,
    /// Viscous joint friction \[N m s/rad\] (zero in Chapter 5: "no internal damping").
    pub friction: [f64; 2],
}

impl TwoLink {
    /// Table A.2, vertical plane (Case I, §5.3).
    pub fn vertical() -> Self {
        Self {
            length: [0.3825, 0.1],
            mass: [0.809, 0.852],
            centre_of_mass: [0.07, 0.2450],
            inertia: [0.1449, 0.1635],
            gravity: 9.81,
            friction: [0.0, 0.0],
        }
    }

    /// Table A.2, horizontal plane (Case II, §5.4): `G(φ) = 0`.
    pub fn horizontal() -> Self {
        Self {
            gravity: 0.0,
            ..Self::vertical()
        }
    }

    /// The manipulator of §6.4.2 (Table 6.3), horizontal plane (`G(φ) = 0`).
    ///
    /// Table 6.3 prints `I₂ = 1.2·10⁴ kg m²`; `1.2·10⁻⁴` is used (a link of 50 g and
    /// 0.1 m cannot have the printed inertia). The thesis calls the joints' friction
    /// "very high" without a value: viscous friction of `0.125 N m s/rad` per joint is
    /// assumed, which limits the steady velocity under the largest torque (0.1 N m) to
    /// the ±0.8 rad/s the critic's RBF grid covers (Table 6.4).
    pub fn manipulator_6_4() -> Self {
        Self {
            length: [0.1, 0.1],
            mass: [0.125, 0.05],
            centre_of_mass: [0.04, 0.06],
            inertia: [0.074, 1.2e-4],
            gravity: 0.0,
            friction: [MANIPULATOR_6_4_FRICTION; 2],
        }
    }

    fn p(&self) -> [f64; 3] {
        let [l1, _] = self.length;
        let [m1, m2] = self.mass;
        let [c1, c2] = self.centre_of_mass;
        let [i1, i2] = self.inertia;
        [
            m1 * c1 * c1 + m2 * l1 * l1 + i1,
            m2 * c2 * c2 + i2,
            m2 * l1 * c2,
        ]
    }
}

impl Dynamics for TwoLink {
    fn state_dim(&self) -> usize {
        4
    }
    fn action_dim(&self) -> usize {
        2
    }
    fn derivative(&self, x: &[f64], u: &[f64], dx: &mut [f64]) {
        let (p1, p2, w1, w2) = (x[0], x[1], x[2], x[3]);
        let [pp1, pp2, pp3] = self.p();
        let (s2, c2) = p2.sin_cos();
        let m11 = pp1 + pp2 + 2.0 * pp3 * c2;
        let m12 = pp2 + pp3 * c2;
        let m22 = pp2;
        // C(φ, φ̇) φ̇
        let c_1 = -pp3 * w2 * s2 * w1 - pp3 * (w1 + w2) * s2 * w2;
        let c_2 = pp3 * w1 * s2 * w1;
        let g_1 = self.gravity * self.length[0] * (self.mass[0] + self.mass[1]) * p1.sin();
        let g_2 = self.gravity * self.length[1] * self.mass[1] * p2.sin();
        let r1 = u[0] - c_1 - g_1 - self.friction[0] * w1;
        let r2 = u[1] - c_2 - g_2 - self.friction[1] * w2;
        let det = m11 * m22 - m12 * m12;
        dx[0] = w1;
        dx[1] = w2;
        dx[2] = (m22 * r1 - m12 * r2) / det;
        dx[3] = (-m12 * r1 + m11 * r2) / det;
    }
}
