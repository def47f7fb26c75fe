"""Explicit Runge-Kutta methods as validated data (Butcher tableaux).

Adding a method is adding a tableau: a :class:`ButcherTableau` checks itself when it is built. The rows of
``a`` sum to ``c`` (consistency), ``a`` is strictly lower triangular (explicit), and the weights ``b`` (and
the embedded weights ``b_hat``, if any) satisfy Butcher's order conditions

    b . Phi(t) = 1 / gamma(t)    for every rooted tree t with |t| <= order,

where Phi(t) is the elementary weight vector of t and gamma(t) its density (Butcher 1963; Hairer, Norsett &
Wanner, *Solving Ordinary Differential Equations I*, 2nd ed., Springer 1993, Sec. II.2). The trees are
generated here (1, 1, 2, 4, 9, 20, 48, 115 of orders 1..8: 200 conditions for an eighth-order method), so
no list of conditions is written out by hand and a transcription error in a coefficient shows up as a
failed condition naming its tree.

The kernels take :meth:`ButcherTableau.arrays` (float64 c, a, b, e = b - b_hat) plus the flags
``stages``, ``fsal``, ``adaptive`` and ``error_order``; :data:`EXPLICIT_METHODS` maps names to the built-in tableaux
(:data:`sweep.integrate.solvers.METHODS` adds the Rosenbrock methods).
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from functools import cache
from math import prod
from types import MappingProxyType

import numpy as np

__all__ = [
    "COEFFICIENT_TOL", "DOP853", "DOP853_ER3", "DP5", "EXPLICIT_METHODS", "MAX_TREE_ORDER", "RK4", "ButcherTableau",
    "Tree", "rooted_trees", "tree_density", "tree_name", "tree_order",
]

Tree = tuple["Tree", ...]
"""A rooted tree as the sorted tuple of its root's subtrees: ``()`` is the single node tau."""

MAX_TREE_ORDER = 8
"""Highest order a tableau may claim (115 trees of order 8; order 9 would add 286 more conditions)."""

COEFFICIENT_TOL = 1e-12
"""Tolerance of the order conditions, relative to 1/gamma(t) (and absolute for row sums a . 1 = c, c ~ 1).

Published coefficients are decimals (DOP853: 30 digits) rounded once to float64, relative error 2**-53 =
1.1e-16 each; a condition b . Phi(t) sums products of up to |t| <= 8 of them with cancellation. The largest
residual of the built-in methods is 2e-14 of 1/gamma (DOP853, order 8; dp5 2e-15, rk4 1e-16), so 1e-12 leaves
a margin of 50 for rounding, while a transcription error in the first 10 significant digits of a coefficient
fails some condition (any single nonzero DOP853 coefficient changed by a relative 1e-10 is caught).
"""


def _grow(tree: Tree) -> Iterator[Tree]:
    """Every tree obtained by attaching one new leaf to one node of ``tree`` (canonical, maybe repeated)."""
    yield tuple(sorted((*tree, ())))
    for i, child in enumerate(tree):
        for grown in _grow(child):
            yield tuple(sorted((*tree[:i], grown, *tree[i + 1 :])))


@cache
def rooted_trees(order: int) -> tuple[Tree, ...]:
    """All rooted trees with ``order`` nodes (up to isomorphism), in a fixed order; cached."""
    if order == 1:
        return ((),)
    return tuple(sorted({grown for tree in rooted_trees(order - 1) for grown in _grow(tree)}))


def tree_order(tree: Tree) -> int:
    """Number of nodes |t|."""
    return 1 + sum(map(tree_order, tree))


def tree_density(tree: Tree) -> int:
    """Density gamma(t) = |t| * product of the densities of the root's subtrees."""
    return tree_order(tree) * prod(map(tree_density, tree))


def tree_name(tree: Tree) -> str:
    """Nested-bracket notation: tau is ``τ``, ``[u,v]`` is a root carrying the subtrees u and v."""
    return "[" + ",".join(map(tree_name, tree)) + "]" if tree else "τ"


def _elementary_weight(tree: Tree, a: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Phi(t): per stage, the product over the root's subtrees u of (a . Phi(u)), where a . Phi(tau) = c."""
    return np.prod([c if not u else a @ _elementary_weight(u, a, c) for u in tree], axis=0) * np.ones_like(c)


def _tuple(values: Sequence[float]) -> tuple[float, ...]:
    return tuple(float(v) for v in values)


@dataclass(frozen=True)
class ButcherTableau:
    """An explicit Runge-Kutta method, optionally with an embedded error estimator over the same stages.

    Attributes
    ----------
    name : method name (used in error messages and as the key in :data:`EXPLICIT_METHODS`).
    c, a, b : nodes (s,), strictly lower triangular coefficients (s, s), weights (s,).
    order : order p of ``b``; order conditions for all trees with |t| <= p are checked.
    b_hat : embedded weights (s,) for the error estimate, or None for a fixed-step method.
    order_hat : order of ``b_hat`` (0 without one); checked like ``order``.

    Sequences are stored as tuples of floats. Every check raises ValueError naming the method.
    """

    name: str
    c: tuple[float, ...]
    a: tuple[tuple[float, ...], ...]
    b: tuple[float, ...]
    order: int
    b_hat: tuple[float, ...] | None = None
    order_hat: int = 0

    def __post_init__(self) -> None:
        for field in ("c", "b") + (("b_hat",) if self.b_hat is not None else ()):
            object.__setattr__(self, field, _tuple(getattr(self, field)))
        object.__setattr__(self, "a", tuple(map(_tuple, self.a)))
        try:
            c, a, b = np.array(self.c), np.array(self.a, dtype=float), np.array(self.b)
        except ValueError as err:  # ragged rows
            raise ValueError(f"{self.name}: a must be a square matrix ({err})") from None
        s = len(b)
        if a.shape != (s, s) or c.shape != (s,) or (self.b_hat is not None and len(self.b_hat) != s):
            raise ValueError(f"{self.name}: inconsistent tableau shapes a{a.shape}, b({s}), c{c.shape}"
                             + (f", b_hat({len(self.b_hat)})" if self.b_hat is not None else ""))
        if np.any(np.triu(a) != 0.0):
            raise ValueError(f"{self.name}: a must be strictly lower triangular (explicit method)")
        row_error = np.abs(a.sum(axis=1) - c).max()
        if row_error > COEFFICIENT_TOL:
            raise ValueError(f"{self.name}: row sums of a must equal c (largest deviation {row_error:.3g})")
        if self.b_hat is None and self.order_hat != 0:
            raise ValueError(f"{self.name}: order_hat={self.order_hat} given without b_hat")
        if self.b_hat == self.b:
            raise ValueError(f"{self.name}: b_hat equals b (the error estimate would vanish)")
        for label, weights, order in (("b", self.b, self.order), ("b_hat", self.b_hat, self.order_hat)):
            if weights is not None:
                self._check_order(a, c, np.array(weights), order, label)

    def _check_order(self, a: np.ndarray, c: np.ndarray, weights: np.ndarray, order: int, label: str) -> None:
        """Raise ValueError at the first tree with |t| <= order whose condition weights . Phi(t) = 1/gamma fails."""
        if not 1 <= order <= MAX_TREE_ORDER:
            raise ValueError(f"{self.name}: order of {label} must be in 1..{MAX_TREE_ORDER}, got {order}")
        for tree in (t for k in range(1, order + 1) for t in rooted_trees(k)):
            value, gamma = float(weights @ _elementary_weight(tree, a, c)), tree_density(tree)
            if abs(value * gamma - 1.0) > COEFFICIENT_TOL:
                raise ValueError(
                    f"{self.name}: order condition for {label} of order {order} fails at tree {tree_name(tree)} "
                    f"(|t|={tree_order(tree)}): {label}.Phi = {value!r} != 1/gamma = 1/{gamma} = {1.0 / gamma!r}"
                )

    @property
    def stages(self) -> int:
        """Number of stages s (derivative evaluations per step, one fewer when ``fsal`` after the first)."""
        return len(self.b)

    @property
    def adaptive(self) -> bool:
        """Whether the method has an embedded error estimator (``b_hat``)."""
        return self.b_hat is not None

    @property
    def implicit(self) -> bool:
        return False

    @property
    def fsal(self) -> bool:
        """First same as last: the last stage is evaluated at the step's end (c = 1, a-row = b), so its
        derivative is the next step's first stage."""
        return self.c[-1] == 1.0 and self.a[-1] == self.b

    @property
    def error_order(self) -> int:
        """Order of the local error estimate, min(order, order_hat); 0 without an estimator.

        A step-size controller uses the exponent 1 / (error_order + 1)."""
        return min(self.order, self.order_hat)

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Fresh C-contiguous float64 arrays (c, a, b, e) for a compiled kernel, e = b - b_hat (zeros if not
        adaptive): the error estimate of a step y -> y + h b.k is h e.k."""
        c, a, b = np.array(self.c), np.array(self.a), np.array(self.b)
        return c, a, b, (b - np.array(self.b_hat) if self.adaptive else np.zeros_like(b))


def _explicit(rows: Sequence[Sequence[float]]) -> tuple[tuple[float, ...], ...]:
    """Square strictly lower triangular a from its lower rows (row i lists a[i][0..i-1])."""
    return tuple(tuple(row) + (0.0,) * (len(rows) - len(row)) for row in rows)


RK4 = ButcherTableau(
    name="rk4",
    c=(0.0, 0.5, 0.5, 1.0),
    a=((0.0, 0.0, 0.0, 0.0), (0.5, 0.0, 0.0, 0.0), (0.0, 0.5, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0)),
    b=(1 / 6, 1 / 3, 1 / 3, 1 / 6),
    order=4,
)
"""Classical fourth-order Runge-Kutta method (fixed step; Kutta 1901)."""

DP5 = ButcherTableau(
    name="dp5",
    c=(0.0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1.0, 1.0),
    a=_explicit((
        (),
        (1 / 5,),
        (3 / 40, 9 / 40),
        (44 / 45, -56 / 15, 32 / 9),
        (19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729),
        (9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656),
        (35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84),
    )),
    b=(35 / 384, 0.0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0.0),
    order=5,
    b_hat=(5179 / 57600, 0.0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100, 1 / 40),
    order_hat=4,
)
"""Dormand-Prince 5(4) ("DOPRI5", MATLAB's ode45): fifth-order step with local extrapolation, fourth-order
embedded estimate, seven stages of which the last is FSAL (six evaluations per accepted step).

J. R. Dormand, P. J. Prince, "A family of embedded Runge-Kutta formulae", J. Comput. Appl. Math. 6 (1980)
19-26; Hairer, Norsett & Wanner, Solving ODEs I, Sec. II.5."""

_DOP853_B = (
    5.42937341165687622380535766363e-2, 0.0, 0.0, 0.0, 0.0,
    4.45031289275240888144113950566, 1.89151789931450038304281599044, -5.8012039600105847814672114227,
    3.1116436695781989440891606237e-1, -1.52160949662516078556178806805e-1,
    2.01365400804030348374776537501e-1, 4.47106157277725905176885569043e-2,
)
_DOP853_ER = (  # published weights er_i of the fifth-order error estimate h er.k of y1 - y1_hat: b_hat = b - er
    0.1312004499419488073250102996e-1, 0.0, 0.0, 0.0, 0.0,
    -0.1225156446376204440720569753e1, -0.4957589496572501915214079952, 0.1664377182454986536961530415e1,
    -0.3503288487499736816886487290, 0.3341791187130174790297318841, 0.8192320648511571246570742613e-1,
    -0.2235530786388629525884427845e-1,
)

DOP853 = ButcherTableau(
    name="dop853",
    c=(
        0.0, 0.526001519587677318785587544488e-1, 0.789002279381515978178381316732e-1,
        0.118350341907227396726757197510, 0.281649658092772603273242802490, 0.333333333333333333333333333333,
        0.25, 0.307692307692307692307692307692, 0.651282051282051282051282051282, 0.6,
        0.857142857142857142857142857142, 1.0,
    ),
    a=_explicit((
        (),
        (5.26001519587677318785587544488e-2,),
        (1.97250569845378994544595329183e-2, 5.91751709536136983633785987549e-2),
        (2.95875854768068491816892993775e-2, 0.0, 8.87627564304205475450678981324e-2),
        (2.41365134159266685502369798665e-1, 0.0, -8.84549479328286085344864962717e-1,
         9.24834003261792003115737966543e-1),
        (3.7037037037037037037037037037e-2, 0.0, 0.0, 1.70828608729473871279604482173e-1,
         1.25467687566822425016691814123e-1),
        (3.7109375e-2, 0.0, 0.0, 1.70252211019544039314978060272e-1, 6.02165389804559606850219397283e-2,
         -1.7578125e-2),
        (3.70920001185047927108779319836e-2, 0.0, 0.0, 1.70383925712239993810214054705e-1,
         1.07262030446373284651809199168e-1, -1.53194377486244017527936158236e-2,
         8.27378916381402288758473766002e-3),
        (6.24110958716075717114429577812e-1, 0.0, 0.0, -3.36089262944694129406857109825,
         -8.68219346841726006818189891453e-1, 2.75920996994467083049415600797e1,
         2.01540675504778934086186788979e1, -4.34898841810699588477366255144e1),
        (4.77662536438264365890433908527e-1, 0.0, 0.0, -2.48811461997166764192642586468,
         -5.90290826836842996371446475743e-1, 2.12300514481811942347288949897e1,
         1.52792336328824235832596922938e1, -3.32882109689848629194453265587e1,
         -2.03312017085086261358222928593e-2),
        (-9.3714243008598732571704021658e-1, 0.0, 0.0, 5.18637242884406370830023853209,
         1.09143734899672957818500254654, -8.14978701074692612513997267357,
         -1.85200656599969598641566180701e1, 2.27394870993505042818970056734e1,
         2.49360555267965238987089396762, -3.0467644718982195003823669022),
        (2.27331014751653820792359768449, 0.0, 0.0, -1.05344954667372501984066689879e1,
         -2.00087205822486249909675718444, -1.79589318631187989172765950534e1,
         2.79488845294199600508499808837e1, -2.85899827713502369474065508674,
         -8.87285693353062954433549289258, 1.23605671757943030647266201528e1,
         6.43392746015763530355970484046e-1),
    )),
    b=_DOP853_B,
    order=8,
    b_hat=tuple(bi - ei for bi, ei in zip(_DOP853_B, _DOP853_ER)),
    order_hat=5,
)
"""Hairer's DOP853 (Dormand-Prince 8(5,3)) with its fifth-order embedded estimate: twelve stages, no FSAL
stage in the tableau (the fifth-order estimator does not use f at the step's end; a kernel may still reuse
that evaluation as the next step's first stage). The third-order estimator, with which the original code damps
the error norm, is :data:`DOP853_ER3`; the dense-output stages are not included.

Hairer, Norsett & Wanner, Solving Ordinary Differential Equations I, 2nd ed. (1993), Sec. II.10 (code
DOP853); coefficients as in the Fortran code dop853.f (http://www.unige.ch/~hairer/software.html). The
eighth-order formula derives from P. J. Prince, J. R. Dormand, "High order embedded Runge-Kutta formulae",
J. Comput. Appl. Math. 7 (1981) 67-75."""

_DOP853_BHH = {0: 0.244094488188976377952755905512, 8: 0.733846688281611857341361741547,
                11: 0.220588235294117647058823529412e-1}  # published bhh_i of the third-order solution
DOP853_ER3 = tuple(b - _DOP853_BHH.get(i, 0.0) for i, b in enumerate(_DOP853_B))
"""Weights of DOP853's third-order error estimate h er3.k (er3 = b - bhh over its twelve stages). dop853.f
measures a step by err5^2 / sqrt(err5^2 + 0.01 err3^2) of the two estimates' norms: of order 8 in h as h -> 0,
so its controller exponent is 1/8 (Hairer, Norsett & Wanner I, Sec. II.10)."""

EXPLICIT_METHODS: Mapping[str, ButcherTableau] = MappingProxyType({m.name: m for m in (RK4, DP5, DOP853)})
"""Built-in methods by name (read-only)."""
