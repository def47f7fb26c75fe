"""What reading and segmenting a large laboratory record costs (issue 34: records of up to 1e5 samples).

    python benchmarks/records_read.py [--quick] [--out benchmarks/results/records_read.json]

A record of N rows (100,000; --quick 20,000) at 1 kHz: a 1 -> 10 um/s velocity step, a hold, a reslide at 10 um/s
(changes at 30 %, 60 % and 80 % of the record), load-point displacement with 0.1 um of noise written to 1 nm,
friction with 1e-3 of noise, written in three styles laboratory software writes:

* ``xlook_tabs``: tab-separated, a row counter, shear and normal stress, a units row (``.  sec  mic  MPa  MPa  .``);
* ``csv_decimal_commas``: semicolons, decimal commas, shear and normal load in kN (mu their ratio);
* ``quoted_time_stamps``: every field quoted, the time as date-and-clock stamps, a status word column (numpy's
  reader refuses it: read column by column).

For each file: ``sweep.fit.records.read_record`` (the file to SI arrays) and ``sweep.fit.segments.record_steps``
(the load history found from the displacement), each timed REPEATS times, the best wall time kept, and the steps
checked against the known ones (starts within 2 sample spacings, velocities within 1 %). The load average is
recorded around the runs (this machine is shared).

Target (the brief of issue 34's record work): 1e5 rows read and segmented "quickly"; the JSON says how quickly.
"""

from __future__ import annotations

import argparse
import datetime as _dt
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import _common as common  # noqa: E402

from sweep.fit.records import read_record  # noqa: E402
from sweep.fit.segments import record_steps  # noqa: E402

DEFAULT_OUT = HERE / "results" / "records_read.json"
REPEATS, REPEATS_QUICK = 3, 2
RATE = 1000.0  # Hz
VELOCITIES = np.array([1e-6, 1e-5, 0.0, 1e-5])  # m/s
CHANGES = np.array([0.3, 0.6, 0.8])  # fractions of the record


def record(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(t [s], load-point displacement [m], mu, starts [s]) of the module docstring's record of ``n`` rows."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / RATE
    starts = np.concatenate(([0.0], CHANGES * n / RATE))
    v = VELOCITIES[np.searchsorted(starts, t, side="right") - 1]
    x = np.concatenate(([0.0], np.cumsum(v[:-1] / RATE))) + 1e-7 * rng.standard_normal(n)
    mu = 0.6 + 1e-3 * rng.standard_normal(n)
    return t, x, mu, starts


def write_files(folder: Path, n: int) -> dict[str, Path]:
    t, x, mu, _ = record(n)
    sigma = 10.0  # MPa
    files = {"xlook_tabs": folder / "xlook.txt", "csv_decimal_commas": folder / "daq.csv",
             "quoted_time_stamps": folder / "export.csv"}
    rows = "\n".join(f"{i}\t{a:.3f}\t{d * 1e6:.3f}\t{m * sigma:.5f}\t{sigma:.3f}\t{m:.5f}"
                     for i, (a, d, m) in enumerate(zip(t, x, mu)))
    files["xlook_tabs"].write_text("Row\tTime\tLP_Disp\tShr_stress\tNor_stress\tmu\n.\tsec\tmic\tMPa\tMPa\t.\n" + rows)
    rows = "\n".join(f"{a:.3f};{d * 1e3:.6f};{m * 50:.5f};50.000".replace(".", ",") for a, d, m in zip(t, x, mu))
    files["csv_decimal_commas"].write_text("Time [s];LP_Disp [mm];Shear load [kN];Normal load [kN]\n" + rows)
    start = np.datetime64("2024-03-05T14:02:07", "us")
    stamps = (start + (t * 1e6).round().astype("timedelta64[us]")).astype(str)
    rows = "\n".join(f'"{s}","RUN","{d * 1e6:.3f}","{m:.5f}"' for s, d, m in zip(stamps, x, mu))
    files["quoted_time_stamps"].write_text('"Timestamp","Status","LP_Disp (um)","mu"\n' + rows)
    return files


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--out", type=Path, default=DEFAULT_OUT)
    args = ap.parse_args()
    t_start = time.perf_counter()
    n, repeats = (20_000, REPEATS_QUICK) if args.quick else (100_000, REPEATS)
    _, _, _, starts = record(n)
    out = {}
    load = [common.loadavg()]
    with tempfile.TemporaryDirectory() as tmp:
        files = write_files(Path(tmp), n)
        for name, path in files.items():
            columns = {"time": "Timestamp"} if name == "quoted_time_stamps" else None
            read_s, seg_s = [], []
            for _ in range(repeats):
                t0 = time.perf_counter()
                rec = read_record(path, columns=columns)
                t1 = time.perf_counter()
                steps = np.array(record_steps(rec))
                seg_s.append(time.perf_counter() - t1)
                read_s.append(t1 - t0)
            found_t = steps[:, 0] - rec.t[0]
            ok = bool(steps.shape == (4, 2) and np.allclose(found_t[1:], starts[1:], atol=2 / RATE)
                      and np.allclose(steps[:, 1], VELOCITIES, rtol=0.01, atol=0))
            out[name] = {"rows": rec.n, "bytes": path.stat().st_size, "read_s_best": min(read_s),
                         "segment_s_best": min(seg_s), "steps_found": steps.tolist(), "steps_right": ok}
            load.append(common.loadavg())
    result = {"benchmark": "records_read", "date": _dt.datetime.now(_dt.UTC).isoformat(timespec="seconds"),
              "machine": common.machine_info(), "quick": args.quick, "repeats": repeats, "loadavg": load,
              "files": out,
              "targets": {"rows": n, "read_and_segment_s_worst": max(f["read_s_best"] + f["segment_s_best"]
                                                                    for f in out.values()),
                          "all_steps_right": all(f["steps_right"] for f in out.values())}}

    def table(r: dict) -> None:
        for name, f in r["files"].items():
            print(f"{name:>20}: {f['rows']} rows ({f['bytes'] / 1e6:.1f} MB)  read {f['read_s_best']:.3f} s  "
                  f"segment {f['segment_s_best']:.3f} s  steps right: {f['steps_right']}")

    common.write_result(result, args.out, t_start, print_table=table)


if __name__ == "__main__":
    main()
