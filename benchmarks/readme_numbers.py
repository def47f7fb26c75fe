"""Rewrite the numbers of README.md that come from measurements, from where they were measured.

Each such number sits in a marked span, ``<!-- n:KEY -->27<!-- /n -->`` (invisible in the rendered README); this
script replaces the text of every span with the value of KEY in :data:`NUMBERS`, read from the benchmark JSON in
benchmarks/results/ (or, for the compile times, from sweep/compile_notice.py, where they are measured and
documented). Run it after a benchmark run:

    python benchmarks/readme_numbers.py          # rewrite README.md
    python benchmarks/readme_numbers.py --check  # exit 1 if README.md is not up to date (tests/test_first_hour.py)
"""

from __future__ import annotations

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
    readme = ROOT / "README.md"
    old = readme.read_text()
    new = rewrite(old)
    if "--check" in argv:
        if new != old:
            print("README.md numbers are stale: run python benchmarks/readme_numbers.py", file=sys.stderr)
            return 1
        return 0
    readme.write_text(new)
    print(f"README.md: {len(SPAN.findall(new))} numbers from benchmarks/results and sweep/compile_notice.py")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
