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

Range: gamma/A up to ~200 (checked) in S. Beyond, and wherever chi gamma/A^2 is large (the slider swings
inertially to xi ~ sqrt(gamma/chi) and the swing ends in a plunge: xi' falls from ~e^-5 to ~e^-(chi xi/A) in a span
of S far below the spacing of doubles near S, and Radau stops with "step size less than spacing"), the same
equations are integrated with S as a fourth state against a time theta (``time_map=True``; by default only where
the S form fails):

    dS/dtheta = 1/(1 + E_S NU (1 + p^2)),   d(xi, u, p)/dtheta = dS/dtheta d(xi, u, p)/dS,

E_S = (1 + tau) R the relaxation rate of p in S. In theta, p relaxes at ~1/(NU (1 + p^2)) (~1/(NU p) while p >> 1,
the plunge, then exponentially once p < 1) wherever E_S NU (1 + p^2) >> 1, and theta = S up to rounding elsewhere: a
change of time, not of the solution (checked: both forms agree to 1e-11 where both run). Radau's Jacobian is then
its own finite-difference one.

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
NU = 1e-9  # of the time theta (module docstring): theta takes over from S once E_S (1 + p^2) > ~1e9
LN_E_MAX = 100.0  # cap of ln((1 + tau) R gamma/A) in S: past a plunge p relaxes at > e^100, ~infinitely fast either way
P_BACK = 1e-3  # theta hands back to S once |p| <= P_BACK handover_eps past the plunge (module docstring)
THETA_MAX = 1e300  # theta grows as E_S NU S late on the slow path (MAX_STEPS bounds the work)
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
    quasistatic_xi_inf: float  # reference_stop(chi, A, mu1, m2).xi_inf (NaN where that reference fails)
    gap: float  # xi_inf / quasistatic_xi_inf - 1
    handover_eps: float
    rtol: float
    nsteps: int
    nfev: int
    njev: int
    seconds: float  # inertial part + continuation (not the quasi-static reference, cached separately)
    time_map: bool  # integrated in theta (sol over theta, first component S) rather than in S
    sol: OdeSolution = field(repr=False, compare=False)
    continuation: ReferenceSolution | None = field(repr=False, compare=False)  # None: no slip left

    def _split(self, tau):
        if self.time_map:
            raise ValueError("the transient of a time-mapped reference is kept over theta, not tau: xi_inf only")
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
        E = a_g * math.exp(min(S - w, LN_E_MAX))  # (1 + tau) R (capped: module docstring)
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


def _theta_rhs_factory(chi, A, mu1, m2, gamma):
    """Right-hand side in theta for the state (S, xi, u, p) (module docstring), from :func:`_rhs_factory`'s
    equations in S; E_S e^(...) kept in logs so that xi' -> e^-(chi xi/A) ~ 0 never overflows the rate."""
    c = chi / A
    ln_a_g = math.log(A / gamma)

    def rhs(theta, y):
        S, xi, u, p = y
        k = (mu1 + 2.0 * m2 * u) / A
        q = p - (chi * xi + mu1 * u + m2 * u * u) / A
        w = q - u
        f1 = math.exp(min(S + w, 700.0))  # (a Newton iterate far off: Radau rejects the step)
        f2 = -math.exp(min(S - u, 700.0)) * math.expm1(min(q, 700.0))
        ln_e = ln_a_g + S - w  # ln E_S
        weight = NU * (1.0 + p * p)
        if ln_e > 700.0 or -ln_e > 700.0:  # E_S weight >> 1: dS/dtheta = 1/(E_S weight), E_S dS/dtheta = 1/weight
            rate = math.exp(-min(ln_e, 700.0)) / weight if ln_e > 0.0 else 1.0
            relax = 1.0 / weight if ln_e > 0.0 else 0.0
        else:
            E = math.exp(ln_e)
            rate = 1.0 / (1.0 + E * weight)
            relax = E * rate
        return np.array([rate, rate * f1, rate * f2, -relax * p + rate * (c * f1 + (1.0 + k) * f2)])

    return rhs


def past_plunge(chi, A, mu1, m2, gamma, y):
    """Whether theta slows S at the state y = (S, xi, u, p): E_S NU (1 + p^2) > 1 (module docstring)."""
    S, xi, u, p = (float(v) for v in y)
    w = p - (chi * xi + mu1 * u + m2 * u * u) / A - u
    return math.log(A / gamma) + S - w > -math.log(NU * (1.0 + p * p))


def _continuation(chi, A, mu1, m2, S_h, xi_h, u_h):
    """The quasi-static reference from the hand-over state, or None where the slip still to come is below 1e-18 of
    xi_h: past a deep plunge (E = xi' psi ~ e^-(chi xi/A), below the range of doubles), where the quasi-static
    reference's own exponentials overflow. Bound: with k = (mu1 + 2 m2 u)/A >= 0 from u_h on (the hand-over
    requires it), E(u) <= E_h e^(-k_h (u - u_h)) and dxi/du = E/(1 - E), so the slip left is <= E_h/((1 - E_h) k_h)."""
    k_h = (mu1 + 2.0 * m2 * u_h) / A
    ln_e = -(chi * xi_h + mu1 * u_h + m2 * u_h * u_h) / A
    if k_h > 0.0 and ln_e < -50.0 and ln_e - math.log(k_h) < math.log(1e-18 * xi_h):
        return None
    return reference_stop_from(chi, A, mu1, m2, S_h, xi_h, u_h)


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
                            handover_eps: float = HANDOVER_EPS, rtol: float = RTOL,
                            time_map: bool | None = None) -> InertialReference:
    """Reference inertial stop transient (cached): Radau on (xi, u, p) in S = ln(1 + tau) up to the hand-over,
    then the quasi-static reference to xi_inf (module docstring). ``time_map``: True integrates (S, xi, u, p) in the
    time theta, False in S, None (default) in S and, where that fails, in theta. With the time map, ``sol`` is
    defined over theta (its first component S), not over S."""
    chi, A, mu1, m2, gamma = float(chi), float(A), float(mu1), float(m2), float(gamma)
    if not (chi > 0.0 and A > 0.0 and gamma > 0.0):
        raise ValueError("chi, A and gamma must be > 0")
    if not has_finite_limit(mu1, m2):
        raise ValueError("no finite limit (need m2 > 0, or m2 = 0 with mu1 > 0)")
    if not 0.0 < handover_eps < 1e-3:
        raise ValueError("handover_eps must lie in (0, 1e-3)")
    t0 = time.perf_counter()
    if time_map is None:
        try:
            return reference_inertial_stop(chi, A, mu1, m2, gamma, handover_eps, rtol, False)
        except RuntimeError:
            return reference_inertial_stop(chi, A, mu1, m2, gamma, handover_eps, rtol, True)
    rhs, jac = _rhs_factory(chi, A, mu1, m2, gamma)
    atol = np.array([1e-16 * min(1.0, A / chi), 1e-20, 1e-18])
    if time_map:
        solver = Radau(_theta_rhs_factory(chi, A, mu1, m2, gamma), 0.0, np.zeros(4), THETA_MAX, rtol=rtol,
                       atol=np.concatenate(([1e-20], atol)))
    else:
        solver = Radau(rhs, 0.0, np.zeros(3), S_MAX, rtol=rtol, atol=atol, jac=jac)
    in_theta = bool(time_map)
    ts, interps, nsteps = [0.0], [], 0
    ok = False
    for _ in range(MAX_STEPS):
        try:
            msg = solver.step()
        except OverflowError as e:  # an exponential of the S form out of range (u lagging S by > ~700)
            raise RuntimeError(f"overflow for chi={chi}, A={A}, mu1={mu1}, m2={m2}, gamma={gamma}") from e
        if solver.status == "failed":
            raise RuntimeError(f"Radau failed for chi={chi}, A={A}, mu1={mu1}, m2={m2}, gamma={gamma}: {msg}")
        if in_theta or not time_map:  # (the S phase after theta: not in sol)
            ts.append(solver.t)
            interps.append(solver.dense_output())
        nsteps += 1
        state = solver.y[1:] if in_theta else solver.y
        ok, p_abs, B = handover_check(chi, A, mu1, m2, gamma, state, handover_eps)
        if ok:
            break
        if in_theta and p_abs <= P_BACK * handover_eps and past_plunge(chi, A, mu1, m2, gamma, solver.y):
            # the plunge is over but the hand-over waits for the slow path: theta would stall S there
            S_b = float(solver.y[0])
            solver = Radau(rhs, S_b, np.array(state, dtype=float), S_MAX, rtol=rtol, atol=atol, jac=jac,
                           first_step=1e-12)  # (scipy's own first guess overflows at the capped rate)
            in_theta = False
            continue
        if solver.status == "finished":
            raise RuntimeError(f"no hand-over by the end of the integration (|p| = {p_abs:.3g}, B = {B:.3g})")
    else:
        raise RuntimeError(f"no hand-over within {MAX_STEPS} steps")
    if in_theta:
        S_h, xi_h, u_h = (float(v) for v in solver.y[:3])
    else:
        S_h = float(solver.t)
        xi_h, u_h, _ = (float(v) for v in solver.y)
    cont = _continuation(chi, A, mu1, m2, S_h, xi_h, u_h)
    xi_inf = xi_h if cont is None else cont.xi_inf
    seconds = time.perf_counter() - t0
    try:  # only for the gap: the quasi-static reference overflows at chi/A ~ 1e6 (tests/reference.py)
        qs = reference_stop(chi, A, mu1, m2).xi_inf
    except (OverflowError, RuntimeError):
        qs = math.nan
    return InertialReference(
        chi=chi, A=A, mu1=mu1, m2=m2, gamma=gamma, xi_inf=xi_inf, tau_handover=math.expm1(S_h), S_handover=S_h,
        xi_handover=xi_h, u_handover=u_h, inertia_at_handover=p_abs, inertia_bound_at_handover=B,
        quasistatic_xi_inf=qs, gap=xi_inf / qs - 1.0, handover_eps=float(handover_eps), rtol=float(rtol),
        nsteps=nsteps, nfev=int(solver.nfev), njev=int(solver.njev), seconds=seconds, time_map=bool(time_map),
        sol=OdeSolution(np.array(ts), interps), continuation=cont)
