"""Dense output of DOP853 (Hairer, Norsett and Wanner, Solving ODEs I, 2nd ed., section II.6; the contd8 of
Hairer's dop853.f, as in scipy.integrate.DOP853): three more stages after an accepted step give a continuous
extension of order 7 over the step.

With K[0..11] the step's stages, K[12] the derivative at its end and K[13..15] the extra stages
(K[s] = f(y0 + h sum_j EXTRA_A[s][j] K[j])), the interpolant at theta = (sigma - sigma0)/h in [0, 1] is

    y(theta) = y0 + theta (F0 + (1 - theta) (F1 + theta (F2 + (1 - theta) (F3 + theta (F4 + (1 - theta) (F5
               + theta F6))))))                                                                          (1)

with F0 = y1 - y0, F1 = h K[0] - F0, F2 = 2 F0 - h (K[12] + K[0]) and F[3 + r] = h sum_j D[r][j] K[j].
The coefficients are those of scipy.integrate._ivp.dop853_coefficients (copied: that module is private);
tests/integrate/test_lanes_sampled.py checks the stages 0..11 against the tableau of sweep.integrate.solvers.
:func:`rows` and :func:`evaluate` are (1) for one component in scalar code (the quasi-static driven lanes' extrema,
sweep/integrate/lanes_driven.py); the sampled lanes write (1) out in their own vector loops.
"""

import numpy as np
from numba import njit

from ..jitcache import pin_module
from .solvers.fastmath import FAST

EXTRA_A = {  # stage -> {j: a_sj}
    13: {0: 0.056167502283047954, 6: 0.25350021021662483, 7: -0.2462390374708025, 8: -0.12419142326381637,
         9: 0.15329179827876568, 10: 0.00820105229563469, 11: 0.007567897660545699, 12: -0.008298},
    14: {0: 0.03183464816350214, 5: 0.028300909672366776, 6: 0.053541988307438566, 7: -0.05492374857139099,
         10: -0.00010834732869724932, 11: 0.0003825710908356584, 12: -0.00034046500868740456, 13: 0.1413124436746325},
    15: {0: -0.42889630158379194, 5: -4.697621415361164, 6: 7.683421196062599, 7: 4.06898981839711,
         8: 0.3567271874552811, 12: -0.0013990241651590145, 13: 2.9475147891527724, 14: -9.15095847217987},
}
D = (  # row r of F[3 + r] = h sum_j D[r][j] K[j]
    {0: -8.428938276109013, 5: 0.5667149535193777, 6: -3.0689499459498917, 7: 2.38466765651207, 8: 2.117034582445028,
     9: -0.871391583777973, 10: 2.2404374302607883, 11: 0.6315787787694688, 12: -0.08899033645133331,
     13: 18.148505520854727, 14: -9.194632392478356, 15: -4.436036387594894},
    {0: 10.427508642579134, 5: 242.28349177525817, 6: 165.20045171727028, 7: -374.5467547226902,
     8: -22.113666853125306, 9: 7.733432668472264, 10: -30.674084731089398, 11: -9.332130526430229,
     12: 15.697238121770845, 13: -31.139403219565178, 14: -9.35292435884448, 15: 35.81684148639408},
    {0: 19.985053242002433, 5: -387.0373087493518, 6: -189.17813819516758, 7: 527.8081592054236,
     8: -11.57390253995963, 9: 6.8812326946963, 10: -1.0006050966910838, 11: 0.7777137798053443,
     12: -2.778205752353508, 13: -60.19669523126412, 14: 84.32040550667716, 15: 11.99229113618279},
    {0: -25.69393346270375, 5: -154.18974869023643, 6: -231.5293791760455, 7: 357.6391179106141, 8: 93.40532418362432,
     9: -37.45832313645163, 10: 104.0996495089623, 11: 29.8402934266605, 12: -43.53345659001114,
     13: 96.32455395918828, 14: -39.17726167561544, 15: -149.72683625798564},
)
INTERPOLATOR_POWER = 7
"""Rows F0..F6 of (1)."""
STAGES = 16
"""K[0..15]: the step's twelve stages, the derivative at its end and the three extra stages."""
EXTRA_MATRIX = np.zeros((len(EXTRA_A), STAGES))
"""EXTRA_A as a matrix: row s - 13, column j."""
D_MATRIX = np.zeros((len(D), STAGES))
"""D as a matrix."""
for _s, _row in EXTRA_A.items():
    for _j, _a in _row.items():
        EXTRA_MATRIX[_s - 13, _j] = _a
for _r, _row in enumerate(D):
    for _j, _d in _row.items():
        D_MATRIX[_r, _j] = _d


@njit(inline="always", fastmath=FAST, error_model="numpy")
def _d_row(r, K, m):
    """sum_j D[r][j] K[j, m]."""
    acc = 0.0
    for j in range(STAGES):
        acc += D_MATRIX[r, j] * K[j, m]
    return acc


@njit(inline="always", fastmath=FAST, error_model="numpy")
def rows(y0, y1, h, K, m):
    """The rows F0..F6 of (1) for component m of a step of size h from y0 to y1 with the stages K (STAGES rows)."""
    f0 = y1 - y0
    return (f0, h * K[0, m] - f0, 2.0 * f0 - h * (K[12, m] + K[0, m]), h * _d_row(0, K, m), h * _d_row(1, K, m),
            h * _d_row(2, K, m), h * _d_row(3, K, m))


@njit(inline="always", fastmath=FAST, error_model="numpy")
def evaluate(theta, y0, F):
    """(y, dy/dtheta, d2y/dtheta2) of (1) at theta with the rows F: the nested form evaluated inside out, its
    derivatives carried along (each factor theta or 1 - theta, of slope +1 or -1)."""
    v, d1, d2 = F[6], 0.0, 0.0
    for r in range(5, -1, -1):
        m, dm = (theta, 1.0) if r % 2 == 1 else (1.0 - theta, -1.0)
        v, d1, d2 = F[r] + m * v, dm * v + m * d1, 2.0 * dm * d1 + m * d2
    return y0 + theta * v, v + theta * d1, 2.0 * d1 + theta * d2


pin_module(__name__)
