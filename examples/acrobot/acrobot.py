"""The acrobot, simulated: two links in a vertical plane, the torque on the second joint.

Model: the acrobot of R. S. Sutton and A. G. Barto, *Reinforcement Learning: An
Introduction* (1998, §11.3; from M. W. Spong, "The swing up control problem for the
Acrobot", IEEE Control Systems Magazine 15(1), 1995), with Gymnasium's Acrobot-v1
parameters and equations (gymnasium 1.x, classic_control/acrobot.py, the "book"
dynamics) and a continuous torque instead of Acrobot-v1's three:

    links       m_1 = m_2 = 1 kg, l_1 = 1 m, centres of mass l_c1 = l_c2 = 0.5 m,
                moments of inertia I_1 = I_2 = 1 kg m^2, g = 9.8 m/s^2
    velocities  clipped to |q_1'| <= 4 pi, |q_2'| <= 9 pi rad/s after every step

With q_1 the first link's angle from hanging and q_2 the second's relative to the first:

    d_1 = m_1 l_c1^2 + m_2 (l_1^2 + l_c2^2 + 2 l_1 l_c2 cos q_2) + I_1 + I_2
    d_2 = m_2 (l_c2^2 + l_1 l_c2 cos q_2) + I_2
    phi_2 = m_2 l_c2 g cos(q_1 + q_2 - pi/2)
    phi_1 = -m_2 l_1 l_c2 q_2'^2 sin q_2 - 2 m_2 l_1 l_c2 q_2' q_1' sin q_2
            + (m_1 l_c1 + m_2 l_1) g cos(q_1 - pi/2) + phi_2
    q_2'' = (tau + d_2 / d_1 phi_1 - m_2 l_1 l_c2 q_1'^2 sin q_2 - phi_2)
            / (m_2 l_c2^2 + I_2 - d_2^2 / d_1)
    q_1'' = -(d_2 q_2'' + phi_1) / d_1

integrated with fourth-order Runge-Kutta in steps of at most 5 ms.

The task's state is x = [theta_1, theta_2, theta_1', theta_2'] with theta_1 = q_1 - pi
the first link's angle from upright (it hangs at +-pi) and theta_2 = q_2 (0: the links in
line), both wrapped to [-pi, pi): upright is x = 0.
"""

import math

from rigkit import rk4
from rigkit.angle import wrap

M1 = M2 = 1.0  # link masses [kg]
L1 = 1.0  # the first link's length [m]
LC1 = LC2 = 0.5  # pivot to each link's centre of mass [m]
I1 = I2 = 1.0  # moments of inertia [kg m^2]
G = 9.8
MAX_VEL_1, MAX_VEL_2 = 4.0 * math.pi, 9.0 * math.pi


def terms(s):
    """The equations' d_1, d_2, phi_1 and phi_2 at s = [q_1, q_2, q_1', q_2']."""
    q1, q2, dq1, dq2 = s
    d1 = M1 * LC1**2 + M2 * (L1**2 + LC2**2 + 2.0 * L1 * LC2 * math.cos(q2)) + I1 + I2
    d2 = M2 * (LC2**2 + L1 * LC2 * math.cos(q2)) + I2
    phi2 = M2 * LC2 * G * math.cos(q1 + q2 - math.pi / 2.0)
    phi1 = (
        -M2 * L1 * LC2 * dq2**2 * math.sin(q2)
        - 2.0 * M2 * L1 * LC2 * dq2 * dq1 * math.sin(q2)
        + (M1 * LC1 + M2 * L1) * G * math.cos(q1 - math.pi / 2.0)
        + phi2
    )
    return d1, d2, phi1, phi2


def elbow_drift(s):
    """The torque-free part of q_2'' = (tau + elbow_drift(s)) / elbow_inertia(s)."""
    d1, d2, phi1, phi2 = terms(s)
    return d2 / d1 * phi1 - M2 * L1 * LC2 * s[2] ** 2 * math.sin(s[1]) - phi2


def elbow_inertia(s):
    """m_2 l_c2^2 + I_2 - d_2^2 / d_1: how hard the elbow is to turn at s."""
    d1, d2, _, _ = terms(s)
    return M2 * LC2**2 + I2 - d2**2 / d1


def derivative(s, tau: float):
    """s' = f(s, tau) for s = [q_1, q_2, q_1', q_2'] (q_1 from hanging)."""
    d1, d2, phi1, phi2 = terms(s)
    _, q2, dq1, dq2 = s
    ddq2 = (tau + d2 / d1 * phi1 - M2 * L1 * LC2 * dq1**2 * math.sin(q2) - phi2) / (
        M2 * LC2**2 + I2 - d2**2 / d1
    )
    ddq1 = -(d2 * ddq2 + phi1) / d1
    return [dq1, dq2, ddq1, ddq2]


class Acrobot:
    """The acrobot's state, stepped with a torque held."""

    H_MAX = 0.005  # longest RK4 step [s]

    def __init__(self):
        self.s = [0.0, 0.0, 0.0, 0.0]  # [q_1, q_2, q_1', q_2'], hanging at rest

    def place(self, x0):
        self.s = [wrap(x0[0] + math.pi), wrap(x0[1]), x0[2], x0[3]]

    def step(self, u, dt):
        tau = u[0]
        q1, q2, dq1, dq2 = rk4.integrate(lambda s: derivative(s, tau), self.s, dt, self.H_MAX)
        self.s = [
            q1,
            q2,
            min(max(dq1, -MAX_VEL_1), MAX_VEL_1),
            min(max(dq2, -MAX_VEL_2), MAX_VEL_2),
        ]

    def state(self):
        q1, q2, dq1, dq2 = self.s
        return [wrap(q1 - math.pi), wrap(q2), dq1, dq2]

    def energy(self) -> float:
        """Kinetic plus potential energy (zero hanging at rest), for the model's test."""
        q1, q2, dq1, dq2 = self.s
        d1, d2, _, _ = terms(self.s)
        d22 = M2 * LC2**2 + I2
        kinetic = 0.5 * (d1 * dq1 * dq1 + 2.0 * d2 * dq1 * dq2 + d22 * dq2 * dq2)
        h1 = -LC1 * math.cos(q1)
        h2 = -L1 * math.cos(q1) - LC2 * math.cos(q1 + q2)
        potential = M1 * G * h1 + M2 * G * h2 + (M1 * LC1 + M2 * (L1 + LC2)) * G
        return kinetic + potential
