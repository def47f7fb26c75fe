"""The load history of a history scene: its ``segments`` option, checked, and the reduced durations per point.

A segment is a mapping with the load-point velocity as a multiple of the grid's V, ``V_ratio`` (>= 0; 0 is a hold),
and exactly one of ``duration`` [s] (time) or ``displacement`` [m] (load-point displacement, V_ratio > 0 only);
``hold = t`` is short for V_ratio = 0, duration = t. In a scene file::

    [[segments]]
    V_ratio = 1
    displacement = 2e-4
    [[segments]]
    hold = 30
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from types import MappingProxyType
from typing import Any

import numpy as np

from ...errors import InputError

__all__ = ["MAX_SEGMENTS", "check_segments", "reduced_durations", "segment_ratios"]

MAX_SEGMENTS = 10_000
"""Most segments a history may have."""
KEYS = ("V_ratio", "duration", "displacement", "hold")


def _number(where: str, name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(f"{where}: {name} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise InputError(f"{where}: {name} must be finite, got {value!r}")
    return value


def check_segments(segments: Any) -> tuple[Mapping[str, float], ...]:
    """The segments, each as {"V_ratio": r, "duration": seconds} or {"V_ratio": r, "displacement": metres}; InputError
    (one line, naming the segment and the key) for anything else."""
    if isinstance(segments, (str, Mapping)) or not isinstance(segments, Sequence):
        raise InputError(f"segments must be a list of tables {{V_ratio, duration | displacement}} or {{hold}}, got "
                         f"{type(segments).__name__}")
    if not 1 <= len(segments) <= MAX_SEGMENTS:
        raise InputError(f"segments must hold 1 to {MAX_SEGMENTS} segments, got {len(segments)}")
    out = []
    for i, seg in enumerate(segments):
        where = f"segments[{i}]"
        if not isinstance(seg, Mapping):
            raise InputError(f"{where} must be a table {{V_ratio, duration | displacement}} or {{hold}}, got {seg!r}")
        unknown = sorted(set(seg) - set(KEYS))
        if unknown:
            raise InputError(f"{where} has unknown key(s) {unknown}; allowed: {list(KEYS)}")
        if "hold" in seg:
            if "duration" in seg or "displacement" in seg or seg.get("V_ratio", 0) != 0:
                raise InputError(f"{where}: hold = t stands alone (it is V_ratio = 0, duration = t), got {dict(seg)}")
            seg = {"V_ratio": 0.0, "duration": seg["hold"]}
        if "V_ratio" not in seg:
            raise InputError(f"{where} needs V_ratio (load-point velocity / the grid's V, >= 0) or hold = seconds")
        r = _number(where, "V_ratio", seg["V_ratio"])
        if r < 0:
            raise InputError(f"{where}: V_ratio must be >= 0 (load-point velocity / V; 0 is a hold), got {r!r}")
        if ("duration" in seg) == ("displacement" in seg):
            raise InputError(f"{where} needs exactly one of duration [s] or displacement [m] (load-point "
                             f"displacement), got {sorted(k for k in seg if k != 'V_ratio') or 'neither'}")
        if "duration" in seg:
            t = _number(where, "duration", seg["duration"])
            if t <= 0:
                raise InputError(f"{where}: duration must be > 0 s, got {t!r}")
            out.append(MappingProxyType({"V_ratio": r, "duration": t}))
        else:
            d = _number(where, "displacement", seg["displacement"])
            if d <= 0:
                raise InputError(f"{where}: displacement must be > 0 m (load-point displacement), got {d!r}")
            if r == 0:
                raise InputError(f"{where}: a load-point displacement needs V_ratio > 0 (a hold takes a duration)")
            out.append(MappingProxyType({"V_ratio": r, "displacement": d}))
    if out[0]["V_ratio"] <= 0:
        raise InputError("segments[0]: V_ratio must be > 0 (the history starts from steady sliding at it), got "
                         f"{out[0]['V_ratio']!r}")
    return tuple(out)


def segment_ratios(segments: Sequence[Mapping[str, float]]) -> np.ndarray:
    """r_j = the load-point velocity of segment j over the grid's V."""
    return np.array([seg["V_ratio"] for seg in segments], float)


def reduced_durations(segments: Sequence[Mapping[str, float]], V: np.ndarray, D0: np.ndarray) -> np.ndarray:
    """T[i, j] = the reduced duration V t_j/D0 of segment j at point i (V, D0 flat per point): t_j V/D0 for a
    duration t_j, d_j/(r_j D0) for a load-point displacement d_j."""
    V, D0 = np.asarray(V, float)[:, None], np.asarray(D0, float)[:, None]
    dur = np.array([seg.get("duration", np.nan) for seg in segments])[None, :]
    disp = np.array([seg.get("displacement", np.nan) for seg in segments])[None, :]
    r = segment_ratios(segments)[None, :]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.isnan(dur), disp / (np.where(r > 0, r, 1.0) * D0) + 0 * V, dur * V / D0)
