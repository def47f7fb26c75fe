"""``sweep fit FILE.toml -o fit.nc [--png fit.png]``: the command-line face of :func:`sweep.fit` (docs/fit.md).

sweep/cli.py registers it with :func:`add_fit_command`; user mistakes raise InputError, which sweep.cli.main turns
into one line ``sweep: error: ...`` and exit code 2. Progress lines go to stderr once the fit has run 2 s. A fit
that failed for some sample (``fit_status`` not ok, sweep.fit.verdict: one warning line says why) still writes its
files, and the command exits 1.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

__all__ = ["add_fit_command"]

DEFAULT_OUT = Path("sweep-out") / "fit.nc"
PROGRESS_AFTER_S = 2.0


def add_fit_command(add) -> None:
    """Register ``fit`` through ``add(name, **kw)`` (the sub-parser factory of sweep.cli.build_parser)."""
    fit = add("fit", help="fit the friction parameters to relaxation curves, relaxed slips or laboratory records "
                          "(netCDF + PNG)")
    fit.add_argument("config", help="fit TOML: preset/[params], free, [bounds], [start], [[data]] file = ... (a "
                                    "record's [[data]] also: columns, units, steps, k, noise, detrend, t_start, "
                                    "t_end, g)")
    fit.add_argument("-o", "--output", type=Path, default=DEFAULT_OUT, help=f"netCDF output (default {DEFAULT_OUT})")
    fit.add_argument("--png", type=Path, help="picture output (default: the output with .png)")
    fit.add_argument("--overwrite", action="store_true", help="replace existing output files")
    fit.add_argument("--search", default=None, metavar="{global,local}",
                     help="global: a coarse grid over the bounds first (default); local: the least squares from the "
                          "start alone (known start, many records, refits: no guard against local minima); "
                          "overrides the file's search")
    fit.add_argument("--g", type=float, default=None, metavar="N/M",
                     help="laboratory records: the machine's g = N/M [m/s^2] (normal load over moving mass) of the "
                          "records that give none; overrides the file's g (default: none: quasi-static, inertia only "
                          "where a slip runs away, docs/fit.md)")
    fit.set_defaults(func=_cmd_fit)


def _cmd_fit(args: argparse.Namespace) -> int:
    from ..errors import InputError
    from ..write.targets import check_targets
    from .config import load_fit_config
    from .core import fit
    from .plot import plot_fit, trend_lines
    from .result import save_fit

    kwargs = load_fit_config(args.config)
    if args.search is not None:
        kwargs["search"] = args.search
    if args.g is not None:
        kwargs["g"] = args.g
    png = args.png or args.output.with_suffix(".png")
    check_targets({"data": args.output, "picture": png}, overwrite=args.overwrite, inputs={"fit file": args.config})
    t0 = time.perf_counter()

    def progress(line: str) -> None:
        if not args.quiet and time.perf_counter() - t0 > PROGRESS_AFTER_S:
            print(f"sweep fit: {line}", file=sys.stderr, flush=True)

    history = "sweep " + " ".join(sys.argv[1:]) if sys.argv[1:] else "sweep fit"
    try:
        ds = fit(**kwargs, progress=progress, history=history)
    except TypeError as exc:  # a wrongly typed TOML value
        raise InputError(f"fit file {args.config!r}: {exc}") from None
    save_fit(ds, args.output, overwrite=args.overwrite)
    plot_fit(ds, png)
    status = ds["fit_status"].values
    meanings = ds["fit_status"].attrs["flag_meanings"].split()
    if not args.quiet:
        for name in ds["parameter"].values.tolist():
            for i, sample in enumerate(ds["sample"].values.tolist()):
                lo, hi = (float(ds[f"{name}_{s}"][i]) for s in ("lower", "upper")) if f"{name}_lower" in ds \
                    else (float("nan"),) * 2
                lab = ds[f"{name}_label"].attrs["flag_meanings"].split()[int(ds[f"{name}_label"][i])] \
                    if f"{name}_label" in ds else ""
                print(f"{sample}: {name} = {float(ds[name][i]):.4g} (95 %: {lo:.4g} .. {hi:.4g}) "
                      f"{lab.replace('_', ' ')}")
        if "record_name" in ds:  # a detrended record's trend slope, fitted with the parameters
            for name, line in zip(ds["record_name"].values.tolist(), trend_lines(ds)):
                if line:
                    print(f"{name}: {line}")
        for i, sample in enumerate(ds["sample"].values.tolist()):
            if status[i]:
                print(f"{sample}: the fit failed ({meanings[int(status[i])]})")
        print(f"wrote {args.output} and {png}")
    return 1 if status.any() else 0
