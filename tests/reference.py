"""Independent high-accuracy reference for the quasi-static stop scene (docs/physics.md 3a), scipy only.

This module must not import anything from the ``sweep`` package: it is what the engine is tested against.

Equations, in the paper's own form (reduced units, ' = d/dtau, u = ln psi, mu1 = mu1(V) given as a number):

    xi' = exp(-(chi xi + mu1 u + m2 u^2)/A - u),    u' = exp(-u) - xi',    xi(0) = 0, u(0) = 0.

They are integrated in the log time S = ln(1 + tau) (d/dS = (1 + tau) d/dtau = e^S d/dtau) with
``scipy.integrate.solve_ivp`` at rtol 1e-13, in two phases whose second state variable is the one that carries
u = ln psi without cancellation (the factor e^S is folded into the exponents, so nothing overflows even where
tau = e^S - 1 itself would exceed the float range):

* early, while u < S/2 (psi < sqrt(1 + tau)), state (xi, u):

      dxi/dS = exp(S - u - (chi xi + mu1 u + m2 u^2)/A),    du/dS = exp(S - u) - dxi/dS;

  here psi ~ 1 and u is small: deep on the stick-slip side (chi << mu1) the slider leaves the unstable steady
  state u* = -chi xi/mu1 ~ 1e-7 at a rate mu1/A, so xi_inf depends on u to ~1e-19 absolute. Written as
  u = v + S, with v = ln(psi/(1 + tau)) ~ -S, that offset drowns in the rounding and the tolerance of v (the
  one-phase DOP853 form was off by 2.4e-7 relative at chi/A = 1e-5, mu1/A = 10);
* late, once u >= S/2 (event), state (xi, v) with v = u - S = ln(psi/(1 + tau)) <= 0 (psi' <= 1):

      dxi/dS = exp(-v - (chi xi + mu1 u + m2 u^2)/A),    dv/dS = expm1(-v) - dxi/dS,     u = v + S;

  since v -> 0 late on (psi ~ tau) psi keeps a relative accuracy ~1e-14 at any tau (integrating u itself would
  leave an error rtol * u in psi/tau, 1e-10 at tau = 1e40).

Method: DOP853 (explicit, order 8) with a budget of right-hand-side evaluations; where that budget runs out
(the stiff "costly corner", small chi/A with mu1 < 0, where psi << tau and u relaxes at the rate
(1 + tau)/psi), the same problem is re-solved with Radau (implicit, order 5) and the analytic Jacobian.

Horizon (finite cases): late on (xi' psi << 1, so du = dtau/psi), exp(chi xi/A) dxi = exp(-dmu(u)/A) du with
dmu(u) = mu1 u + m2 u^2, so the slip still to come after the horizon is

    xi_inf - xi_end = (A/chi) ln(1 + (chi/A) exp(-chi xi_end/A) T(u_end)),   T(u) = int_u^inf exp(-dmu(s)/A) ds

(T in closed form: exponential for m2 = 0, erfcx for m2 > 0). The horizon S_end is chosen so that T is below
1e-17 * min(1, A/chi) (at least S_end = 460, tau ~ 1e200); the integration is extended if u lags S so that
the bound is not met at the end. The remaining tail is then *added* to xi_end (it is the leading-order
correction; its own error is relative O(xi' psi, psi/tau - 1), i.e. utterly negligible) and reported in
``tail``: it is < 1e-14 relative in every case we run, so xi_inf carries the integrator's error only
(< 1e-13 relative: against the m2 = 0 closed form in tests/integrate/test_reference.py and, over chi/A 1e-5..1e4 and
m1/A 0.1..10, in tests/protocols/test_extremes.py; DOP853 and Radau agree to 1e-13 on the case table. The engine's error
estimates are checked down to rtol 1e-9 with an atol floor of 1e-12, so the reference must be well below both).

No finite limit (docs/physics.md 6: m2 < 0, or m2 = 0 with mu1 <= 0): ``finite`` is False, ``xi_inf`` is NaN and
xi(tau), psi(tau) are available up to ``tau_horizon`` (1e12); asking beyond raises ValueError.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import OdeSolution, solve_ivp
from scipy.optimize import brentq
from scipy.special import erfcx

RTOL = 1e-13
S_MIN_FINITE = 460.0  # tau ~ 1e200
TAU_HORIZON_NO_LIMIT = 1e12
TAIL_TARGET = 1e-17  # T(u_end) target, times min(1, A/chi)
DOP853_MAX_NFEV = 120_000  # ~10^4 steps; beyond that the problem is stiff: switch to Radau

__all__ = ["ReferenceSolution", "TwoPhaseSolution", "reference_stop", "reference_stop_from", "has_finite_limit",
           "tail_integral"]


def has_finite_limit(mu1: float, m2: float) -> bool:
    """docs/physics.md 6: xi_inf is finite iff m2 > 0, or m2 == 0 and mu1 > 0."""
    return m2 > 0.0 or (m2 == 0.0 and mu1 > 0.0)


def tail_integral(u0: float, A: float, mu1: float, m2: float) -> float:
    """T(u0) = int_{u0}^inf exp(-(mu1 s + m2 s^2)/A) ds (finite cases only)."""
    if m2 == 0.0:
        return (A / mu1) * math.exp(-mu1 * u0 / A)
    a = m2 / A
    b = mu1 / (2.0 * m2)
    x = math.sqrt(a) * (u0 + b)
    expo = -(mu1 * u0 + m2 * u0 * u0) / A
    if x < 0.0:  # the minimum of dmu lies beyond u0: use erfc directly (no cancellation issue there)
        return 0.5 * math.sqrt(math.pi / a) * math.exp(a * b * b) * math.erfc(x)
    return 0.5 * math.sqrt(math.pi / a) * float(erfcx(x)) * math.exp(expo)


def _u_for_tail(A: float, chi: float, mu1: float, m2: float) -> float:
    """Smallest u0 (>= 0) with T(u0) <= TAIL_TARGET * min(1, A/chi), by bisection on log T (T decreasing)."""
    target = math.log(TAIL_TARGET * min(1.0, A / chi))

    def g(u):
        t = tail_integral(u, A, mu1, m2)
        return (math.log(t) if t > 0.0 else -1e300) - target

    lo, hi = 0.0, 100.0
    if g(lo) <= 0.0:
        return 0.0
    while g(hi) > 0.0:
        hi *= 2.0
        if hi > 1e9:
            raise RuntimeError("tail does not decay: no finite limit?")
    return brentq(g, lo, hi, xtol=1e-6)


class TwoPhaseSolution:
    """Dense output over S of the two phases (module docstring), as the state (xi, u = ln psi); ``ts`` are the
    step points of both phases (increasing)."""

    def __init__(self, early: OdeSolution | None, late: OdeSolution | None):
        """``early`` is None for a start already in the late phase (:func:`reference_stop_from`)."""
        self.early, self.late = early, late
        self.S_switch = late.t_min if late is not None else math.inf
        if early is None:
            self.ts = late.ts
        else:
            self.ts = early.ts if late is None else np.concatenate((early.ts, late.ts[1:]))

    def __call__(self, S) -> np.ndarray:
        S = np.asarray(S, dtype=float)
        flat = np.atleast_1d(S).ravel()
        y = np.empty((2, flat.size))
        first = flat <= self.S_switch if self.early is not None else np.zeros(flat.shape, dtype=bool)
        if np.any(first):
            y[:, first] = self.early(flat[first])
        if np.any(~first):
            xi, v = self.late(flat[~first])
            y[:, ~first] = xi, v + flat[~first]
        return y.reshape((2,) + S.shape)


@dataclass(frozen=True)
class ReferenceSolution:
    """Reference stop transient for (chi, A, mu1, m2). ``sol`` gives the state (xi, u = ln psi) at S = ln(1 + tau)
    (:class:`TwoPhaseSolution`)."""

    chi: float
    A: float
    mu1: float
    m2: float
    finite: bool
    xi_inf: float  # NaN when there is no finite limit
    xi_end: float  # xi at the horizon
    tail: float  # slip added beyond the horizon (finite cases; 0 otherwise)
    S_end: float  # horizon in S = ln(1 + tau)
    tau_horizon: float  # e^S_end - 1 (inf if it overflows)
    method: str  # "DOP853" or "Radau"
    nfev: int
    seconds: float
    sol: TwoPhaseSolution = field(repr=False, compare=False)

    def _S(self, tau) -> np.ndarray:
        tau = np.asarray(tau, dtype=float)
        if np.any(tau < 0.0) or np.any(np.isnan(tau)):
            raise ValueError("tau must be >= 0")
        S = np.log1p(tau)
        if not self.finite and np.any(S > self.S_end * (1.0 + 1e-12)):
            raise ValueError(f"no finite limit: xi(tau) is only computed up to tau = {self.tau_horizon:.3g}")
        return S

    def _state(self, tau):
        """(S, xi, u) at tau; beyond the horizon xi and u - S are frozen at their values there."""
        S = self._S(tau)
        Sc = np.minimum(S, self.S_end)
        y = self.sol(Sc)
        return S, y[0], y[1] + (S - Sc)

    def xi(self, tau):
        """Reduced slip xi(tau) (vectorised). Beyond the horizon of a finite case: the remaining tail is
        below 1e-14 relative, and xi_inf is returned."""
        S, xi, _ = self._state(tau)
        if self.finite:
            xi = np.where(S >= self.S_end, self.xi_inf, xi)
        return xi[()] if xi.ndim == 0 else xi

    slip_at_tau = xi

    def psi(self, tau):
        """Reduced contact age psi(tau) = V phi/D0 (vectorised). Beyond a finite case's horizon psi/(1 + tau) is
        frozen at its value there (d(psi - tau)/dtau = -xi' psi ~ 0, so psi/(1 + tau) = 1 to ~1e-14)."""
        _, _, u = self._state(tau)
        p = np.exp(u)
        return p[()] if p.ndim == 0 else p

    def tau_at_fraction(self, f: float) -> float:
        """tau at which xi = f * xi_inf (0 < f < 1), by root finding on the dense output (in S)."""
        if not self.finite:
            raise ValueError("no finite limit: no fraction of xi_inf")
        if not 0.0 < f < 1.0:
            raise ValueError("f must lie in (0, 1)")
        target = f * self.xi_inf
        ts = self.sol.ts
        xs = self.sol(ts)[0]
        i = int(np.searchsorted(xs, target))  # xs is increasing (checked in tests)
        if i == 0 or i >= len(ts):
            raise RuntimeError("fraction not bracketed by the dense output")
        S_root = brentq(lambda S: float(self.sol(S)[0]) - target, ts[i - 1], ts[i], xtol=1e-300, rtol=1e-15,
                        maxiter=200)
        return float(np.expm1(S_root))


def _rhs_factory(chi, A, mu1, m2, late):
    """Right-hand side and Jacobian in S for the early state (xi, u) or, if ``late``, the late state (xi, v),
    v = u - S (module docstring)."""
    c = 1.0 / A

    def parts(S, y):
        """(u, lag = S - u = ln((1 + tau)/psi), q = (chi xi + dmu(u))/A, e = (1 + tau) xi' = exp(lag - q)); late,
        the lag is -v itself (S - (v + S) would round v away where it is tiny)."""
        xi, w = y
        u, lag = (w + S, -w) if late else (w, S - w)
        q = (chi * xi + mu1 * u + m2 * u * u) * c
        return u, lag, q, math.exp(lag - q)

    def rhs(S, y):
        _, lag, q, e = parts(S, y)
        # early: du/dS = e^lag (1 - e^-q) with expm1, since q ~ 1e-7 where the slider leaves the unstable state
        return np.array([e, math.expm1(lag) - e if late else -math.exp(lag) * math.expm1(-q)])

    def jac(S, y):
        u, lag, _, e = parts(S, y)
        de_dxi = -chi * c * e
        de_dw = -(1.0 + (mu1 + 2.0 * m2 * u) * c) * e
        return np.array([[de_dxi, de_dw], [-de_dxi, -math.exp(lag) - de_dw]])

    return rhs, jac


class _Budget(Exception):
    pass


def _switch(S, y):
    """Event of the hand-over to the late state: u = S/2 (crossed upwards)."""
    return y[1] - 0.5 * S


_switch.terminal = True
_switch.direction = 1.0


def _solve_phase(chi, A, mu1, m2, S0, S_end, y0, method, count, budget, late):
    rhs, jac = _rhs_factory(chi, A, mu1, m2, late)
    # u early: nearly relative (1e-20 resolves the 1e-7 offset from the unstable state to 1e-13; a smaller floor
    # makes the steps vanish where u = O(S^2) at the start)
    atol = np.array([1e-16 * min(1.0, A / chi), 1e-14 if late else 1e-20])

    def f(S, y):
        count[0] += 1
        if count[0] > budget:
            raise _Budget
        return rhs(S, y)

    options = {"jac": jac} if method == "Radau" else {}
    res = solve_ivp(f, (S0, S_end), y0, method=method, rtol=RTOL, atol=atol, dense_output=True,
                    events=None if late else _switch, **options)
    if not res.success:
        raise RuntimeError(f"{method} failed for chi={chi}, A={A}, mu1={mu1}, m2={m2}: {res.message}")
    return res


def _solve(chi, A, mu1, m2, S_end, method, budget, S0=0.0, xi0=0.0, u0=0.0):
    """Both phases from the state (xi0, u0) at S0 (default: the stop, (0, 0) at 0) up to S_end; returns
    (TwoPhaseSolution, (xi, u) at S_end, evaluations)."""
    count = [0]
    if S0 > 0.0 and u0 >= 0.5 * S0:  # the start is already in the late phase
        late = _solve_phase(chi, A, mu1, m2, S0, S_end, [xi0, u0 - S0], method, count, budget, late=True)
        return TwoPhaseSolution(None, late.sol), late.y[:, -1] + [0.0, S_end], count[0]
    early = _solve_phase(chi, A, mu1, m2, S0, S_end, [xi0, u0], method, count, budget, late=False)
    if early.status != 1:  # u stayed below S/2 up to the horizon
        return TwoPhaseSolution(early.sol, None), early.y[:, -1], count[0]
    S_sw, (xi_sw, u_sw) = float(early.t_events[0][0]), early.y_events[0][0]
    late = _solve_phase(chi, A, mu1, m2, S_sw, S_end, [xi_sw, u_sw - S_sw], method, count, budget, late=True)
    return TwoPhaseSolution(early.sol, late.sol), late.y[:, -1] + [0.0, S_end], count[0]


@functools.cache
def reference_stop(chi: float, A: float, mu1: float, m2: float, method: str = "auto") -> ReferenceSolution:
    """Reference quasi-static stop transient (cached). ``method``: "auto" (DOP853 with a budget of
    DOP853_MAX_NFEV evaluations, then Radau), "DOP853" (no budget) or "Radau" (forced; for cross-checks)."""
    return _reference(float(chi), float(A), float(mu1), float(m2), method, 0.0, 0.0, 0.0)


@functools.cache
def reference_stop_from(chi: float, A: float, mu1: float, m2: float, S0: float, xi0: float, u0: float,
                        method: str = "auto") -> ReferenceSolution:
    """As :func:`reference_stop`, but the quasi-static transient continues from the state xi = xi0, u = ln psi =
    u0 at S = S0 = ln(1 + tau0) (cached; used by reference_inertial.py after its hand-over). ``sol``, ``xi`` and
    ``psi`` are then defined for tau >= tau0 only; ``xi_inf`` is the limit of that continuation."""
    S0, xi0, u0 = float(S0), float(xi0), float(u0)
    if not (S0 >= 0.0 and math.isfinite(xi0) and math.isfinite(u0)):
        raise ValueError("need S0 >= 0 and a finite state")
    return _reference(float(chi), float(A), float(mu1), float(m2), method, S0, xi0, u0)


def _reference(chi, A, mu1, m2, method, S0, xi0, u0) -> ReferenceSolution:
    if not (chi > 0.0 and A > 0.0):
        raise ValueError("chi and A must be > 0")
    t0 = time.perf_counter()
    finite = has_finite_limit(mu1, m2)
    if finite:
        u_need = _u_for_tail(A, chi, mu1, m2)
        S_end = max(S_MIN_FINITE, u_need + 10.0)
    else:
        u_need = None
        S_end = math.log1p(TAU_HORIZON_NO_LIMIT)
    if S0 >= S_end:
        raise ValueError(f"start S0 = {S0} lies beyond the horizon S_end = {S_end}")

    methods = ["DOP853", "Radau"] if method == "auto" else [method]
    for _ in range(8):  # extend the horizon if u lags S too much for the tail bound
        res = None
        for m in methods:
            try:
                res = _solve(chi, A, mu1, m2, S_end, m, DOP853_MAX_NFEV if m == "DOP853" and method == "auto"
                             else math.inf, S0, xi0, u0)
                used = m
                break
            except _Budget:
                continue
        if res is None:
            raise RuntimeError("DOP853 step budget exhausted and no fallback")
        sol, (xi_end, u_end), nfev = res
        if not finite or u_end >= u_need:
            break
        S_end += 2.0 * (u_need - u_end) + 10.0
    else:
        raise RuntimeError("could not reach the horizon needed for the tail bound")

    if finite:
        T = tail_integral(u_end, A, mu1, m2)
        tail = (A / chi) * math.log1p((chi / A) * math.exp(-chi * xi_end / A) * T)
        xi_inf = xi_end + tail
    else:
        tail = 0.0
        xi_inf = math.nan
    tau_h = math.expm1(S_end) if S_end < 709.0 else math.inf
    return ReferenceSolution(chi=chi, A=A, mu1=mu1, m2=m2, finite=finite, xi_inf=xi_inf, xi_end=xi_end,
                             tail=tail, S_end=S_end, tau_horizon=tau_h, method=used, nfev=int(nfev),
                             seconds=time.perf_counter() - t0, sol=sol)
