"""The stop equations for a linearly implicit (Rosenbrock) step: scalar, in contact-age time s, with a step rule.

In s the state is the single number xi (u = s - xi, :mod:`sweep.integrate.models.stop`):

    dxi/ds = E(xi, s) = exp(-(chi xi + mu1 u + m2 u^2)/A),
    J = dE/dxi = E (g - k),    dE/ds = -g E,    g = a + 2 b u,  k = chi/A, a = mu1/A, b = m2/A.

Why a second form: in the costly corner of the grid (small chi/A with mu1 < 0) the slider creeps along a slow
manifold (E ~ 1, u drifting over hundreds of s) that attracts at the rate |g| ~ |mu1|/A. An explicit method
must resolve that rate everywhere (thousands of RK4 steps, stability-limited), a Rosenbrock method only the
drift. The Jacobian is one number, so the "linear solve" of every stage is one multiplication by 1/(1/(gamma H)
- J), computed once per step.

The step in s follows a rule (no controller), H = h w(s, u):

    w = 1/(1/(s + s_c) + r),    r = (g + sqrt(g^2 + |b|/4))/2 + STIFF_RATE_FLOOR,

logarithmic early (s_c as in :mod:`sweep.integrate.models.stop`) and, late, resolving only the decay rate g of E in the
tail (g > 0), not the attraction rate of the manifold (g < 0), which the explicit map's r = sqrt(g^2 + |b|/4)
must follow. The rule is smooth in the state, so the Richardson pair (steps h and h/2) keeps its asymptotic
expansion (Hairer, Norsett & Wanner I, Sec. II.8: step sizes h theta(s) with smooth theta).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ...accuracy import STIFF_RATE_FLOOR
from ...jitcache import pin, pin_module
from ..solvers.vmath import exp_f32, exp_f64
from .stop import FAST


def make_stiff_rate(dtype):
    """(stiff_rate, step_factor) for one float type, vectorisable over lanes:
    stiff_rate(xi, s, k, a, b) -> (E = dxi/ds, exponent of E); step_factor(s, g, b, s_c) -> w of the step rule
    (module docstring) at the local rate g."""
    f = np.dtype(dtype).type
    exp = exp_f32 if f is np.float32 else exp_f64
    one, half, quarter, floor = f(1.0), f(0.5), f(0.25), f(STIFF_RATE_FLOOR)

    @njit(inline="always", fastmath=FAST, error_model="numpy", cache=True)
    def stiff_rate(xi, s, k, a, b):
        u = s - xi
        expo = -(k * xi + u * (a + b * u))
        return exp(expo), expo

    @njit(inline="always", fastmath=FAST, error_model="numpy", cache=True)
    def step_factor(s, g, b, s_c):
        r = half * (g + math.sqrt(g * g + quarter * abs(b))) + floor
        return (s + s_c) / (one + r * (s + s_c))

    return pin(stiff_rate, f.__name__), pin(step_factor, f.__name__)


pin_module(__name__)
