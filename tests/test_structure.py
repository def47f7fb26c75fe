"""The package's structure: no import cycles (module-level and function-level imports alike), every import follows the
flow of the layers (docs/design.md, "Layout"), and no module outside sweep/protocols/ compares a protocol's name."""

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
    for node in _runtime_nodes(ast.parse(path.read_text())):
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


def _runtime_nodes(tree: ast.AST):
    """The nodes of ``tree`` outside ``if TYPE_CHECKING:`` blocks (annotations only: not imported when run)."""
    stack = [tree]
    while stack:
        node = stack.pop()
        yield node
        for child in ast.iter_child_nodes(node):
            if isinstance(child, ast.If) and getattr(child.test, "id", None) == "TYPE_CHECKING":
                stack.extend(child.orelse)
                continue
            stack.append(child)


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
            below = ("sweep.integrate.models", "sweep.integrate.solvers")
            assert not {d for d in inside if not d.startswith(below)}, name


def test_every_state_law_names_a_kernel_family_the_package_has():
    """The state laws' registry is what the package dispatches on: each law's stop kernel family is one the compile
    notice knows and, without the aging identity, one the stop engine dispatches to."""
    from sweep.integrate.models.state_laws import STATE_LAWS
    from sweep.protocols.stop.engine import GENERAL_PATHS
    from sweep.run.compile_notice import COLD_COMPILE_S

    for law in STATE_LAWS.values():
        assert law.stop_family is None or law.stop_family in COLD_COMPILE_S, law.name
        if law.stop_family and not law.aging_identity:
            assert law.stop_family in GENERAL_PATHS, law.name


LAYERS = (
    ("sweep._version sweep._lazy sweep._moved sweep.accuracy sweep.physics sweep.status sweep.errors sweep.jitcache "
     "sweep.log sweep.protocols sweep.protocols.base"),
    "sweep.integrate",
    "sweep.scene",
    "sweep.plan",
    "sweep.write sweep.assemble",
    "sweep.plot",
    "sweep.run",
    "sweep.protocols.stop sweep.protocols.driven sweep.protocols.history sweep.analysis",
    "sweep.fit",
    "sweep.api sweep.figures sweep.cli",
)
"""The layers, lowest first (docs/design.md, "Layout"): a module imports its own layer and those below it only. The
ground floor holds what everything uses and the protocols' catalogue and interface; the protocols' implementations
sit above the machinery they plug into (plan, run, write, assemble, plot)."""


def layer(module: str) -> int:
    """The layer of ``module``: that of the longest prefix named in LAYERS."""
    best, found = -1, None
    for i, names in enumerate(LAYERS):
        for prefix in names.split():
            if (module == prefix or module.startswith(prefix + ".")) and len(prefix) > best:
                best, found = len(prefix), i
    assert found is not None, f"{module} is in no layer of LAYERS"
    return found


def test_every_import_follows_the_flow():
    against = [f"{name} (layer {layer(name)}) imports {dep} (layer {layer(dep)})"
               for name, deps in import_graph().items() for dep in deps if layer(dep) > layer(name)]
    assert not against, "\n".join(against)


def test_the_layer_check_finds_an_import_against_the_flow():
    assert layer("sweep.scene.scene") < layer("sweep.run.runner") < layer("sweep.protocols.stop.engine")
    assert layer("sweep.protocols") == layer("sweep.errors") < layer("sweep.protocols.driven.plan")


PROTOCOL_NAMES = {"stop", "driven"}  # ("history" is also every file's CF attribute: not a sign)


def protocol_name_uses(path: Path) -> list[str]:
    """Comparisons with a protocol's name, and tables keyed by one, in ``path``: ``scene.protocol == "stop"``,
    ``x in ("stop", ...)``, ``{"driven": ...}``."""
    text = path.read_text()
    found = []
    for node in ast.walk(ast.parse(text)):
        if isinstance(node, ast.Compare):
            operands = [node.left, *node.comparators]
            named = any(isinstance(c, ast.Constant) and c.value in PROTOCOL_NAMES for c in operands) or any(
                isinstance(c, (ast.Tuple, ast.List, ast.Set)) and any(
                    isinstance(e, ast.Constant) and e.value in PROTOCOL_NAMES for e in c.elts) for c in operands)
        elif isinstance(node, ast.Dict):
            named = any(isinstance(k, ast.Constant) and k.value in PROTOCOL_NAMES for k in node.keys)
        else:
            continue
        if named:
            found.append(f"{path}:{node.lineno}: {ast.get_source_segment(text, node)}")
    return found


def test_no_module_outside_the_protocols_compares_a_protocol_name():
    outside = [p for p in ROOT.rglob("*.py") if "protocols" not in p.relative_to(ROOT).parts]
    found = [use for path in outside for use in protocol_name_uses(path)]
    assert not found, "\n".join(found)


def test_the_protocol_name_check_finds_a_comparison(tmp_path):
    sample = tmp_path / "sample.py"
    sample.write_text('def f(scene):\n'
                      '    return scene.protocol == "driven" or scene.protocol in ("stop",) or {"stop": 1}\n')
    assert len(protocol_name_uses(sample)) == 3
