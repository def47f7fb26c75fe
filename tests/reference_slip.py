"""Independent high-accuracy scipy reference for the SLIP state law (Ruina 1983), with an ``aging=True`` switch
that reproduces the aging-law reference (tests/reference.py) from the same code. Nothing here imports ``sweep``.

Notation (reduced, docs/physics.md 2): ' = d/dtau, u = ln psi, k = chi/A, a = mu1(V)/A, b = m2/A,
L = k xi + a u + b u^2 (stop) and E = xi' psi = exp(-L).

1. State laws. Aging: psi' = 1 - xi' psi. Slip: psi' = -xi' psi ln(xi' psi). The quasi-static force balance is
   the same for both, A ln(xi' psi) = -chi xi - dmu(psi) (stop) or chi (tau - xi) - dmu(psi) (driven).

2. Stop scene, contact-age time s (ds = dtau/psi): dxi/ds = E, and du/ds = 1 - E = E expm1(L) (aging) or
   du/ds = -E ln E = E L (slip). Hence, with h(L) = expm1(L) (aging) or h(L) = L (slip),

       du/dxi = h(L),   dxi/du = 1/h(L),   dtau = e^(u + L) dxi = e^(u + L) du / h(L).

   The two laws agree to first order in L (the early stage, tau << 1, is the same: xi = ln(1 + k tau)/k).
   L > 0 for every xi > 0 (L = 0 at the start with dL/dxi = k > 0, and wherever L = 0, dL/dxi = k > 0), so u
   increases strictly with xi, and xi strictly with s. Since xi(s) increases and dxi/ds = E is bounded below
   while u stays bounded, xi_inf = lim xi is the point where the solution u(xi) of du/dxi = h(L), u(0) = 0,
   blows up (u -> inf), or +inf if it exists for all xi.

   Slip law: du/dxi = k xi + a u + b u^2 is a Riccati equation.
   * b = 0: linear, u = (k/a^2)(e^(a xi) - 1 - a xi) (a != 0), u = k xi^2/2 (a = 0): exists for all xi, so NO
     finite limit, whatever the sign of mu1 (a > 0: xi ~ ln(ln s)/a; a < 0: L -> k/|a|, xi grows linearly in s,
     i.e. like ln tau; a = 0: xi ~ sqrt(ln s)).
   * b < 0: u tracks the stable root of b u^2 + a u + k xi ~ sqrt(k xi/|b|): no blow-up, no finite limit.
   * b > 0: du/dxi >= k xi - a^2/(4b) > 0 eventually and then >= b u^2/2: blow-up at a finite xi. FINITE.
   => slip law: xi_inf finite  <=>  m2 > 0 (the sign of mu1(V) does not matter; compare the aging law: m2 > 0,
   or m2 = 0 and mu1 > 0).
   2b. Closed form (b > 0, :func:`slip_xi_inf_airy`): v = u + a/(2b) gives v' = b v^2 + k (xi - xi0) with
   xi0 = a^2/(4 b k), and v = -y'/(b y) the Airy equation y'' = -b k (xi - xi0) y. With c = (b k)^(1/3),
   X = c (xi0 - xi): y = Ai(X) + r Bi(X), r fixed by y'(0)/y(0) = -a/2, and xi_inf = xi0 - X*/c at the first
   zero X* of y below X0 = c xi0. Special cases: mu1 = 0: xi_inf = 1.98635270743/(b k)^(1/3) (first zero of
   Ai(-x) + Bi(-x)/sqrt 3); mu1 < 0 with X0 >~ 10 (soft springs, the costly corners): r ~ exp(-4/3 X0^1.5), so
   xi_inf = a^2/(4 b k) + 2.33811/(b k)^(1/3) to rounding: the slider creeps along L ~ 0 up to the fold xi0 of
   that manifold and leaves it through an Airy layer. The closed form agrees with the integration to < 3e-13 on
   every m2 > 0 case of tests/cases.py; only xi_inf has one (not xi(tau)).
   Comparison: expm1(L) >= L, so u_aging(xi) >= u_slip(xi) and the aging solution blows up first:
   xi_inf(aging) <= xi_inf(slip), strictly. Physically the slip law heals only by slipping (no healing at
   rest), so the slider must slip further before its contacts have strengthened enough to arrest it.

3. Numerics (:func:`stop`). Phase 1, independent variable xi, state (u, S = ln(1 + tau)):
       du/dxi = h(L),  dS/dxi = exp(u + L - S)
   until h(L) >= H_SWITCH (= 1: u moves faster than xi) AND a + 2 b u >= 0 (from there on dL/du > 0, so L and
   u keep growing; the event is min of the two, crossing 0 upwards). This phase also carries the slow creep
   manifold of the costly corner (a < 0, L ~ k/|a| small, stiffness |a + 2 b u| per unit xi: Radau).
   Phase 2, independent variable t = ln u, state (xi, S):
       dxi/dt = u/h(L),  dS/dt = u exp(u + L - S)/h(L).
   Aging: until L >= L_END_AGING (= 40, E < 5e-18), then the closed-form remainder of tests/reference.py:
   e^(k xi) dxi = e^-(a u + b u^2) du/(1 - E), E decreasing, so with T~(U) = e^(aU + bU^2) int_U^inf
   e^-(a u + b u^2) du (1/a, or sqrt(pi/b)/2 erfcx(sqrt(b)(U + a/(2b)))):
       R_lo = log1p(k E_U T~(U))/k <= xi_inf - xi_U <= log1p(k E_U T~(U)/(1 - E_U))/k = R_hi.
   Slip: until u = U_END (1e6, or more until the bound below holds). For u >= U, with xi_U <= xi(u) <= xi_inf:
       F(k xi_U + k R_hi) <= R = xi_inf - xi_U <= F(k xi_U) = R_hi,   F(c) = int_U^inf du/(b u^2 + a u + c),
       F(c) = (2/p) g(D/p^2),  p = 2 b U + a > 0,  D = a^2 - 4 b c,  g(x) = atanh(sqrt x)/sqrt x (x > 0),
       arctan(sqrt -x)/sqrt -x (x < 0), 1 (x = 0)   [series sum x^n/(2n+1) for |x| < 1e-3].
   xi_inf = xi_U + (R_lo + R_hi)/2, bound (R_hi - R_lo)/2 ~ k/(6 b^3 U^4): < 1e-18 in every case of the table.
   The slip-law tail is ALGEBRAIC in u (R ~ 1/(b u)) where the aging tail is Gaussian (~ e^(-b u^2)): late on
   ln tau ~ u + L - ln(L (1 + dL/du)) ~ b u^2, so xi_inf - xi(tau) ~ 1/sqrt(b ln tau): at tau = 1e200 still
   3.5 % of xi_inf (sample1, Fig. 3b point: u = 58) or 5 % (m2/A = 0.05). No integration in tau or s can reach
   xi_inf to rtol; the remainder (in u) is mandatory. In s: du/ds = E L ~ b u^2 e^(-b u^2), so u ~ sqrt(ln s/b)
   and xi_inf - xi ~ 1/sqrt(b ln s): a tolerance of 1e-9 would need ln s ~ 1e18.

   Both phases run with solve_ivp at rtol RTOL = 1e-13 (DOP853, with a budget of evaluations, then Radau with an
   analytic Jacobian; method="DOP853"/"Radau" forces one, for cross-checks).

   Cost: ~35 000 evaluations, 0.3-0.8 s per slip case (the S equation relaxes at the rate dS/dt ~ 2 b u^2 in
   t = ln u, stiff for DOP853 while S is carried: up to S_CAP); corners ~70 000; the two extreme cases of
   tests/cases.py run Radau for 3-9 s.

4. Driven scene (:func:`driven`): z = tau - xi, w = ln xi' = k z - a u - b u^2 - u,
       z' = 1 - e^w,   u' = e^-u - e^w (aging),   u' = -e^w (w + u) (slip).
   Linearised about z = u = 0 (w = k z - (a + 1) u): aging u' = -u - w, slip u' = -(w + u): the SAME
   u' = -k z + a u, z' = -k z + (a + 1) u, so s^2 + (k - a) s + k = 0, i.e. A s^2 + (chi - mu1) s + chi = 0 for
   both laws: same Hopf line chi_c = mu1, same growth rate and period near it (the laws differ at second order
   in the amplitude only). Cycles are measured as the engine does (sweep/integrate/models/driven.py): the maxima of z
   are
   the upward zero crossings of w (z' = 1 - e^w), located by solve_ivp's event root finding. Found here
   (sample2's A, m1, m2 at V0): m2 > 0 supercritical for the slip law too (a limit cycle below the line, amplitude
   1.02 at chi = 0.9 chi_c against 1.55 for aging; 0.69 vs 1.09 at 0.95 chi_c); m2 = 0 degenerate as for aging:
   neutral orbits of any amplitude at chi = chi_c (|growth| < 3e-12 per unit tau over 50 cycles), runaway below.

5. For an engine implementing the slip law (numbers from the table of tests/cases.py):
   * finite limit iff m2 > 0: the m2 = 0, mu1 > 0 points, finite for aging, are no_finite_limit for slip;
   * xi_inf(slip)/xi_inf(aging) ranges from 1.004 (costly corners: both creep to the same fold) to 47 (chi/A =
     1000, mu1/A = 3, m2/A = 0.3: 0.271 vs 0.00577); 1.6-5.4 on the preset points outside the corners;
   * the aging stop kernel's trick xi + u = s does not hold (du/ds = E L): the state is (xi, u) in s, or better
     u(xi) (phase 1) and xi(u) (phase 2) as here; the s-time right-hand side -E ln E has the same stiffness
     structure as aging's early (rate ~ k) and in the corners (rate |a + 2 b u|);
   * u at the end of the transient is modest (u ~ 5e-4 to 4.6 at the hand-over h(L) = 1; u ~ 25-60 at tau = 1e50
     to 1e200), but no finite horizon gives xi_inf: use the remainder R(U) = F(k xi_U) (bound ~ k R/(3 b^2 U^3))
     or the Airy closed form for xi_inf itself;
   * t50 is often modest (1.3 to 1.7e5 tau on the preset points) but t90 is astronomically late (8e27 for the
     sample1 Fig. 3b point, 1e151 for sample2 at K/M = 1e6, V = 0.1 um/s) and beyond any float for chi/A = 1000
     (t50 = 1.8e93 there): such times must come back as NaN/inf with a status, not as a converged-looking number;
   * driven: same linear theory, so locate_hopf and growth_rate_linear need no change; only u' differs.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq
from scipy.special import erfcx

__all__ = ["has_finite_limit", "stop", "StopSolution", "tail_F", "slip_remainder", "aging_remainder",
           "riccati_m2zero_u", "slip_xi_inf_airy", "driven", "DrivenSolution", "linear_roots"]

RTOL = 1e-13
H_SWITCH = 1.0  # phase 1 -> 2 once h(L) >= H_SWITCH (and a + 2 b u >= 0)
L_END_AGING = 40.0  # aging phase 2 ends at L = 40 (E < 4.3e-18)
U_END_SLIP = 1e6  # slip phase 2 ends at u = U (extended if the remainder bound is not met)
TAIL_BOUND_REL = 1e-16  # required bound on the remainder's error, relative to xi_inf
DOP853_MAX_NFEV = 200_000
TAU_HORIZON_NO_LIMIT = 1e12
XI_MAX = 1e12  # phase-1 range of xi (only reached without a finite limit)
S_CAP = 600.0  # S = ln(1 + tau) is carried up to here (tau ~ 1e260; Scene allows tau <= 1e250)


def has_finite_limit(mu1: float, m2: float, aging: bool = False) -> bool:
    """Slip law: m2 > 0 (module docstring, section 2). Aging law: m2 > 0, or m2 = 0 and mu1 > 0."""
    if aging:
        return m2 > 0.0 or (m2 == 0.0 and mu1 > 0.0)
    return m2 > 0.0


def riccati_m2zero_u(xi, k: float, a: float):
    """Slip law, m2 = 0: the exact u(xi) = (k/a^2)(e^(a xi) - 1 - a xi) (k xi^2/2 at a = 0)."""
    xi = np.asarray(xi, dtype=float)
    if a == 0.0:
        return 0.5 * k * xi * xi
    x = a * xi
    return (k / (a * a)) * (np.expm1(x) - x)


def _g(x: float) -> float:
    """sum_n x^n/(2n + 1): atanh(sqrt x)/sqrt x for x > 0, arctan(sqrt -x)/sqrt -x for x < 0 (x < 1)."""
    if abs(x) < 1e-3:
        return sum(x ** n / (2 * n + 1) for n in range(8))
    if x > 0.0:
        r = math.sqrt(x)
        return math.atanh(r) / r
    r = math.sqrt(-x)
    return math.atan(r) / r


def tail_F(U: float, a: float, b: float, c: float) -> float:
    """F(c) = int_U^inf du/(b u^2 + a u + c), b > 0, for b u^2 + a u + c > 0 on [U, inf) and p = 2bU + a > 0."""
    p = 2.0 * b * U + a
    if not p > 0.0:
        raise ValueError("need 2 b U + a > 0")
    D = a * a - 4.0 * b * c
    return (2.0 / p) * _g(D / (p * p))


def slip_remainder(U: float, xi_U: float, k: float, a: float, b: float) -> tuple[float, float]:
    """(estimate, bound) of xi_inf - xi(U) for the slip law (module docstring, section 3)."""
    r_hi = tail_F(U, a, b, k * xi_U)
    r_lo = tail_F(U, a, b, k * (xi_U + r_hi))
    return 0.5 * (r_hi + r_lo), 0.5 * (r_hi - r_lo)


def _scaled_gauss_tail(U: float, a: float, b: float) -> float:
    """e^(aU + bU^2) int_U^inf e^-(a u + b u^2) du, for a + 2 b U > 0, b >= 0."""
    if b == 0.0:
        return 1.0 / a
    return 0.5 * math.sqrt(math.pi / b) * float(erfcx(math.sqrt(b) * (U + 0.5 * a / b)))


def aging_remainder(U: float, L_U: float, k: float, a: float, b: float) -> tuple[float, float]:
    """(estimate, bound) of xi_inf - xi(U) for the aging law, from the state at u = U where L = L_U."""
    E = math.exp(-L_U)
    T = E * _scaled_gauss_tail(U, a, b)
    r_lo = math.log1p(k * T) / k
    r_hi = math.log1p(k * T / (1.0 - E)) / k
    return 0.5 * (r_hi + r_lo), 0.5 * (r_hi - r_lo)


def slip_xi_inf_airy(chi: float, A: float, mu1: float, m2: float) -> float:
    """Slip law, m2 > 0: xi_inf in closed form (module docstring, section 2b). With v = u + a/(2b) the Riccati
    du/dxi = k xi + a u + b u^2 becomes v' = b v^2 + k (xi - xi0), xi0 = a^2/(4 b k); v = -y'/(b y) linearises
    it to y'' = -b k (xi - xi0) y, an Airy equation in X = c (xi0 - xi), c = (b k)^(1/3):
        y = Ai(X) + r Bi(X),  y'(0)/y(0) = -b v(0) = -a/2  =>  r = -(c Ai'(X0) - a/2 Ai(X0))/(c Bi'(X0) - a/2 Bi(X0)),
    X0 = c xi0, and u blows up where y first vanishes: xi_inf = xi0 - X*/c, X* the largest zero of y below X0.
    Evaluated with the exponentially scaled airye (no overflow: X0 reaches ~1500 on the extreme cases). For
    mu1 < 0 and X0 >> 1, r ~ e^(-4/3 X0^1.5) and X* -> -2.33811 (the first zero of Ai): xi_inf ~ xi0 + 2.33811/c,
    the fold of the slow creep manifold (the slider creeps on it until xi0, then slips off in the Airy layer).
    Accuracy: r loses digits to cancellation for mu1 > 0 (c Bi'/Bi - a/2 ~ c/(4 X0)): ~1e-12 for X0 <~ 30."""
    from scipy.special import airy, airye
    k, a, b = chi / A, mu1 / A, m2 / A
    if not (b > 0.0 and k > 0.0):
        raise ValueError("needs m2 > 0 and chi > 0")
    c = (b * k) ** (1.0 / 3.0)
    xi0 = a * a / (4.0 * b * k)
    X0 = c * xi0
    z0 = 2.0 / 3.0 * X0 ** 1.5
    eai, eaip, ebi, ebip = airye(X0)
    rs = -(c * eaip - 0.5 * a * eai) / (c * ebip - 0.5 * a * ebi)  # r e^(2 z0)

    def pos(X):  # y e^(zeta) / (positive), X >= 0
        e = airye(X)
        return e[0] + rs * e[2] * math.exp(2.0 * (2.0 / 3.0 * X ** 1.5 - z0))

    def neg(X):  # y, X <= 0 (r e^(z0)... r itself, underflowing harmlessly to 0 for large z0)
        e = airy(X)
        return e[0] + rs * math.exp(-2.0 * z0) * e[2]

    grid = np.linspace(X0, 0.0, max(2, int(20 * X0) + 2))
    vals = [pos(X) for X in grid]
    for i in range(1, len(grid)):
        if vals[i - 1] * vals[i] <= 0.0:
            Xs = brentq(pos, grid[i], grid[i - 1], xtol=1e-15, rtol=1e-15)
            return xi0 - Xs / c
    grid = np.linspace(0.0, -30.0, 3001)
    vals = [neg(X) for X in grid]
    for i in range(1, len(grid)):
        if vals[i - 1] * vals[i] <= 0.0:
            Xs = brentq(neg, grid[i], grid[i - 1], xtol=1e-15, rtol=1e-15)
            return xi0 - Xs / c
    raise RuntimeError("no zero of y found")


class _Budget(Exception):
    pass


def _h(L, aging):
    """h(L): expm1(L) (aging, clamped at L = 700 against trial steps far off) or L (slip)."""
    return math.expm1(min(L, 700.0)) if aging else L


def _dh(L, aging):
    return math.exp(min(L, 700.0)) if aging else 1.0


def _inv_h(L, aging):
    """1/h(L) = dxi/du, without overflow (aging: e^-L/(1 - e^-L))."""
    return math.exp(-L) / -math.expm1(-L) if aging else 1.0 / L


def _dlog_h(L, aging):
    """h'(L)/h(L)."""
    return 1.0 / -math.expm1(-L) if aging else 1.0 / L


def _exp(x):
    return math.exp(min(x, 700.0))


def _phase1(k, a, b, aging, S_max, method, count, budget, h_switch):
    def L_of(xi, u):
        return k * xi + u * (a + b * u)

    def f(xi, y):
        count[0] += 1
        if count[0] > budget:
            raise _Budget
        u, S = y
        L = L_of(xi, u)
        return np.array([_h(L, aging), _exp(u + L - S)])

    def jac(xi, y):
        u, S = y
        L = L_of(xi, u)
        Lu = a + 2.0 * b * u
        e = _exp(u + L - S)
        return np.array([[_dh(L, aging) * Lu, 0.0], [e * (1.0 + Lu), -e]])

    def switch(xi, y):
        u = y[0]
        return min(_h(L_of(xi, u), aging) - h_switch, a + 2.0 * b * u)

    switch.terminal, switch.direction = True, 1.0

    def horizon(xi, y):
        return y[1] - S_max

    horizon.terminal, horizon.direction = True, 1.0
    opts = {"jac": jac} if method == "Radau" else {}
    res = solve_ivp(f, (0.0, XI_MAX), [0.0, 0.0], method=method, rtol=RTOL, atol=[1e-22, 1e-14],
                    dense_output=True, events=(switch, horizon), **opts)
    if not res.success:
        raise RuntimeError(f"phase 1 ({method}) failed: {res.message}")
    return res


def _phase2(k, a, b, aging, xi0, u0, S0, t_end, S_max, method, count, budget):
    """Phase 2 in t = ln u: state (xi, S) while S < min(S_max, S_CAP), then (xi) alone (the S equation relaxes at
    the rate dS/dt ~ 2 b u^2: stiff late on, and tau beyond e^S_CAP is not asked for). Returns (part with S,
    part without S or None)."""
    def f(t, y):
        count[0] += 1
        if count[0] > budget:
            raise _Budget
        u = math.exp(t)
        L = k * y[0] + u * (a + b * u)
        ih = _inv_h(L, aging)
        if len(y) == 1:
            return np.array([u * ih])
        # u e^(u + L - S)/h(L) = u e^(u - S) (e^L/h(L)) = u e^(u - S) ih e^L, grouped so that nothing overflows
        return np.array([u * ih, u * _exp(u + L - y[1]) * ih])

    def jac(t, y):
        u = math.exp(t)
        L = k * y[0] + u * (a + b * u)
        ih, dl = _inv_h(L, aging), _dlog_h(L, aging)
        dxi = -u * ih * dl * k  # d(u/h)/dxi = -u h'/h^2 k
        if len(y) == 1:
            return np.array([[dxi]])
        e = u * _exp(u + L - y[1]) * ih
        return np.array([[dxi, 0.0], [e * k * (1.0 - dl), -e]])

    def big_L(t, y):
        u = math.exp(t)
        return k * y[0] + u * (a + b * u) - L_END_AGING

    big_L.terminal, big_L.direction = True, 1.0

    def horizon(t, y):
        return y[1] - min(S_max, S_CAP)

    horizon.terminal, horizon.direction = True, 1.0
    opts = {"jac": jac} if method == "Radau" else {}
    ev = [big_L] if aging else []
    first = solve_ivp(f, (math.log(u0), t_end), [xi0, S0], method=method, rtol=RTOL, atol=[1e-16, 1e-14],
                      dense_output=True, events=ev + [horizon], **opts)
    if not first.success:
        raise RuntimeError(f"phase 2 ({method}) failed: {first.message}")
    if first.status != 1 or len(first.t_events[-1]) == 0 or S_max <= S_CAP:  # ended, by L or without S_CAP
        return first, None
    second = solve_ivp(f, (float(first.t[-1]), t_end), first.y[:1, -1], method=method, rtol=RTOL, atol=[1e-16],
                       dense_output=False, events=ev, **opts)
    if not second.success:
        raise RuntimeError(f"phase 2 ({method}) failed: {second.message}")
    return first, second


@dataclass(frozen=True)
class StopSolution:
    """Reference quasi-static stop for one law. ``xi_inf`` NaN without a finite limit."""

    chi: float
    A: float
    mu1: float
    m2: float
    aging: bool
    finite: bool
    xi_inf: float
    xi_end: float  # xi at the end of phase 2
    u_end: float  # u = ln psi there
    remainder: float  # xi_inf - xi_end (closed form)
    remainder_bound: float  # bound on the remainder's own error
    xi_switch: float  # xi at the phase 1 -> 2 hand-over (nan if none)
    u_switch: float
    S_end: float  # ln(1 + tau) at the end of the computed transient
    method: str
    nfev: int
    seconds: float
    p1: object = field(repr=False, compare=False)
    p2: object = field(repr=False, compare=False)

    def _state(self, tau: float) -> tuple[float, float]:
        """(xi, u) at one tau >= 0, by root finding on S = ln(1 + tau) in the dense output."""
        if tau < 0.0 or not math.isfinite(tau):
            raise ValueError("tau must be finite and >= 0")
        S = math.log1p(tau)
        if S == 0.0:
            return 0.0, 0.0
        p1, p2 = self.p1, self.p2
        S1_end = float(p1.y[1, -1])
        if S <= S1_end or p2 is None:
            if S > S1_end * (1.0 + 1e-12):
                raise ValueError(f"tau = {tau:g} lies beyond the computed transient (tau = {math.expm1(S1_end):g})")
            x_end = float(p1.t[-1])
            xi = brentq(lambda x: float(p1.sol(x)[1]) - S, 0.0, x_end, xtol=1e-300, rtol=1e-15, maxiter=300) \
                if S < S1_end else x_end
            return xi, float(p1.sol(xi)[0])
        t0, t1 = float(p2.t[0]), float(p2.t[-1])
        if float(p2.y[1, -1]) < S <= float(p2.y[1, -1]) * (1.0 + 1e-12):  # at the horizon (event rounding)
            return float(p2.y[0, -1]), math.exp(t1)
        if S > float(p2.y[1, -1]):
            if self.aging and self.finite:  # beyond L = 40: xi = xi_inf, and psi' = 1 - E = 1 to < 1e-17
                S_e, u_e = float(p2.y[1, -1]), t1
                u_e = math.exp(u_e)
                return self.xi_inf, u_e + math.log1p(math.expm1(S - S_e) * math.exp(S_e - u_e))
            if not self.finite:
                raise ValueError(f"no finite limit: xi(tau) is only computed up to S = {self.S_end:g}")
            raise ValueError(f"tau = {tau:g} lies beyond the computed transient (S = {self.S_end:g})")
        t = brentq(lambda t: float(p2.sol(t)[1]) - S, t0, t1, xtol=1e-15, rtol=1e-15, maxiter=300)
        return float(p2.sol(t)[0]), math.exp(t)

    def tau_at_fraction(self, f: float) -> float:
        """tau at which xi = f xi_inf (0 < f < 1); inf where that lies beyond tau ~ e^S_CAP (the slip law's late
        fractions: xi_inf - xi ~ 1/(b u), ln tau ~ b u^2, so f = 0.99 is typically far beyond 1e308)."""
        if not self.finite:
            raise ValueError("no finite limit: no fraction of xi_inf")
        if not 0.0 < f < 1.0:
            raise ValueError("f must lie in (0, 1)")
        target = f * self.xi_inf
        p1, p2 = self.p1, self.p2
        if target <= float(p1.t[-1]):
            return float(np.expm1(p1.sol(target)[1]))
        if target > float(p2.y[0, -1]):
            return math.inf
        t = brentq(lambda t: float(p2.sol(t)[0]) - target, float(p2.t[0]), float(p2.t[-1]), xtol=1e-15,
                   rtol=1e-15, maxiter=300)
        return float(np.expm1(p2.sol(t)[1]))

    def xi(self, tau):
        out = np.array([self._state(float(t))[0] for t in np.atleast_1d(tau)])
        return out[0] if np.ndim(tau) == 0 else out

    def psi(self, tau):
        out = np.array([math.exp(self._state(float(t))[1]) for t in np.atleast_1d(tau)])
        return out[0] if np.ndim(tau) == 0 else out


def _solve(k, a, b, aging, finite, method, budget, u_end, h_switch):
    count = [0]
    S_max = math.inf if finite else math.log1p(TAU_HORIZON_NO_LIMIT)
    p1 = _phase1(k, a, b, aging, S_max, method, count, budget, h_switch)
    if p1.status != 1 or len(p1.t_events[0]) == 0:  # horizon (no finite limit) or end of the xi range
        return p1, (None, None), count[0]
    xi_sw = float(p1.t_events[0][0])
    u_sw, S_sw = (float(v) for v in p1.y_events[0][0])
    p2, p3 = _phase2(k, a, b, aging, xi_sw, u_sw, S_sw, math.log(u_end), S_max, method, count, budget)
    return p1, (p2, p3), count[0]


def stop(chi: float, A: float, mu1: float, m2: float, aging: bool = False, method: str = "auto",
         u_end: float | None = None, h_switch: float = H_SWITCH) -> StopSolution:
    """Reference quasi-static stop (module docstring). ``u_end``: slip law only, end of phase 2 in u (default
    U_END_SLIP, extended until the remainder bound is below TAIL_BOUND_REL xi_inf); ``h_switch``: the phase
    hand-over threshold (for independence checks)."""
    chi, A, mu1, m2 = float(chi), float(A), float(mu1), float(m2)
    if not (chi > 0.0 and A > 0.0):
        raise ValueError("chi and A must be > 0")
    t0 = time.perf_counter()
    k, a, b = chi / A, mu1 / A, m2 / A
    finite = has_finite_limit(mu1, m2, aging)
    U = float(u_end) if u_end is not None else U_END_SLIP
    methods = ["DOP853", "Radau"] if method == "auto" else [method]
    for _ in range(6):
        for m in methods:
            try:
                p1, (p2, p3), nfev = _solve(k, a, b, aging, finite, m, DOP853_MAX_NFEV if (m == "DOP853" and
                                      method == "auto") else math.inf, U, h_switch)
                used = m
                break
            except _Budget:
                continue
        else:
            raise RuntimeError("no method succeeded")
        if not finite:
            last = p2 if p2 is not None else p1
            return StopSolution(chi, A, mu1, m2, aging, False, math.nan, math.nan, math.nan, 0.0, 0.0, math.nan,
                                math.nan, float(last.y[1, -1]), used, nfev, time.perf_counter() - t0, p1, p2)
        if p2 is None:
            raise RuntimeError("finite case without a hand-over to phase 2")
        last = p3 if p3 is not None else p2
        xi_e, S_e = float(last.y[0, -1]), float(p2.y[1, -1])
        u_e = math.exp(float(last.t[-1]))
        if aging:
            L_e = k * xi_e + u_e * (a + b * u_e)
            rem, bound = aging_remainder(u_e, L_e, k, a, b)
        else:
            rem, bound = slip_remainder(u_e, xi_e, k, a, b)
        if aging or u_end is not None or bound <= TAIL_BOUND_REL * (xi_e + rem):
            break
        U *= 10.0
    else:
        raise RuntimeError("remainder bound not met")
    return StopSolution(chi, A, mu1, m2, aging, True, xi_e + rem, xi_e, u_e, rem, bound,
                        float(p2.y[0, 0]), math.exp(float(p2.t[0])), S_e, used, nfev, time.perf_counter() - t0,
                        p1, p2)


# ---------------------------------------------------------------------------------------------------------
# driven scene


def linear_roots(chi: float, mu1: float, A: float) -> np.ndarray:
    """Roots of A s^2 + (chi - mu1) s + chi = 0 (either law), larger real part first."""
    r = np.roots([A, chi - mu1, chi]).astype(complex)
    return r[np.lexsort((-r.imag, -r.real))]


@dataclass(frozen=True)
class DrivenSolution:
    """Cycles of the driven scene, counted as the engine counts them: cycle n (n >= 1) ends at the (n+1)-th
    maximum of z (the start z = p, z' < 0, is not counted); amplitude[n] = (z_max - z_min)/2 with the minimum
    just before that maximum, period[n] = time between the n-th and (n+1)-th maxima, growth[n] =
    ln(amplitude[n]/amplitude[n-1])/period[n] (NaN for n = 1). Arrays are indexed by n (index 0 unused, NaN)."""

    chi: float
    A: float
    mu1: float
    m2: float
    aging: bool
    perturbation: float
    amplitude: np.ndarray
    period: np.ndarray
    growth: np.ndarray
    regime: str  # "steady", "stick_slip", "neutral", "runaway" or "undecided" (see driven())
    peak_w: float
    nfev: int


def driven(chi: float, A: float, mu1: float, m2: float, perturbation: float = 1e-3, aging: bool = False,
           cycles: int = 12, method: str = "DOP853", rtol: float = 1e-12, w_runaway: float = math.log(1e8),
           stationary_tol: float = 1e-7, decayed: float = 1e-3, stop_when_decided: bool = True) -> DrivenSolution:
    """Driven scene from z(0) = perturbation, u(0) = 0 (module docstring, section 4), for ``cycles`` cycles
    (engine numbering) or until decided earlier. Regime: runaway if w = ln xi' passes ``w_runaway``; steady if
    the amplitude (or the state) falls below ``decayed`` x perturbation; if three successive amplitudes are
    stationary (|a_n/a_(n-1) - 1| <= stationary_tol): neutral where the amplitude is still the first cycle's
    (within 1 %), else stick_slip (a limit cycle reached by growing); else undecided (the per-cycle growth rates
    still say which way it goes). ``stop_when_decided=False`` runs all ``cycles`` cycles (unless runaway) and
    decides at the end."""
    k, a, b = chi / A, mu1 / A, m2 / A
    count = [0]

    def w_of(z, u):
        return k * z - u * (a + b * u) - u

    def f(t, y):
        count[0] += 1
        z, u = y
        w = w_of(z, u)
        e = math.exp(w)
        du = math.exp(-u) - e if aging else -e * (w + u)
        return np.array([1.0 - e, du])

    def jac(t, y):
        z, u = y
        w = w_of(z, u)
        e = math.exp(w)
        wu = -(a + 2.0 * b * u) - 1.0
        if aging:
            return np.array([[-e * k, -e * wu], [-e * k, -math.exp(-u) - e * wu]])
        return np.array([[-e * k, -e * wu], [-e * (w + u) * k - e * k, -e * (w + u) * wu - e * (wu + 1.0)]])

    def maximum(t, y):  # z' = 1 - e^w crosses 0 downwards <=> w crosses 0 upwards
        return w_of(*y)

    maximum.direction = 1.0

    def minimum(t, y):
        return w_of(*y)

    minimum.direction = -1.0

    def runaway(t, y):
        return w_of(*y) - w_runaway

    runaway.terminal, runaway.direction = True, 1.0
    opts = {"jac": jac} if method in ("Radau", "BDF") else {}
    omega = math.sqrt(max(k - 0.25 * (k - a) ** 2, 1e-6 * k))
    span = 2.0 * math.pi / omega
    t, y = 0.0, np.array([perturbation, 0.0])
    maxima, minima = [], []  # (time, z)
    regime, peak_w = "undecided", w_of(*y)
    amps = [math.nan]
    def cycle_amplitudes():
        out = [math.nan]
        for i in range(1, len(maxima)):
            t_prev, (t_max, z_max) = maxima[i - 1][0], maxima[i]
            z_min = [v for s, v in minima if t_prev < s < t_max]
            out.append(0.5 * (z_max - z_min[-1]) if z_min else math.nan)
        return out

    while True:
        res = solve_ivp(f, (t, t + 4.0 * span), y, method=method, rtol=rtol, atol=1e-14 * perturbation,
                        events=(maximum, minimum, runaway), dense_output=True, **opts)
        if not res.success:
            raise RuntimeError(res.message)
        peak_w = max(peak_w, max(w_of(*res.sol(s)) for s in np.linspace(t, res.t[-1], 200)))
        maxima += [(float(s), float(v[0])) for s, v in zip(res.t_events[0], res.y_events[0])]
        minima += [(float(s), float(v[0])) for s, v in zip(res.t_events[1], res.y_events[1])]
        amps = cycle_amplitudes()
        if res.status == 1:
            regime = "runaway"
            break
        t, y = float(res.t[-1]), res.y[:, -1]
        n = len(amps) - 1
        if not stop_when_decided and n < cycles and max(abs(y[0]), abs(y[1])) >= 1e-9 * perturbation:
            continue
        if (n >= 1 and amps[-1] < decayed * perturbation) or max(abs(y[0]), abs(y[1])) < decayed * perturbation:
            regime = "steady"
            break
        if n >= 4 and all(abs(amps[j] / amps[j - 1] - 1.0) <= stationary_tol for j in range(n - 2, n + 1)):
            regime = "neutral" if abs(amps[-1] / amps[1] - 1.0) <= 1e-2 else "stick_slip"
            break
        if n >= cycles:
            break
    n = len(amps)
    amplitude = np.array(amps)
    period = np.full(n, np.nan)
    growth = np.full(n, np.nan)
    for i in range(1, n):
        period[i] = maxima[i][0] - maxima[i - 1][0]
        if i >= 2:
            growth[i] = math.log(amplitude[i] / amplitude[i - 1]) / period[i]
    return DrivenSolution(chi, A, mu1, m2, aging, perturbation, amplitude, period, growth, regime, peak_w, count[0])
