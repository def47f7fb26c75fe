"""The package's import graph has no cycles (module-level and function-level imports alike): every layer imports
only the layers below it (docs/design.md 3)."""

from __future__ import annotations

import ast
from pathlib import Path

import sweep

ROOT = Path(sweep.__file__).parent


def module_name(path: Path) -> str:
    parts = path.relative_to(ROOT.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports_of(path: Path) -> set[str]:
    """The sweep modules that ``path`` imports anywhere in its body (relative imports resolved)."""
    name = module_name(path)
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            # "from package import module" imports the module; the package itself only for names defined in it
            submodules = [f"{target}.{alias.name}" for alias in node.names if f"{target}.{alias.name}" in MODULES]
            names = [alias for alias in node.names if f"{target}.{alias.name}" not in MODULES]
            candidates = submodules + ([target] if names else [])
        elif isinstance(node, ast.Import):
            candidates = [alias.name for alias in node.names]
        else:
            continue
        found |= {c for c in candidates if c.startswith("sweep") and c in MODULES}
    return found - {name}


MODULES = {module_name(p): p for p in ROOT.rglob("*.py")}


def find_cycle(graph: dict[str, set[str]]) -> list[str] | None:
    """A cycle of the graph (as a list of modules) or None (depth-first search)."""
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(node: str) -> list[str] | None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph[node]):
            if state.get(nxt) == 1:
                return stack[stack.index(nxt):] + [nxt]
            if nxt not in state and (cycle := visit(nxt)):
                return cycle
        stack.pop()
        state[node] = 2
        return None

    for node in sorted(graph):
        if node not in state and (cycle := visit(node)):
            return cycle
    return None


def import_graph() -> dict[str, set[str]]:
    # a package's __init__ re-exports its modules: edges into a package are edges into its __init__ only
    return {name: {m for m in imports_of(path) if m != "sweep"} for name, path in MODULES.items() if name != "sweep"}


def test_the_import_graph_has_no_cycles():
    assert find_cycle(import_graph()) is None, " -> ".join(find_cycle(import_graph()))


def test_the_cycle_finder_finds_a_cycle():
    graph = {"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": set()}
    assert find_cycle(graph) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_models_do_not_import_the_drivers_and_solvers_do_not_import_the_models():
    """The layering of the numerical core: solvers <- models <- integrate <- engine."""
    graph = import_graph()
    for name, deps in graph.items():
        inside = {d for d in deps if d.startswith("sweep.integrate")}
        if name.startswith("sweep.integrate.solvers"):
            assert not {d for d in inside if not d.startswith("sweep.integrate.solvers")}, name
        if name.startswith("sweep.integrate.models"):
            assert not {d for d in inside if not d.startswith(("sweep.integrate.models", "sweep.integrate.solvers"))}, name


def test_the_model_registry_names_every_state_law_and_existing_modules():
    """sweep.integrate.models.REGISTRY is the one table of what exists: its state laws are those of models/state_laws.py,
    and every module it names exists."""
    from sweep.integrate.models import REGISTRY
    from sweep.integrate.models.state_laws import STATE_LAWS

    assert {law for (_, _, law) in REGISTRY} == set(STATE_LAWS)
    for rhs, drivers in REGISTRY.values():
        for module in (rhs, *drivers.split(" / ")):
            assert f"sweep.{module}" in MODULES, module
