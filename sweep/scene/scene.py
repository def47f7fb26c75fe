"""Scene: a frozen, validated description of one study (docs/design.md), built from Python or from TOML.

Everything is checked here, before any compilation or computation, and every error names its field and
the allowed range. SI units throughout: K_over_M [s-2], V [m s-1], times [s].
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields, replace
from pathlib import Path
from typing import Any

import numpy as np

from .. import protocols
from ..errors import InputError
from ..integrate.models.state_laws import STATE_LAWS as _LAWS
from ..integrate.solvers import METHODS
from ..protocols.base import Options
from .params import LAB_NAMES, FrictionParams, K_over_M_from_k, require_finite, require_positive
from .presets import presets

__all__ = ["Scene", "PROTOCOLS", "DEFAULT_ATOL", "EXTRA_AXES", "LAB_AXES", "AXIS_UNITS",
           "default_scene", "load_scene"]

PROTOCOLS = protocols.names()
"""The protocols a scene may name (sweep/protocols/: each owns its fields, plan, chunks, schema and picture)."""
MODELS = ("auto", "quasistatic", "inertial")
STATE_LAWS = tuple(sorted(_LAWS))
"""The state laws (sweep/integrate/models/state_laws.py; docs/physics.md 7), as their registry has them."""
MODEL_TOL_RANGE = (1e-6, 0.5)
"""Allowed bound on the relative error of the model choice (Scene.model_tol)."""
PERTURBATION_RANGE = (1e-8, 1.0)
"""Allowed initial spring stretch of the driven scene (reduced, z = tau - xi)."""
DEFAULT_ATOL = {"xi_inf": 1e-12, "trajectory": 1e-12, "slip_at": 1e-12, "t50": 0.0, "t90": 0.0}
"""Absolute floors per observable with a numerical tolerance, in the observable's reduced unit (xi for slips, tau for
times)."""
RTOL_RANGE = (1e-10, 1e-2)
PRECISIONS = ("float64", "float32")
FLOAT32_RTOL_MIN = 1e-5
TAU_MAX = 1e250
"""Largest reduced time that can be asked for (float64 carries tau up to ~1e308)."""
EXTRA_AXES = ("A", "m1", "m2", "D0")
"""Friction parameters a stop scene may sweep beside (K/M, V) (Scene.axes), in the order of the Dataset's dims."""
LAB_AXES = ("a", "b", "Dc")
"""The laboratory's friction parameters as axes (docs/physics.md 7b: A = a, m1 = b - a, D0 = Dc at m2 = 0), each point
with its own; where ``a`` is an axis, m1 = b - a follows it (b held, or b's axis)."""
STIFFNESS_AXIS = "k"
"""The laboratory's stiffness k [1/m] as the first axis instead of K_over_M (K/M = k g; sweep.scene.params)."""
AXIS_UNITS = {"K_over_M": "s-2", "V": "m s-1", "A": "1", "m1": "1", "m2": "1", "D0": "m", "a": "1", "b": "1",
              "Dc": "m", "k": "m-1"}
POSITIVE_AXES = ("K_over_M", "V", "A", "D0", "a", "Dc", "k")
"""Axes whose values must be > 0 (the others, m1, m2 and b, only finite)."""
LAB_AXIS_NAMES = {"a": "direct-effect coefficient a (= A)", "b": "evolution coefficient b (m1 = b - a)",
                  "Dc": "critical slip distance Dc (= D0)",
                  "k": "stiffness k, friction per metre of load-point displacement (K/M = k g)"}
"""long_name of the laboratory's axes (the paper's are in sweep.assemble.dataset.AXIS_NAMES)."""
_SOURCES = {"K_over_M": ("k",), "A": ("a",), "m1": ("a", "b"), "D0": ("Dc",)}
"""The laboratory's axes each paper parameter follows where they are axes."""
PARAMETER_NAMES = frozenset({"K_over_M", "V", *EXTRA_AXES, *LAB_AXES, STIFFNESS_AXIS, *LAB_NAMES, "m0", "g"})
"""Names an axis of a protocol's options may not take (the scene's parameters)."""


def _plain(value: Any) -> Any:
    """A numpy scalar as the Python number it holds, so that messages print ``-1000.0``, not ``np.float64(...)``."""
    return value.item() if isinstance(value, np.generic) else value


def _axis(name: str, values: Any) -> np.ndarray:
    """Validate one grid axis: 1-D, non-empty, finite, strictly increasing, > 0 (except m1 and m2: any finite)."""
    try:
        arr = np.array(values, dtype=float).reshape(-1) if np.ndim(values) <= 1 else None
    except (TypeError, ValueError):
        raise InputError(f"{name} must be a 1-D sequence of numbers, got {values!r}") from None
    if arr is None:
        raise InputError(f"{name} must be 1-D, got an array of shape {np.shape(values)}")
    if arr.size == 0:
        raise InputError(f"{name} is empty: give at least one value")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name} contains NaN or inf: all values must be finite")
    if name in POSITIVE_AXES and np.any(arr <= 0):
        raise InputError(f"{name} must be > 0 (allowed range: 0 < {name} < inf), got min {_plain(arr.min())!r}")
    if np.any(np.diff(arr) <= 0):
        raise InputError(f"{name} must be strictly increasing (sorted, no duplicates)")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Scene:
    """What to study: protocol, friction parameters, the (K/M, V) grid, observables and accuracy, and the protocol's own
    fields (``options``).

    Parameters
    ----------
    protocol : "stop" | "driven"
        "stop": the paper's experiment, steady sliding at V, drive frozen at t = 0 (docs/physics.md 3a). "driven": the
        drive keeps moving at V; steady sliding perturbed by ``perturbation`` is followed until its regime is
        decided (docs/physics.md 3b; quasi-static model, sweep/integrate/models/driven.py).
    params : FrictionParams
        Friction law; see :data:`sweep.presets`.
    K_over_M : array [s-2] or None
        Spring stiffness over slider mass; strictly increasing, > 0. None where ``axes`` gives the laboratory's
        stiffness ``k`` [1/m] instead (K/M = k g; the Dataset's first dim is then ``k``).
    V : array [m s-1]
        Driving velocity before the stop; strictly increasing, > 0.
    rtol : float
        Relative accuracy of every observable w.r.t. the exact solution of the model, 1e-10 <= rtol <= 1e-2.
    atol : mapping, optional
        Absolute floors per observable (reduced units), overriding :data:`DEFAULT_ATOL`.
    observables : tuple of str, optional
        stop: subset of ``OBSERVABLES`` (default ("xi_inf",)); driven: subset of ``DRIVEN_OBSERVABLES`` (default
        all). Stop: xi_inf (with slip_inf, stress_relaxation, stable, status) is always computed; "trajectory"
        adds xi(tau), psi(tau); "slip_at" the slip at ``t_obs``; "t50"/"t90" the times to 50 %/90 % of the
        relaxed slip. Driven: regime (with status) is always stored.
    trajectory_tau : (min, max, num)
        Log-spaced reduced times of the trajectory samples, 0 < min < max <= 1e250, num >= 2.
    t_obs : sequence of float [s]
        Times after the stop for "slip_at" (>= 0, strictly increasing).
    method : "auto" | "rk4" | "dp5" | "dop853" | "ros4"
        Integration method (:data:`sweep.integrate.solvers.METHODS`); "auto" lets the plan pick, per point, the cheapest
        that meets rtol (sweep.plan.plan: rk4, and the Rosenbrock ros4 at the stiff points of relaxed-slip sweeps).
        rk4 and ros4 run with fixed steps, dp5 and dop853 with adaptive steps; ros4 computes the relaxed slip
        only (observables = ("xi_inf",)).
    step : float, optional
        Override of the planned fixed step h (0 < step <= 2; fixed-step methods only): in the scaled log time
        sigma for rk4, in the step rule of ros4 (models/stop_stiff.py); default from rtol. The number of steps
        of each point then follows from its own horizon.
    precision : "float64" | "float32"
        Arithmetic of the relaxed-slip lanes. float32 is about twice as fast there and keeps ~7 digits: allowed
        only for rtol >= 1e-5, a fixed-step method and observables = ("xi_inf",).
    max_steps : int
        Step budget per point; a point that needs more gets status max_steps.
    perturbation : float
        driven only: initial spring stretch z(0) = tau - xi away from steady sliding (reduced, 1e-8..1).
    max_cycles : int
        driven only: oscillation cycles per point before it is left ``undecided`` (>= 4).
    model : "auto" | "quasistatic" | "inertial"
        The paper's quasi-static model, the full Newton equation with the inertia number gamma = V^2/(g D0)
        (docs/physics.md 3a/3b), or (default) per point the quasi-static model where its estimated error is at most
        ``model_tol`` and the inertial one elsewhere (sweep/protocols/stop/model_choice.py; the file records the
        choice per point
        in ``model`` and the estimate in ``model_error``). Stop scenes with the inertial model compute the relaxed
        slip only (observables = ("xi_inf",)); with "auto", a point that needs inertia while time-resolved
        observables are asked for keeps its quasi-static values with status model_error_above_tol.
    model_tol : float
        Bound on the relative error of the model choice, 1e-6 <= model_tol <= 0.5 (default 1e-2); ``rtol`` bounds
        the numerical error of the model used.
    state_law : "aging" | "slip"
        How the contact age evolves (docs/physics.md 7): the paper's aging law (default), or Ruina's slip law
        psi' = -xi' psi ln(xi' psi). The slip law runs with model="quasistatic"; its stop scene computes the
        relaxed slip only (observables = ("xi_inf",), finite only for m2 > 0), through the general two-state
        formulation (the fast paths of the aging law rest on its identity xi + ln psi = s).
    axes : mapping, optional
        Further axes of the grid, stop protocol only: {name: values} for any of A, m1, m2 [1] and D0 [m]
        (:data:`EXTRA_AXES`; strictly increasing, A and D0 > 0), or the laboratory's a, b [1] and Dc [m]
        (:data:`LAB_AXES`: A = a, m1 = b - a, D0 = Dc per point, at m2 = 0; never beside the paper's), and ``k``
        [1/m] instead of K_over_M. Each replaces that parameter of ``params``: the Dataset's dims are then K_over_M
        (or k), V and those names in the order of EXTRA_AXES, LAB_AXES, every point with its own parameters (e.g. a
        grid over (A, m1) at one (K/M, V)). A protocol's options may name further axes (a history's
        ``hold = "t_hold"``: Protocol.option_axes), which follow, in the order the options name them.
        TOML: tables [A], [m1], [k], [t_hold], ... like [K_over_M].
    simulated_hopf_line : bool
        Also locate the Hopf line of the scene's model by simulation at each V (coordinate
        ``K_over_M_c_simulated``, drawn on the maps next to the analytic line; sweep.analysis.hopf.with_simulated_line).
        Default False: the analytic line ``chi_c`` answers where the line is, and the simulation compiles and runs
        the driven kernel (~7 s to compile on first use, ~2 ms per velocity); True checks the analytic line.
    options : mapping, optional
        The protocol's own fields (sweep.protocols.base.Protocol.option_fields; in a scene file, top-level keys),
        checked by the protocol; held as a read-only record with its defaults filled in. The stop's and the driven
        scene's fields above (trajectory_tau, t_obs, step, precision; perturbation, max_cycles) are in it too; a
        protocol that does not use one of them refuses a value other than its default.
    """

    protocol: str
    params: FrictionParams
    K_over_M: np.ndarray | None
    V: np.ndarray
    rtol: float = 1e-6
    atol: Mapping[str, float] = field(default_factory=dict)
    observables: tuple[str, ...] | None = None
    trajectory_tau: tuple[float, float, int] = (1e-3, 1e6, 61)
    t_obs: tuple[float, ...] = ()
    method: str = "auto"
    step: float | None = None
    precision: str = "float64"
    max_steps: int = 1_000_000
    perturbation: float = 1e-3
    max_cycles: int = 2000
    model: str = "auto"
    model_tol: float = 1e-2
    state_law: str = "aging"
    simulated_hopf_line: bool = False
    axes: Mapping[str, Any] = field(default_factory=dict)
    options: Mapping[str, Any] | None = None

    def __post_init__(self) -> None:
        set_ = lambda name, value: object.__setattr__(self, name, value)  # noqa: E731 (frozen dataclass)
        if self.protocol not in protocols.names():
            raise InputError(f"protocol must be one of {protocols.names()}, got {self.protocol!r}")
        protocol = protocols.get(self.protocol)
        if not isinstance(self.params, FrictionParams):
            raise InputError(f"params must be a sweep.FrictionParams, got {type(self.params).__name__}")
        if self.K_over_M is None:
            if not isinstance(self.axes, Mapping) or STIFFNESS_AXIS not in self.axes:
                raise InputError("K_over_M is missing: give K_over_M [s-2] or the laboratory's stiffness as "
                                 "axes={'k': [...]} [1/m]")
            set_("K_over_M", _axis(STIFFNESS_AXIS, self.axes[STIFFNESS_AXIS]) * self.params.g)
        elif isinstance(self.axes, Mapping) and STIFFNESS_AXIS in self.axes and not _same_numbers(
                self.K_over_M, np.multiply(self.axes[STIFFNESS_AXIS], self.params.g)):  # (a replace()d scene's own)
            raise InputError("the stiffness is given twice: give K_over_M [s-2] or the axis k [1/m] "
                             "(K/M = k g), not both (K_over_M=None with axes={'k': ...})")
        else:
            set_("K_over_M", _axis("K_over_M", self.K_over_M))
        set_("V", _axis("V", self.V))
        rtol = require_positive("rtol", self.rtol)
        if not RTOL_RANGE[0] <= rtol <= RTOL_RANGE[1]:
            raise InputError(f"rtol must be in [{RTOL_RANGE[0]:g}, {RTOL_RANGE[1]:g}], got {rtol!r}")
        set_("rtol", rtol)
        allowed, always = protocol.observables, protocol.always
        if self.observables is None:
            obs = protocol.default_observables
        else:
            obs = (self.observables,) if isinstance(self.observables, str) else tuple(self.observables)
        unknown = [o for o in obs if o not in allowed]
        if unknown:
            raise InputError(f"unknown observable(s) {unknown} in observables of protocol {self.protocol!r}; "
                             f"allowed: {list(allowed)}")
        set_("observables", tuple(o for o in allowed if o in obs or o == always))
        atol = dict(self.atol)
        for name, value in atol.items():
            if name not in DEFAULT_ATOL:
                raise InputError(f"atol has unknown observable {name!r}; allowed: {list(DEFAULT_ATOL)}")
            if require_finite(f"atol[{name!r}]", value) < 0:
                raise InputError(f"atol[{name!r}] must be >= 0 (allowed range: 0 <= atol < inf), got {value!r}")
        set_("atol", {**DEFAULT_ATOL, **{k: float(v) for k, v in atol.items()}})
        if self.method != "auto" and self.method not in METHODS:
            raise InputError(f"method must be 'auto' or one of {sorted(METHODS)}, got {self.method!r}")
        self._check_model()
        if self.options is not None and not isinstance(self.options, Mapping):
            raise InputError(f"options must be a mapping {{name: value}} of the fields of protocol {self.protocol!r}, "
                             f"got {type(self.options).__name__}")
        given = dict(self.options or {})
        if isinstance(self.options, Options):  # a scene's own record (dataclasses.replace): its keywords decide
            given = {name: value for name, value in given.items() if name not in PROTOCOL_FIELDS}
        options = self._protocol_fields(protocol, given)
        set_("options", protocol.make_options(self, options))
        for name in PROTOCOL_FIELDS:  # the protocol's own fields, as checked, also where they always were
            if name in self.options:
                set_(name, self.options[name])
        self._check_axes()  # before the protocol's check, which may read the axes its options name
        protocol.check(self)
        if isinstance(self.max_steps, bool) or not isinstance(self.max_steps, (int, np.integer)) or self.max_steps < 1:
            raise InputError(f"max_steps must be an integer >= 1, got {_plain(self.max_steps)!r}")
        if not isinstance(self.simulated_hopf_line, (bool, np.bool_)):
            raise InputError(f"simulated_hopf_line must be true or false, got {self.simulated_hopf_line!r}")
        set_("simulated_hopf_line", bool(self.simulated_hopf_line))
        if self.axes and self.simulated_hopf_line:
            raise InputError(f"simulated_hopf_line needs one parameter set (it is located per V); leave it false "
                             f"with axes {list(self.axes)}")

    def _check_axes(self) -> None:
        """The axes: the friction parameters' (paper's or laboratory's, never both), k, and those the protocol's
        options name (Protocol.option_axes), in the order of :attr:`dims`."""
        protocol = protocols.get(self.protocol)
        declared = protocol.option_axes(self.options)
        allowed = (*EXTRA_AXES, *LAB_AXES, STIFFNESS_AXIS)
        if not isinstance(self.axes, Mapping):
            raise InputError(f"axes must be a mapping {{name: values}} with names from {list(allowed)}, got "
                             f"{type(self.axes).__name__}")
        for name, spec in declared.items():
            if name in PARAMETER_NAMES:
                raise InputError(f"{spec.where} names axis {name!r}, which is a parameter of the scene: choose "
                                 f"another name (e.g. {name + '_axis'!r})")
        unknown = [n for n in self.axes if n not in allowed and n not in declared]
        if unknown:
            named = f"; the options name {list(declared)}" if declared else ""
            raise InputError(f"axes has unknown name(s) {unknown} (no parameter, and no option names them); allowed: "
                             f"{list(allowed)}{named} (K_over_M and V are the scene's own axes)")
        missing = [n for n in declared if n not in self.axes]
        if missing:
            spec = declared[missing[0]]
            raise InputError(f"{spec.where} names axis {missing[0]!r}, which the scene does not give: add a table "
                             f"[{missing[0]}] (values or start/stop/num, in {spec.units}) or axes={{{missing[0]!r}: "
                             f"[...]}}")
        friction = [n for n in (*EXTRA_AXES, *LAB_AXES, STIFFNESS_AXIS) if n in self.axes]
        if friction and not protocol.extra_axes:
            offered = [name for name in protocols.names() if protocols.get(name).extra_axes]
            names = " and ".join(map(repr, offered))
            raise InputError(f"axes {friction}: extra axes are offered for protocol {names} only, got protocol "
                             f"{self.protocol!r}")
        lab = [n for n in LAB_AXES if n in self.axes]
        paper = [n for n in EXTRA_AXES if n in self.axes]
        if lab and paper:
            raise InputError(f"axes mix the paper's {paper} and the laboratory's {lab} friction parameters: give "
                             f"one set (a = A, b = A + m1, Dc = D0 at m2 = 0)")
        if lab and self.params.m2 != 0.0:
            raise InputError(f"axes {lab} are the laboratory's parameters, which describe m2 = 0 only; params has "
                             f"m2 = {self.params.m2!r} (give the paper's axes A, m1, D0, or params with m2 = 0)")
        axes = {n: _axis(n, self.axes[n]) for n in (*EXTRA_AXES, *LAB_AXES, STIFFNESS_AXIS) if n in self.axes}
        for name, spec in declared.items():
            arr = _axis(name, self.axes[name])
            low = arr.min()
            if low < spec.minimum or (low == spec.minimum and not spec.inclusive):
                op = ">=" if spec.inclusive else ">"
                raise InputError(f"axis {name} ({spec.where}) must be {op} {spec.minimum:g} {spec.units}, got min "
                                 f"{_plain(low)!r}")
            axes[name] = arr
        if STIFFNESS_AXIS in axes:  # k first: it is the grid's first dim
            axes = {STIFFNESS_AXIS: axes.pop(STIFFNESS_AXIS), **axes}
        object.__setattr__(self, "axes", axes)

    def _protocol_fields(self, protocol, given: dict[str, Any]) -> dict[str, Any]:
        """``given`` (the options) with the protocol's own fields given as Scene keywords (PROTOCOL_FIELDS: the stop's
        and the driven scene's, kept as keywords for the code and files that name them); InputError for such a field
        given both ways, or given a value to a protocol that does not use it."""
        for name in PROTOCOL_FIELDS:
            value, default = getattr(self, name), SCENE_DEFAULTS[name]
            if name in protocol.option_fields:
                if _differs(value, default):
                    if name in given and _differs(given[name], value):
                        raise InputError(f"{name} is given twice, as {value!r} and in options as {given[name]!r}")
                    given.setdefault(name, value)
            elif _differs(value, default):
                raise InputError(f"{name} is not used by protocol {self.protocol!r} (leave it at {default!r}), got "
                                 f"{_plain(value)!r}")
        return given

    def _check_model(self) -> None:
        if self.model not in MODELS:
            raise InputError(f"model must be one of {list(MODELS)}, got {self.model!r}")
        tol = require_positive("model_tol", self.model_tol)
        if not MODEL_TOL_RANGE[0] <= tol <= MODEL_TOL_RANGE[1]:
            raise InputError(f"model_tol must be in [{MODEL_TOL_RANGE[0]:g}, {MODEL_TOL_RANGE[1]:g}] (relative "
                             f"error of the model choice), got {tol!r}")
        object.__setattr__(self, "model_tol", tol)
        self._check_state_law()

    def _check_state_law(self) -> None:
        if self.state_law not in _LAWS:
            raise InputError(f"state_law must be one of {sorted(_LAWS)}, got {self.state_law!r}")
        protocol = protocols.get(self.protocol)
        if not protocol.supports(self.model, self.state_law):
            have = sorted(m for (m, law) in protocol.models if law == self.state_law)
            if not have:
                laws = sorted({law for (_, law) in protocol.models})
                raise InputError(f"state_law {self.state_law!r} is not offered on protocol {self.protocol!r}; "
                                 f"supported: {laws}")
            raise InputError(f"state_law {self.state_law!r} runs with model {' or '.join(map(repr, have))} only on "
                             f"protocol {self.protocol!r}, got model={self.model!r}")

    @property
    def dims(self) -> tuple[str, ...]:
        """Names of the grid's axes: (K_over_M or k, V) and the extra axes, in the order of the Dataset's dims."""
        rest = tuple(d for d in self.axes if d != STIFFNESS_AXIS)
        return (STIFFNESS_AXIS if STIFFNESS_AXIS in self.axes else "K_over_M", "V") + rest

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(self.axis(d).size for d in self.dims)

    def axis(self, name: str) -> np.ndarray:
        """The values of grid axis ``name`` (one of :attr:`dims`; K_over_M also where the grid's first axis is k)."""
        return self.K_over_M if name == "K_over_M" else self.V if name == "V" else self.axes[name]

    def axis_attrs(self, name: str) -> dict[str, str]:
        """units and long_name of a grid axis other than the paper's (K_over_M, V, A, m1, m2, D0: the Dataset's
        own words): the laboratory's, with how it maps, and those the protocol's options name."""
        if name in LAB_AXIS_NAMES:
            maps = {"k": f"K_over_M = k g, g = {self.params.g!r} m s-2", "a": "A = a", "Dc": "D0 = Dc",
                    "b": "m1 = b - a (m2 = 0)"}[name]
            return {"units": AXIS_UNITS[name], "long_name": LAB_AXIS_NAMES[name], "comment": maps}
        spec = protocols.get(self.protocol).option_axes(self.options)[name]
        return {"units": spec.units, "long_name": spec.long_name}

    def broadcast(self, name: str, dims: tuple[str, ...] | None = None) -> np.ndarray | float:
        """K_over_M, V or a friction parameter (A, m1, m2, D0, V0, g; a, b, Dc), or an axis of the options, shaped
        to broadcast over ``dims`` (default :attr:`dims`; axes of the grid only): an axis among ``dims`` as an
        array with ones on the other dims, a parameter that follows the laboratory's axes (K_over_M = k g, A = a,
        m1 = b - a, D0 = Dc) computed from them, any other parameter as the number of ``params``."""
        dims = self.dims if dims is None else dims
        if name in dims:
            shape = [1] * len(dims)
            shape[dims.index(name)] = -1
            return self.axis(name).reshape(shape)
        if any(d in dims for d in _SOURCES.get(name, ())):
            if name == "m1":  # b held where it is not an axis
                return self.broadcast("b", dims) - self.broadcast("A", dims)
            return (K_over_M_from_k(self.broadcast("k", dims), self.params.g) if name == "K_over_M"
                    else self.broadcast(_SOURCES[name][0], dims))
        if name in LAB_AXES:
            return float(self.params.to_lab()[name])
        return float(getattr(self.params, name))

    def on_dims(self, names: Sequence[str]) -> tuple[str, ...]:
        """The grid dims among ``names`` (what a quantity of those parameters varies along; a paper parameter also
        along the laboratory's axes it follows), in grid order."""
        wanted = set(names).union(*(_SOURCES.get(n, ()) for n in names))
        return tuple(d for d in self.dims if d in wanted)

    def at_points(self, name: str, points: np.ndarray) -> np.ndarray | float:
        """K_over_M, V or a friction parameter at the flat grid indices ``points`` (C order over :attr:`dims`): an
        array where ``name`` varies over the grid, else the number of ``params``."""
        dims = self.on_dims((name,))
        if not dims:
            return self.broadcast(name)
        index = np.unravel_index(np.asarray(points), self.shape)
        value = self.broadcast(name, dims)
        return value[tuple(index[self.dims.index(d)] for d in dims)]

    def sub_grid(self, block: Sequence[slice]) -> Scene:
        """The same scene over the block ``block`` of its grid (one slice per dim of :attr:`dims`): a chunk of a run
        (sweep/run/layout.py). Every point's inputs are computed from its own axis values, so a point has the same
        numbers in the sub-grid as in the whole grid."""
        return self.on_values({d: self.axis(d)[s] for d, s in zip(self.dims, block)})

    def on_values(self, values: Mapping[str, np.ndarray]) -> Scene:
        """The same scene over the axis values ``values`` ({dim: values} for every dim of :attr:`dims`)."""
        first = self.dims[0]
        return replace(self, K_over_M=values["K_over_M"] if first == "K_over_M" else None, V=values["V"],
                       axes={d: values[d] for d in self.dims if d not in ("K_over_M", "V")})

    @property
    def time_resolved(self) -> bool:
        """True when values inside the transient are asked for (not only its limit xi_inf)."""
        return protocols.get(self.protocol).time_resolved(self)

    @property
    def n_points(self) -> int:
        return math.prod(self.shape)

    @property
    def tau_samples(self) -> np.ndarray:
        """Reduced times of the trajectory samples (empty unless "trajectory" is observed)."""
        if "trajectory" not in self.observables:
            return np.empty(0)
        lo, hi, num = self.trajectory_tau
        return np.logspace(math.log10(lo), math.log10(hi), num)

    def to_toml(self) -> str:
        """Canonical TOML: resolved parameters and explicit axis values (round-trips through load_scene)."""
        lines = [f'protocol = "{self.protocol}"', f"rtol = {self.rtol!r}"]
        lines.append("observables = [" + ", ".join(f'"{o}"' for o in self.observables) + "]")
        lines.append(f"trajectory_tau = [{self.trajectory_tau[0]!r}, {self.trajectory_tau[1]!r}, "
                     f"{self.trajectory_tau[2]}]")
        lines.append("t_obs = [" + ", ".join(repr(t) for t in self.t_obs) + "]")
        lines.append(f'method = "{self.method}"')
        if self.step is not None:
            lines.append(f"step = {self.step!r}")
        lines.append(f'precision = "{self.precision}"')
        lines.append(f"max_steps = {int(self.max_steps)}")
        lines += protocols.get(self.protocol).toml_lines(self)
        lines.append(f'model = "{self.model}"')
        lines.append(f"model_tol = {self.model_tol!r}")
        lines.append(f'state_law = "{self.state_law}"')
        lines.append(f"simulated_hopf_line = {str(self.simulated_hopf_line).lower()}")
        lines.append("[atol]")
        lines += [f"{k} = {v!r}" for k, v in sorted(self.atol.items())]
        lines.append("[params]")
        lines += [f"{k} = {v!r}" for k, v in self.params.as_dict().items()]
        for name in self.dims:
            lines.append(f"[{name}]")
            lines.append("values = [" + ", ".join(repr(float(x)) for x in self.axis(name)) + "]")
        return "\n".join(lines) + "\n"


PROTOCOL_FIELDS = ("trajectory_tau", "t_obs", "step", "precision", "perturbation", "max_cycles")
"""Fields of :class:`Scene` that belong to one protocol (the stop's, the driven scene's: each its option_fields):
checked by that protocol, refused by the others unless left at their defaults."""
SCENE_DEFAULTS = {f.name: f.default for f in fields(Scene)}


def _differs(value: Any, default: Any) -> bool:
    """Whether a field's value is not its default (a tuple and a list of the same numbers are the same)."""
    try:
        return not np.array_equal(np.asarray(value, dtype=object), np.asarray(default, dtype=object))
    except (TypeError, ValueError):
        return True


def _same_numbers(x: Any, y: Any) -> bool:
    try:
        return bool(np.array_equal(np.asarray(x, float), np.asarray(y, float)))
    except (TypeError, ValueError):
        return False


def _times(name: str, values: Sequence[float]) -> np.ndarray:
    arr = np.array(values, dtype=float).reshape(-1)
    if arr.size and (not np.all(np.isfinite(arr)) or np.any(arr < 0) or np.any(np.diff(arr) <= 0)):
        raise InputError(f"{name} must be finite, >= 0 and strictly increasing [s], got {list(values)!r}")
    return arr


def _axis_from_toml(name: str, spec: Any, positive: bool | None = None) -> np.ndarray:
    """An axis from its table (values, or start/stop/num with spacing "log" by default where its values are > 0:
    ``positive``, by default the friction parameters' and K/M's, V's)."""
    positive = name in POSITIVE_AXES if positive is None else positive
    if not isinstance(spec, Mapping):
        raise InputError(f"[{name}] must be a table with start/stop/num[/spacing] or values")
    extra = set(spec) - {"start", "stop", "num", "spacing", "values"}
    if extra:
        raise InputError(f"[{name}] has unknown key(s) {sorted(extra)}; allowed: start, stop, num, spacing, values")
    if "values" in spec:
        if set(spec) - {"values"}:
            raise InputError(f"[{name}]: give either values or start/stop/num, not both")
        return _axis(name, spec["values"])
    missing = {"start", "stop", "num"} - set(spec)
    if missing:
        raise InputError(f"[{name}] is missing {sorted(missing)}")
    spacing = spec.get("spacing", "log" if positive else "linear")
    start, stop = require_finite(f"{name}.start", spec["start"]), require_finite(f"{name}.stop", spec["stop"])
    if spacing == "log" and min(start, stop) <= 0:
        raise InputError(f"{name}.start and {name}.stop must be > 0 for spacing \"log\", got {start!r}, {stop!r}"
                         + ("" if positive else '; use spacing = "linear"'))
    num = spec["num"]
    if isinstance(num, bool) or not isinstance(num, int) or num < 1:
        raise InputError(f"{name}.num must be an integer >= 1, got {num!r}")
    if spacing == "log":
        return _axis(name, np.logspace(math.log10(start), math.log10(stop), num))
    if spacing == "linear":
        return _axis(name, np.linspace(start, stop, num))
    raise InputError(f'{name}.spacing must be "log" or "linear", got {spacing!r}')


SCENE_KEYS = ({f.name for f in fields(Scene)} - {"axes", "options"}) | {"preset"} | set(EXTRA_AXES) | set(LAB_AXES) \
    | {STIFFNESS_AXIS}
"""Keys of a scene TOML: the Scene's fields (its extra axes as tables [A], [m1], [m2], [D0], [a], [b], [Dc], [k])
and ``preset``; the tables of axes that a protocol's options name are allowed beside them (:func:`_option_axes`)."""


def _option_axes(cfg: Mapping[str, Any]) -> dict[str, Any]:
    """The axes that the options of a scene file's protocol name (Protocol.option_axes; none for a protocol that
    is not known, which the Scene refuses)."""
    name = cfg.get("protocol", "stop")
    if not isinstance(name, str) or name not in protocols.names():
        return {}
    return protocols.get(name).option_axes(cfg)


def _check_keys(cfg: Mapping[str, Any], also: frozenset[str] = frozenset()) -> None:
    """InputError naming the keys of a scene file that no command knows (a misspelt ``rtoll`` is never ignored);
    ``also``: the keys of the command reading it (``sweep hopf``: :data:`HOPF_KEYS`)."""
    allowed = SCENE_KEYS | also | option_keys()
    unknown = set(cfg) - allowed - set(_option_axes(cfg))
    if unknown:
        raise InputError(f"unknown key(s) {sorted(unknown)} in scene; allowed: {sorted(allowed)}")


HOPF_KEYS = frozenset({"bistable_band"})
"""Keys of a scene file that only ``sweep hopf`` reads (sweep.locate_hopf's options)."""


def option_keys() -> frozenset[str]:
    """The keys of a scene file that are a protocol's own fields (Protocol.option_fields), of every protocol."""
    return frozenset(name for p in protocols.names() for name in protocols.get(p).option_fields)


def scene_from_mapping(cfg: Mapping[str, Any]) -> Scene:
    """Build a Scene from a parsed TOML mapping (same fields as :class:`Scene`, plus ``preset``; the fields of its
    protocol's options as top-level keys)."""
    _check_keys(cfg)
    if "K_over_M" not in cfg and STIFFNESS_AXIS not in cfg:
        raise InputError("scene is missing the [K_over_M] axis table (or the laboratory's stiffness [k] in 1/m)")
    if "V" not in cfg:
        raise InputError("scene is missing the [V] axis table")
    params = _params_from(cfg)
    declared = _option_axes(cfg)
    grid = ("preset", "params", "K_over_M", "V", *EXTRA_AXES, *LAB_AXES, STIFFNESS_AXIS, *declared)
    kwargs = {k: v for k, v in cfg.items() if k not in grid}
    options = {k: kwargs.pop(k) for k in (option_keys() - set(SCENE_DEFAULTS)) & set(kwargs)}
    if options:
        kwargs["options"] = options
    axes = {n: _axis_from_toml(n, cfg[n]) for n in (*EXTRA_AXES, *LAB_AXES, STIFFNESS_AXIS) if n in cfg}
    axes.update({n: _axis_from_toml(n, cfg[n], positive=not spec.inclusive) for n, spec in declared.items()
                 if n in cfg})
    if axes:
        kwargs["axes"] = axes
    if "trajectory_tau" in kwargs and isinstance(kwargs["trajectory_tau"], Mapping):
        t = kwargs["trajectory_tau"]
        kwargs["trajectory_tau"] = (t.get("min"), t.get("max"), t.get("num"))
    K_over_M = _axis_from_toml("K_over_M", cfg["K_over_M"]) if "K_over_M" in cfg else None
    return Scene(params=params, K_over_M=K_over_M,
                 V=_axis_from_toml("V", cfg["V"]), **{"protocol": "stop", **kwargs})  # protocol may be in kwargs


PAPER_ONLY = ("A", "m1", "m2", "D0", "m0")
"""[params] keys of the paper's law alone (V0 and g are shared with the laboratory's)."""


def _params_from(cfg: Mapping[str, Any]) -> FrictionParams:
    """FrictionParams from ``preset`` and/or a ``[params]`` table of a parsed TOML mapping: the paper's (A, m1, m2,
    D0, m0) or the laboratory's (a, b, Dc, mu0; FrictionParams.from_lab), never a mix; V0 and g with either."""
    given = cfg.get("params", {})
    if not isinstance(given, Mapping):
        raise InputError(f"[params] must be a table of friction parameters, got {given!r}")
    lab = sorted(set(given) & (set(LAB_NAMES) - {"V0"}))
    if lab:
        paper = sorted(set(given) & set(PAPER_ONLY))
        if paper:
            raise InputError(f"[params] mixes the paper's {paper} and the laboratory's {lab} names: give one set "
                             f"(A, m1, m2, D0, m0 or a, b, Dc, mu0; V0 and g with either)")
        base = {}
        if "preset" in cfg:
            preset = _params_from({"preset": cfg["preset"]})
            try:
                base = preset.to_lab() | {"g": preset.g}
            except InputError as exc:
                raise InputError(f"[params] gives the laboratory's {lab} over preset {cfg['preset']!r}, whose {exc}"
                                 ) from None
        values = {**base, **given}
        missing = [n for n in ("a", "b", "Dc") if n not in values]
        if missing:
            raise InputError(f"[params] in the laboratory's names needs a, b and Dc; missing {missing}")
        unknown = sorted(set(values) - {*LAB_NAMES, "g"})
        if unknown:
            raise InputError(f"[params] has unknown key(s) {unknown} (laboratory's fields: a, b, Dc, mu0, V0, g)")
        return FrictionParams.from_lab(**values)
    if "preset" in cfg:
        if cfg["preset"] not in presets:
            import difflib

            close = difflib.get_close_matches(str(cfg["preset"]), list(presets), n=1)
            raise InputError(f"preset must be one of {sorted(presets)}, got {cfg['preset']!r}"
                             + (f": did you mean {close[0]!r}?" if close else ""))
        return presets[cfg["preset"]].replace(**cfg.get("params", {}))
    if "params" in cfg:
        try:
            return FrictionParams(**cfg["params"])
        except TypeError as exc:
            raise InputError(f"[params]: {exc} (fields: A, m1, m2, D0, V0, m0, g)") from None
    raise InputError("scene needs preset = \"sample1\"|\"sample2\" and/or a [params] table")


def _read_toml(source: str | Path) -> dict[str, Any]:
    text = str(source)
    if "\n" not in text:
        path = Path(text)
        if not path.is_file():
            raise InputError(f"scene file {text!r} does not exist")
        try:
            text = path.read_text()
        except UnicodeDecodeError:
            raise InputError(f"scene file {text!r} is not a TOML text file") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"malformed TOML in scene: {exc}") from None


def hopf_config(source: str | Path) -> tuple[FrictionParams, np.ndarray, dict[str, Any]]:
    """(params, V axis, keyword arguments of sweep.locate_hopf) from a TOML file with preset and/or [params], a
    [V] axis table and optionally rtol, model, model_tol, state_law and bistable_band (true: measure the bistable
    band above an inverted line by simulation). The other keys of a scene (e.g. [K_over_M]) are allowed, so that a
    scene file serves both commands, and unused; any other key is refused, as in a scene."""
    cfg = _read_toml(source)
    _check_keys(cfg, HOPF_KEYS)
    if "V" not in cfg:
        raise InputError("hopf needs the [V] axis table of velocities [m s-1]")
    if "bistable_band" in cfg and not isinstance(cfg["bistable_band"], bool):
        raise InputError(f"bistable_band must be true or false, got {cfg['bistable_band']!r}")
    kwargs = {k: cfg[k] for k in ("rtol", "model", "model_tol", "state_law", "bistable_band") if k in cfg}
    return _params_from(cfg), _axis_from_toml("V", cfg["V"]), kwargs


def load_scene(source: str | Path) -> Scene:
    """Read a Scene from a TOML file path (or a TOML string if it contains a newline)."""
    return scene_from_mapping(_read_toml(source))


def default_scene() -> Scene:
    """The built-in scene of ``sweep run``: preset sample2, K/M 1e3..1e6 s^-2 (200), V 0.1..100 um/s (100)."""
    return Scene(protocol="stop", params=presets["sample2"], K_over_M=np.logspace(3, 6, 200),
                 V=np.logspace(-7, -4, 100), rtol=1e-6)


def __getattr__(name: str):
    """OBSERVABLES and DRIVEN_OBSERVABLES: the observables of the stop and driven protocols (Protocol.observables)."""
    protocol = {"OBSERVABLES": "stop", "DRIVEN_OBSERVABLES": "driven"}.get(name)
    if protocol is not None:
        return protocols.get(protocol).observables
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
