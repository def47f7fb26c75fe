"""Every calibrated accuracy constant of the engine, each with the measurement that set it.

Grouped by the part of the engine that reads it. A constant here is a choice that trades cost for accuracy and was
set by a measurement (named in its docstring, with the benchmark or test that repeats it); structural constants of
a method (tableau coefficients, controller SAFETY/MIN/MAX factors: sweep/integrate/solvers/controllers.py) live with it.
Changing a value here changes the numbers of the runs that use it, and the plan's hash (a resume of a run made
with the old value is refused).
"""

from __future__ import annotations

import math

# ---------------------------------------------------------------------------------------------------------------
# Driven scene: the stepper and the regime decisions (sweep/integrate/driven.py)
# ---------------------------------------------------------------------------------------------------------------

RUNAWAY_XI_DOT = 1e8
"""Slip velocity xi' = V_slip/V beyond which the quasi-static model is declared broken down (regime runaway): far
past any stick-slip peak of the presets (xi' ~ 1e3), well before exp(w) can overflow."""
W_RUNAWAY = math.log(RUNAWAY_XI_DOT)
DECAYED = 1e-3
"""Amplitude, relative to the perturbation, below which a decaying oscillation is steady sliding."""
GROWTH_RTOL = 1e-3
"""Agreement of three successive per-cycle growth rates for the linear decay to count as established."""
STATIONARY_TOL = 1e-7
"""Largest |a_k/a_(k-1) - 1| of a stationary cycle (three in a row)."""
NEUTRAL_SPREAD = 1e-2
"""Stationary cycles within this relative distance of the first cycle's amplitude are neutral, not a limit cycle."""
NEUTRAL_START = 2.0
"""...and only where the first cycle is no larger than NEUTRAL_START x the amplitude of the linear oscillation
through the initial state: an orbit that grew within its first cycle (far below the line) reached a limit cycle,
however flat its later cycles are."""
STIFF_SWITCH = 1.5
"""A driven step runs RODAS3 instead of Dormand-Prince where h times the inertial mode's rate exceeds this (DP5 is
stable up to ~3.3 on the negative axis; half of that leaves the explicit steps accuracy-limited)."""
MIN_CYCLES = 3
"""Cycles needed before a regime is decided from their amplitudes (three growth rates)."""
REBOUND = 1e-4
"""A maximum of z whose cycle (half its rise from the last minimum) is below REBOUND x the previous cycle's amplitude
is a rebound inside a slip (the slider nearly stops and slips on), not the end of a cycle: it is skipped, and the
cycle runs on to the next maximum with the lower of the minima. Issue 35's grid: 2 inertial points rebounded by
6.5e-6 in z after each slip of amplitude 9.9, so their cycles alternated 9.9 / 6e-6 and never became stationary
(undecided after max_steps, 1e6 steps each)."""
SLAVED_INERTIA = (1e-2, 1e-2, 1e-3)
"""(low, high, slow): the inertial driven model runs on its slow manifold (w = ln xi' slaved to second order,
sweep/integrate/models/driven.py ``make_slaved_rhs``, the explicit stepper) where the inertial term
P = gamma xi''/A >= -low (decelerating), P <= high (accelerating: towards a slip) and gamma xi'/A <= slow, and where
the full system's w is within SLAVED_ENTRY of the manifold's; the full system beyond twice these bounds. Measured on
every 8th of the 244 points of the issue-35 grid that run away quasi-statically (31 points, gamma/A 2e-7..2e-4,
stick-slip), stepper rtol 1e-10, against the full system: periods within 1.4e-8, amplitudes 1.1e-8 (the full
system's own rtol 1e-9 vs 1e-10 difference: 1.4e-8 on every 16th); high 3e-2: period 4.3e-7 off (the expansion
fails first just before a slip). At gamma/A = 1e-2 (tests/integrate/test_driven.py's Radau case) slow 1e-2 put the
amplitude 2.3e-6 off, 3e-3 9.6e-7, 1e-3 3.5e-9 (the full system: 3.8e-9). The first-order form (w1, error O(P^2))
held to (1e-3, 3e-4, 1e-3) only (2.9e-8; high 1e-3: 4.2e-7). At rtol 1e-9 the 31 points take 224,260 -> 131,941
steps (the full system's dp5 steps at its stability limit on the slip's ends, and RODAS3's, go)."""
SLAVED_ENTRY = 100.0
"""The inertial driven model enters its slow manifold only where the full system's w is within SLAVED_ENTRY x the
stepper's absolute tolerance (rtol x the largest |z|) of the manifold's w (:data:`SLAVED_INERTIA`): after a slip the
inertial mode may still ring (P crosses zero while the fast mode has not relaxed), and the jump of w onto the
manifold stays below ~1e-7 of the cycle. Without this test, bounds wider than the first-order ones left 3 of the 16
calibration points undecided (their cycles jittering above STATIONARY_TOL with where the entry fell); 10 instead of
100: 1.25x the steps, the same accuracy."""
SLAVED_TOL = 0.1
"""The explicit steps on the slow manifold (:data:`SLAVED_INERTIA`) run at this fraction of the stepper's tolerance.
Where they are accuracy-bound (the long stick phases and the acceleration into a slip; the full system's steps there
were held far below the tolerance by dp5's stability or taken by RODAS3), cycles of periods ~3,000 tau jittered by
~1e-6 from one to the next (at 1e-9; stationary at 1e-10) and never passed STATIONARY_TOL."""


def driven_stepper_rtol(rtol: float) -> float:
    """Local tolerance of the driven stepper: the regime decisions compare amplitudes of successive cycles to
    STATIONARY_TOL (1e-7), so the integration must be far tighter than that whatever the scene's rtol."""
    return min(1e-2 * rtol, 1e-9)

# ---------------------------------------------------------------------------------------------------------------
# Inertial stop (sweep/integrate/stop_inertial.py)
# ---------------------------------------------------------------------------------------------------------------

HANDOVER_FRACTION = 0.1
"""The inertial term is handed over to the quasi-static form once below this fraction of rtol, now and (by the
slaved bound) later (docs/physics.md 3a): the neglected term then shifts xi_inf by <= HANDOVER_FRACTION rtol times
the slip still to come. Moving the threshold x100 either way moves xi_inf by < 6e-15 on the reference's cases
(tests/integrate/test_reference_inertial.py)."""

# ---------------------------------------------------------------------------------------------------------------
# Adaptive per-point solutions whose error is estimated from a pair of tolerances (inertial stop, slip-law stop)
# ---------------------------------------------------------------------------------------------------------------

TIGHTER = 10.0
"""Such a solution is run at local tolerances rtol/TIGHTER and rtol/TIGHTER^2; the tighter value is kept and the
difference, ~the error of the looser run, is its error estimate. (The looser pair rtol, rtol/10 flagged 20 % of the
default scene error_above_tol with the inertial model: the adaptive steps' global error reaches ~5x their local
tolerance.)"""
GENERAL_ESTIMATE_GAIN = 2.0
"""Estimate of the general (slip-law) stop path = GENERAL_ESTIMATE_GAIN x max(|x1 - x2|, |x2 - x3|) of its runs at
rtol/TIGHTER^(1, 2, 3), x2 returned (sweep/integrate/stop_slip.py): as the step ladder's non-asymptotic estimate
(CONSERVATIVE_GAIN below). On tests/integrate/test_slip_law.py's cases at rtol 1e-6 and 1e-9 it bounds the true error
and
stays within 100x of it."""

# ---------------------------------------------------------------------------------------------------------------
# Quasi-static stop: the closed-form tail and the time map (sweep/integrate/models/stop.py)
# ---------------------------------------------------------------------------------------------------------------

E_TAIL_MAX = 0.05
"""The closed-form tail is used only once E = xi' psi has fallen below this."""
TAIL_SAFETY = 1e-3
"""Fraction of the tolerance allowed for the truncation of the tail series."""
RATE_FLOOR = 0.1
"""Floor of the late rate r(u) of the time map (bounds the step in s by h/RATE_FLOOR)."""

# ---------------------------------------------------------------------------------------------------------------
# Stiff points: the Rosenbrock step rule (sweep/integrate/models/stop_stiff.py)
# ---------------------------------------------------------------------------------------------------------------

STIFF_RATE_FLOOR = 0.03
"""Floor of the late rate r of the Rosenbrock step rule (bounds the step in s by h/STIFF_RATE_FLOOR; 0.03 costs
a third fewer steps than 0.1 in the costly corner at equal error: benchmarks/work_precision.py)."""

# ---------------------------------------------------------------------------------------------------------------
# Step rules of the stop scene (sweep/plan/plan.py)
# ---------------------------------------------------------------------------------------------------------------

C_STABLE = 6.0e-4
"""Bound on the RK4 error constant |err/xi_inf| / h^4 where steady sliding is stable (chi > mu1)."""
C_UNSTABLE = 2.0e-3
"""Bound on the RK4 error constant where steady sliding is unstable (chi <= mu1)."""
TIME_RESOLVED_FACTOR = 30.0
"""Time-resolved observables (values inside the transient, not only its limit) have error constants up to
~6x those of xi_inf (tests/plan/test_accuracy.py); when they are asked for, C is multiplied by this factor."""
H_MAX = 0.7
"""Upper bound on the (coarse) step in sigma (keeps RK4 stable along the slow creep manifold)."""
CTRL_TOL_FACTOR = {"dp5": 0.05, "dop853": 0.5}
"""Local tolerance of the adaptive controller per unit rtol, such that the error estimate of the returned (coarse)
solution stays below rtol: at most 0.4 rtol on tests/integrate/test_error_estimates.py's table at rtol 1e-3..1e-9,
relaxed slip
and time-resolved observables (dp5 was 0.2 while the fine solution was returned; dop853's embedded fifth-order
estimate overstates its eighth-order error increasingly as rtol falls: 0.4 rtol at 1e-3, 0.003 rtol at 1e-9)."""
AUTO_METHOD = (("rk4", 2e-4), ("dp5", 0.0))
"""Time-resolved scenes (one point per thread): (method, smallest rtol it is chosen for), by decreasing rtol, the
cheaper per point of rk4 (fixed step) and dp5 (adaptive), measured on a 40 x 25 default-scene grid with a 200-sample
trajectory (1 thread, us a point rk4 / dp5): 272 / 323 at rtol 1e-2 and 288 / 324 at 1e-3 (dp5 flagging
3-32 points error_above_tol there), 373 / 337 at 1e-4, 539 / 349 at 1e-5, 851 / 379 at 1e-6, 2617 / 504 at 1e-8.
Relaxed-slip scenes take the adaptive lanes instead (sweep.plan.plan.LANES_METHOD)."""
STEP_SAFETY = 2.0
"""Margin of the fixed-step rule: the error estimate (~ERROR_GAIN times the error) stays below rtol / STEP_SAFETY on
the calibration set."""
PILOT_FACTOR = 2.5
"""Pilot step of the lanes / the step meeting rtol at the largest error constant (see :func:`pilot_step_for`)."""
H_PILOT = 1.0
"""Largest pilot step h0 (its coarse run has 2 h0, inside RK4's stability interval along the decay; a coarser
pilot that goes non-finite only sends the point down the ladder)."""
STIFF_K_MAX = 0.03
"""Stiff points (Rosenbrock ros4 in the lanes, models/stop_stiff.py): chi/A <= STIFF_K_MAX, mu1 < 0, m2 > 0 and a
slow creep manifold of length x attraction rate |mu1/A|^3 / (4 (m2/A)(chi/A)) >= STIFF_WORK_MIN. There, on the
calibration set of benchmarks/calibrate_stiff.py, ros4 needs ~40x fewer steps than RK4 (which is
stability-limited along the manifold) at equal error; elsewhere RK4 is cheaper (up to 2x)."""
STIFF_WORK_MIN = 300.0
"""See STIFF_K_MAX: the least length x attraction rate of the creep manifold for a point to count as stiff."""
C_STIFF = 0.01
"""Bound on the ros4 error constant |err/xi_inf| / h^4 over the stiff region (measured max 6.0e-3)."""
STIFF_PILOT_FACTOR = 6.0
"""PILOT_FACTOR of the ros4 lanes: larger than RK4's because C_STIFF bounds constants spread over ~60x (median
1.1e-4, benchmarks/results/calibrate_stiff.json), so the rule's step is ~2.8x finer than a typical stiff point
needs (measured on the costly corner of benchmarks/work_precision.py: 2.5 -> 6 takes 25-30 % off its ladder at
rtol 1e-7..1e-10, next rung 1.5x -> 2.5x below the pilot)."""
STIFF_H_PILOT = 0.6
"""Cap of the ros4 lanes' STIFF_PILOT_FACTOR rule (:func:`stiff_pilot_step_for`): coarser pilot pairs are not yet
asymptotic there (on the corner at rtol 1e-4, h0 = 0.97 takes 396 steps in all against 168 from h0 = 0.6)."""

# ---------------------------------------------------------------------------------------------------------------
# The step ladder of the lanes (sweep/integrate/ladder.py)
# ---------------------------------------------------------------------------------------------------------------

ORDER_WINDOW = 1.0
"""Largest distance of the observed order from the method's order for the ladder to count as asymptotic."""
SHARP_GAIN = 2.0
"""Estimate / Richardson error of an asymptotic ladder (covers the o(h^q) terms)."""
CONSERVATIVE_GAIN = 2.0
"""Estimate / max(|x_b - x_a|, |x_c - x_b|) where the ladder is not asymptotic. Not |x_c - x_b| alone: errors
that stagnate over two rungs before falling (measured: -2.2e-9, -2.6e-9 after 3.1e-7 at chi/A = 10, mu1/A = -3,
m2/A = 0.05) make it 0.3x the error."""
TARGET = 0.7
"""The next rung aims at an estimate of TARGET x tolerance."""
MIN_RATIO, MAX_RATIO = 1.5, 8.0
"""Bounds on the ratio of successive steps below the pilot pair."""
MAX_RUNS = 5
"""Runs per point at most (pilot pair + three rungs); then the point keeps its estimate (error_above_tol if over)."""

# ---------------------------------------------------------------------------------------------------------------
# The per-point stop path: Richardson pairs (sweep/integrate/stop_point.py)
# ---------------------------------------------------------------------------------------------------------------

ERROR_GAIN = 15.0
"""Nominal ratio of the Richardson estimate of a fine solution, ERROR_GAIN/(2^p - 1) |fine - coarse|, to its true
error: the estimate of the relaxed-slip lanes (sweep.protocols.stop.engine), whose step rules (sweep.plan.plan) are
calibrated on it."""
def lane_control_tolerance(rtol: float, scale: float = 1.0) -> float:
    """Local tolerance of the adaptive lanes' first run for a scene's rtol (sweep/integrate/tolerance_ladder.py):
    rtol min(20, ``scale`` sqrt(1e-3 / rtol)); the sampled lanes take SAMPLED_TOL_SCALE.
    dop853's global error falls faster than its local tolerance (slope ~1.5 per decade from 5e-4 to 5e-7, ~1.1
    beyond; the returned run's estimate was 0.9, 0.02, 0.012 and 0.008 x rtol at most on the default scene at rtol
    1e-3, 1e-6, 1e-8, 1e-10 with the local tolerance rtol / 2), so the tolerance can be looser than rtol the tighter
    rtol is: rtol x min(20, sqrt(1e-3 / rtol) / 2) keeps the 99.9th percentile of estimate / tolerance near 0.3 there
    (a point whose estimate exceeds its tolerance is run again at TOL_RATIO times tighter, so a looser rule costs
    time, never accuracy), and takes 1.5-1.9x fewer attempts than rtol / 2 at rtol <= 1e-6.

    Since the larger first step (LANE_H0_FACTOR) the rule is twice that, rtol x min(20, sqrt(1e-3 / rtol)) (the same
    at rtol <= 2.5e-7): measured (model "quasistatic", ``execute``, 1 thread, us a point, x1 / x2 / x4 the rule
    above), default scene 1.01 / 0.94 / 0.94 at rtol 1e-3, 1.12 / 1.06 / 1.05 at 1e-4, 1.27 / 1.22 / 1.25 at 1e-5,
    1.50 / 1.49 / 1.62 at 1e-6; its costly corner 2.08 / 1.98 / 2.05, 2.26 / 2.19 / 2.41, 2.50 / 2.46 / 2.81,
    2.95 / 3.14 / 3.68 (x4 runs 1-8 % of the points again). The max errors stay 0.4-0.5 rtol."""
    return rtol * min(20.0, scale * math.sqrt(1e-3 / rtol))


SAMPLED_TOL_SCALE = 0.5
"""``scale`` of :func:`lane_control_tolerance` for the sampled lanes (sweep/integrate/lanes_sampled.py): the rule
before the relaxed-slip lanes' was loosened, as calibrated for samples. With the looser one, one slip_at sample's
estimate fell below its true error at rtol 1e-3 (tests/integrate/test_lanes_sampled.py: 3.98e-11 against 4.69e-11, case
g_chiA100_mA1), and the samples' speed was not measured."""


LANE_H0_FACTOR = 8.0
"""First trial step of the adaptive lanes, relative to ctrl_tol^(1/(q+1)) (q: the embedded estimate's order): at that
scale the first step's error norm was 1e-7..1e-5 (dop853 on the default scene, rtol 1e-3), and the PI controller
then grows the step by ~1.4x a step only (its memory of the tiny first error holds it back), so a run spent 2-3
attempts reaching the steps its accuracy allows. Measured (model "quasistatic", ``execute``, 1 thread, us a point;
x1 capped at 0.5 before): default scene x1 / x3 / x5 / x8 / x12: 1.35 / 1.17 / 1.08 / 1.00 / 0.97 at rtol 1e-3,
1.88 / 1.68 / 1.61 / 1.49 / 1.58 at 1e-6 (x12: 1,771 of 20,000 points run again, against 110 at x1 and 393 at x8),
4.02 / 3.82 / 3.70 / 3.58 at 1e-9; its costly corner 2.38 -> 2.04 (x8) at 1e-3, 3.36 -> 2.89 at 1e-6, 7.84 -> 7.42
at 1e-9. The same max errors (0.4-0.5 rtol): a first step too large is rejected like any other."""
LANE_H0_MAX = 3.0
"""Cap of that first step in sigma (x8 meets it at rtol >= ~1e-3; larger first steps were measured no faster)."""
TOL_RATIO = 10.0
"""Tightening of the control tolerance for a point of the adaptive lanes whose estimate exceeds its tolerance
(sweep/integrate/tolerance_ladder.py)."""
LANE_TOL_FLOOR = 1e-14
"""Smallest control tolerance of the adaptive lanes: below it the steps' rounding (2.2e-16 per step) dominates."""
COARSE_GAIN = 2.0
"""Estimate of the returned coarse solution = COARSE_GAIN |coarse - fine| (+ the hedges): it bounds the coarse error
whenever the fine one is at most half of it (or of the other sign), and exceeds it by at most 3x then
(asymptotically the fine error is 2^-p of the coarse one: 1/16 for rk4, 1/32 for dp5, 1/256 for dop853)."""
TAIL_RTOL = 2.0**-52
"""The per-point path integrates until the closed-form tail's error bound is below TAIL_SAFETY (atol + TAIL_RTOL
|xi|): a few steps more (E decays exponentially there), and the bound, not sharp where the two neglected terms of
the tail series cancel (up to 1e3x the true tail error), stays negligible next to any integration error."""
TAIL_SHARE = 0.05
"""The adaptive lanes (sweep/integrate/lanes_adaptive.py) also stop a run once the closed-form tail's error bound is
below this share of the run's own twin difference |x_fine - x| (the estimate is COARSE_GAIN times it, plus twice both
tails' bounds: at most ~10 % more, so it stays as sharp). The run then ends a step or two earlier than with the
bound at TAIL_RTOL: default scene (model "quasistatic", 1 thread, ``execute``) 12.0 -> 10.3 attempts a point and
1.52 -> 1.35 us at rtol 1e-3, 41.0 -> 39.9 and 4.16 -> 4.02 us at 1e-9; its costly corner 23.0 -> 21.1 and 2.65 ->
2.34 us at 1e-3. A tail bound tied to the tolerance instead (TAIL_SAFETY rtol |xi|, as in the fixed-step lanes) saves
a step more but dominates the estimate where the true error is far below the tolerance (it is then no longer within
100x of the true error: tests/integrate/test_error_estimates.py)."""
TAIL_TIGHTENING = 0.01
"""Samples beyond the transient come from the closed-form continuation once E < TAIL_SAFETY TAIL_TIGHTENING rtol."""
TAU_INTEGRATED = 1e12
"""Sampled adaptive lanes (sweep/integrate/lanes_sampled.py): samples beyond this reduced time come from the
closed-form continuation once E < TAIL_SAFETY TAIL_TIGHTENING rtol (the steps of the tail grow slowly there: u ~ ln
tau)."""
SAMPLES_PER_EFOLD = 4.0
"""Below it, samples per e-fold of tau still to come, the rest come from the closed-form continuation once E is
negligible; denser ones are integrated and read off the steps' interpolants. A continued sample costs ~16
transcendental calls for the run and its twin with their bounds (~0.3 us), a sample off an interpolant ~40 ns, and an
e-fold of tau (u grows by 1) a step or so of the tail (~0.4 us an attempt). Measured (1 thread, rtol 1e-6): the fit's
200 samples over 4.5 decades (19 an e-fold), all continued 32 us a point, all integrated 26 us; a 61-sample trajectory
over 1e-3..1e6 (3 an e-fold), all integrated 31 us, continued past 1e3 28 us; to 1e11, 33 and 29 us."""
THETA_MISS = 1e-4
"""What a sample's theta may miss by, relative to rtol (sweep/integrate/lanes_sampled.py newton_step_for): a Newton
step below sqrt(THETA_MISS rtol) ends the iteration, one fewer than a fixed 1e-8 at rtol >= 1e-8 (the kernel 14.7 us
a 200-sample curve instead of 17-22 at rtol 1e-6)."""

# ---------------------------------------------------------------------------------------------------------------
# The choice of model per point (sweep/protocols/stop/model_choice.py)
# ---------------------------------------------------------------------------------------------------------------

ESTIMATE_RTOL = 1e-3
"""Tolerance of the first-order correction's integration (the estimate is needed to a few %, not to rtol): over
117 points where it is trusted, estimate/true gap spans the same 0.946..1.106 at 1e-3 as at 1e-4, in half the steps
(37 vs 74). In the lanes it is the tail test's tolerance; the steps are ESTIMATE_STEP."""
ESTIMATE_STEP = H_MAX
"""Fixed RK4 step in sigma of the lane run that carries the first-order correction
(sweep/protocols/stop/model_choice.py). Against
the correction at rtol 1e-7 (per-point RODAS3), |y/xi_inf| where it exceeds 1e-4: within 0.41 % on the default grid
(9,329 points, 24 steps per point) and 0.88 % over chi/A 1e2..1e7 x V 1e-8..1e-3 (724 points; 42 steps); at half
the step 0.25 % in twice the steps, at twice the step 12-26 %; the per-point RODAS3 at ESTIMATE_RTOL was within
2.3 %. No lane run failed at this step on either grid (a failed one falls back to the per-point module)."""
ESTIMATE_MARGIN = 1.5
"""A point keeps the quasi-static model only where ESTIMATE_MARGIN x its estimate is within model_tol, where the
expansion is well trusted (tau <= CLOSE_TRUST below): there the true gap is at most 1.33x the estimate."""
CLOSE_TRUST = 2.0
"""tau = gamma/A (1 + (chi + |mu1|)/A) up to which ESTIMATE_MARGIN applies (WIDE_MARGIN beyond)."""
WIDE_MARGIN = 2.0
"""The routing margin for CLOSE_TRUST < tau <= FIRST_ORDER_TRUST, where the true gap is up to 1.66x the estimate."""
FIRST_ORDER_TRUST = 4.0
"""The first-order estimate is trusted where tau = gamma/A (1 + (chi + |mu1|)/A) <= FIRST_ORDER_TRUST: the inertial
time gamma/A short against the fastest time of the quasi-static stop, its stiff start A/(chi + |mu1|). Measured
against the inertial model over chi/A 0.1..1e3, mu1/A -4..10, m2/A 0..2 (true gap / estimate; both at rtol 1e-9):
0.81..1.33 at tau = 2, 0.75..1.49 at 3, 0.70..1.66 at 4, 0.66..1.83 at 5 (47 points per value,
tests/protocols/test_stop_inertial.py); an earlier sweep of 230 points per value gave 0.80..1.17 at 1, 0.70..1.33 at 2,
0.63..1.49 at 3, 0.58..1.66 at 4. The expansion fails outright far beyond (down to 1e-6 at chi/A = 1e3,
gamma/A = 1, tau = 1e3, where the slider rebounds inertially); there the gap is measured by solving the point with
inertia. (Trusted only up to tau = 2 before, the default scene solved 27 points with inertia, tau 2.03..2.86, all
with measured gaps ~3e-4 against model_tol 1e-2, at more cost than its 20,000 quasi-static points.)"""

# ---------------------------------------------------------------------------------------------------------------
# The Hopf line located by simulation (sweep/analysis/hopf.py)
# ---------------------------------------------------------------------------------------------------------------

SIGN_PERTURBATION = 1e-5
"""Initial stretch of the runs whose growth rate decides the side of the line: small enough to stay linear."""
SIGN_CYCLES = 4
"""Cycles over which that growth rate is measured."""
STEPPER_RTOL = 1e-10
"""Local tolerance of the driven stepper while locating the line (the growth rate vanishes there)."""
BRACKET = 0.1
"""Initial bracket chi_c_linear x (1 -+ BRACKET), widened by the same factors until the measured signs differ."""
INERTIA_NEGLIGIBLE = 1e-2
"""Inertia is left out of the line's location where gamma/A < INERTIA_NEGLIGIBLE x rtol (:func:`_locate`)."""
TYPE_DISTANCE = 0.004
"""Relative distance d from the line of the runs that decide the bifurcation type (d, 2d, 4d below; d, d/4 above)."""
SQRT_LAW_SPREAD = 0.15
"""Tolerance of the square-root law of the limit-cycle amplitudes below a supercritical line."""
LARGE_PERTURBATION = 0.5
"""Large start above the line that finds a stick-slip attractor of a subcritical line."""
TYPE_CYCLES = 10_000
"""Cycle budget of the runs that decide the type."""
