"""The shape of the package's code: import cycles, the longest functions and the largest positional argument lists
in sweep/ (the figures the core's restructuring is judged by; docs/design.md 9 says which files a state law, a
stepper or a GPU target touches). Writes benchmarks/results/structure.json (or --out).

    python benchmarks/structure.py [--quick] [--out benchmarks/results/structure.json]

It reads the sources only (well under a second): --quick changes nothing and is accepted so that every script in
benchmarks/ takes the same smoke-run flags (tests/test_benchmarks.py).
"""

from __future__ import annotations

import argparse
import ast
import json
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "tests"))

from test_structure import MODULES, find_cycle, import_graph  # noqa: E402


def functions() -> list[dict[str, object]]:
    """Every function and method of sweep/ with its length in lines and its positional parameters."""
    out = []
    for name, path in MODULES.items():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                params = [a.arg for a in node.args.posonlyargs + node.args.args if a.arg not in ("self", "cls")]
                out.append({"function": f"{name}.{node.name}", "line": node.lineno,
                            "lines": node.end_lineno - node.lineno + 1, "positional": len(params)})
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="accepted for the smoke run; the script is already quick")
    ap.add_argument("--out", type=Path, default=HERE / "results" / "structure.json")
    args = ap.parse_args(argv)
    funcs = functions()
    report = {
        "import_cycle": find_cycle(import_graph()),
        "modules": len(MODULES),
        "longest_functions": sorted(funcs, key=lambda f: -f["lines"])[:8],
        "largest_positional_lists": sorted(funcs, key=lambda f: -f["positional"])[:8],
    }
    path = args.out
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(report, indent=1) + "\n")
    print(f"import cycle: {report['import_cycle']}; {report['modules']} modules")
    for key in ("longest_functions", "largest_positional_lists"):
        print(key)
        for f in report[key]:
            print(f"  {f['function']} (line {f['line']}): {f['lines']} lines, {f['positional']} positional")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
