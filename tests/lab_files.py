"""Laboratory record files as real experiments write them, from the independent scipy reference
(tests/reference_records.py): the truth (times, friction, load-point displacement, the load history) and a file of
it in the layout of one laboratory program.

Histories: velocity steps up and down (1 -> 10 -> 100 -> 10 um/s) and slide-hold-slide (holds of 3, 30 and 300 s at
1 um/s). Sampling as a data logger's: 100 Hz for a while after each change, 10 Hz in a slide, 1 Hz in a hold, each
time jittered by up to a fifth of its spacing. Friction noise, a linear drift in time, displacement noise and the
displacement written to a resolution (quantisation). Layouts (:data:`LAYOUTS`): xlook/biax/PSU-style files with a
units row, csv with decimal commas (semicolons, or commas with every field quoted), a block of ``key = value`` lines
above the header, a spreadsheet export with a byte-order mark, a second header block and blank lines inside the data,
a trailing comment line, the friction column named with a unicode mu, shear stress with the normal stress given only
in the header or as its own column, a servo's log of the commanded velocity in UTF-16 with the time in ms.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from reference_records import record_reference

TRUTH = {"a": 0.01, "b": 0.015, "Dc": 1e-5, "mu0": 0.6}
K = 2e3  # 1/m: k_c = (b - a)/Dc = 500 1/m, stable
HISTORIES = {
    "steps": ([1e-6, 1e-5, 1e-4, 1e-5], [30.0, 15.0, 2.0, 15.0]),
    "shs": ([1e-6, 0.0, 1e-6, 0.0, 1e-6, 0.0, 1e-6], [30.0, 3.0, 30.0, 30.0, 30.0, 300.0, 40.0]),
}
"""Load-point velocities [m/s] and durations [s] of each history."""


@dataclass
class Lab:
    """The truth of one generated record: sample times t [s], friction mu [1] as written (noise and drift
    included), mu_true [1] (the reference, no noise nor drift), load-point displacement [m] as written and its truth,
    the history (velocities [m/s], durations [s]), and the steps ((start [s], velocity [m/s]), ...)."""

    t: np.ndarray
    mu: np.ndarray
    mu_true: np.ndarray
    disp: np.ndarray
    disp_true: np.ndarray
    velocities: list
    durations: list
    noise: float
    drift: float

    @property
    def steps(self) -> list[tuple[float, float]]:
        starts = np.concatenate(([0.0], np.cumsum(self.durations)[:-1]))
        return [(float(s), float(v)) for s, v in zip(starts, self.velocities)]

    def spacing_at(self, time: float) -> float:
        """The sample spacing [s] around ``time``: the largest of the two intervals beside it."""
        i = int(np.clip(np.searchsorted(self.t, time), 1, self.t.size - 1))
        return float(max(self.t[i] - self.t[i - 1], self.t[min(i + 1, self.t.size - 1)] - self.t[i]))


def sample_times(velocities, durations, rng, fast=100.0, fast_for=2.0, slide=10.0, hold=1.0, jitter=0.2):
    """A data logger's sample times [s]: ``fast`` Hz for ``fast_for`` s after each change (the first included),
    then ``slide`` Hz while sliding and ``hold`` Hz in a hold, each time but the first jittered by up to ``jitter``
    of its spacing."""
    t, start = [], 0.0
    for v, d in zip(velocities, durations):
        rate = slide if v > 0 else hold
        quick = np.arange(0.0, min(fast_for, d), 1.0 / fast)
        rest = np.arange(quick[-1] + 1.0 / fast if quick.size else 0.0, d, 1.0 / rate)
        seg = np.concatenate((quick, rest))
        dt = np.diff(np.append(seg, d))
        t.append(start + seg + jitter * dt * rng.uniform(size=seg.size) * (seg > 0))
        start += d
    t = np.concatenate(t + [[start]])
    return np.round(t, 4)


def make(history: str = "steps", seed: int = 0, noise: float = 3e-4, drift: float = 2e-5,
         disp_noise: float = 5e-8, quantum: float = 1e-8, **times) -> Lab:
    """One record of ``history`` (:data:`HISTORIES`) on the reference at :data:`TRUTH` and :data:`K`: friction with
    Gaussian ``noise`` [1] and a linear ``drift`` [1/s], the displacement [m] with Gaussian ``disp_noise`` written to
    ``quantum`` [m]; ``times`` go to :func:`sample_times`."""
    rng = np.random.default_rng(seed)
    velocities, durations = HISTORIES[history]
    t = sample_times(velocities, durations, rng, **times)
    mu_true, disp_true = record_reference(TRUTH["a"], TRUTH["b"], TRUTH["Dc"], TRUTH["mu0"], K, velocities,
                                          durations, t)
    mu = mu_true + noise * rng.standard_normal(t.size) + drift * t
    disp = disp_true + disp_noise * rng.standard_normal(t.size)
    if quantum:
        disp = np.round(disp / quantum) * quantum
    return Lab(t, mu, mu_true, disp, disp_true, list(velocities), list(durations), noise, drift)


# --- layouts --------------------------------------------------------------------------------------------------------

def _write(path: Path, lines: list[str], newline: str = "\n", encoding: str = "utf-8") -> Path:
    path.write_bytes((newline.join(lines) + newline).encode(encoding))
    return path


def xlook(lab: Lab, path: Path) -> Path:
    """xlook/biax: tab-separated, a title, the names, a units row (a row counter's '.', mic, sec), CR LF."""
    sigma = 10.0 + 0.02 * np.sin(lab.t / 9)
    rows = [f"{i}\t{d * 1e6:.3f}\t{m * s:.5f}\t{s:.5f}\t{a:.4f}\t{m:.6f}"
            for i, (a, d, m, s) in enumerate(zip(lab.t, lab.disp, lab.mu, sigma))]
    head = ["p5021 biax granite gouge", "Rec_Num\tLP_Disp\tShr_stress\tNor_stress\tTime\tmu",
            ".\tmic\tMPa\tMPa\tsec\t."]
    return _write(path, head + rows, newline="\r\n")


def psu_tab(lab: Lab, path: Path) -> Path:
    """PSU-style: tab-separated, names then a units row with unicode µm and a 'μ' friction column."""
    rows = [f"{a:.4f}\t{d * 1e6:.3f}\t{m:.6f}" for a, d, m in zip(lab.t, lab.disp, lab.mu)]
    return _write(path, ["Time\tLP Disp\tμ", "s\tµm\t-"] + rows)


def mu_ascii(lab: Lab, path: Path) -> Path:
    """Blank-separated, the displacement in 'μm' (Greek mu) and friction named 'mu'."""
    rows = [f"{a:.4f} {d * 1e6:.3f} {m:.6f}" for a, d, m in zip(lab.t, lab.disp, lab.mu)]
    return _write(path, ["t [s]  disp [μm]  mu [-]"] + rows)


def decimal_commas(lab: Lab, path: Path) -> Path:
    """A European csv: semicolons, decimal commas, friction named 'µ'."""
    rows = [f"{a:.4f};{d * 1e6:.3f};{m:.6f}".replace(".", ",") for a, d, m in zip(lab.t, lab.disp, lab.mu)]
    return _write(path, ["Time (s);LP Displacement (µm);µ"] + rows, encoding="latin-1")


def quoted_decimal_commas(lab: Lab, path: Path) -> Path:
    """A spreadsheet's comma-separated export in a decimal-comma locale: every field quoted, the quotes holding the
    decimal comma ("0,600123")."""
    rows = [",".join(f'"{x}"' for x in (f"{a:.4f}", f"{d * 1e6:.3f}", f"{m:.6f}")).replace(".", ",")
            for a, d, m in zip(lab.t, lab.disp, lab.mu)]
    return _write(path, ['"Time (s)","LP Disp (um)","Friction"'] + rows)


def key_value_block(lab: Lab, path: Path) -> Path:
    """A block of ``key = value`` lines (no comment mark) above the header, the stiffness among them; shear stress
    in MPa with the normal stress given only there."""
    rows = [f"{a:.4f},{d * 1e6:.3f},{m * 12.5:.6f}" for a, d, m in zip(lab.t, lab.disp, lab.mu)]
    head = ["Experiment = p5112", "Operator = JD", "Normal stress = 12.5 MPa", f"k = {K * 1e-6:g} 1/um",
            "Sampling = variable", "", "Time (s),LP Disp (um),Shear Stress (MPa)"]
    return _write(path, head + rows)


def normal_column(lab: Lab, path: Path) -> Path:
    """Shear Stress (MPa) and Normal Stress (MPa) columns (constant normal stress)."""
    rows = [f"{a:.4f},{d * 1e6:.3f},{m * 12.5:.6f},12.500" for a, d, m in zip(lab.t, lab.disp, lab.mu)]
    return _write(path, ["Time (s),LP Disp (um),Shear Stress (MPa),Normal Stress (MPa)"] + rows)


def spreadsheet_bom(lab: Lab, path: Path) -> Path:
    """A spreadsheet export: UTF-8 byte-order mark, quoted names, comma-separated, CR LF, an empty trailing cell."""
    rows = [f"{a:.5f},{d * 1e3:.8f},{m:.6f}," for a, d, m in zip(lab.t, lab.disp, lab.mu)]
    return _write(path, ['"Time (s)","Load Point Displacement (mm)","Friction Coefficient",'] + rows,
                  newline="\r\n", encoding="utf-8-sig")


def second_header(lab: Lab, path: Path) -> Path:
    """Blank lines inside the data and a second header block where the logger was restarted (the same names and
    units again), then a trailing comment line."""
    rows = [f"{a:.4f}\t{d * 1e6:.3f}\t{m:.6f}" for a, d, m in zip(lab.t, lab.disp, lab.mu)]
    head = ["Time (s)\tLP_Disp (um)\tmu"]
    half = len(rows) // 2
    return _write(path, head + rows[:half // 2] + [""] + rows[half // 2:half] + ["", "Logger restarted"] + head +
                  rows[half:] + ["End of data"])


def trailing_comment(lab: Lab, path: Path) -> Path:
    """A csv with a ``# end of record`` comment and an ``END`` line after the data."""
    rows = [f"{a:.4f},{d * 1e6:.3f},{m:.6f}" for a, d, m in zip(lab.t, lab.disp, lab.mu)]
    return _write(path, ["time [s],lp_disp [um],friction [-]"] + rows + ["# end of record", "END"])


def velocity_ms(lab: Lab, path: Path) -> Path:
    """A servo's log: time in ms, the commanded load-point velocity in um/s (no displacement), friction as 'COF',
    the names as a comment line, UTF-16 with its byte-order mark (a spreadsheet's "Unicode text")."""
    v = np.array(lab.velocities)[np.searchsorted(np.cumsum(lab.durations), lab.t, side="right").clip(0, len(
        lab.velocities) - 1)]
    rows = [f"{a * 1e3:.1f}\t{u * 1e6:.2f}\t{m:.6f}" for a, u, m in zip(lab.t, v, lab.mu)]
    return _write(path, ["# servo log v2", "# Time (ms)\tV_LP (um/s)\tCOF"] + rows, encoding="utf-16")


LAYOUTS = {f.__name__: f for f in (xlook, psu_tab, mu_ascii, decimal_commas, quoted_decimal_commas, key_value_block,
                                   normal_column, spreadsheet_bom, second_header, trailing_comment, velocity_ms)}
"""Each layout's writer: (Lab, path) -> the path written."""
