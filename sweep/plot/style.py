"""The look shared by every picture of sweep: sizes, units on the axes, the caption naming the parameters, and the
marks every (K/M, V) picture carries (the no-Hopf-line band, failed points).

Pictures are written at a fixed pixel size (figure size x DPI, no tight bounding box), so that a test can check
what it gets. Colour maps are perceptually uniform (viridis, cividis, magma).
"""

from __future__ import annotations

import ast
import functools
import math
import os
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")  # files only; no display needed
import matplotlib.pyplot as plt  # noqa: E402
import matplotlib.ticker as mticker  # noqa: E402
import numpy as np  # noqa: E402
import xarray as xr  # noqa: E402

from ..scene.presets import presets  # noqa: E402

__all__ = ["DPI", "SIZES", "KM_LABEL", "V_LABEL", "TAU_LABEL", "CHI_LABEL", "new_figure", "figure_legend", "save",
           "label",
           "caption", "file_params", "preset_name", "um_per_s", "km_per_chi", "no_hopf_line_band",
           "mark_no_hopf_line", "mark_failed", "flag_names", "thinned"]

DPI = 100
SIZES = {"single": (6.4, 4.8), "map": (7.6, 5.6), "pair": (12.8, 5.2)}
"""Figure sizes in inches: 640 x 480, 760 x 560 and 1280 x 520 pixels at :data:`DPI`."""
KM_LABEL = "K/M [s$^{-2}$]"
V_LABEL = "V [µm/s]"
TAU_LABEL = "reduced time τ = V t/D$_0$ [1]"
CHI_LABEL = "reduced stiffness χ = K D$_0$/(M g) [1]"
NO_LINE_COLOUR = "#dbe9f6"
"""Pale blue of the V range without a Hopf line on curves (stick-slip is hatched: the two never overlap)."""
SHORT_LABELS = {
    "xi_inf": "relaxed slip ξ$_∞$ = Δx$_∞$/D$_0$ [1]",
    "stress_relaxation": "stress relaxation K Δx$_∞$/(M g) = χ ξ$_∞$ [1]",
    "xi": "slip since the stop ξ = x/D$_0$ [1]",
    "psi": "contact age ψ = V φ/D$_0$ [1]",
    "amplitude": "stick-slip amplitude (half peak-to-peak of τ - ξ) [1]",
}


def new_figure(size: str = "single", ncols: int = 1):
    """(figure, axes) of one of :data:`SIZES`; ``axes`` is an array when ``ncols`` > 1."""
    return plt.subplots(1, ncols, figsize=SIZES[size], dpi=DPI, layout="constrained")


def figure_legend(fig, axes) -> None:
    """One legend for the whole figure, below its panels: the entries of every panel, each label once (side by
    side maps share most of them; a legend inside a map would hide data)."""
    entries: dict[str, object] = {}
    for ax in np.atleast_1d(axes):
        for handle, text in zip(*ax.get_legend_handles_labels()):
            entries.setdefault(text, handle)
    if entries:  # three columns under two panels, two under one (three would be wider than the figure)
        ncol = min(len(entries), 3 if np.atleast_1d(axes).size > 1 else 2)
        fig.legend(list(entries.values()), list(entries), loc="outside lower center", ncol=ncol, fontsize=7,
                   frameon=False)


LOG_MINOR_SUBS = (2.0, 5.0)
"""Minor ticks of every log axis, per decade: at 2 and 5 (not matplotlib's 2..9). Each tick is a few artists that the
constrained layout measures and the drawing measures again: the default landscape's four log axes and colorbars had
~250 of them, ~0.3 s of its ~0.9 s picture."""


_SUPERSCRIPT = str.maketrans("-0123456789", "\u207b\u2070\u00b9\u00b2\u00b3\u2074\u2075\u2076\u2077\u2078\u2079")


class DecadeFormatter(mticker.LogFormatterSciNotation):
    """Labels of log axes: a power of ten as plain text with superscript digits ("10\u207b\u00b3"), which the layout
    measures and the drawing renders without mathtext's parser and layout (~0.1 s of a landscape picture's tick
    labels); any other label as matplotlib's own formatter writes it."""

    def __call__(self, x, pos=None):
        exponent = math.log10(abs(x)) if x else math.nan
        if x > 0 and exponent == round(exponent):
            return "10" + str(int(round(exponent))).translate(_SUPERSCRIPT)
        return super().__call__(x, pos)


def save(fig, path: str | os.PathLike) -> Path:
    """Write ``fig`` to ``path`` (PNG, parents created) at its own pixel size and close it."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    for axis in (a for ax in fig.axes for a in (ax.xaxis, ax.yaxis)):
        if axis.get_scale() == "log":
            axis.set_minor_locator(mticker.LogLocator(subs=LOG_MINOR_SUBS))
            if type(axis.get_major_formatter()) is mticker.LogFormatterSciNotation:  # matplotlib's default only
                axis.set_major_formatter(DecadeFormatter())
    fig.savefig(path, dpi=DPI)
    plt.close(fig)
    return path


def label(ds: xr.Dataset, name: str) -> str:
    """Axis label of a variable, with its units in brackets."""
    if name in SHORT_LABELS:
        return SHORT_LABELS[name]
    return f"{ds[name].attrs.get('long_name', name)} [{ds[name].attrs.get('units', '?')}]"


@functools.lru_cache(maxsize=4)
def scene_table(text: str) -> dict:
    """The scene TOML of a file, parsed once (a 1000 x 1000 grid's is 43 kB, ~30 ms to parse, and a picture reads it
    for every caption and Hopf line); callers must not change the dict."""
    return tomllib.loads(text)


def file_params(ds: xr.Dataset) -> dict[str, float]:
    """The friction parameters a file was computed with: the [params] table of its scene (sweep and stop files),
    or the ``params`` attribute of a Hopf file (sweep.locate_hopf); empty if neither is there."""
    if "scene" in ds.attrs:
        return dict(scene_table(ds.attrs["scene"]).get("params", {}))
    if "params" in ds.attrs:
        return dict(ast.literal_eval(str(ds.attrs["params"])))
    return {}


def preset_name(params: dict[str, float]) -> str | None:
    """The preset whose parameters these are (all fields equal to 1e-12 relative), else None."""
    for name, preset in presets.items():
        if params and all(k in params and math.isclose(params[k], v, rel_tol=1e-12)
                          for k, v in preset.as_dict().items()):
            return name
    return None


LAB_SCENE_KEYS = ("a", "b", "Dc", "k")
"""Axis tables that mark a scene as given in the laboratory's parameters (its caption then names them)."""


def _speaks_lab(params: dict[str, float], scene: dict) -> bool:
    """Whether a caption names the laboratory's a, b, Dc, mu0: the law is theirs (m2 = 0) and the scene is a load
    history or has axes in their names (files store the paper's parameters, whichever were given)."""
    return (params.get("m2", 0.0) == 0.0 and {"A", "m1", "D0", "m0"} <= set(params)
            and (scene.get("protocol") == "history" or any(n in scene for n in LAB_SCENE_KEYS)))


def caption(ds: xr.Dataset, what: str) -> str:
    """``what`` followed by the parameters of the file: preset, A, m1, m2, D0, V0 (a, b, Dc, mu0, V0 for a load
    history or a scene with laboratory axes, docs/physics.md 7b), rtol and model."""
    params = file_params(ds)
    scene = scene_table(ds.attrs["scene"]) if "scene" in ds.attrs else {}
    name = preset_name(params)
    v0 = f"V0={params.get('V0', 1e-6) * 1e6:g} µm/s"
    if _speaks_lab(params, scene):
        shown = (f"a={params['A']:g}, b={params['A'] + params['m1']:g}, Dc={params['D0'] * 1e6:g} µm, "
                 f"mu0={params['m0']:g}, {v0}")
    else:
        shown = ", ".join(f"{k}={params[k]:g}" for k in ("A", "m1", "m2") if k in params)
        if "D0" in params:
            shown += f", D0={params['D0'] * 1e6:g} µm, {v0}"
    model = scene.get("model") or str(ds.attrs.get("model", "")).split(" ")[0]
    rtol = scene.get("rtol", ds.attrs.get("rtol"))
    numerics = ", ".join(x for x in (f"rtol {rtol:g}" if rtol is not None else "",
                                     f"model {model}" if model else "") if x)
    return f"{what}\n{'preset ' + name + ': ' if name else ''}{shown}; {numerics}"


def um_per_s(ds: xr.Dataset) -> np.ndarray:
    """The V axis of a file in µm/s (files store m s-1)."""
    return ds["V"].values * 1e6


def km_per_chi(ds: xr.Dataset) -> float:
    """K/M per unit chi, g/D0 [s-2] (the file's own conversion)."""
    return float(ds["K_over_M"].values[0] / ds["chi"].values[0])


def no_hopf_line_band(v: np.ndarray, mu1: np.ndarray) -> list[tuple[float, float]]:
    """The V intervals [same units as ``v``] where mu1(V) <= 0 (no Hopf line: steady sliding is stable at every
    stiffness), limits interpolated linearly in ln V (mu1 = m1 - 2 m2 ln(V/V0) is linear there, so exactly)."""
    v, mu1 = np.asarray(v, float), np.asarray(mu1, float)
    out = np.append(mu1 <= 0, False)
    bands, start = [], None
    for i in range(v.size + 1):
        if out[i] and start is None:
            start = v[0] if i == 0 else _crossing(v[i - 1], v[i], mu1[i - 1], mu1[i])
        elif not out[i] and start is not None:
            bands.append((start, v[-1] if i == v.size else _crossing(v[i - 1], v[i], mu1[i - 1], mu1[i])))
            start = None
    return bands


def _crossing(v0: float, v1: float, m0: float, m1: float) -> float:
    """V where mu1 = 0 between two samples (mu1 is linear in ln V)."""
    return float(np.exp(np.log(v0) + (np.log(v1) - np.log(v0)) * m0 / (m0 - m1)))


def mark_no_hopf_line(ax, v: np.ndarray, mu1: np.ndarray, axis: str = "y", over_data: bool = True) -> None:
    """Mark the V range where mu1(V) <= 0 on ``ax`` (V along ``axis``): a band edged by dash-dotted lines, labelled
    "no Hopf line". Over a map (``over_data``) the band is only a light white tint so the data stay legible, and
    the legend shows its edge (black on a white halo, visible on any colour)."""
    span, line = (ax.axhspan, ax.axhline) if axis == "y" else (ax.axvspan, ax.axvline)
    text = "no Hopf line: μ$_1$(V) ≤ 0, stable at every K/M"
    bands = no_hopf_line_band(v, mu1)
    for i, (lo, hi) in enumerate(bands):
        if over_data:
            span(lo, hi, facecolor="white", alpha=0.25, lw=0, zorder=1.5)
        else:
            span(lo, hi, facecolor=NO_LINE_COLOUR, lw=0, zorder=0, label=None if i else text)
    edges = [e for band in bands for e in band if e not in (v[0], v[-1])]
    for i, edge in enumerate(edges):
        if over_data:
            line(edge, color="white", lw=2.4, zorder=2.5)
        line(edge, color="k" if over_data else "0.4", ls="-.", lw=1.2, zorder=2.5,
             label="no Hopf line beyond (μ$_1$(V) ≤ 0, tinted): stable at every K/M" if over_data and not i else None)


def thinned(n: int, most: int = 25) -> np.ndarray:
    """Indices of at most ``most`` of ``n`` points, evenly spread: markers that stay apart on a dense axis instead of
    merging into a band that hides the line under them."""
    return np.unique(np.linspace(0, n - 1, min(n, most)).round().astype(int))


def flag_names(ds: xr.Dataset, name: str) -> list[str]:
    """Meanings of a flag variable, indexed by code."""
    return ds[name].attrs["flag_meanings"].split()


def mark_failed(ax, ds: xr.Dataset, x: np.ndarray, y: np.ndarray) -> None:
    """Cross the points whose status is not ok; the legend says which statuses and how many.

    ``x``, ``y``: the points' coordinates on ``ax``, broadcast to the shape of ``ds["status"]``; a point whose ``y``
    is not finite is crossed at the foot of the axes."""
    status = ds["status"].values
    failed = status != 0
    if not failed.any():
        return
    names = flag_names(ds, "status")
    codes, counts = np.unique(status[failed], return_counts=True)
    text = ", ".join(f"{names[c]} {n}" for c, n in zip(codes, counts))
    x, y = np.broadcast_to(x, status.shape)[failed], np.broadcast_to(y, status.shape)[failed]
    style = dict(marker="x", ls="none", color="#d62728", ms=5, mew=1.2, zorder=4)
    ax.plot(x[np.isfinite(y)], y[np.isfinite(y)], label=f"failed (status): {text}", **style)
    # a failed point without a value (e.g. no finite limit) is crossed at the foot of the axes
    ax.plot(x[~np.isfinite(y)], np.full((~np.isfinite(y)).sum(), 0.03), transform=ax.get_xaxis_transform(), **style)
