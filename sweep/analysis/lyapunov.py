"""The type of the Hopf bifurcation of the driven scene from its normal form (docs/hopf-type.md): the first Lyapunov
coefficient l1 along the Hopf line with its error, the Bautin (generalised Hopf) points where l1 changes sign, and
the bistable band above an inverted (subcritical) line, measured by simulation.

Equations (docs/physics.md 3b), reduced time tau, rates over A: k = chi/A, a = mu1(V)/A, b = m2/A, g = gamma/A.
With L = k z - (a + 1) u - b u^2 (= ln xi' in the quasi-static model):

    quasi-static, aging:  z' = 1 - e^L,   u' = e^-u - e^L                        state (z, u)
    quasi-static, slip:   z' = 1 - e^L,   u' = -e^L (L + u)                      state (z, u)
    inertial, aging:      z' = 1 - e^w,   u' = e^-u - e^w,   w' = (L - w) e^-w / g   state (z, u, w)

(the package has no inertial slip-law model, so none here). Steady sliding is the origin. On the Hopf line
k_c = a (1 + g) the Jacobian has the eigenvalues +-i omega, omega = sqrt(a) (eq. 4 in tau units), and, with inertia,
-(1 + g)/g.

**l1** (Kuznetsov, Elements of Applied Bifurcation Theory, 3rd ed., eq. 3.20 and 5.39): with J q = i omega q,
J^T p = -i omega p, <p, q> = conj(p) . q = 1, and B, C the second and third derivatives of the right-hand side at the
origin (symmetric multilinear forms, written out exactly in :func:`model_forms`),

    l1 = Re[ <p, C(q, q, qbar)> - 2 <p, B(q, J^-1 B(q, qbar))> + <p, B(qbar, (2 i omega - J)^-1 B(q, q))> ] / (2 omega)

so that the critical mode x = 2 Re(w q) + O(|w|^2) obeys w' = lambda w + c1 w |w|^2, Re c1 = omega l1, i.e. the
radius r = |w| obeys r' = Re(lambda) r + omega l1 r^3 (per unit tau). l1 < 0: direct (supercritical), l1 > 0:
inverted (subcritical). The value depends on the scale of q; the sign does not.

**Normalisation** (NORMALISATION): q is scaled so that its first component has modulus 1/2 ("stretch"): then r is
the amplitude of the spring stretch z = tau - xi (to leading order, the driven scene's ``amplitude``), and just below
a direct line the stationary cycle has r^2 = Re(dlambda/dk) (k - k_c) / (omega l1). For a textbook oscillator whose
first component is x this is the "z = x + i y" scaling (Lienard: l1 = -1/8). ``normalisation="unit"`` gives
Kuznetsov's <q, q> = 1 instead (l1 scales with the square of the
eigenvector's length: unit = 4 |q_0|^2 x stretch, q_0 the first component of the unit vector; Lienard: -1/4).

The second Lyapunov coefficient is not computed: its sign at the Bautin point comes from simulation (the bistable
band of sweep/analysis/bistable.py exists on the inverted side and shrinks like l1^2: l2 < 0; docs/hopf-type.md 4).

**Error** (:func:`first_lyapunov_with_error`): l1 again from central finite differences of the right-hand side
(B and C by polarisation of the second and third directional derivatives, complex directions, steps h and h/2,
h = FD_STEP / |q|); with l1_R the Richardson extrapolation of the two,

    l1_error = |l1_fd(h/2) - l1_fd(h)| / 3 + |l1 - l1_R| + ROUNDOFF eps S

S the sum of the moduli of the three terms of the bracket above over 2 omega. The first two terms bound how far
the exact value may sit from an independent evaluation (they are dominated by the finite differences' own error,
so l1_error is an upper estimate: the exact value is closer); the last is the rounding of the exact evaluation. A
wrong derivative in :func:`model_forms` shows as an l1_error of the order of l1 (tested).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import NamedTuple

import numpy as np

from .. import physics
from ..errors import InputError
from ..plan.plan import line_uses_inertia
from ..scene.params import FrictionParams

__all__ = ["BautinPoint", "Forms", "HopfNormalForm", "LyapunovLine", "NORMALISATION", "TYPES", "bautin_points",
           "first_lyapunov", "first_lyapunov_with_error", "lyapunov_line", "model_forms", "reduced_l1"]

NORMALISATION = "stretch"
"""q scaled so that |q_0| = 1/2: the normal-form radius is the amplitude of the spring stretch z (module docstring)."""
FD_STEP = 2e-3
"""Finite-difference step of the error estimate, relative to |q| (the third derivative's truncation h^2 and its
rounding eps/h^3 balance near eps^(1/5) ~ 7e-4)."""
ROUNDOFF = 64.0
"""Rounding of the exact evaluation: ROUNDOFF x eps x the sum of the moduli of the terms of l1."""
TYPES = ("none", "supercritical", "subcritical", "degenerate")
"""Type flag from l1: no line (mu1 <= 0), l1 < -error (direct), l1 > error (inverted), |l1| <= error."""
SCAN_POINTS = 400
"""Velocities (log-spaced) on which l1 is scanned for sign changes before each root is refined."""

Form2 = Callable[[np.ndarray, np.ndarray], np.ndarray]
Form3 = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


class Forms(NamedTuple):
    """A vector field at an equilibrium, batched over N points: Jacobian J (N, n, n), its derivative along the
    bifurcation parameter dJ (N, n, n) (or None), the exact multilinear forms B(v1, v2) and C(v1, v2, v3) on (N, n)
    complex vectors, and the field f(y) itself on (N, n) (complex) states, equilibrium y0 (N, n), for the
    finite-difference check."""

    J: np.ndarray
    dJ: np.ndarray | None
    B: Form2
    C: Form3
    f: Callable[[np.ndarray], np.ndarray]
    y0: np.ndarray


class HopfNormalForm(NamedTuple):
    """Normal-form data of a batch of Hopf points (arrays over N)."""

    l1: np.ndarray
    """First Lyapunov coefficient [1] in the stated normalisation."""
    omega: np.ndarray
    """Critical pulsation (imaginary part of the critical eigenvalue) [1/time of the field]."""
    q: np.ndarray
    """Right eigenvectors (N, n)."""
    p: np.ndarray
    """Left eigenvectors (N, n), <p, q> = 1."""
    dlambda: np.ndarray
    """d lambda / d(parameter) = <p, dJ q> (complex; NaN where dJ is None)."""
    terms: np.ndarray
    """Sum of the moduli of the three terms of l1 over 2 omega (the rounding scale)."""


def _bdot(p: np.ndarray, x: np.ndarray) -> np.ndarray:
    """<p, x> = sum conj(p) x over the last axis."""
    return np.einsum("ni,ni->n", p.conj(), x)


def _solve(M: np.ndarray, x: np.ndarray) -> np.ndarray:
    return np.linalg.solve(M, x[..., None])[..., 0]


def _critical_pair(J: np.ndarray, normalisation: str, index: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(omega, q, p) of the eigenvalue with positive imaginary part nearest the imaginary axis."""
    n_pts = J.shape[0]
    lam, vec = np.linalg.eig(J)
    score = np.where(lam.imag > 0.0, np.abs(lam.real), np.inf)
    pick = np.argmin(score, axis=1)
    rows = np.arange(n_pts)
    lam0 = lam[rows, pick]
    q = vec[rows, :, pick]
    lamT, vecT = np.linalg.eig(np.swapaxes(J, 1, 2))
    pickT = np.argmin(np.abs(lamT - lam0.conj()[:, None]), axis=1)
    p = vecT[rows, :, pickT]
    if normalisation == "stretch":
        q = q * (0.5 / q[:, index])[:, None]  # q_index = 1/2, real
    elif normalisation == "unit":
        q = q / np.linalg.norm(q, axis=1)[:, None]
    else:
        raise InputError(f"normalisation must be 'stretch' or 'unit', got {normalisation!r}")
    p = p / _bdot(p, q).conj()[:, None]
    return lam0.imag, q, p


def first_lyapunov(forms: Forms, normalisation: str = NORMALISATION, index: int = 0) -> HopfNormalForm:
    """l1 of every point of ``forms`` at its Hopf point (module docstring; Kuznetsov's formula), with q normalised by
    ``normalisation`` ("stretch": |q[index]| = 1/2; "unit": <q, q> = 1)."""
    return _l1(forms.J, forms.B, forms.C, forms.dJ, normalisation, index)


def _l1(J, B: Form2, C: Form3, dJ, normalisation: str, index: int) -> HopfNormalForm:
    omega, q, p = _critical_pair(J, normalisation, index)
    n = J.shape[1]
    qb = q.conj()
    eye = np.eye(n)[None]
    h11 = _solve(J.astype(complex), B(q, qb))  # J^-1 B(q, qbar)
    h20 = _solve(2j * omega[:, None, None] * eye - J, B(q, q))
    t1, t2, t3 = _bdot(p, C(q, q, qb)), -2.0 * _bdot(p, B(q, h11)), _bdot(p, B(qb, h20))
    l1 = (t1 + t2 + t3).real / (2.0 * omega)
    terms = (np.abs(t1) + np.abs(t2) + np.abs(t3)) / (2.0 * omega)
    dlam = _bdot(p, np.einsum("nij,nj->ni", dJ, q)) if dJ is not None else np.full(J.shape[0], np.nan + 0j)
    return HopfNormalForm(l1, omega, q, p, dlam, terms)


# --- finite-difference forms (the error estimate) ---------------------------------------------------------------

def _fd_forms(f: Callable[[np.ndarray], np.ndarray], y0: np.ndarray, h: np.ndarray) -> tuple[Form2, Form3]:
    """B and C of f at y0 from central differences of order h^2 along complex directions (f is analytic), by
    polarisation: B(x, y) = [D2(x + y) - D2(x - y)] / 4, C(x, x, y) = [D3(x + y) - D3(x - y) - 2 D3(y)] / 6."""
    hh = h[:, None]
    f0 = f(y0.astype(complex))

    def d2(v):
        return (f(y0 + hh * v) - 2.0 * f0 + f(y0 - hh * v)) / hh**2

    def d3(v):
        return (f(y0 + 2 * hh * v) - 2.0 * f(y0 + hh * v) + 2.0 * f(y0 - hh * v) - f(y0 - 2 * hh * v)) / (2 * hh**3)

    def B(x, y):
        return 0.25 * (d2(x + y) - d2(x - y))

    def C(x, x2, y):  # the l1 formula needs C(q, q, qbar) only: x2 is x
        return (d3(x + y) - d3(x - y) - 2.0 * d3(y)) / 6.0

    return B, C


def first_lyapunov_with_error(forms: Forms, normalisation: str = NORMALISATION,
                              index: int = 0) -> tuple[HopfNormalForm, np.ndarray]:
    """(normal form with the exact l1, l1_error): the error estimate of the module docstring (finite differences at
    two steps against the exact forms, plus rounding)."""
    nf = first_lyapunov(forms, normalisation, index)
    scale = np.linalg.norm(nf.q, axis=1)
    fd = []
    for step in (FD_STEP, 0.5 * FD_STEP):
        B, C = _fd_forms(forms.f, forms.y0, step / scale)
        fd.append(_l1(forms.J, B, C, None, normalisation, index).l1)
    richardson = fd[1] + (fd[1] - fd[0]) / 3.0
    error = np.abs(fd[1] - fd[0]) / 3.0 + np.abs(nf.l1 - richardson) + ROUNDOFF * np.finfo(float).eps * nf.terms
    return nf, error


# --- the model ----------------------------------------------------------------------------------------------------

def model_forms(k, a, b, g, law: str = "aging") -> Forms:
    """The driven scene's right-hand side at steady sliding (module docstring), batched over the arrays k, a, b, g
    (reduced by A; g = 0: quasi-static, the state (z, u); g > 0: inertial, (z, u, w)), with its exact second and
    third derivatives B, C and the Jacobian's derivative along k. ``law``: "aging", or "slip" (quasi-static only)."""
    k, a, b, g = (np.atleast_1d(np.asarray(x, dtype=float)) for x in (k, a, b, g))
    k, a, b, g = np.broadcast_arrays(k, a, b, g)
    if law not in ("aging", "slip"):
        raise InputError(f"state_law must be 'aging' or 'slip', got {law!r}")
    inertial = g > 0.0
    if inertial.any() and not inertial.all():
        raise InputError("model_forms takes quasi-static (g = 0) or inertial (g > 0) points, not both at once")
    if inertial.all():
        if law != "aging":
            raise InputError("state_law 'slip' has no inertial driven model in the package (aging only)")
        return _inertial_forms(k, a, b, g)
    return _quasistatic_forms(k, a, b, law)


def _quasistatic_forms(k, a, b, law: str) -> Forms:
    n_pts = k.size
    kc, ac, bc = k[:, None], a[:, None], b[:, None]
    J = np.zeros((n_pts, 2, 2))
    J[:, 0, 0], J[:, 0, 1], J[:, 1, 0], J[:, 1, 1] = -k, a + 1.0, -k, a
    dJ = np.zeros((n_pts, 2, 2))
    dJ[:, 0, 0], dJ[:, 1, 0] = -1.0, -1.0

    def dL(v):  # first derivative of L = k z - (a + 1) u - b u^2 at u = 0
        return k * v[:, 0] - (a + 1.0) * v[:, 1]

    def d2L(v, x):
        return -2.0 * b * v[:, 1] * x[:, 1]

    def dM(v):  # M = L + u = ln E (slip law)
        return k * v[:, 0] - a * v[:, 1]

    def e2(v, x):  # second derivative of e^L at L = 0
        return dL(v) * dL(x) + d2L(v, x)

    def e3(v, x, y):
        return dL(v) * dL(x) * dL(y) + dL(v) * d2L(x, y) + dL(x) * d2L(v, y) + dL(y) * d2L(v, x)

    def B(v, x):
        first = -e2(v, x)
        if law == "aging":
            second = v[:, 1] * x[:, 1] - e2(v, x)
        else:  # -(e^L M)'' with M = 0 at the origin
            second = -(dL(v) * dM(x) + dL(x) * dM(v) + d2L(v, x))
        return np.stack([first, second], axis=1)

    def C(v, x, y):
        first = -e3(v, x, y)
        if law == "aging":
            second = -v[:, 1] * x[:, 1] * y[:, 1] - e3(v, x, y)
        else:
            second = -(e2(v, x) * dM(y) + e2(v, y) * dM(x) + e2(x, y) * dM(v)
                       + dL(v) * d2L(x, y) + dL(x) * d2L(v, y) + dL(y) * d2L(v, x))
        return np.stack([first, second], axis=1)

    def f(y):
        z, u = y[:, 0], y[:, 1]
        L = kc[:, 0] * z - (ac[:, 0] + 1.0) * u - bc[:, 0] * u**2
        e = np.exp(L)
        second = np.exp(-u) - e if law == "aging" else -e * (L + u)
        return np.stack([1.0 - e, second], axis=1)

    return Forms(J, dJ, B, C, f, np.zeros((n_pts, 2)))


def _inertial_forms(k, a, b, g) -> Forms:
    n_pts = k.size
    J = np.zeros((n_pts, 3, 3))
    J[:, 0, 2] = -1.0
    J[:, 1, 1], J[:, 1, 2] = -1.0, -1.0
    J[:, 2, 0], J[:, 2, 1], J[:, 2, 2] = k / g, -(a + 1.0) / g, -1.0 / g
    dJ = np.zeros((n_pts, 3, 3))
    dJ[:, 2, 0] = 1.0 / g

    def dN(v):  # N = L - w
        return k * v[:, 0] - (a + 1.0) * v[:, 1] - v[:, 2]

    def d2N(v, x):
        return -2.0 * b * v[:, 1] * x[:, 1]

    def B(v, x):
        ww = v[:, 2] * x[:, 2]
        third = (d2N(v, x) - dN(v) * x[:, 2] - dN(x) * v[:, 2]) / g
        return np.stack([-ww, v[:, 1] * x[:, 1] - ww, third], axis=1)

    def C(v, x, y):
        www = v[:, 2] * x[:, 2] * y[:, 2]
        third = (-d2N(v, x) * y[:, 2] - d2N(v, y) * x[:, 2] - d2N(x, y) * v[:, 2]
                 + dN(v) * x[:, 2] * y[:, 2] + dN(x) * v[:, 2] * y[:, 2] + dN(y) * v[:, 2] * x[:, 2]) / g
        return np.stack([-www, -v[:, 1] * x[:, 1] * y[:, 1] - www, third], axis=1)

    def f(y):
        z, u, w = y[:, 0], y[:, 1], y[:, 2]
        e = np.exp(w)
        return np.stack([1.0 - e, np.exp(-u) - e, (k * z - (a + 1.0) * u - b * u**2 - w) * np.exp(-w) / g], axis=1)

    return Forms(J, dJ, B, C, f, np.zeros((n_pts, 3)))


def reduced_l1(a, b, g, law: str = "aging", error: bool = True,
               normalisation: str = NORMALISATION) -> tuple[np.ndarray, np.ndarray, HopfNormalForm]:
    """(l1, l1_error, normal form) on the Hopf line k = a (1 + g) of the reduced parameters a = mu1/A > 0, b = m2/A,
    g = gamma/A (arrays; g = 0 quasi-static, else inertial; all of one kind). l1_error is NaN without ``error``."""
    a, b, g = np.broadcast_arrays(*(np.atleast_1d(np.asarray(x, dtype=float)) for x in (a, b, g)))
    forms = model_forms(a * (1.0 + g), a, b, g, law)
    if error:
        nf, err = first_lyapunov_with_error(forms, normalisation)
    else:
        nf, err = first_lyapunov(forms, normalisation), np.full(a.shape, np.nan)
    return nf.l1, err, nf


# --- along a Hopf line --------------------------------------------------------------------------------------------

class LyapunovLine(NamedTuple):
    """l1 along a Hopf line over V (arrays over V; NaN and type "none" where mu1(V) <= 0)."""

    l1: np.ndarray
    """First Lyapunov coefficient [1] (stretch normalisation, tau time)."""
    l1_error: np.ndarray
    """Its error estimate [1] (module docstring)."""
    kind: np.ndarray
    """Index into TYPES."""
    amplitude_coefficient: np.ndarray
    """c in: stationary stretch amplitude r = sqrt(c d) at the relative distance d = 1 - chi/chi_c below a direct
    line (c = Re(dlambda/dk) k_c / (omega l1)); NaN where the line is not direct."""
    inertial: np.ndarray
    """Whether the inertial model was used (bool)."""
    gamma_over_A: np.ndarray
    """gamma/A at each V [1] (whatever the model)."""


def _check(params: FrictionParams, V, model: str, state_law: str, model_tol: float) -> np.ndarray:
    if not isinstance(params, FrictionParams):
        raise InputError(f"params must be a sweep.FrictionParams, got {type(params).__name__}")
    if model not in ("auto", "quasistatic", "inertial"):
        raise InputError(f"model must be one of ['auto', 'quasistatic', 'inertial'], got {model!r}")
    if state_law not in ("aging", "slip") or (state_law == "slip" and model != "quasistatic"):
        raise InputError(f"state_law must be 'aging' or 'slip' (slip with model 'quasistatic' only), got "
                         f"state_law={state_law!r}, model={model!r}")
    if not (math.isfinite(model_tol) and 1e-6 <= model_tol <= 0.5):
        raise InputError(f"model_tol must be in [1e-06, 0.5], got {model_tol!r}")
    v = np.asarray(V, dtype=float).reshape(-1)
    if v.size == 0 or not np.all(np.isfinite(v)) or np.any(v <= 0):
        raise InputError(f"V must be a non-empty sequence of finite velocities > 0 [m s-1], got {V!r}")
    return v


def lyapunov_line(params: FrictionParams, V: Sequence[float] | np.ndarray, model: str = "auto",
                  state_law: str = "aging", model_tol: float = 1e-2, error: bool = True) -> LyapunovLine:
    """l1 and its error at every velocity ``V`` [m s-1] on the Hopf line chi_c = mu1(V) (1 + gamma/A) of ``model``
    ("quasistatic", "inertial", or "auto": inertial where gamma/A > ``model_tol``, as sweep.locate_hopf), with the
    type it gives (TYPES) and the square-root law's coefficient on the direct side."""
    v = _check(params, V, model, state_law, model_tol)
    p = params
    a = np.asarray(physics.mu1(v, p.m1, p.m2, p.V0), dtype=float).reshape(-1) / p.A
    g_all = np.asarray(physics.inertia_number(v, p.D0, p.g), dtype=float).reshape(-1) / p.A
    inertial = np.asarray(line_uses_inertia(g_all, model, model_tol), dtype=bool).reshape(-1)
    g = np.where(inertial, g_all, 0.0)
    l1, err, coef = (np.full(v.size, np.nan) for _ in range(3))
    kind = np.zeros(v.size, np.int8)
    for sel in (inertial & (a > 0), ~inertial & (a > 0)):  # one batch per model
        if not sel.any():
            continue
        l1[sel], err[sel], nf = reduced_l1(a[sel], p.m2 / p.A, g[sel], state_law, error)
        k_c = a[sel] * (1.0 + g[sel])
        with np.errstate(invalid="ignore", divide="ignore"):
            coef[sel] = np.where(l1[sel] < 0, nf.dlambda.real * k_c / (nf.omega * l1[sel]), np.nan)
    has = a > 0
    bound = np.where(np.isfinite(err), err, 0.0)
    kind[has] = np.where(l1[has] < -bound[has], 1, np.where(l1[has] > bound[has], 2, 3))
    if not error:
        kind[has & (l1 == 0.0)] = 3
    coef[kind != 1] = np.nan
    return LyapunovLine(l1, err, kind, coef, inertial, g_all)


class BautinPoint(NamedTuple):
    """A generalised Hopf (Bautin) point: where l1 changes sign along the line."""

    V: float
    """Velocity [m s-1]."""
    gamma_over_A: float
    """gamma/A there [1]."""
    K_over_M: float
    """K/M on the Hopf line there [s-2]."""
    direct_above: bool
    """Whether the line is direct (l1 < 0) at larger V."""
    bracket: tuple[float, float]
    """The final bracket in V [m s-1] (relative width in gamma/A <= the tolerance)."""


def bautin_points(params: FrictionParams, V_range: tuple[float, float], model: str = "inertial",
                  state_law: str = "aging", rtol: float = 1e-4) -> list[BautinPoint]:
    """Bautin points on the Hopf line of ``model`` ("inertial" along the whole line; "quasistatic") between the
    velocities ``V_range`` [m s-1]: l1 scanned on SCAN_POINTS log-spaced V where mu1 > 0, a root accepted only
    between scan points where |l1| exceeds l1_error on both sides (so the quasi-static m2 = 0 line, l1 = 0
    identically, has none), then bisected in ln V to a relative width ``rtol`` in gamma/A (gamma ~ V^2); the point
    is the root of the chord of l1 across that bracket."""
    if model not in ("inertial", "quasistatic"):
        raise InputError(f"model must be 'inertial' or 'quasistatic' (one model along the whole line), got {model!r}")
    lo, hi = (float(x) for x in V_range)
    _check(params, [lo, hi], model, state_law, 1e-2)
    if not hi > lo:
        raise InputError(f"V_range must be (low, high) with high > low > 0 [m s-1], got {V_range!r}")
    if not (math.isfinite(rtol) and 1e-12 <= rtol <= 0.1):
        raise InputError(f"rtol must be in [1e-12, 0.1] (relative width in gamma/A), got {rtol!r}")
    p = params
    v = np.geomspace(lo, hi, SCAN_POINTS)
    line = lyapunov_line(p, v, model=model, state_law=state_law)
    sign = np.where(line.kind == 1, -1, np.where(line.kind == 2, 1, 0))
    known = np.flatnonzero(sign != 0)
    points = []
    for i, j in zip(known[:-1], known[1:]):
        if sign[i] == sign[j]:
            continue
        x_lo, x_hi = math.log(v[i]), math.log(v[j])
        f_lo, f_hi = line.l1[i], line.l1[j]
        while x_hi - x_lo > 0.5 * rtol:  # gamma ~ V^2: relative width 2 dx in gamma/A
            mid = 0.5 * (x_lo + x_hi)
            l1_mid = _l1_at(p, math.exp(mid), model, state_law)
            if l1_mid == 0.0:
                x_lo = x_hi = mid
                break
            if np.sign(l1_mid) == np.sign(f_lo):
                x_lo, f_lo = mid, l1_mid
            else:
                x_hi, f_hi = mid, l1_mid
        # the root of the chord across the final bracket: its error (~ the bracket squared) is far inside the bracket
        x_b = x_lo if x_lo == x_hi else x_lo + (x_hi - x_lo) * f_lo / (f_lo - f_hi)
        v_b = math.exp(x_b)
        g = float(physics.inertia_number(v_b, p.D0, p.g)) / p.A if model == "inertial" else 0.0
        mu1 = float(physics.mu1(v_b, p.m1, p.m2, p.V0))
        points.append(BautinPoint(v_b, float(physics.inertia_number(v_b, p.D0, p.g)) / p.A,
                                  mu1 * (1.0 + g) * p.g / p.D0, bool(sign[j] < 0),
                                  (math.exp(x_lo), math.exp(x_hi))))
    return points


def _l1_at(p: FrictionParams, v: float, model: str, state_law: str) -> float:
    """Exact l1 at one velocity on the line of ``model`` (no error estimate: the bisection needs the sign)."""
    a = float(physics.mu1(v, p.m1, p.m2, p.V0)) / p.A
    g = float(physics.inertia_number(v, p.D0, p.g)) / p.A if model == "inertial" else 0.0
    return float(reduced_l1(a, p.m2 / p.A, g, state_law, error=False)[0][0])
