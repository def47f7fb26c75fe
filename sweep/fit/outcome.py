"""What a fit found (sweep.fit.core.run_fit), before it becomes a Dataset (sweep.fit.result)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .globalstage import GlobalResult
from .local import LocalFit
from .problem import Problem
from .profiles import Profile
from .space import ParamSpace
from .uncertainty import Interval
from .verdict import Verdict

__all__ = ["FitOutcome"]


@dataclass
class FitOutcome:
    """Everything a fit found, per problem (lists in the order of ``problems``); sweep.fit.result turns it into the
    Dataset."""

    problems: list[Problem]
    space: ParamSpace
    global_results: list[GlobalResult] | None
    """Per problem, the global stage's best point and landscape; None where none ran (search "local")."""
    fits: list[LocalFit]
    s2: list[float]
    covariances: list[np.ndarray]
    crit: list[float]
    profiles: list[list[Profile]] | None
    intervals: list[list[Interval]] | None
    labels: list[list[str]] | None
    rounds: dict[str, int]
    seconds: dict[str, float]
    settings: dict[str, object]
    engine_error: np.ndarray
    """Per problem, the engine's largest error estimate at the best fit in units of the noise (sweep.fit.core)."""
    verdicts: list[Verdict] | None = None
    """Per problem, whether its fit can be trusted (sweep.fit.verdict); None: every fit taken as ok."""
