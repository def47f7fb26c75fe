"""Rewrite the numbers of README.md that come from measurements, from where they were measured.

Each such number sits in a marked span, ``<!-- n:KEY -->27<!-- /n -->`` (invisible in the rendered README); this
script replaces the text of every span with the value of KEY in :data:`NUMBERS`, read from the benchmark JSON in
benchmarks/results/ (or, for the compile times, from sweep/compile_notice.py, where they are measured and
documented). Run it after a benchmark run:

    python benchmarks/readme_numbers.py          # rewrite README.md
    python benchmarks/readme_numbers.py --check  # exit 1 if README.md is not up to date (tests/test_first_hour.py)
    python benchmarks/readme_numbers.py --out /tmp/n.json   # README.md left alone: the numbers as JSON

With --out the script only reads: it writes every key's value, the README's spans and whether README.md is up to
date to that JSON, and leaves README.md as it is. --quick changes nothing (the script reads a few small files);
it is accepted so that every script in benchmarks/ takes the same smoke-run flags (tests/test_benchmarks.py).
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
SPAN = re.compile(r"<!-- n:(?P<key>[\w.]+) -->(?P<text>.*?)<!-- /n -->")


def _json(name: str) -> dict:
    return json.loads((RESULTS / f"{name}.json").read_text())


def _sci(x: float) -> str:
    """4.7e-4 (two digits, no zero-padded exponent)."""
    mantissa, exponent = f"{x:.1e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _compile_seconds() -> int:
    """Seconds to compile the default scene's kernel families from an empty cache (sweep/compile_notice.py)."""
    sys.path.insert(0, str(ROOT))
    from sweep.compile_notice import COLD_COMPILE_S, kernel_families
    from sweep.scene import default_scene

    return sum(COLD_COMPILE_S[f] for f in kernel_families(default_scene()))


def _auto() -> dict:
    return _json("models")["cost"]["default_scene"]


NUMBERS: dict[str, Callable[[], str]] = {
    "auto_inertial_points": lambda: f"{_auto()['auto']['inertial_points']:,}",
    "auto_points": lambda: f"{_auto()['points']:,}",
    "auto_largest_quasistatic_error": lambda: _sci(
        _auto()["model_error_vs_inertial_rtol_1e-6"]["auto"]["max_true_error_on_quasistatic_points"]),
    "cold_process_s": lambda: f"{_json('throughput')['cold_start']['process_wall_s_median']:.1f}",
    "cold_import_s": lambda: f"{_json('throughput')['cold_start']['import_only_process_wall_s_median']:.1f}",
    "compile_s": lambda: f"{_compile_seconds()}",
}
"""Key of a marked span -> its text, from the measurement."""


def rewrite(text: str) -> str:
    """``text`` with every marked span set to its measured value (KeyError for an unknown key)."""
    return SPAN.sub(lambda m: f"<!-- n:{m['key']} -->{NUMBERS[m['key']]()}<!-- /n -->", text)


def main(argv: list[str]) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--check", action="store_true", help="exit 1 if README.md is not up to date; write nothing")
    ap.add_argument("--out", type=Path, help="write the numbers as JSON here and leave README.md alone")
    ap.add_argument("--quick", action="store_true", help="accepted for the smoke run; the script is already quick")
    args = ap.parse_args(argv)
    readme = ROOT / "README.md"
    old = readme.read_text()
    new = rewrite(old)
    if args.out is not None:
        spans = [m["key"] for m in SPAN.finditer(old)]
        stale = sorted({m["key"] for m in SPAN.finditer(old) if m["text"] != NUMBERS[m["key"]]()})
        result = {"benchmark": "benchmarks/readme_numbers.py", "results_dir": str(RESULTS),
                  "numbers": {key: value() for key, value in NUMBERS.items()}, "readme_spans": spans,
                  "readme_stale_keys": stale, "readme_up_to_date": new == old}
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(result, indent=1) + "\n")
        print(f"{len(spans)} marked numbers in README.md, {len(stale)} stale; wrote {args.out} (README.md untouched)")
    if args.check:
        if new != old:
            print("README.md numbers are stale: run python benchmarks/readme_numbers.py", file=sys.stderr)
            return 1
        return 0
    if args.out is not None:
        return 0
    readme.write_text(new)
    print(f"README.md: {len(SPAN.findall(new))} numbers from benchmarks/results and sweep/compile_notice.py")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
