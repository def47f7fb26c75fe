"""Independent high-accuracy reference for the INERTIAL stop scene (docs/physics.md 3a, "With inertia"), scipy only.

This module must not import anything from the ``sweep`` package: it is what the engine is tested against. It uses
the quasi-static reference (tests/reference.py) for the late part of the stop, after a hand-over that is shown
below to cost less than the threshold ``handover_eps`` (relative) in xi_inf.

Equations (reduced units, ' = d/dtau, u = ln psi, w = ln xi', mu1 = mu1(V) given as a number, gamma > 0 the
inertia number):

    gamma xi'' = -chi xi - mu1 u - m2 u^2 - A ln(xi' psi),   psi' = 1 - xi' psi,   xi(0) = 0, xi'(0) = 1, psi(0) = 1.

State. With q = w + u = ln(xi' psi) and its quasi-static value q_qs = -Q, Q = (chi xi + mu1 u + m2 u^2)/A, the
third state variable is the inertial correction itself,

    p = q - q_qs = q + Q = -gamma xi''/A          (so w = p - Q - u),

and the equations become (k = (mu1 + 2 m2 u)/A, c = chi/A):

    xi' = e^w,    u' = -e^-u expm1(p - Q),    p' = -R (p - p*),    R = (A/gamma) e^-w,
    p* = (gamma/A) xi' (c xi' + (1 + k) u').

Carrying p (rather than w) keeps the inertial term accurate to its own relative tolerance when it is tiny, which
the hand-over test needs (w + Q + u would cancel to ~rtol |w|). They are integrated in the log time
S = ln(1 + tau) (d/dS = e^S d/dtau; the factors e^S are folded into the exponents) with scipy's Radau class,
stepped by hand, with the analytic Jacobian, rtol 1e-12 and tiny atol. R is the inertial relaxation rate
A/(gamma xi'): stiff when gamma/A << 1 and, in every stop, late on as xi' -> 0.

Hand-over. p' = -R (p - p*) with R > 0 is exact, so for all later times

    |p| <= max(|p(tau_h)|, sup_{tau > tau_h} |p*|).

Late on (0 < xi' psi <= 1, so 0 <= u' <= 1/psi and xi' <= 1/psi):
|p*| <= B = (gamma/A) (xi'/psi) (c + |1 + k|), and xi'/psi = e^{q - 2u} = e^{p - Q - 2u}. If moreover k >= 0
(k only grows with u), Q is nondecreasing, so xi' psi stays <= its current value times e^(2 eps) and u keeps
growing; then the future B is at most e^{2 eps} (gamma/A) e^{-c xi_h} G(u) with
G(u) = exp(-(mu1 u + m2 u^2)/A - 2u) (c + 1 + k(u)), u >= u_h, whose log-derivative
-k - 2 + (2 m2/A)/(c + 1 + k) decreases with u: if it is <= 0 at u_h, G never grows again. So the hand-over is
made at the first Radau step point where ALL of these hold:

    xi' psi <= 1/2,   k >= 0,   d ln G/du <= 0,   |p| <= eps,   B <= eps,

and then |p| <= eps (1 + O(eps)) for ever after (the value alone would not do: p(0) = 0, but p grows in the
initial layer of thickness gamma/A and can oscillate when gamma/A is large). After the hand-over the quasi-static
reference continues from (xi, u) at that S (``reference_stop_from``), including its closed-form tail. Neglecting
p changes the velocity by a factor e^p, so the hand-over moves xi_inf by at most ~eps times the slip still to
come (tests/integrate/test_reference_inertial.py checks that moving eps by 100x either way changes xi_inf by < 1e-12).

Accuracy: xi_inf moves by < 4e-14 relative between rtol 1e-11, 1e-12 and 1e-13 and by < 6e-15 with eps x100 or
/100 (gamma/A 1e-3..10, sample2 at 1 and 100 um/s, chi/A = 2 mu1/A = 1.5). Cost: 3000-8000 Radau steps, 0.5-1.5 s.

Range: gamma/A up to ~200 (checked). Beyond (gamma/A = 1e3, chi/A = 2) the end of the quarter swing, where xi'
falls from ~e^-5 to ~e^-(chi xi/A) in a time far below the spacing of doubles near S, cannot be resolved in S and
Radau stops ("step size less than spacing"): that needs another independent variable.

Only finite-limit cases (m2 > 0, or m2 = 0 with mu1 > 0; docs/physics.md 6) are accepted.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field

import numpy as np
from reference import ReferenceSolution, has_finite_limit, reference_stop, reference_stop_from
from scipy.integrate import OdeSolution, Radau

RTOL = 1e-12
HANDOVER_EPS = 1e-12  # |p| and its bound B at the hand-over
XIPSI_MAX = 0.5  # xi' psi at the hand-over (late regime)
S_MAX = 300.0  # no hand-over by tau ~ 1e130: give up
MAX_STEPS = 2_000_000

__all__ = ["InertialReference", "reference_inertial_stop", "HANDOVER_EPS"]


@dataclass(frozen=True)
class InertialReference:
    """Reference inertial stop transient for (chi, A, mu1, m2, gamma). ``sol`` gives the state (xi, u = ln psi,
    p = ln(xi' psi) - q_qs) at S = ln(1 + tau) for S <= S_handover; beyond, ``continuation`` (the quasi-static
    reference from the hand-over state) takes over."""

    chi: float
    A: float
    mu1: float
    m2: float
    gamma: float
    xi_inf: float
    tau_handover: float
    S_handover: float
    xi_handover: float
    u_handover: float
    inertia_at_handover: float  # |q - q_qs| = |gamma xi''/A| there
    inertia_bound_at_handover: float  # B (bounds |q - q_qs| for ever after, with the above)
    quasistatic_xi_inf: float  # reference_stop(chi, A, mu1, m2).xi_inf
    gap: float  # xi_inf / quasistatic_xi_inf - 1
    handover_eps: float
    rtol: float
    nsteps: int
    nfev: int
    njev: int
    seconds: float  # inertial part + continuation (not the quasi-static reference, cached separately)
    sol: OdeSolution = field(repr=False, compare=False)
    continuation: ReferenceSolution = field(repr=False, compare=False)

    def _split(self, tau):
        tau = np.asarray(tau, dtype=float)
        if np.any(tau < 0.0) or np.any(np.isnan(tau)):
            raise ValueError("tau must be >= 0")
        S = np.log1p(tau)
        return tau, S, S <= self.S_handover

    def state(self, tau) -> np.ndarray:
        """(xi, u, p) at tau <= tau_handover (vectorised; shape (3,) + shape(tau))."""
        tau, S, before = self._split(tau)
        if not np.all(before):
            raise ValueError(f"the inertial state is only kept up to tau_handover = {self.tau_handover:.6g}")
        return self.sol(S)

    def xi(self, tau):
        """Reduced slip xi(tau) (vectorised): the inertial solution up to the hand-over, then the quasi-static
        continuation (which returns xi_inf beyond its own horizon)."""
        tau, S, before = self._split(tau)
        flat_tau, flat_S, flat_b = np.atleast_1d(tau).ravel(), np.atleast_1d(S).ravel(), np.atleast_1d(before).ravel()
        out = np.empty(flat_tau.size)
        if np.any(flat_b):
            out[flat_b] = self.sol(flat_S[flat_b])[0]
        if np.any(~flat_b):
            out[~flat_b] = self.continuation.xi(flat_tau[~flat_b])
        out = out.reshape(tau.shape)
        return out[()] if out.ndim == 0 else out

    def velocity(self, tau):
        """xi'(tau) = e^w, w = p - Q - u, for tau <= tau_handover (vectorised)."""
        xi, u, p = self.state(tau)
        Q = (self.chi * xi + self.mu1 * u + self.m2 * u * u) / self.A
        v = np.exp(p - Q - u)
        return v[()] if v.ndim == 0 else v


def _rhs_factory(chi, A, mu1, m2, gamma):
    """Right-hand side and analytic Jacobian in S for the state (xi, u, p) (module docstring)."""
    c = chi / A
    a_g = A / gamma

    def parts(S, y):
        xi, u, p = y
        k = (mu1 + 2.0 * m2 * u) / A
        q = p - (chi * xi + mu1 * u + m2 * u * u) / A
        w = q - u
        f1 = math.exp(S + w)  # dxi/dS = (1 + tau) xi'
        eu = math.exp(S - u)
        f2 = -eu * math.expm1(q)  # du/dS = (1 + tau) psi^-1 (1 - xi' psi)
        E = a_g * math.exp(S - w)  # (1 + tau) R
        return p, k, q, f1, eu, f2, E

    def rhs(S, y):
        p, k, _, f1, _, f2, E = parts(S, y)
        return np.array([f1, f2, -E * p + c * f1 + (1.0 + k) * f2])

    def jac(S, y):
        p, k, _, f1, _, f2, E = parts(S, y)
        k1 = 1.0 + k
        d1 = [-c * f1, -k1 * f1, f1]  # d f1 / d(xi, u, p): f1 * dw
        d2 = [c * f1, -f2 + k * f1, -f1]
        d3 = [-E * p * c + c * d1[0] + k1 * d2[0],
              -E * p * k1 + c * d1[1] + (2.0 * m2 / A) * f2 + k1 * d2[1],
              E * p - E + c * d1[2] + k1 * d2[2]]
        return np.array([d1, d2, d3])

    return rhs, jac


def handover_check(chi, A, mu1, m2, gamma, y, eps):
    """(ok, |p|, B) for the state y = (xi, u, p) (module docstring: all five conditions)."""
    xi, u, p = (float(v) for v in y)
    c = chi / A
    k = (mu1 + 2.0 * m2 * u) / A
    q = p - (chi * xi + mu1 * u + m2 * u * u) / A
    B = (gamma / A) * math.exp(q - 2.0 * u) * (c + abs(1.0 + k))
    dlnG = -k - 2.0 + (2.0 * m2 / A) / (c + 1.0 + k) if k >= 0.0 else math.inf
    ok = q <= math.log(XIPSI_MAX) and k >= 0.0 and dlnG <= 0.0 and abs(p) <= eps and B <= eps
    return ok, abs(p), B


@functools.cache
def reference_inertial_stop(chi: float, A: float, mu1: float, m2: float, gamma: float,
                            handover_eps: float = HANDOVER_EPS, rtol: float = RTOL) -> InertialReference:
    """Reference inertial stop transient (cached): Radau on (xi, u, p) in S = ln(1 + tau) up to the hand-over,
    then the quasi-static reference to xi_inf (module docstring)."""
    chi, A, mu1, m2, gamma = float(chi), float(A), float(mu1), float(m2), float(gamma)
    if not (chi > 0.0 and A > 0.0 and gamma > 0.0):
        raise ValueError("chi, A and gamma must be > 0")
    if not has_finite_limit(mu1, m2):
        raise ValueError("no finite limit (need m2 > 0, or m2 = 0 with mu1 > 0)")
    if not 0.0 < handover_eps < 1e-3:
        raise ValueError("handover_eps must lie in (0, 1e-3)")
    t0 = time.perf_counter()
    rhs, jac = _rhs_factory(chi, A, mu1, m2, gamma)
    atol = np.array([1e-16 * min(1.0, A / chi), 1e-20, 1e-18])
    solver = Radau(rhs, 0.0, np.zeros(3), S_MAX, rtol=rtol, atol=atol, jac=jac)
    ts, interps = [0.0], []
    ok = False
    for _ in range(MAX_STEPS):
        msg = solver.step()
        if solver.status == "failed":
            raise RuntimeError(f"Radau failed for chi={chi}, A={A}, mu1={mu1}, m2={m2}, gamma={gamma}: {msg}")
        ts.append(solver.t)
        interps.append(solver.dense_output())
        ok, p_abs, B = handover_check(chi, A, mu1, m2, gamma, solver.y, handover_eps)
        if ok:
            break
        if solver.status == "finished":
            raise RuntimeError(f"no hand-over by S = {S_MAX} (|p| = {p_abs:.3g}, B = {B:.3g})")
    else:
        raise RuntimeError(f"no hand-over within {MAX_STEPS} steps")
    S_h = float(solver.t)
    xi_h, u_h, _ = (float(v) for v in solver.y)
    cont = reference_stop_from(chi, A, mu1, m2, S_h, xi_h, u_h)
    seconds = time.perf_counter() - t0
    qs = reference_stop(chi, A, mu1, m2).xi_inf
    return InertialReference(
        chi=chi, A=A, mu1=mu1, m2=m2, gamma=gamma, xi_inf=cont.xi_inf, tau_handover=math.expm1(S_h), S_handover=S_h,
        xi_handover=xi_h, u_handover=u_h, inertia_at_handover=p_abs, inertia_bound_at_handover=B,
        quasistatic_xi_inf=qs, gap=cont.xi_inf / qs - 1.0, handover_eps=float(handover_eps), rtol=float(rtol),
        nsteps=len(interps), nfev=int(solver.nfev), njev=int(solver.njev), seconds=seconds,
        sol=OdeSolution(np.array(ts), interps), continuation=cont)
