"""The one shared table of quasi-static stop reference cases (docs/physics.md 3a), used by test_reference.py (the
reference against closed forms) and test_accuracy.py (the engine against the reference).

A case is given in reduced form (chi, A, mu1 = mu1(V), m2); ``case_params(case)`` returns physical parameters
(SI) that reproduce exactly that chi and mu1, for feeding the engine:

* generic cases: D0 = 1e-6 m, V = V0 = 1e-6 m/s (so mu1(V) = m1: m1 is set to mu1), K/M = chi g/D0;
* preset cases (sample1/sample2 of docs/physics.md 5 at a given K/M, V): the preset's A, m1, m2, D0 with that K/M
  and V; chi = (K/M) D0/g and mu1 = m1 - 2 m2 ln(V/V0) are computed here with the same formulas.

Naming: ``g_*`` generic, ``s1_*``/``s2_*`` presets; ``chiA`` = chi/A, ``mA`` = mu1/A, ``m2A`` = m2/A.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

V0 = 1e-6  # m/s
G = 9.81  # m/s^2
D0_GENERIC = 1e-6  # m

PRESETS = {  # docs/physics.md 5 (paper Table I, our reading)
    "sample1": {"A": 0.012, "m1": 0.010, "m2": 0.0014, "D0": 1e-6},
    "sample2": {"A": 0.007, "m1": 0.0125, "m2": 0.0033, "D0": 0.7e-6},
}


@dataclass(frozen=True)
class StopCase:
    name: str
    chi: float
    A: float
    mu1: float
    m2: float
    expect_finite: bool
    why: str
    preset: str | None = None  # physical origin, when the case comes from a preset
    K_over_M: float | None = None  # s^-2
    V: float | None = None  # m/s

    @property
    def hopf_side(self) -> str:
        """'stable' (chi > mu1), 'hopf' (chi == mu1) or 'stick-slip' (chi < mu1); quasi-static Hopf line."""
        return "stable" if self.chi > self.mu1 else ("hopf" if self.chi == self.mu1 else "stick-slip")


def generic(name, chi_over_A, mu1_over_A, m2_over_A=0.0, A=0.01, why=""):
    A = float(A)
    mu1, m2 = mu1_over_A * A, m2_over_A * A
    finite = m2 > 0.0 or (m2 == 0.0 and mu1 > 0.0)
    return StopCase(name=name, chi=chi_over_A * A, A=A, mu1=mu1, m2=m2, expect_finite=finite, why=why)


def from_preset(name, preset, K_over_M, V, why=""):
    p = PRESETS[preset]
    chi = K_over_M * p["D0"] / G
    mu1 = p["m1"] - 2.0 * p["m2"] * math.log(V / V0)
    return StopCase(name=name, chi=chi, A=p["A"], mu1=mu1, m2=p["m2"], expect_finite=p["m2"] > 0.0, why=why,
                    preset=preset, K_over_M=float(K_over_M), V=float(V))


STOP_CASES = [
    # --- m2 = 0: closed form xi_inf = A ln(chi/m1)/(chi - m1) exists (checked in test_reference.py)
    generic("g_chiA0.01_mA1", 0.01, 1.0, why="soft spring, deep in stick-slip (chi << mu1), large slip"),
    generic("g_chiA0.01_mA0.3_slowtail", 0.01, 0.3, why="soft spring + slow tail tau^-0.3"),
    generic("g_chiA0.1_mA3", 0.1, 3.0, why="strong velocity weakening, below Hopf line"),
    generic("g_chiA1_mA1_hopf", 1.0, 1.0, why="on the quasi-static Hopf line chi = mu1 (closed form A/m1)"),
    generic("g_chiA1_mA0.3_slowtail", 1.0, 0.3, why="above the Hopf line, slow tail (m1/A = 0.3)"),
    generic("g_chiA3_mA3_nearhopf", 3.0, 3.0 / 1.001, why="just above the Hopf line (chi = 1.001 mu1)"),
    generic("g_chiA10_mA0.3_slowtail", 10.0, 0.3, why="stiff-ish spring, slow tail"),
    generic("g_chiA10_mA3", 10.0, 3.0, why="stable sliding, fast tail"),
    generic("g_chiA100_mA1", 100.0, 1.0, why="stiff start, decay rate chi/A = 100"),
    generic("g_chiA1000_mA1_stiff", 1000.0, 1.0, why="the stiff corner: decay rate chi/A = 1000"),
    generic("g_chiA1000_mA0.3_stiff_slowtail", 1000.0, 0.3, why="stiff start and slow tail together"),
    # --- m2 > 0, mu1 > 0
    generic("g_chiA0.01_mA1_m2A0.1", 0.01, 1.0, 0.1, why="soft spring with curvature m2"),
    generic("g_chiA1_mA0.3_m2A0.05", 1.0, 0.3, 0.05, why="slow tail cut off by m2 (Gaussian in ln psi)"),
    generic("g_chiA1000_mA3_m2A0.3_stiff", 1000.0, 3.0, 0.3, why="stiff corner with m2 > 0"),
    # --- m2 > 0, mu1 < 0 (velocity strengthening locally; finite only thanks to m2)
    generic("g_chiA0.1_mA-0.5_m2A0.2", 0.1, -0.5, 0.2, why="mu1 < 0, moderate: no Hopf line"),
    generic("g_chiA0.01_mA-3_m2A0.47_corner", 0.01, -3.0, 0.47, A=0.007,
            why="costly corner: small chi/A, strongly negative mu1, psi << tau for decades (xi_inf ~ 490)"),
    # --- presets (docs/physics.md 5) at a few (K/M, V) of the default grid K/M 1e3..1e6 s^-2, V 0.1..100 um/s
    from_preset("s1_KM7.4e4_V10um", "sample1", 7.4e4, 10e-6, why="paper Fig. 3b point, chi = 7.5e-3 > mu1(V)"),
    from_preset("s1_KM1e3_V0.1um", "sample1", 1e3, 0.1e-6, why="softest/slowest grid corner, stick-slip side"),
    from_preset("s1_KM1e6_V100um", "sample1", 1e6, 100e-6, why="stiffest/fastest grid corner, mu1(V) < 0"),
    from_preset("s2_KM2.8e5_V1um", "sample2", 2.8e5, 1e-6, why="paper Fig. 4 transient at 1 um/s (mu1 = m1)"),
    from_preset("s2_KM2.8e5_V10um", "sample2", 2.8e5, 10e-6, why="paper Fig. 4 transient at 10 um/s, mu1 < 0"),
    from_preset("s2_KM1e3_V100um_corner", "sample2", 1e3, 100e-6,
                why="costly corner of the default grid: chi/A ~ 0.01, mu1(V) ~ -0.018, xi_inf ~ 350"),
    from_preset("s2_KM1e4_V100um_corner", "sample2", 1e4, 100e-6, why="costly corner, chi/A ~ 0.1"),
    from_preset("s2_KM1e6_V0.1um", "sample2", 1e6, 0.1e-6, why="stiff spring, slow drive: chi/A ~ 10"),
    from_preset("s2_KM1e3_V0.1um", "sample2", 1e3, 0.1e-6, why="soft spring, slow drive: stick-slip side"),
]

NO_LIMIT_CASES = [
    generic("nolim_m2neg_mupos", 1.0, 1.0, -0.1, why="m2 < 0: dmu -> -inf, xi grows without bound"),
    generic("nolim_m2neg_muneg", 1.0, -0.5, -0.1, why="m2 < 0 and mu1 < 0"),
    generic("nolim_m2zero_mu0", 1.0, 0.0, why="m2 = 0, mu1 = 0: xi ~ (A/chi) ln ln tau"),
    generic("nolim_m2zero_muneg", 1.0, -0.5, why="m2 = 0, mu1 < 0: xi ~ |mu1| ln(tau)/chi"),
    generic("nolim_m2zero_muneg_soft", 0.1, -1.0, A=0.007, why="m2 = 0, mu1 < 0, soft spring"),
]

EXTREME_CASES = [  # beyond the presets' range: here DOP853 runs out of its budget and the reference uses Radau
    generic("x_chiA0.001_mA-6_m2A0.47", 0.001, -6.0, 0.47, A=0.007,
            why="deeper than the costly corner (chi/A = 1e-3, mu1/A = -6): psi << tau, xi_inf ~ 2e4"),
    generic("x_chiA0.01_mA-6_m2A0.1", 0.01, -6.0, 0.1, A=0.007, why="strongly negative mu1, weak m2: xi_inf ~ 9000"),
]

ALL_CASES = STOP_CASES + NO_LIMIT_CASES + EXTREME_CASES

assert len({c.name for c in ALL_CASES}) == len(ALL_CASES), "case names must be unique"
assert all(c.expect_finite for c in STOP_CASES + EXTREME_CASES) and not any(c.expect_finite for c in NO_LIMIT_CASES)


def case_params(case: StopCase) -> dict:
    """Physical (SI) parameters reproducing the case's chi and mu1(V): keys A, m1, m2, D0, V, K_over_M, V0, g,
    plus the reduced chi and mu1 for reference."""
    if case.preset is not None:
        p = PRESETS[case.preset]
        out = {"A": p["A"], "m1": p["m1"], "m2": p["m2"], "D0": p["D0"], "V": case.V, "K_over_M": case.K_over_M}
    else:
        out = {"A": case.A, "m1": case.mu1, "m2": case.m2, "D0": D0_GENERIC, "V": V0,
               "K_over_M": case.chi * G / D0_GENERIC}
    out.update(V0=V0, g=G, chi=case.chi, mu1=case.mu1)
    return out
