"""Command line: ``sweep run | plot | hopf | reproduce | info``."""

from __future__ import annotations

import argparse
import os
import shlex
import shutil
import signal
import sys
import threading
import time
import warnings
from pathlib import Path

import numpy as np

from ._version import __version__
from .errors import InputError, JournalWarning
from .log import configured as logging_configured

DEFAULT_OUT = Path("sweep-out") / "landscape.nc"
FIGURES_OUT = Path("sweep-out") / "figures"
OVERWRITE_HELP = "replace output files that exist (without it, an existing file is never replaced)"
FIGURE_NAMES = ("fig2", "fig3a", "fig3b", "fig4a", "fig4b")
"""The keys of sweep.figures.FIGURES, spelt out so that the parser needs no matplotlib (tests check they agree)."""


def _cmd_run(args: argparse.Namespace) -> int:
    from .run.compile_notice import announce_if_cold
    from .run.size import check_fits, estimate_size
    from .scene.plausibility import warn_implausible, warn_implausible_params
    from .scene.scene import default_scene, load_scene

    scene = load_scene(args.config) if args.config else default_scene()
    warn_implausible(scene.K_over_M, scene.V)  # before any work, the dry run included
    warn_implausible_params(scene.params, scene.axes)
    size = estimate_size(scene, journaled=True)
    if args.dry_run:
        return _dry_run(scene, size, args.output)
    _check_run_targets(scene, args)
    check_fits(scene, size)  # (api.prepare_run checks again) before the plan's and the kernels' imports: at once
    announce_if_cold(scene)  # within a second of the start, before the plan imports and compiles anything
    from . import protocols
    from .run.compile_notice import SLOW_S

    protocol = protocols.get(scene.protocol)
    picture = _StagedPicture(_png(args))
    try:
        ds, totals, compile_s, elapsed, compute_s = _run_to_file(scene, args, warm=protocol.warm_up_timed,
                                                                 picture=picture)
        out = args.output
        # the rate of the computing alone: with the file and the picture in it, the default scene's 20,000 points
        # read ~20,000 points/s, of a computing at ~500,000
        kernel = (f"; kernel {'compiled' if compile_s > SLOW_S else 'loaded'} in {compile_s:.1f} s beforehand"
                  if protocol.warm_up_timed else ", including compilation on a first run")
        print(f"wrote {out} ({scene.n_points} points in {elapsed:.2f} s: computed in {_seconds(compute_s)} s, "
              f"{scene.n_points / max(compute_s, 1e-9):,.0f} points/s, then the file and the picture{kernel})")
        for line in protocol.summary(totals, ds):
            print(line)
        for png in picture.publish():
            print(f"wrote {png}")
    finally:
        picture.discard()
    if picture.error is not None:  # the results are safe on disk; a failed picture must not hide that
        exc = picture.error
        print(f"sweep: could not draw the picture ({type(exc).__name__}: {exc}); the data are in {out}",
              file=sys.stderr)
        return 1
    return _most_failed(ds, totals, out)


class _StagedPicture:
    """``sweep run``'s picture(s), drawn while the data file is written (api.PreparedRun.finish: ``picture``) into a
    hidden folder beside them, and moved into place by :meth:`publish` once the data are safe: a run whose file
    could not be written leaves no new picture and keeps an old one. A failed drawing is kept in ``error``."""

    def __init__(self, png: Path) -> None:
        self.png, self.folder, self.drawn, self.error = Path(png), None, [], None

    def __call__(self, ds) -> None:
        import tempfile

        from .plot.files import plot_file

        try:
            self.png.parent.mkdir(parents=True, exist_ok=True)
            self.folder = Path(tempfile.mkdtemp(prefix=f".{self.png.name}.", dir=self.png.parent))
            self.drawn = plot_file(ds, self.folder / self.png.name)
        except Exception as exc:  # noqa: BLE001 (reported after the data are written)
            self.error = exc

    def publish(self) -> list[Path]:
        """Move the pictures drawn into place; returns their paths."""
        placed = [self.png.parent / path.name for path in self.drawn]
        for path, target in zip(self.drawn, placed):
            os.replace(path, target)
        self.drawn = []
        return placed

    def discard(self) -> None:
        """Remove the hidden folder (and what was not published)."""
        if self.folder is not None:
            shutil.rmtree(self.folder, ignore_errors=True)
            self.folder = None


def _png(args: argparse.Namespace) -> Path:
    """The picture of a command that writes data and a picture: --png, else the output with .png."""
    return args.png or args.output.with_suffix(".png")


def _check_run_targets(scene, args: argparse.Namespace) -> None:
    """Before any work: the data file and the pictures ``sweep run`` will write (sweep/write/targets.py), none of them
    the
    scene file or one another; the data file's folder, free space and lock are checked by api.prepare_run."""
    from .write.targets import check_targets, picture_paths

    targets = {"data": args.output}
    if not args.output.is_dir():  # (refused below; its picture's name cannot be made from a folder's)
        pictures = picture_paths(_png(args), scene.protocol, trajectories="trajectory" in scene.observables,
                                 points=scene.n_points)
        targets.update({("picture" if i == 0 else "second picture"): path for i, path in enumerate(pictures)})
    check_targets(targets, overwrite=args.overwrite, inputs={"scene file": args.config})


def _dry_run(scene, size, output: Path) -> int:
    """``sweep run --dry-run``: the size from the grid's shape (refused, like the run, if it does not fit in
    memory or its output's disk), then the plan and, where its protocol measures it, the pilot's estimate of the
    time, both from a subsample where the grid is large (Protocol.dry_run)."""
    from . import protocols
    from .run.size import check_fits
    from .write.targets import check_free_space, existing_folder

    protocol = protocols.get(scene.protocol)
    axes = " x ".join(f"{n} {'K/M' if d == 'K_over_M' else d}" for n, d in zip(scene.shape, scene.dims))
    print(f"{'grid':>28}: {axes} = {scene.n_points:,} points, "
          + (f"rtol {scene.rtol:g}, " if protocol.warm_up_timed else "")
          + f"observables {', '.join(scene.observables)}")
    folder = existing_folder(output)
    for line in size.lines(folder):
        print(line)
    sys.stdout.flush()
    check_fits(scene, size)  # before the imports of the plan and the kernels (~1 s): a refusal answers at once
    for line in protocol.dry_run(scene):
        print(line)
    check_free_space(folder, size.disk, output)  # the time estimated too: what the run would need, then why not
    return 0


MOST_FAILED = 0.5
"""A run in which more than this fraction of the points failed (a status other than ok and no_finite_limit, which
is the model's answer) exits with code 1."""


def _most_failed(ds, totals, out: Path) -> int:
    """Exit code of a finished run: 1, with a one-line summary on stderr, where most points failed (NOT_FAILED)."""
    from .scene.plausibility import not_ok_summary

    bad, text = not_ok_summary(totals.counts["status"], ds["status"].attrs["flag_meanings"].split(), failed_only=True)
    if bad <= MOST_FAILED * totals.points:
        return 0
    return _fail(f"{bad} of {totals.points} points failed ({text}); the values are in {out} but most are NaN "
                 "or inaccurate: check the units (K_over_M [s-2], V [m/s]) and ranges", 1)


def _seconds(x: float) -> str:
    """Seconds with two decimals, or two significant digits below 0.1 s (a small grid computes in milliseconds:
    "0.00 s" beside its rate would say nothing)."""
    return f"{x:.2f}" if x >= 0.1 else f"{x:.2g}"


def _run_to_file(scene, args: argparse.Namespace, warm: bool, picture=None):
    """run_sweep into args.output, journaled (resumable with --resume), through api.prepare_run: every check, the
    lock and the journal's check before the kernels are loaded (``warm``: separately, timed; a dask run always
    warms up before its fan-out); ``picture(ds)`` drawn while the file is written (api.PreparedRun.finish).
    Returns (Dataset, the run's totals, seconds warming up, seconds running (the picture included), seconds of the
    chunk loop)."""
    from .api import prepare_run, warm_up_kernels
    from .run.compile_notice import timed

    dask = args.workers is not None or args.scheduler is not None
    with prepare_run(scene, args.output, resume=args.resume, overwrite=args.overwrite, chunk_size=args.chunk_size,
                     backend="dask" if dask else "threads", workers=args.workers, scheduler=args.scheduler) as run:
        t_warm = time.perf_counter()
        if warm or dask:
            with timed("kernels"):  # says so before a first compile (empty numba cache) and when it takes long
                warm_up_kernels(scene, fan_out=dask)
        compile_s = time.perf_counter() - t_warm
        t0 = time.perf_counter()
        ds = run.finish(progress=None if not args.quiet else False, history=_history(), picture=picture)
    return ds, run.totals, compile_s, time.perf_counter() - t0, run.compute_s


def _history() -> str:
    """The command line, for the file's history attribute."""
    return "sweep " + " ".join(shlex.quote(a) for a in sys.argv[1:])


def _cmd_plot(args: argparse.Namespace) -> int:
    from .plot.files import has_trajectories, plot_file
    from .write.read import read_sweep_file
    from .write.targets import check_targets, picture_paths

    ds, kind = read_sweep_file(args.file)
    png = args.output or Path(args.file).with_suffix(".png")
    if kind == "fit":
        return _plot_fit_file(ds, png, args)
    pictures = picture_paths(png, kind, trajectories=has_trajectories(ds),
                             points=ds.sizes.get("K_over_M", 1) * ds.sizes.get("V", 1), variable=args.variable)
    check_targets({f"picture {i + 1}" if i else "picture": path for i, path in enumerate(pictures)},
                  overwrite=args.overwrite, inputs={"sweep file": args.file})
    for written in plot_file(ds, png, variable=args.variable):
        print(f"wrote {written}")
    return 0


def _plot_fit_file(ds, png: Path, args: argparse.Namespace) -> int:
    """``sweep plot`` of a fit file: the picture ``sweep fit`` wrote beside it, again (sweep.fit.plot_fit)."""
    from .fit.plot import plot_fit
    from .write.targets import check_targets

    if args.variable is not None:
        raise InputError(f"--variable is for sweep files; a fit file is drawn whole (got {args.variable!r})")
    check_targets({"picture": png}, overwrite=args.overwrite, inputs={"fit file": args.file})
    print(f"wrote {plot_fit(ds, png)}")
    return 0


FLAGS = ("status", "regime", "bifurcation", "model")
"""Flag variables that ``sweep info`` counts, where the file has them."""


def _cmd_info(args: argparse.Namespace) -> int:
    """``sweep info FILE``: what the file is, where it comes from, its axes, flag counts and value ranges."""
    from .status import flag_summary
    from .write.read import read_sweep_file

    ds, kind = read_sweep_file(args.file)
    print(f"{args.file}: {ds.attrs.get('title', '')} ({kind} file)")
    print(f"  source: {ds.attrs.get('source', '?')}")
    print(f"  history: {ds.attrs.get('history', '?')}")
    print("  dims: " + ", ".join(f"{k}={v}" for k, v in ds.sizes.items()))
    for name in ds["status"].dims if "status" in ds.data_vars else ("K_over_M", "V"):  # the grid's axes
        if name in ds.dims:
            c = ds[name]
            print(f"  {name}: {float(c.min()):.4g} .. {float(c.max()):.4g} [{c.attrs.get('units', '?')}]")
    for key in sorted(k for k in ds.attrs if k.startswith("plan_")):
        print(f"  {key}: {ds.attrs[key]}")
    for name in FLAGS:
        if name in ds and "flag_meanings" in ds[name].attrs:
            print("  " + flag_summary(ds, name))
    for name, var in ds.data_vars.items():
        if var.dtype.kind not in "biuf":  # a fit's labels and messages: text
            continue
        vals = var.values[np.isfinite(var.values)] if var.dtype.kind == "f" else var.values
        rng = f"{float(vals.min()):.4g} .. {float(vals.max()):.4g}" if vals.size else "all NaN"
        print(f"  {name:18s} [{var.attrs.get('units', '')}] {rng}  {var.attrs.get('long_name', '')}")
    return 0


def _cmd_hopf(args: argparse.Namespace) -> int:
    """``sweep hopf CONFIG.toml -o hopf.nc``: the Hopf line over the file's V axis, netCDF + PNG."""
    from .analysis.hopf import hopf_summary, locate_hopf
    from .plot.files import plot_hopf
    from .scene.scene import hopf_config
    from .status import flag_summary
    from .write.netcdf import save
    from .write.targets import check_targets

    params, v, kwargs = hopf_config(args.config)
    check_targets({"data": args.output, **({} if args.output.is_dir() else {"picture": _png(args)})},
                  overwrite=args.overwrite, inputs={"scene file": args.config})  # before the computation
    t0 = time.perf_counter()
    ds = locate_hopf(params, v, progress=False if args.quiet else None, **kwargs)
    ds.attrs["history"] = _history()
    out = save(ds, args.output, overwrite=args.overwrite)
    print(f"wrote {out} ({v.size} velocities in {time.perf_counter() - t0:.2f} s; {flag_summary(ds, 'bifurcation')}; "
          f"{flag_summary(ds, 'model')})")
    print(hopf_summary(ds))
    print(f"wrote {plot_hopf(ds, _png(args))}")
    return 0


def _cmd_reproduce(args: argparse.Namespace) -> int:
    """``sweep reproduce NAME -o DIR``: the paper's figures, each as netCDF + PNG + a text of key numbers."""
    from .figures import reproduce

    for done in reproduce(args.name, args.output, overwrite=args.overwrite):
        print(f"{done.name}: computed in {done.seconds:.2f} s; wrote {done.data}, {done.png}, {done.text}")
        for line in done.key_numbers:
            print(f"  {line}")
    return 0


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be an integer >= 1, got {value}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="sweep", description=__doc__)
    parser.add_argument("--version", action="version", version=f"sweep {__version__}")
    common = argparse.ArgumentParser(add_help=False)  # -v / -q after any command: sweep run -q, sweep hopf -v
    talk = common.add_mutually_exclusive_group()
    talk.add_argument("-v", "--verbose", action="store_true", help="also debug details (logger 'sweep')")
    talk.add_argument("-q", "--quiet", action="store_true", help="warnings and errors only, no progress bar")
    sub = parser.add_subparsers(dest="command", required=True)
    add = lambda name, **kw: sub.add_parser(name, parents=[common], **kw)  # noqa: E731
    run = add("run", help="run a scene (default: the built-in sample2 landscape) and write netCDF + PNG")
    run.add_argument("config", nargs="?", help="scene TOML file (omit for the built-in default scene)")
    run.add_argument("-o", "--output", type=Path, default=DEFAULT_OUT, help=f"netCDF output (default {DEFAULT_OUT})")
    run.add_argument("--png", type=Path, help="picture output (default: the output with .png)")
    run.add_argument("--dry-run", action="store_true", help="print the plan and an estimated time, then exit")
    run.add_argument("--resume", action="store_true",
                     help="continue an interrupted run into the same output: compute only the chunks missing from "
                          "its journal (OUTPUT.journal), after checking that the scene and plan are the same and "
                          "every chunk is whole (a damaged one is moved to OUTPUT.rejected and computed again)")
    run.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP + "; without --resume, also start over "
                     "from an existing journal (deleted)")
    run.add_argument("--chunk-size", type=_positive_int, default=None,
                     help="points per chunk (journal entry); default 4096 for stop (up to 16384 on a large grid, "
                          "keeping at least 60 chunks), 1024 for driven scenes")
    run.add_argument("--workers", type=_positive_int, default=None,
                     help="run the chunks on a dask LocalCluster of N one-thread worker processes (pip install "
                          "'.[distributed]' from the sweep checkout); same numbers as the default threads backend")
    run.add_argument("--scheduler", default=None, metavar="ADDRESS",
                     help="run the chunks on an existing dask cluster, e.g. tcp://host:8786 (its workers need sweep "
                          "installed)")
    run.set_defaults(func=_cmd_run)
    plot = add("plot", help="draw the picture that fits a sweep file: stop landscape (and transients), "
                                       "driven regimes, or Hopf line")
    plot.add_argument("file")
    plot.add_argument("-o", "--output", type=Path, help="PNG path (default: the file with .png)")
    plot.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)
    plot.add_argument("--variable", default=None,
                      help="draw this (K_over_M, V) variable alone (default: xi_inf and the stress relaxation of a "
                           "stop sweep, the regime and amplitude of a driven one)")
    plot.set_defaults(func=_cmd_plot)
    hopf = add("hopf", help="locate the Hopf line over the V axis of a scene file (netCDF + PNG)")
    hopf.add_argument("config", help="TOML with preset and/or [params], a [V] axis table, optional rtol, model")
    hopf.add_argument("-o", "--output", type=Path, default=Path("sweep-out") / "hopf.nc", help="netCDF output")
    hopf.add_argument("--png", type=Path, help="picture output (default: the output with .png)")
    hopf.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)
    hopf.set_defaults(func=_cmd_hopf)
    rep = add("reproduce", help="regenerate the paper's figures from the presets (netCDF + PNG + key "
                                           "numbers beside the paper's)")
    rep.add_argument("name", choices=[*FIGURE_NAMES, "all"], metavar="NAME",
                     help=f"one of {', '.join([*FIGURE_NAMES, 'all'])}")
    rep.add_argument("-o", "--output", type=Path, default=FIGURES_OUT,
                     help=f"output folder (default {FIGURES_OUT})")
    rep.add_argument("--overwrite", action="store_true", help=OVERWRITE_HELP)
    rep.set_defaults(func=_cmd_reproduce)
    info = add("info", help="summarise a sweep file")
    info.add_argument("file")
    info.set_defaults(func=_cmd_info)
    from .fit.cli import add_fit_command  # sweep fit: its own module (sweep/fit/cli.py)

    add_fit_command(add)
    return parser


def _show_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """Warnings of sweep (implausible inputs, failed points, files refused from a journal) as one line
    ``sweep: warning: ...``; others as usual."""
    from .scene.plausibility import PlausibilityWarning

    if issubclass(category, (PlausibilityWarning, JournalWarning)):
        print(f"sweep: warning: {message}", file=sys.stderr)
    else:
        _python_show_warning(message, category, filename, lineno, file, line)


_python_show_warning = warnings.showwarning


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit code: 0 done, 1 finished with failures (a summary says which), 2 a
    user mistake (one line on stderr, no traceback), 3 a file could not be written during the run (disk full,
    permission...: one line; a journaled run keeps its finished chunks for --resume), 130 interrupted (Ctrl-C)."""
    previous_show_warning, warnings.showwarning = warnings.showwarning, _show_warning
    previous_sigint = _exit_on_ctrl_c_while_compiling()
    try:
        args = build_parser().parse_args(argv)
        _check_numba_settings()
        with logging_configured(verbose=args.verbose, quiet=args.quiet):
            return args.func(args)
    except InputError as exc:
        return _fail(f"error: {exc}", 2)
    except (FileNotFoundError, PermissionError, IsADirectoryError, NotADirectoryError) as exc:
        return _fail(f"error: {exc}", 2)
    except OSError as exc:  # OutputError (sweep/write/targets.py: a write failed during the run), or a picture
        return _fail(f"error: {exc}", 3)
    except KeyboardInterrupt:
        return _fail("interrupted (Ctrl-C)", 130)
    except Exception as exc:
        from .run.runner import Interrupted

        if isinstance(exc, Interrupted):  # Ctrl-C during a journaled run: nothing finished is lost
            return _fail(str(exc), 130)
        raise
    finally:  # called from Python (a notebook, a test), main leaves the warning, signal and logging set-up as found
        warnings.showwarning = previous_show_warning
        if previous_sigint is not None:
            signal.signal(signal.SIGINT, previous_sigint)


def _exit_on_ctrl_c_while_compiling():
    """Install a SIGINT handler for the command (main thread only; returns the previous handler, or None): Ctrl-C
    raises KeyboardInterrupt as usual, except while numba compiles, where the interrupt would be lost inside LLVM's
    code generation (sweep.jitcache.compiling): then the one-line message and exit 130 at once. Nothing is lost:
    numba writes its cache files and sweep its journal chunks atomically."""
    if threading.current_thread() is not threading.main_thread():
        return None

    def on_sigint(signum, frame):
        jitcache = sys.modules.get("sweep.jitcache")
        if jitcache is not None and jitcache.compiling():
            sys.stdout.flush()
            print("sweep: interrupted (Ctrl-C)", file=sys.stderr, flush=True)
            os._exit(130)
        raise KeyboardInterrupt

    return signal.signal(signal.SIGINT, on_sigint)


def _fail(message: str, code: int) -> int:
    """Print ``sweep: message`` on one line of stderr; return the exit code."""
    print(f"sweep: {message}", file=sys.stderr)
    return code


def _check_numba_settings() -> None:
    """InputError for a NUMBA_NUM_THREADS that numba would refuse when sweep's kernels load (with a traceback from
    inside its import): it must be a whole number >= 1."""
    threads = os.environ.get("NUMBA_NUM_THREADS")
    if threads is not None and not (threads.strip().isdigit() and int(threads) >= 1):
        raise InputError(f"NUMBA_NUM_THREADS must be a whole number >= 1 (the threads of the kernels; this machine "
                         f"has {os.cpu_count()} cores), got {threads!r}: unset it or set e.g. NUMBA_NUM_THREADS=2")


def entry_point() -> None:
    """The ``sweep`` command: :func:`main`, then exit with its code. After a Ctrl-C the process ends with
    ``os._exit(130)``: CPython can turn a normal exit after a caught KeyboardInterrupt into death by SIGINT (exit
    status -2 instead of 130) when the interrupt arrived inside an import; everything is written atomically, so
    nothing is lost by skipping the interpreter's finalisation."""
    code = main()
    if code == 130:
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(130)
    sys.exit(code)


if __name__ == "__main__":
    entry_point()
