"""The cart-pole of Barto, Sutton and Anderson, simulated.

Model: a pole hinged on a cart that a force pushes along a track (A. G. Barto, R. S.
Sutton and C. W. Anderson, "Neuronlike adaptive elements that can solve difficult
learning control problems", IEEE Transactions on Systems, Man, and Cybernetics 13(5),
1983), with their parameters and without friction, in the corrected form of R. V.
Florian ("Correct equations for the dynamics of the cart-pole system", 2007) — the
equations and parameters of Gymnasium's CartPole (classic_control/cartpole.py):

    cart        m_c = 1.0 kg
    pole        m_p = 0.1 kg, half-length l = 0.5 m (its centre of mass), a uniform rod
    gravity     g = 9.8 m/s^2
    force       F within +-10 N (continuous here; CartPole pushes +-10 N only)

State x = [x, theta, x_dot, theta_dot]: the cart's position on the track (m), the pole's
angle from upright (rad, positive with the pole leaning towards +x; it hangs at theta =
+-pi), their velocities; input u = F, positive towards +x. With M = m_c + m_p:

    theta'' = (g sin th - cos th (F + m_p l th'^2 sin th) / M) / (l (4/3 - m_p cos^2 th / M))
    x''     = (F + m_p l (th'^2 sin th - theta'' cos th)) / M

integrated with fourth-order Runge-Kutta in steps of at most 1 ms. The track's ends are
the task's operating range (the rig ends a trial there), not the model's.
"""

import math

from rigkit import rk4
from rigkit.angle import wrap

M_C, M_P, L, G = 1.0, 0.1, 0.5, 9.8
M = M_C + M_P


def derivative(x, f: float):
    """x' = f(x, u) of the model above."""
    _, th, v, w = x
    s, c = math.sin(th), math.cos(th)
    temp = (f + M_P * L * w * w * s) / M
    thdd = (G * s - c * temp) / (L * (4.0 / 3.0 - M_P * c * c / M))
    xdd = temp - M_P * L * thdd * c / M
    return [v, w, xdd, thdd]


def energy(x) -> float:
    """Kinetic plus potential energy (zero hanging at rest), for the model's test."""
    _, th, v, w = x
    j = M_P * L * L / 3.0  # the rod about its centre of mass
    vx, vy = v + L * w * math.cos(th), -L * w * math.sin(th)
    kinetic = 0.5 * M_C * v * v + 0.5 * M_P * (vx * vx + vy * vy) + 0.5 * j * w * w
    return kinetic + M_P * G * L * (math.cos(th) + 1.0)


class CartPole:
    """The cart-pole's state, stepped with an action held."""

    H_MAX = 0.001  # longest RK4 step [s]

    def __init__(self):
        self.x = [0.0, math.pi, 0.0, 0.0]

    def place(self, x0):
        self.x = [x0[0], wrap(x0[1]), x0[2], x0[3]]

    def step(self, u, dt):
        f = u[0]
        x = rk4.integrate(lambda s: derivative(s, f), self.x, dt, self.H_MAX)
        self.x = [x[0], wrap(x[1]), x[2], x[3]]

    def state(self):
        return list(self.x)
