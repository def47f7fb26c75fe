"""The load history of a history scene: its ``segments`` option, checked, and the reduced durations per point.

A segment is a mapping with the load-point velocity as a multiple of the grid's V, ``V_ratio`` (>= 0; 0 is a hold),
and exactly one of ``duration`` [s] (time) or ``displacement`` [m] (load-point displacement, V_ratio > 0 only);
``hold = t`` is short for V_ratio = 0, duration = t. In a scene file::

    [[segments]]
    V_ratio = 1
    displacement = 2e-4
    [[segments]]
    hold = 30

Any of these numbers may instead name a grid axis (a string): ``hold = "t_hold"`` with a table ``[t_hold]`` (or
``axes={"t_hold": [...]}`` in Python) sweeps the hold time, each point with its own. The axis's unit follows the key
(:data:`AXIS_UNITS`: V_ratio 1, duration and hold s, displacement m).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from types import MappingProxyType
from typing import Any

import numpy as np

from ...errors import InputError

__all__ = ["AXIS_UNITS", "MAX_SEGMENTS", "check_segments", "reduced_durations", "segment_axes", "segment_ratios",
           "segment_values"]

MAX_SEGMENTS = 10_000
"""Most segments a history may have."""
KEYS = ("V_ratio", "duration", "displacement", "hold")
AXIS_UNITS = {"V_ratio": "1", "duration": "s", "hold": "s", "displacement": "m"}
"""The unit of an axis that a segment's key names."""
AXIS_WORDS = {"V_ratio": "load-point velocity over V", "duration": "duration of the segment",
              "hold": "hold time (load point at rest)", "displacement": "load-point displacement of the segment"}


def _is_name(value: Any) -> bool:
    return isinstance(value, str)


def _number(where: str, name: str, value: Any) -> float | str:
    """``value`` as a float, or as the axis name it is (checked by the scene against its axes)."""
    if _is_name(value):
        if not value.isidentifier():
            raise InputError(f"{where}: {name} = {value!r} names an axis: use letters, digits and _ (e.g. \"t_hold\")")
        return value
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise InputError(f"{where}: {name} must be a number, got {value!r}")
    value = float(value)
    if not math.isfinite(value):
        raise InputError(f"{where}: {name} must be finite, got {value!r}")
    return value


def check_segments(segments: Any) -> tuple[Mapping[str, float | str], ...]:
    """The segments, each as {"V_ratio": r, "duration": seconds} or {"V_ratio": r, "displacement": metres} (a hold
    as {"V_ratio": 0, "duration": t}), any number possibly an axis name; InputError (one line, naming
    the segment and the key) for anything else. An axis's values are checked by the scene (:func:`segment_axes`)."""
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
            t = _number(where, "hold", seg["hold"])
            if not _is_name(t) and t <= 0:
                raise InputError(f"{where}: hold must be > 0 s, got {t!r}")
            out.append(MappingProxyType({"V_ratio": 0.0, "duration": t}))
            continue
        if "V_ratio" not in seg:
            raise InputError(f"{where} needs V_ratio (load-point velocity / the grid's V, >= 0) or hold = seconds")
        r = _number(where, "V_ratio", seg["V_ratio"])
        if not _is_name(r) and r < 0:
            raise InputError(f"{where}: V_ratio must be >= 0 (load-point velocity / V; 0 is a hold), got {r!r}")
        if ("duration" in seg) == ("displacement" in seg):
            raise InputError(f"{where} needs exactly one of duration [s] or displacement [m] (load-point "
                             f"displacement), got {sorted(k for k in seg if k != 'V_ratio') or 'neither'}")
        if "duration" in seg:
            t = _number(where, "duration", seg["duration"])
            if not _is_name(t) and t <= 0:
                raise InputError(f"{where}: duration must be > 0 s, got {t!r}")
            out.append(MappingProxyType({"V_ratio": r, "duration": t}))
        else:
            d = _number(where, "displacement", seg["displacement"])
            if not _is_name(d) and d <= 0:
                raise InputError(f"{where}: displacement must be > 0 m (load-point displacement), got {d!r}")
            if r == 0:
                raise InputError(f"{where}: a load-point displacement needs V_ratio > 0 (a hold takes a duration)")
            out.append(MappingProxyType({"V_ratio": r, "displacement": d}))
    if not _is_name(out[0]["V_ratio"]) and out[0]["V_ratio"] <= 0:
        raise InputError("segments[0]: V_ratio must be > 0 (the history starts from steady sliding at it), got "
                         f"{out[0]['V_ratio']!r}")
    return tuple(out)


def segment_axes(segments: Any) -> dict[str, tuple[str, str, bool]]:
    """The axes that ``segments`` name (checked or as given; entries not understood name none): axis -> (unit, where,
    positive). ``positive``: values must be > 0 (durations, displacements, a first segment's or a displacement
    segment's V_ratio), else >= 0 (another V_ratio: 0 is a hold). InputError where one name stands for two units."""
    if isinstance(segments, (str, Mapping)) or not isinstance(segments, Sequence):
        return {}
    out: dict[str, tuple[str, str, bool]] = {}
    for i, seg in enumerate(segments):
        if not isinstance(seg, Mapping):
            continue
        for key in KEYS:
            name = seg.get(key)
            if not _is_name(name):
                continue
            positive = key != "V_ratio" or i == 0 or "displacement" in seg
            if key == "duration" and seg.get("V_ratio", 0) == 0:  # a checked hold is V_ratio = 0, duration = t
                key = "hold"
            unit, where = AXIS_UNITS[key], f"segments[{i}].{key}"
            if name in out:
                if out[name][0] != unit:
                    raise InputError(f"{where} names axis {name!r}, which {out[name][1]} names too with unit "
                                     f"{out[name][0]!r}: an axis has one unit (V_ratio 1, duration/hold s, "
                                     f"displacement m)")
                positive = positive or out[name][2]
                where = out[name][1]
            out[name] = (unit, where, positive)
    return out


def segment_values(segments: Sequence[Mapping[str, float | str]], values: Callable[[str], np.ndarray],
                   n_points: int) -> dict[str, np.ndarray]:
    """Per point and segment (points, segments): "V_ratio", "duration" [s] and "displacement" [m] (NaN where the
    segment has none); ``values(name)``: an axis's value at every point (flat, the grid's C order)."""
    out = {}
    for key in ("V_ratio", "duration", "displacement"):
        cols = []
        for seg in segments:
            x = seg.get(key, np.nan)
            cols.append(values(x) if _is_name(x) else np.full(n_points, float(x)))
        out[key] = np.stack(cols, axis=1).astype(float) if cols else np.empty((n_points, 0))
    return out


def segment_ratios(segments: Sequence[Mapping[str, float]]) -> np.ndarray:
    """r_j = the load-point velocity of segment j over the grid's V (segments without axes)."""
    return np.array([seg["V_ratio"] for seg in segments], float)


def reduced_durations(table: Mapping[str, np.ndarray], V: np.ndarray, D0: np.ndarray) -> np.ndarray:
    """T[i, j] = the reduced duration V t_j/D0 of segment j at point i (``table``: :func:`segment_values`; V, D0
    flat per point): t_j V/D0 for a duration t_j, d_j/(r_j D0) for a load-point displacement d_j."""
    V, D0 = np.asarray(V, float)[:, None], np.asarray(D0, float)[:, None]
    dur, disp, r = table["duration"], table["displacement"], table["V_ratio"]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(np.isnan(dur), disp / (np.where(r > 0, r, 1.0) * D0) + 0 * V, dur * V / D0)
