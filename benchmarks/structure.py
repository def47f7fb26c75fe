"""The shape of the package's code: import cycles, the longest functions and the largest positional argument lists
in sweep/ (the figures the core's restructuring is judged by; docs/design.md 9 says which files a state law, a
stepper or a GPU target touches). Writes benchmarks/results/structure.json.

    python benchmarks/structure.py
"""

from __future__ import annotations

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


def main() -> None:
    funcs = functions()
    report = {
        "import_cycle": find_cycle(import_graph()),
        "modules": len(MODULES),
        "longest_functions": sorted(funcs, key=lambda f: -f["lines"])[:8],
        "largest_positional_lists": sorted(funcs, key=lambda f: -f["positional"])[:8],
    }
    path = HERE / "results" / "structure.json"
    path.write_text(json.dumps(report, indent=1) + "\n")
    print(f"import cycle: {report['import_cycle']}; {report['modules']} modules")
    for key in ("longest_functions", "largest_positional_lists"):
        print(key)
        for f in report[key]:
            print(f"  {f['function']} (line {f['line']}): {f['lines']} lines, {f['positional']} positional")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
