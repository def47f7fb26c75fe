"""Independent high-accuracy reference for the quasi-static stop scene (PHYSICS.md 3a), scipy only.

This module must not import anything from the ``sweep`` package: it is what the engine is tested against.

Equations, in the paper's own form (reduced units, ' = d/dtau, u = ln psi, mu1 = mu1(V) given as a number):

    xi' = exp(-(chi xi + mu1 u + m2 u^2)/A - u),    u' = exp(-u) - xi',    xi(0) = 0, u(0) = 0.

They are integrated in the log time S = ln(1 + tau) (d/dS = (1 + tau) d/dtau = e^S d/dtau) with
``scipy.integrate.solve_ivp`` at rtol 1e-12, state (xi, v) with v = u - S = ln(psi/(1 + tau)) <= 0
(psi' <= 1 so psi <= 1 + tau). The factor e^S is folded into the exponents,

    dxi/dS = exp(-v - (chi xi + mu1 u + m2 u^2)/A),    dv/dS = expm1(-v) - dxi/dS,     u = v + S,

so nothing overflows even where tau = e^S - 1 itself would exceed the float range (the horizon in S is not
limited by tau <= 1e308), and since v -> 0 late on (psi ~ tau) psi keeps a relative accuracy ~1e-14 at any
tau (integrating u = ln psi itself would leave an error rtol * u in psi/tau, 1e-10 at tau = 1e40).

Method: DOP853 (explicit, order 8) with a budget of right-hand-side evaluations; where that budget runs out
(the stiff "costly corner", small chi/A with mu1 < 0, where psi << tau and dv/dS relaxes at the rate
(1 + tau)/psi), the same problem is re-solved with Radau (implicit, order 5) and the analytic Jacobian.

Horizon (finite cases): late on (xi' psi << 1, so du = dtau/psi), exp(chi xi/A) dxi = exp(-dmu(u)/A) du with
dmu(u) = mu1 u + m2 u^2, so the slip still to come after the horizon is

    xi_inf - xi_end = (A/chi) ln(1 + (chi/A) exp(-chi xi_end/A) T(u_end)),   T(u) = int_u^inf exp(-dmu(s)/A) ds

(T in closed form: exponential for m2 = 0, erfcx for m2 > 0). The horizon S_end is chosen so that T is below
1e-17 * min(1, A/chi) (at least S_end = 460, tau ~ 1e200); the integration is extended if u lags S so that
the bound is not met at the end. The remaining tail is then *added* to xi_end (it is the leading-order
correction; its own error is relative O(xi' psi, psi/tau - 1), i.e. utterly negligible) and reported in
``tail``: it is < 1e-14 relative in every case we run, so xi_inf carries the integrator's error only
(~1e-12 relative, verified against the m2 = 0 closed form in tests/test_reference.py).

No finite limit (PHYSICS.md 6: m2 < 0, or m2 = 0 with mu1 <= 0): ``finite`` is False, ``xi_inf`` is NaN and
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

RTOL = 1e-12
S_MIN_FINITE = 460.0  # tau ~ 1e200
TAU_HORIZON_NO_LIMIT = 1e12
TAIL_TARGET = 1e-17  # T(u_end) target, times min(1, A/chi)
DOP853_MAX_NFEV = 120_000  # ~10^4 steps; beyond that the problem is stiff: switch to Radau

__all__ = ["ReferenceSolution", "reference_stop", "has_finite_limit", "tail_integral"]


def has_finite_limit(mu1: float, m2: float) -> bool:
    """PHYSICS.md 6: xi_inf is finite iff m2 > 0, or m2 == 0 and mu1 > 0."""
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


@dataclass(frozen=True)
class ReferenceSolution:
    """Reference stop transient for (chi, A, mu1, m2). ``sol`` is a scipy OdeSolution in S = ln(1 + tau),
    state (xi, v = ln(psi/(1 + tau)))."""

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
    sol: OdeSolution = field(repr=False, compare=False)

    def _S(self, tau) -> np.ndarray:
        tau = np.asarray(tau, dtype=float)
        if np.any(tau < 0.0) or np.any(np.isnan(tau)):
            raise ValueError("tau must be >= 0")
        S = np.log1p(tau)
        if not self.finite and np.any(S > self.S_end * (1.0 + 1e-12)):
            raise ValueError(f"no finite limit: xi(tau) is only computed up to tau = {self.tau_horizon:.3g}")
        return S

    def _state(self, tau):
        S = self._S(tau)
        Sc = np.minimum(S, self.S_end)
        y = self.sol(Sc.ravel()).reshape((2,) + S.shape)
        return S, y[0], y[1]

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
        S, _, v = self._state(tau)  # v frozen beyond the horizon: psi/(1 + tau) -> const there
        p = np.exp(v + S)
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


def _rhs_factory(chi, A, mu1, m2):
    """Right-hand side and Jacobian in S for the state (xi, v), v = u - S = ln(psi/(1 + tau)) <= 0."""
    c = 1.0 / A

    def rhs(S, y):
        xi, v = y
        u = v + S
        e = math.exp(-v - (chi * xi + mu1 * u + m2 * u * u) * c)  # (1 + tau) xi'
        return np.array([e, math.expm1(-v) - e])  # expm1(-v) = (1 + tau)/psi - 1

    def jac(S, y):
        xi, v = y
        u = v + S
        e = math.exp(-v - (chi * xi + mu1 * u + m2 * u * u) * c)
        de_dxi = -chi * c * e
        de_dv = -(1.0 + (mu1 + 2.0 * m2 * u) * c) * e
        return np.array([[de_dxi, de_dv], [-de_dxi, -math.exp(-v) - de_dv]])

    return rhs, jac


class _Budget(Exception):
    pass


def _solve(chi, A, mu1, m2, S_end, method, budget):
    rhs, jac = _rhs_factory(chi, A, mu1, m2)
    atol = np.array([1e-16 * min(1.0, A / chi), 1e-14])
    if method == "DOP853":
        count = [0]

        def f(S, y):
            count[0] += 1
            if count[0] > budget:
                raise _Budget
            return rhs(S, y)

        res = solve_ivp(f, (0.0, S_end), [0.0, 0.0], method="DOP853", rtol=RTOL, atol=atol, dense_output=True)
    else:
        res = solve_ivp(rhs, (0.0, S_end), [0.0, 0.0], method="Radau", jac=jac, rtol=RTOL, atol=atol,
                        dense_output=True)
    if not res.success:
        raise RuntimeError(f"{method} failed for chi={chi}, A={A}, mu1={mu1}, m2={m2}: {res.message}")
    return res


@functools.cache
def reference_stop(chi: float, A: float, mu1: float, m2: float, method: str = "auto") -> ReferenceSolution:
    """Reference quasi-static stop transient (cached). ``method``: "auto" (DOP853 with a budget of
    DOP853_MAX_NFEV evaluations, then Radau), "DOP853" (no budget) or "Radau" (forced; for cross-checks)."""
    chi, A, mu1, m2 = float(chi), float(A), float(mu1), float(m2)
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

    methods = ["DOP853", "Radau"] if method == "auto" else [method]
    for _ in range(8):  # extend the horizon if u lags S too much for the tail bound
        res = None
        for m in methods:
            try:
                res = _solve(chi, A, mu1, m2, S_end, m, DOP853_MAX_NFEV if method == "auto" else math.inf)
                used = m
                break
            except _Budget:
                continue
        if res is None:
            raise RuntimeError("DOP853 step budget exhausted and no fallback")
        u_end = float(res.y[1, -1]) + S_end
        if not finite or u_end >= u_need:
            break
        S_end += 2.0 * (u_need - u_end) + 10.0
    else:
        raise RuntimeError("could not reach the horizon needed for the tail bound")

    xi_end = float(res.y[0, -1])
    if finite:
        T = tail_integral(u_end, A, mu1, m2)
        tail = (A / chi) * math.log1p((chi / A) * math.exp(-chi * xi_end / A) * T)
        xi_inf = xi_end + tail
    else:
        tail = 0.0
        xi_inf = math.nan
    tau_h = math.expm1(S_end) if S_end < 709.0 else math.inf
    return ReferenceSolution(chi=chi, A=A, mu1=mu1, m2=m2, finite=finite, xi_inf=xi_inf, xi_end=xi_end,
                             tail=tail, S_end=S_end, tau_horizon=tau_h, method=used, nfev=int(res.nfev),
                             seconds=time.perf_counter() - t0, sol=res.sol)
