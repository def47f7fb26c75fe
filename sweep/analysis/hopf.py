"""The Hopf line located by simulation (docs/physics.md 3b): where the measured growth rate of small oscillations of the
driven scene changes sign, and the type of the bifurcation decided from simulations around it.

For each V: the line is bracketed around the linear prediction chi_c = mu1(V) (1 + gamma/A) (gamma = 0 for the
quasi-static model), the sign of the growth rate measured from the simulated envelope
(sweep/integrate/models/driven.py, a perturbation of SIGN_PERTURBATION, SIGN_CYCLES cycles) is checked at both ends,
and the bracket is narrowed around the root estimated from the measured rates until its relative width is below
``rtol`` (default 0.1 %; :func:`_locate`); K_over_M_c is its midpoint. The linear value is stored beside it. Where
mu1(V) <= 0 there is no line (steady sliding is stable at every stiffness): NaN and bifurcation "none". The
searches of all velocities advance in lockstep, each round's driven runs in one batch (sweep/analysis/hopf_batch.py).

The bifurcation type is decided from simulations, never assumed:

* supercritical: just below the line a small perturbation grows into stationary limit cycles (regime
  stick_slip) whose amplitudes follow the square root law: of the runs at distances d, 2d and 4d (d =
  TYPE_DISTANCE), the closest and farthest decided ones in the ratio sqrt(d2/d1) within SQRT_LAW_SPREAD;
* subcritical: above the line (at d, then at d/4, still outside the located bracket) a large start
  (LARGE_PERTURBATION, or 1.2x the largest stick-slip cycle found below) keeps a stick-slip attractor while a
  small one decays (hysteresis; the window can be narrow: m2 = 0 at gamma/A = 0.1 keeps cycles at 0.1 % above the
  line, not at 0.4 %);
* degenerate: no limit cycle on either side: just below the line a small start runs away, just above it a large
  start decays (quasi-static m2 = 0, whose orbits at the line are neutral; the located line is a bracket, so the
  neutral orbits themselves are tested at the exact line in tests/integrate/test_driven.py);
* undetermined: none of these (e.g. a slow transient left undecided); the type is not guessed.

Next to it, the type from the normal form (sweep/analysis/lyapunov.py, docs/hopf-type.md): the first Lyapunov
coefficient ``l1`` with its error ``l1_error`` at every V (the model of that V), the type it gives
(``bifurcation_l1``) and whether the two types agree where both exist (``types_agree``); the Bautin points where l1
changes sign between the smallest and largest V (inertial model along the whole line unless ``model`` is
"quasistatic": "auto" switches model at gamma/A = model_tol, a false type change) as attributes; with
``bistable_band``, the upper edge of the bistable band above the line where l1 > 0, measured by simulation
(sweep/analysis/bistable.py). :func:`hopf_summary` gives the lines ``sweep hopf`` prints.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import xarray as xr

from .. import physics
from ..accuracy import (
    BRACKET,
    INERTIA_NEGLIGIBLE,
    LARGE_PERTURBATION,
    SIGN_CYCLES,
    SIGN_PERTURBATION,
    SQRT_LAW_SPREAD,
    STEPPER_RTOL,
    TYPE_CYCLES,
    TYPE_DISTANCE,
)
from ..assemble.dataset import REFERENCES, versions
from ..errors import InputError
from ..integrate.driven import Regime
from ..plan.plan import line_uses_inertia
from ..run.compile_notice import announce_if_cold, driven_families
from ..run.progress import Progress
from ..scene.params import FrictionParams
from ..scene.plausibility import warn_implausible
from ..scene.scene import MODEL_TOL_RANGE, MODELS, STATE_LAWS
from ..status import MODEL_FLAG
from . import bistable
from .hopf_batch import TYPE_RTOL, Run, Search, drive
from .lyapunov import TYPES, bautin_points, lyapunov_line

__all__ = ["hopf_summary", "locate_hopf", "with_simulated_line"]

BIFURCATIONS = ("none", "supercritical", "subcritical", "degenerate", "undetermined")
AGREEMENT = ("not_compared", "agree", "disagree")
"""types_agree: simulation and l1 both decided a type (none / undetermined are not compared)."""
BAUTIN_RTOL = 1e-4
"""Relative width in gamma/A of the bracket left around each Bautin point (issue target 1e-3)."""
BAND_RTOL = 1e-2
"""Relative precision of the bistable band's upper edge."""


SMALL_START = 1e-4
"""Initial stretch of the small starts above the line (which must decay where the line is subcritical)."""
BELOW_START = 1e-3
"""Initial stretch of the runs below the line, which grow into the limit cycle (amplitudes 0.07..0.4 at 0.4 % below
sample2's line): against 1e-4, the same regimes and amplitudes within 9e-8, 17 % fewer steps (45 velocities at
0.4 and 1.6 % below the line)."""
STRADDLE = 0.45
"""Once the root estimate x has settled (it moved by less than STRADDLE rtol x in the last round), the growth rate
is measured at x (1 -+ STRADDLE rtol): where the signs differ there, the bracket left is 0.9 rtol wide."""


def _root_estimate(points: list[tuple[float, float]]) -> float:
    """Where the measured growth rate r(k) vanishes, from the (k, r) ``points``: inverse quadratic interpolation
    through the three with the smallest |r| (the chord's root through two of them where the rates of a pair are
    within 1e-12 relative of each other, or fewer than three are given)."""
    near = sorted(points, key=lambda point: abs(point[1]))[:3]
    rates = [r for _, r in near]
    if len(near) == 3 and all(abs(r1 - r2) > 1e-12 * max(abs(r1), abs(r2)) for i, r1 in enumerate(rates)
                              for r2 in rates[i + 1:]):
        return sum(k_i * math.prod(-r_j / (r_i - r_j) for j, r_j in enumerate(rates) if j != i)
                   for i, (k_i, r_i) in enumerate(near))
    (k1, r1), (k2, r2) = near[0], next((point for point in near[1:] if point[1] != near[0][1]), near[0])
    return k1 if r1 == r2 else k1 - r1 * (k2 - k1) / (r2 - r1)


def _locate(a: float, b: float, g: float, rtol: float) -> Search:
    """Search (sweep/analysis/hopf_batch.py) for the reduced critical stiffness k_c = chi_c/A where the measured
    growth rate changes sign, bracketed around the linear value a (1 + g); returns (k_c, evaluations).

    The growth rate is a smooth function of k through the line (linear for the quasi-static model: Re sigma =
    (a - k)/2), so after the initial bracket a (1 + g) (1 -+ BRACKET) (widened by the same factors until the signs
    differ) each round estimates the root x from the rates measured so far (:func:`_root_estimate`, inside the
    bracket) and measures the rate at x, or, once x has settled, at both sides x -+ s: s = STRADDLE rtol x, or
    less where an end of the bracket is closer (that end is then one side; s >= STRADDLE rtol x / 10). Settled: x
    moved by less than STRADDLE rtol x since the last round (the first estimate, from the chord, is compared with
    the linear value and must be within a quarter of that). The bracket is the tightest pair of measured points
    with opposite signs; K_c is its midpoint once narrower than ``rtol`` after a round at both sides of a settled
    estimate (a single run near the root can leave a bracket narrower than rtol with the root at one end), or
    narrower than rtol / 10. Measured (sample2; the inertial m2 = 0
    line at gamma/A 1e-3..10; rtol 1e-3..1e-8): 4 to 6 runs (bisection: 2 + log2(0.2/rtol), 10 at rtol 1e-3), the
    midpoint within 0.03 rtol of the linear value. Safeguard (Brent's): an estimate outside the bracket, or two
    rounds in a row that do not halve it, make the next round a bisection (the midpoint), so the bracket at least
    halves every third round.

    Inertia moves the line by g = gamma/A relative; below INERTIA_NEGLIGIBLE x rtol that shift is far inside the
    bracket, and the explicit driven stepper, whose steps follow the inertial time gamma/A, would take ~1/g steps
    per cycle for nothing: the line is then located with g = 0 (the bifurcation type still uses the true g)."""
    if g < INERTIA_NEGLIGIBLE * rtol:
        g = 0.0

    def rates(ks: list[float]) -> Search:  # one round: the growth rates measured at the stiffnesses ks
        results = yield [Run(x, a, b, g, SIGN_PERTURBATION, SIGN_CYCLES) for x in ks]
        return [r.growth_rate for r in results]

    lo, hi = a * (1.0 + g) * (1.0 - BRACKET), a * (1.0 + g) * (1.0 + BRACKET)
    evaluations = 2
    r_lo, r_hi = yield from rates([lo, hi])
    while not (r_lo > 0.0 > r_hi) and evaluations < 40:
        lo, hi = lo * (1.0 - BRACKET), hi * (1.0 + BRACKET)
        r_lo, r_hi = yield from rates([lo, hi])
        evaluations += 2
    if not (r_lo > 0.0 > r_hi):
        return math.nan, evaluations
    points = [(lo, r_lo), (hi, r_hi)]
    # the last estimate (first the linear value, trusted to a quarter: the measured line is within ~2e-6 of it, the
    # chord's root is not where the rate bends) and the rounds in a row that did not halve the bracket
    previous, trust, slow = a * (1.0 + g), 0.25, 0
    centred = False  # the last round measured both sides of a settled estimate
    while (hi - lo) > rtol * 0.5 * (hi + lo) or not (centred or (hi - lo) <= 0.1 * rtol * 0.5 * (hi + lo)):
        half = STRADDLE * rtol * 0.5 * (lo + hi)
        x = _root_estimate(points)
        if slow >= 2 or not lo < x < hi:
            x, slow = 0.5 * (lo + hi), 0
        if abs(x - previous) <= trust * half:  # settled: a bracket centred on x (an end of the bracket as a side)
            side = max(min(half, x - lo, hi - x), 0.1 * half)
            ks, centred = [k for k in (x - side, x + side) if lo < k < hi], True
        else:
            ks, centred = [x], False
        previous, trust = x, 1.0
        measured = list(zip(ks, (yield from rates(ks))))
        evaluations += len(ks)
        for k, r in measured:
            if not (r > 0.0 or r < 0.0):  # zero (or no rate measured): the line is there
                return k, evaluations
        points += measured
        width = hi - lo
        inside = sorted([(lo, r_lo), *measured, (hi, r_hi)])
        lo, r_lo, hi, r_hi = min(((k1, r1, k2, r2) for (k1, r1), (k2, r2) in zip(inside, inside[1:])
                                  if r1 > 0.0 > r2), key=lambda pair: pair[2] - pair[0])
        slow = slow + 1 if hi - lo > 0.5 * width else 0
    return 0.5 * (lo + hi), evaluations


def _bifurcation(k_c: float, a: float, b: float, g: float, rtol: float) -> Search:
    """Search (sweep/analysis/hopf_batch.py) for the type of the bifurcation at k_c (module docstring); returns
    (type, the limit-cycle amplitude at distance TYPE_DISTANCE below the line, NaN if none was decided there).

    The runs at d and 4d below come first (one round): where both end in stick-slip they are the closest and the
    farthest decided ones whatever the run at 2d gives, so it is run only where one of them does not."""
    run = lambda x, start: Run(x, a, b, g, start, TYPE_CYCLES, TYPE_RTOL)  # noqa: E731
    outcome = lambda r: (int(r.regime), float(r.amplitude))  # noqa: E731
    distances = TYPE_DISTANCE * np.array([1.0, 2.0, 4.0])
    near, far = map(outcome, (yield [run(k_c * (1.0 - distances[0]), BELOW_START),
                                     run(k_c * (1.0 - distances[2]), BELOW_START)]))
    below = [near, None, far]
    amp_near = near[1] if near[0] == Regime.STICK_SLIP else math.nan
    for _ in range(2):
        cycles = [(d, out[1]) for d, out in zip(distances, below) if out is not None and out[0] == Regime.STICK_SLIP]
        if len(cycles) >= 2:
            (d1, a1), (d2, a2) = cycles[0], cycles[-1]
            if abs(a2 / a1 / math.sqrt(d2 / d1) - 1.0) <= SQRT_LAW_SPREAD:
                return "supercritical", amp_near
        if below[1] is not None:
            break
        below[1] = outcome((yield [run(k_c * (1.0 - distances[1]), BELOW_START)])[0])
    # a large start: at least the size of the stick-slip cycles found below, which a subcritical (inverted) line
    # keeps on its stable side too, within a window that can be narrow (two distances above the line, the closer
    # one still outside the located bracket)
    large = max([LARGE_PERTURBATION] + [1.2 * amp for _, amp in cycles])
    first_large = None
    for d in (TYPE_DISTANCE, max(0.25 * TYPE_DISTANCE, rtol)):  # the bracket reaches rtol/2 above k_c
        above_large = int((yield [run(k_c * (1.0 + d), large)])[0].regime)
        first_large = above_large if first_large is None else first_large
        if above_large == Regime.STICK_SLIP and (yield [run(k_c * (1.0 + d), SMALL_START)])[0].regime == Regime.STEADY:
            return "subcritical", amp_near
    if below[0][0] == Regime.RUNAWAY and first_large == Regime.STEADY:
        return "degenerate", math.nan
    return "undetermined", amp_near


def _line_search(a: float, b: float, g: float, rtol: float, typed: bool) -> Search:
    """Search for the line at one V and, with ``typed``, its type: returns (k_c, evaluations, type, amplitude)."""
    k_c, evaluations = yield from _locate(a, b, g, rtol)
    if not math.isfinite(k_c):
        return k_c, evaluations, "none", math.nan
    if not typed:
        return k_c, evaluations, "undetermined", math.nan
    kind, amp = yield from _bifurcation(k_c, a, b, g, rtol)
    return k_c, evaluations, kind, amp


def locate_hopf(params: FrictionParams, V: Sequence[float], model: str = "auto", rtol: float = 1e-3,
                bifurcation: bool = True, model_tol: float = 1e-2, state_law: str = "aging",
                progress: bool | None = False, lyapunov: bool = True, bistable_band: bool = False) -> xr.Dataset:
    """The Hopf line over the velocities ``V`` [m s-1] (Dataset over V).

    Variables: ``K_over_M_c`` [s-2] located by simulation (the midpoint of a bracket of opposite signs of the
    measured growth rate, relative width < ``rtol``), ``K_over_M_c_linear`` [s-2] (eq. 3), ``chi_c`` [1],
    ``Omega_c`` [s-1] (eq. 4), ``bifurcation`` (flag: none / supercritical / subcritical / degenerate /
    undetermined; decided from simulations, module docstring) and ``limit_cycle_amplitude`` [1] just below a
    supercritical line. NaN and "none" where mu1(V) <= 0: steady sliding is then stable at every stiffness.
    ``model``: "quasistatic", "inertial" (the full Newton equation with gamma = V^2/(g D0); linear line chi_c = mu1
    (1 + gamma/A)) or "auto" (default): per V, inertial where gamma/A > ``model_tol``, the relative shift of the
    line by inertia (flag variable ``model``). ``state_law``: "aging" (the paper's) or "slip" (quasi-static only;
    docs/physics.md 7). ``progress``: a bar over the velocities on stderr (None: on an interactive terminal once the
    run takes more than ~2 s; sweep/run/progress.py).

    ``lyapunov`` (default True; analytic, ~1 ms): the variables ``l1`` [1], ``l1_error`` [1], ``bifurcation_l1``
    (flag: none / supercritical / subcritical / degenerate from the sign of l1 against its error) and
    ``types_agree`` (not_compared / agree / disagree with ``bifurcation``), and the attributes ``bautin_*`` (the
    Bautin points between min(V) and max(V), module docstring; ``bautin`` says "none" otherwise).
    ``bistable_band`` (default False; ~1 s a velocity): ``bistable_K_over_M_upper`` [s-2], the upper edge of the
    band above the line where l1 > 0 in which a large start ends in stick-slip while steady sliding is stable
    (NaN where not measured), and ``bistable_width`` [1] = upper edge / K_over_M_c_linear - 1.
    """
    if model not in MODELS:
        raise InputError(f"model must be one of {list(MODELS)}, got {model!r}")
    if not (math.isfinite(model_tol) and MODEL_TOL_RANGE[0] <= model_tol <= MODEL_TOL_RANGE[1]):
        raise InputError(f"model_tol must be in [{MODEL_TOL_RANGE[0]:g}, {MODEL_TOL_RANGE[1]:g}], got "
                         f"{float(model_tol)!r}")
    if not isinstance(params, FrictionParams):
        raise InputError(f"params must be a sweep.FrictionParams, got {type(params).__name__}")
    if state_law not in STATE_LAWS or (state_law != "aging" and model != "quasistatic"):
        raise InputError(f"state_law must be one of {list(STATE_LAWS)} (other than 'aging' with model 'quasistatic' "
                         f"only), got state_law={state_law!r}, model={model!r}")
    v = np.asarray(V, dtype=float).reshape(-1)
    if v.size == 0 or not np.all(np.isfinite(v)) or np.any(v <= 0):
        raise InputError(f"V must be a non-empty sequence of finite velocities > 0 [m s-1], got {V!r}")
    if not (math.isfinite(rtol) and 1e-8 <= rtol <= 0.1):
        raise InputError(f"rtol must be in [1e-8, 0.1] (relative width of the located bracket), got {rtol!r}")
    warn_implausible(V=v)
    announce_if_cold(families=driven_families(model))
    p = params
    mu1 = np.asarray(physics.mu1(v, p.m1, p.m2, p.V0), dtype=float)
    inertial = line_uses_inertia(np.asarray(physics.inertia_number(v, p.D0, p.g)) / p.A, model, model_tol)
    gamma = np.asarray(physics.inertia_number(v, p.D0, p.g), dtype=float) * inertial
    chi_c, kinds, amps, evals = (np.full(v.size, np.nan), np.zeros(v.size, np.int8), np.full(v.size, np.nan),
                                 np.zeros(v.size, np.int64))
    lined = np.flatnonzero(mu1 > 0.0)
    bar = Progress(v.size, progress, label="hopf", unit="velocities")
    bar.update(v.size - lined.size)
    try:
        found = drive([_line_search(mu1[i] / p.A, p.m2 / p.A, gamma[i] / p.A, rtol, bifurcation) for i in lined],
                      state_law, done=lambda _: bar.update(1))
    finally:
        bar.__exit__()
    for i, (k_c, evaluations, kind, amp) in zip(lined, found):
        chi_c[i], evals[i], kinds[i], amps[i] = k_c * p.A, evaluations, BIFURCATIONS.index(kind), amp
    to_km = p.g / p.D0
    extra, attrs = (_normal_form(p, v, mu1, gamma, inertial, kinds, model, model_tol, state_law, bistable_band, to_km,
                                 bifurcation) if lyapunov else ({}, {}))
    var = lambda data, units, name, **attrs: xr.Variable("V", data, {"units": units, "long_name": name, **attrs})  # noqa: E731
    ds = xr.Dataset(
        {
            "K_over_M_c": var(chi_c * to_km, "s-2", "K/M on the Hopf line, located by simulation"),
            "K_over_M_c_linear": var(np.asarray(physics.chi_c_inertial(mu1, p.A, gamma)) * to_km, "s-2",
                                     "K/M on the Hopf line, linear theory (eq. 3; times 1 + gamma/A with inertia)"),
            "model": var(inertial.astype(np.int8), "1", "model used at this V", **MODEL_FLAG),
            "gamma": var(np.asarray(physics.inertia_number(v, p.D0, p.g)), "1", "inertia number V^2/(g D0)"),
            "chi_c": var(chi_c, "1", "reduced critical stiffness located by simulation"),
            "Omega_c": var(np.asarray(physics.Omega_c(v, mu1, p.A, p.D0)), "s-1",
                           "critical pulsation (V/D0) sqrt(mu1/A) (eq. 4)"),
            "bifurcation": var(kinds, "1", "type of the Hopf bifurcation, decided from simulations",
                               flag_values=np.arange(len(BIFURCATIONS), dtype=np.int8),
                               flag_meanings=" ".join(BIFURCATIONS)),
            "limit_cycle_amplitude": var(amps, "1", f"stick-slip amplitude (tau - xi) at {TYPE_DISTANCE:g} below "
                                         "the line (NaN: none decided there)"),
            "simulations": var(evals, "1", "driven simulations spent on locating the line"),
            "mu1": var(mu1, "1", "velocity-weakening slope mu1(V)"),
            **{name: var(data, units, long, **more) for name, (data, units, long, more) in extra.items()},
        },
        coords={"V": var(v, "m s-1", "driving velocity")},
        attrs={"Conventions": "CF-1.11", "title": "Hopf line of the Baumberger-Gauthier spring-block model",
               "source": versions(), "references": REFERENCES, "rtol": rtol,
               "state_law": state_law,
               "model": model + (f" (model_tol {model_tol:g}: inertial where gamma/A > model_tol)"
                                 if model == "auto" else ""),
               "method": (f"regula falsi (Illinois) on the growth rate measured over {SIGN_CYCLES} cycles of a "
                          f"{SIGN_PERTURBATION:g} perturbation (dp5, local rtol {STEPPER_RTOL:g}); type from runs "
                          f"at {TYPE_DISTANCE:g} and {4 * TYPE_DISTANCE:g} below and above the line"),
               "params": str(p.as_dict()), **attrs},
    )
    return ds


def _normal_form(p: FrictionParams, v: np.ndarray, mu1: np.ndarray, gamma: np.ndarray, inertial: np.ndarray,
                 kinds: np.ndarray, model: str, model_tol: float, state_law: str, band: bool, to_km: float,
                 simulated: bool) -> tuple[dict, dict]:
    """The Hopf file's variables and attributes from l1 (module docstring): {name: (data, units, long_name,
    attrs)}, {attribute: value}."""
    line = lyapunov_line(p, v, model=model, state_law=state_law, model_tol=model_tol)
    agree = np.zeros(v.size, np.int8)
    if simulated:
        sim = np.array([BIFURCATIONS[c] for c in kinds])
        by_l1 = np.array([TYPES[c] for c in line.kind])
        compared = np.isin(sim, ("supercritical", "subcritical", "degenerate")) & (by_l1 != "none")
        agree[compared] = np.where(sim[compared] == by_l1[compared], 1, 2)
    upper = np.full(v.size, np.nan)
    if band:
        inverted = np.flatnonzero(line.kind == TYPES.index("subcritical"))
        for i in inverted:
            bistable.check_band_inputs(mu1[i] / p.A, p.m2 / p.A, gamma[i] / p.A, BAND_RTOL)
        bands = drive([bistable.band_search(mu1[i] / p.A, p.m2 / p.A, gamma[i] / p.A, BAND_RTOL) for i in inverted],
                      state_law)
        for i, found in zip(inverted, bands):
            if found.bistable and math.isfinite(found.d_hi):
                upper[i] = mu1[i] * (1.0 + gamma[i] / p.A) * (1.0 + found.d_hi) * to_km
    flags = lambda names: {"flag_values": np.arange(len(names), dtype=np.int8), "flag_meanings": " ".join(names)}  # noqa: E731
    extra = {
        "l1": (line.l1, "1", "first Lyapunov coefficient (normal form; stretch normalisation, tau time)",
               {"comment": "l1 < 0: direct (supercritical); > 0: inverted (subcritical); docs/hopf-type.md"}),
        "l1_error": (line.l1_error, "1", "error estimate of l1 (exact vs finite-difference derivatives at two steps, "
                     "plus rounding)", {}),
        "bifurcation_l1": (line.kind, "1", "type of the Hopf bifurcation from the sign of l1 against its error",
                           flags(TYPES)),
        "types_agree": (agree, "1", "type from l1 against the type from simulations", flags(AGREEMENT)),
    }
    if band:
        with np.errstate(invalid="ignore"):
            width = upper / (np.asarray(physics.chi_c_inertial(mu1, p.A, gamma)) * to_km) - 1.0
        extra["bistable_K_over_M_upper"] = (upper, "s-2", "upper edge of the bistable band above an inverted line "
                                            "(large start: stick-slip; small start: steady), by simulation", {})
        extra["bistable_width"] = (width, "1", "relative width of the bistable band above the line", {})
    return extra, _bautin_attrs(p, v, model, state_law)


def _bautin_attrs(p: FrictionParams, v: np.ndarray, model: str, state_law: str) -> dict:
    """Attributes of the Bautin points between min(V) and max(V) on the inertial line (the quasi-static one for
    model "quasistatic")."""
    line_model = "quasistatic" if model == "quasistatic" else "inertial"
    where = f"on the {line_model} line between V = {v.min():.4g} and {v.max():.4g} m s-1"
    if not v.max() > v.min():
        return {"bautin": "not searched (a single V)"}
    points = bautin_points(p, (float(v.min()), float(v.max())), model=line_model, state_law=state_law,
                           rtol=BAUTIN_RTOL)
    if not points:
        return {"bautin": f"none {where} (l1 keeps its sign, or stays within its error)"}
    return {"bautin": f"{len(points)} Bautin point(s) {where}, bracket {BAUTIN_RTOL:g} relative in gamma/A",
            "bautin_V": np.array([b.V for b in points]),
            "bautin_gamma_over_A": np.array([b.gamma_over_A for b in points]),
            "bautin_K_over_M": np.array([b.K_over_M for b in points]),
            "bautin_direct_above": np.array([int(b.direct_above) for b in points], dtype=np.int8)}


def hopf_summary(ds: xr.Dataset) -> str:
    """The lines ``sweep hopf`` prints about the type of the line (a Hopf file of :func:`locate_hopf`): counts of the
    type from l1 and of its agreement with the simulated type, the Bautin points, the bistable band where measured."""
    if "l1" not in ds:
        return "type from l1: not computed (locate_hopf(..., lyapunov=False))"
    names = ds["bifurcation_l1"].attrs["flag_meanings"].split()
    codes = ds["bifurcation_l1"].values
    counts = ", ".join(f"{names[c]} {int(n)}" for c, n in zip(*np.unique(codes, return_counts=True)))
    lines = [f"type from l1 (normal form): {counts}"]
    has = np.isfinite(ds["l1"].values)
    if has.any():
        lines.append(f"  l1 {np.nanmin(ds['l1'].values):.4g} .. {np.nanmax(ds['l1'].values):.4g}, error at most "
                     f"{np.nanmax(ds['l1_error'].values):.2g}")
    agree = ds["types_agree"].values
    if (agree > 0).any():
        lines.append(f"  agrees with the simulated type at {int((agree == 1).sum())} of {int((agree > 0).sum())} "
                     "velocities" + ("" if (agree != 2).all() else " (DISAGREES at V = " + ", ".join(
                         f"{x * 1e6:.4g}" for x in ds["V"].values[agree == 2]) + " um/s)"))
    lines.append(f"Bautin: {ds.attrs.get('bautin', 'not searched')}")
    if "bautin_V" in ds.attrs:
        for v_b, g_b, km, up in zip(*(np.atleast_1d(ds.attrs[k]) for k in ("bautin_V", "bautin_gamma_over_A",
                                                                          "bautin_K_over_M", "bautin_direct_above"))):
            lines.append(f"  V = {v_b * 1e6:.6g} um/s, gamma/A = {g_b:.6g}, K/M = {km:.6g} s-2: "
                         f"{'direct' if up else 'inverted'} at larger V")
    if "bistable_K_over_M_upper" in ds:
        width = ds["bistable_width"].values
        sel = np.isfinite(width)
        lines.append(f"bistable band above the line measured at {int(sel.sum())} V" + (": relative width " + ", ".join(
            f"{w:.3g} at {x * 1e6:.4g} um/s" for w, x in zip(width[sel], ds["V"].values[sel])) if sel.any() else ""))
    return "\n".join(lines)


def with_simulated_line(ds: xr.Dataset, params: FrictionParams, model: str = "auto",
                        model_tol: float = 1e-2, state_law: str = "aging") -> xr.Dataset:
    """``ds`` (a sweep over V) with the coordinate ``K_over_M_c_simulated`` [s-2]: the Hopf line of ``model``
    located by simulation at each V (:func:`locate_hopf` without the type; ~2 ms per velocity), next to the
    analytic chi_c."""
    line = locate_hopf(params, ds["V"].values, model=model, bifurcation=False, model_tol=model_tol,
                       state_law=state_law)
    attrs = {**line["K_over_M_c"].attrs, "comment": line.attrs["method"]}
    return ds.assign_coords(K_over_M_c_simulated=("V", line["K_over_M_c"].values, attrs))
