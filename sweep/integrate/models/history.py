"""Load-history scene (docs/physics.md, "Load histories"): the quasi-static right-hand side under a piecewise-constant
load-point velocity, for the aging and the slip law.

Reduced as in the driven scene (xi = x/D0, tau = V t/D0, psi = V phi/D0, u = ln psi, V the grid's velocity), with the
load point moving at r V (r = the segment's ``V_ratio``) and the friction measured from the steady state at V in
units of A, s = (mu - mu_d(V))/A = chi z/A (z the reduced spring stretch beyond its length at rest):

    force balance (paper eq. 1, 6, quasi-static):  w = ln xi' = s - a u - b u^2 - u,    a = mu1(V)/A, b = m2/A
    spring (dmu/dt = k_lab (v_lp - v), k_lab = K/(M g)):   s' = k (r - e^w),             k = chi/A
    state law (sweep/integrate/models/state_laws.py):       aging u' = e^-u - e^w;  slip u' = -e^w (w + u)

Steady sliding at r V: u = -ln r, w = ln r, s = -a ln r + b (ln r)^2. The log-velocity w is a function of the state,
so a hold (r = 0, w -> -inf) and a reslide are the same smooth equations.

With inertia (G = gamma/A > 0, gamma = V^2/(g D0); Newton's law M x'' = K (x_lp - x) - M g mu(x', phi), PHYSICS.md 7)
s is the spring's force, the friction the laboratory measures, and the slider's friction lags it by the inertial
term: G xi'' = s - a u - b u^2 - u - w = P, so w = ln xi' becomes a third state,

    w' = P e^-w / G,    s' = k (r - e^w),    u' = e^-u - e^w (aging)

relaxing at the rate R = e^-w/G (stiff for small G and at small slip velocity, in every hold).

Plunge-resolving time sigma (as the stop's, sweep/integrate/models/stop_inertial.py). Where k G is large an inertial
swing (a step up, the start of a hold, a reslide) ends in a plunge: the slider overshoots, the spring's force s
falls far below the friction, and w falls to s - a u - b u^2 - u (measured: to -55 at k G = 2e2, -164 at 2e3)
while P = O(1) relaxes at the rate R = e^-w/G, which grows by e per unit fall of w: w(tau) has a log singularity and
the steps in tau shrink below the resolution of tau (step_underflow). :func:`inertial_history_mapped` integrates
(s, u, w, tau) in sigma instead, with its analytic Jacobian for Rosenbrock steps:

    dtau/dsigma = W = 1/(1 + mu R d^2),   d = max(0, |P| - P_z),   d(s, u, w)/dsigma = W (the rates above),

mu = PLUNGE_WEIGHT, P_z = DEAD_BAND tol (1 + |w|). W = 1 on the slow path (P slaved, ~ rate/R, inside the band) and
up to rounding in the swing (R ~ 1/G, P ~ sqrt(k G): mu R P^2 ~ 1e-6 k), and W ~ 1/(mu R P^2) in the plunge,
where w then falls at ~1/(mu P) per unit sigma, smoothly, until P enters the band (the last P_z of the fall: R
constant to a factor e^P_z, a linear stiff decay that the L-stable steps follow in tau). The map changes the time,
not the solution; W R is computed as 1/(1/R + mu d^2), finite however large R.
"""

from __future__ import annotations

import math

from numba import njit

from ...jitcache import pin_module
from ..solvers.fastmath import FAST
from ..solvers.vmath import EXP_MAX

__all__ = ["AGING", "LAW_CODES", "LN_R_MAX", "PLUNGE_WEIGHT", "SLIP", "history_rates", "inertial_history_mapped",
           "steady_state", "DEAD_BAND"]

PLUNGE_WEIGHT = 1e-6
"""mu of the time map dtau/dsigma = 1/(1 + mu R P^2) (module docstring): sigma takes over from tau once the inertial
term relaxes at a rate R > ~1/(mu P^2), in the plunge at the end of a swing, and not on the slow path (the stop's
value, sweep.integrate.models.stop_inertial.PLUNGE_WEIGHT)."""
DEAD_BAND = 10.0
"""The map is off (W = 1) where |P| <= P_z = DEAD_BAND tol (1 + |w|) (tol: the step's local tolerance, which
bounds the error of w at tol (1 + |w|)): there w has at most P_z left to fall, R is constant to a factor e^P_z and
P decays like a linear stiff mode, which the L-stable steps in tau follow; without the band the map would hold tau
still (W ~ 1/(mu R P^2), R up to e^600) while the error control keeps P at the noise of w (measured: P ~ 1e-5
at w = -164, steps of 1e-16, max_steps)."""
LN_R_MAX = 600.0
"""Cap of ln R = -w - ln G in the mapped system: beyond it P relaxes in far less than any step, and W R stays ~1/(mu
P^2) whatever R, so the cap only keeps R finite."""
AGING, SLIP = 0, 1
LAW_CODES = {"aging": AGING, "slip": SLIP}
"""State law name (Scene.state_law) -> the integer the kernels branch on."""


@njit(inline="always", fastmath=FAST, error_model="numpy")
def history_rates(s, u, r, k, a, b, law):
    """(s', u', w) at the state (s, u) under the load-point velocity ratio r (module docstring; exponents clamped at
    EXP_MAX so that an overflowing stage is rejected by the step's error test instead of raising)."""
    w = s - u * (a + b * u) - u
    e = math.exp(min(w, EXP_MAX))
    ds = k * (r - e)
    if law == SLIP:
        du = -e * (w + u)
    else:
        du = math.exp(min(-u, EXP_MAX)) - e
    return ds, du, w


@njit(inline="always", fastmath=FAST, error_model="numpy")
def inertial_history_mapped(sigma, y, p, f, J, ft, jacobian):
    """The inertial history equations (aging law) in the plunge-resolving time sigma (module docstring): y = (s, u,
    w, tau), p = (k, a, b, G, r, mu, c) with c the dead band's scale (P_z = c (1 + |w|)); rates into f and, when
    ``jacobian``, df/dy into J (autonomous: ft = 0)."""
    k, a, b, g, r, mu, c = p
    s, u, w = y[0], y[1], y[2]
    P = s - u * (a + b * u) - u - w
    ln_r = -w - math.log(g)
    free = 1.0 if ln_r < LN_R_MAX else 0.0  # d ln R/dw = -1 below the cap, 0 above
    R = math.exp(min(ln_r, LN_R_MAX))
    sign_p, sign_w = (1.0 if P >= 0.0 else -1.0), (1.0 if w >= 0.0 else -1.0)
    d = abs(P) - c * (1.0 + abs(w))  # beyond the dead band |P| <= P_z
    band = d > 0.0
    RW = 1.0 / (1.0 / R + mu * d * d) if band else R  # W R, finite however large R (W = 1/(1 + mu R d^2))
    W = RW / R
    e, e_u = math.exp(min(w, EXP_MAX)), math.exp(min(-u, EXP_MAX))
    g0, g1 = k * (r - e), e_u - e
    f[0], f[1], f[2], f[3] = W * g0, W * g1, P * RW, W
    if jacobian:
        # with dP = (1, p1, -1, 0), p1 = -(a + 2 b u + 1), d ln R = (0, 0, -free, 0) and, beyond the band,
        # d(d) = sign(P) dP - c sign(w) (0, 0, 1, 0):
        # dW = -W (1 - W) d ln R - 2 mu d W RW d(d),   d(RW) = W RW d ln R - 2 mu d RW^2 d(d)
        p1 = -(a + 2.0 * b * u + 1.0)
        m = 2.0 * mu * d if band else 0.0
        dd0, dd1, dd2 = sign_p, sign_p * p1, -sign_p - c * sign_w
        q = m * W * RW
        dW0, dW1, dW2 = -q * dd0, -q * dd1, W * (1.0 - W) * free - q * dd2
        q = m * RW * RW
        dR0, dR1, dR2 = -q * dd0, -q * dd1, -W * RW * free - q * dd2
        J[0, 0], J[0, 1], J[0, 2], J[0, 3] = g0 * dW0, g0 * dW1, W * (-k * e) + g0 * dW2, 0.0
        J[1, 0], J[1, 1], J[1, 2], J[1, 3] = g1 * dW0, W * (-e_u) + g1 * dW1, W * (-e) + g1 * dW2, 0.0
        J[2, 0], J[2, 1], J[2, 2], J[2, 3] = RW + P * dR0, p1 * RW + P * dR1, -RW + P * dR2, 0.0
        J[3, 0], J[3, 1], J[3, 2], J[3, 3] = dW0, dW1, dW2, 0.0
        ft[0], ft[1], ft[2], ft[3] = 0.0, 0.0, 0.0, 0.0


@njit(inline="always", fastmath=FAST, error_model="numpy")
def steady_state(r, a, b):
    """(s, u) of steady sliding at the load-point velocity r V (r > 0): u = -ln r, s = -a ln r + b (ln r)^2."""
    lr = math.log(r)
    return -a * lr + b * lr * lr, -lr


pin_module(__name__)
