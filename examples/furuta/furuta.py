"""The rotary inverted (Furuta) pendulum of the Quanser QUBE-Servo 2, simulated.

Model: the Lagrangian dynamics of the Furuta pendulum (B. S. Cazzolato and Z. Prime, "On
the Dynamics of the Furuta Pendulum", Journal of Control Science and Engineering, 2011,
article 528341), for the QUBE-Servo 2's slender rotary arm and pendulum as the Quanser
QUBE-Servo 2 Rotary Pendulum Workbook models them, with the parameters of the Quanser
QUBE-Servo 2 User Manual:

    motor       R_m = 8.4 ohm, k_t = k_m = 0.042 N m/A = V s/rad
    rotary arm  m_r = 0.095 kg, L_r = 0.085 m
    pendulum    m_p = 0.024 kg, L_p = 0.129 m, g = 9.81 m/s^2

and one of two published sets of the equivalent viscous damping (DAMPING):

    "gym-brt"   D_r = 0.00027, D_p = 0.00005 N m s/rad: Blue River Technology's QUBE-Servo 2
                simulator (github.com/BlueRiverTech/quanser-openai-driver,
                gym_brt/quanser/qube_simulator.py), the default
    "manual"    D_r = 0.0015, D_p = 0.0005 N m s/rad: the User Manual's

With the manual's damping the pendulum's swing decays with a time constant J_b / D_p of
0.27 s, and none of pump.py's energy-pumping controllers brings it within 1.4 rad of
upright in a 4 s trial, even at +-10 V; with gym-brt's (2.7 s) they swing it up at +-5 V.

State x = [theta, alpha, theta_dot, alpha_dot]: the arm's angle, the pendulum's angle
from upright (it hangs at alpha = +-pi), their velocities; input u = V_m, the motor
voltage. As the workbook writes the model: J_r = m_r L_r^2 / 12, J_p = m_p L_p^2 / 12, the
pendulum's centre of mass l_p = L_p / 2 from its pivot, and, with
J_a = J_r + m_p L_r^2 (the arm with the pendulum's mass at its tip),
K = m_p L_p^2 / 4 (the pendulum about the arm's axis, times sin^2 alpha),
J_b = J_p + m_p L_p^2 / 4 (the pendulum about its pivot), C = m_p L_r l_p and the motor
torque tau = k_t (V_m - k_m theta') / R_m:

    (J_a + K sin^2 a) theta'' + C cos a alpha''
        = tau - D_r theta' - 2 K sin a cos a theta' alpha' + C sin a alpha'^2
    C cos a theta'' + J_b alpha''
        = m_p g l_p sin a - D_p alpha' + K sin a cos a theta'^2

(the Euler-Lagrange equations of T = (J_a + K sin^2 a) theta'^2 / 2 + J_b alpha'^2 / 2
+ C cos a theta' alpha', V = m_p g l_p cos a), integrated with fourth-order Runge-Kutta in
steps of at most 1 ms.
"""

import math

from rigkit import rk4
from rigkit.angle import wrap

# Motor
R_M, K_T, K_M = 8.4, 0.042, 0.042
# Rotary arm
M_R, L_R = 0.095, 0.085
# Pendulum link
M_P, L_P = 0.024, 0.129
G = 9.81
# Equivalent viscous damping (D_r, D_p) [N m s/rad], by source (the docstring)
DAMPING = {"gym-brt": (0.00027, 0.00005), "manual": (0.0015, 0.0005)}
DEFAULT_DAMPING = "gym-brt"

J_R = M_R * L_R**2 / 12.0
J_P = M_P * L_P**2 / 12.0
L_CM = L_P / 2.0  # pivot to the pendulum's centre of mass
J_A = J_R + M_P * L_R**2
K = M_P * L_P**2 / 4.0
J_B = J_P + K
C = M_P * L_R * L_CM  # coupling


def derivative(x, u: float, damping=DAMPING[DEFAULT_DAMPING]):
    """x' = f(x, u) of the model above, with damping = (D_r, D_p)."""
    d_r, d_p = damping
    _, a, td, ad = x
    s, c = math.sin(a), math.cos(a)
    tau = K_T * (u - K_M * td) / R_M
    # M [theta'', alpha'']^T = b
    m11 = J_A + K * s * s
    m12 = C * c
    m22 = J_B
    b1 = tau - d_r * td - 2.0 * K * s * c * td * ad + C * s * ad * ad
    b2 = M_P * G * L_CM * s - d_p * ad + K * s * c * td * td
    det = m11 * m22 - m12 * m12
    tdd = (m22 * b1 - m12 * b2) / det
    add = (m11 * b2 - m12 * b1) / det
    return [td, ad, tdd, add]


class Furuta:
    """The pendulum's state, stepped with an action held."""

    H_MAX = 0.001  # longest RK4 step [s]

    def __init__(self, damping: str = DEFAULT_DAMPING):
        self.damping = DAMPING[damping]
        self.x = [0.0, math.pi, 0.0, 0.0]

    def place(self, x0):
        self.x = [x0[0], wrap(x0[1]), x0[2], x0[3]]

    def step(self, u, dt):
        v, d = u[0], self.damping
        x = rk4.integrate(lambda s: derivative(s, v, d), self.x, dt, self.H_MAX)
        # The arm turns freely here (the rig's operating range stops it): only the
        # pendulum's angle wraps.
        self.x = [x[0], wrap(x[1]), x[2], x[3]]

    def state(self):
        return list(self.x)

    def energy(self) -> float:
        """Kinetic plus potential energy (zero hanging at rest), for the model's test."""
        _, a, td, ad = self.x
        s, c = math.sin(a), math.cos(a)
        kinetic = 0.5 * (J_A + K * s * s) * td * td + 0.5 * J_B * ad * ad + C * c * td * ad
        return kinetic + M_P * G * L_CM * (math.cos(a) + 1.0)
