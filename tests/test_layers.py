"""The package's floor plan: every import goes down the layers, and no import cycle.

:data:`LAYERS` is the one statement of the order (docs/architecture.md draws it). A unit is a
module or subpackage directly under ``assembler_pin``; a unit may import from itself and from
units of lower layers only. Every ``import`` is parsed with :mod:`ast`, those inside functions
and under ``if TYPE_CHECKING:`` included, so a cycle cannot hide behind a deferred import.
"""

from __future__ import annotations

import ast
import re
from collections import defaultdict
from pathlib import Path

PACKAGE = Path(__file__).resolve().parents[1] / "assembler_pin"

#: The layers, lowest first; a unit imports only from its own layer's unit and the ones below.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("exceptions",),
    ("config",),
    ("common", "scenarios"),
    ("model",),
    ("kinematics",),
    ("collision", "statics"),
    ("compliance", "constraints", "dynamics"),
    ("state",),
    ("helper_arm", "optimize", "supports"),
    ("solver", "export"),
    ("motion", "carrier", "plots"),
    ("maps", "walk", "simulate", "reproduce"),
    ("hexapod",),
    ("viz", "bench"),
    ("cli",),
)

#: Imports that go up the layers today, (importer, imported) as dotted module names.
KNOWN_UPWARD: set[tuple[str, str]] = set()

#: Import cycles among modules today, each as its sorted tuple of dotted module names.
KNOWN_CYCLES: set[tuple[str, ...]] = set()


def _module_name(path: Path) -> str:
    parts = path.relative_to(PACKAGE.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {_module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def _targets(importer: str, is_package: bool, node: ast.Import | ast.ImportFrom) -> list[str]:
    """The package modules one import statement loads (``from x import y`` loads x.y if a module)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if a.name.split(".")[0] == "assembler_pin"]
    if node.level:
        base = importer.split(".") if is_package else importer.split(".")[:-1]
        base = base[: len(base) - node.level + 1]
        module = ".".join([*base, node.module] if node.module else base)
    else:
        module = node.module or ""
    if module.split(".")[0] != "assembler_pin":
        return []
    return [f"{module}.{a.name}" if f"{module}.{a.name}" in MODULES else module for a in node.names]


def _type_only_lines(tree: ast.Module) -> set[int]:
    """Lines of the imports under ``if TYPE_CHECKING:`` (read by type checkers, never run)."""
    lines = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            lines |= {n.lineno for n in ast.walk(node) if isinstance(n, ast.Import | ast.ImportFrom)}
    return lines


def import_edges(*, type_only: bool = True) -> list[tuple[str, str, int]]:
    """Every (importer, imported module, line) of the package, at any depth of the source.

    Args:
        type_only: include the imports under ``if TYPE_CHECKING:``.
    """
    edges = []
    for name, path in MODULES.items():
        tree = ast.parse(path.read_text(encoding="utf-8"))
        skip = set() if type_only else _type_only_lines(tree)
        for node in ast.walk(tree):
            if isinstance(node, ast.Import | ast.ImportFrom) and node.lineno not in skip:
                edges += [(name, t, node.lineno) for t in _targets(name, path.name == "__init__.py", node)]
    return edges


def unit(module: str) -> str:
    """The unit of a dotted module name: the module or subpackage directly under the package."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def layer_of() -> dict[str, int]:
    return {name: i for i, layer in enumerate(LAYERS) for name in layer}


def test_every_unit_has_a_layer():
    layers = layer_of()
    units = {m.split(".")[1] for m in MODULES if "." in m}
    assert units <= set(layers), f"units without a layer in LAYERS: {sorted(units - set(layers))}"
    assert set(layers) <= units, f"layers name no unit: {sorted(set(layers) - units)}"
    assert len(layers) == sum(len(layer) for layer in LAYERS), "a unit is listed twice"


def test_the_architecture_page_shows_these_layers():
    page = (PACKAGE.parent / "docs" / "architecture.md").read_text(encoding="utf-8")
    shown = [tuple(re.findall(r"`(\w+)`", line)) for line in re.findall(r"^\d+\. (.+)$", page, re.MULTILINE)]
    assert shown == list(LAYERS), "docs/architecture.md's numbered list of layers differs from LAYERS"


def test_no_import_goes_up_the_layers():
    layers = layer_of()
    bad = []
    for importer, imported, line in import_edges():
        a, b = unit(importer), unit(imported)
        if not a or a == b:  # the top-level __init__ (lazy names) and imports within a unit
            continue
        if layers[a] <= layers[b] and (importer, imported) not in KNOWN_UPWARD:
            bad.append(f"{MODULES[importer].relative_to(PACKAGE.parent)}:{line}: {importer} -> {imported}")
    assert not bad, "imports against the layers (lowest first):\n" + "\n".join(sorted(bad))


def test_known_upward_edges_still_exist():
    edges = {(a, b) for a, b, _ in import_edges()}
    assert KNOWN_UPWARD <= edges, f"remove from KNOWN_UPWARD: {sorted(KNOWN_UPWARD - edges)}"


def test_imports_inside_library_functions_name_what_they_delay():
    """A package import inside a function (outside the command line's lazy ``run`` functions)
    only delays a heavy or optional library, and says which on its line (``# delays scipy``),
    or serves a file that also runs as a script without its package (``# script: ...``)."""
    bad = []
    for name, path in MODULES.items():
        if name.startswith("assembler_pin.cli"):
            continue
        source = path.read_text(encoding="utf-8")
        lines = source.splitlines()
        for fn in ast.walk(ast.parse(source)):
            if not isinstance(fn, ast.FunctionDef | ast.AsyncFunctionDef):
                continue
            for node in ast.walk(fn):
                if isinstance(node, ast.Import | ast.ImportFrom) and _targets(name, path.name == "__init__.py", node):
                    line = lines[node.lineno - 1]
                    if "# delays " not in line and "# script: " not in line:
                        bad.append(f"{path.relative_to(PACKAGE.parent)}:{node.lineno}: {line.strip()}")
    assert not bad, "imports inside functions that delay no heavy library:\n" + "\n".join(bad)


#: Names a module other than a package's ``__init__`` may re-export: the motion notebook imports
#: them from there.
RE_EXPORTS = {("assembler_pin.motion.timing", "read_trajectory"), ("assembler_pin.motion.timing", "trajectory_states")}


def test_only_packages_re_export():
    """One home per name: a module's ``__all__`` lists only what it defines (a package's
    ``__init__`` gathers the names of its modules)."""
    bad = []
    for name, path in MODULES.items():
        if path.name == "__init__.py":
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        imported = {a.asname or a.name for n in tree.body if isinstance(n, ast.ImportFrom) for a in n.names}
        for node in tree.body:
            if isinstance(node, ast.Assign) and any(getattr(t, "id", "") == "__all__" for t in node.targets):
                exported = ast.literal_eval(node.value)
                bad += [f"{name}.{n}" for n in exported if n in imported and (name, n) not in RE_EXPORTS]
    assert not bad, f"names re-exported outside a package's __init__: {bad}"


def _cycles(graph: dict[str, set[str]]) -> list[tuple[str, ...]]:
    """The strongly connected components of more than one module (Tarjan, iterative)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found = []
    for root in sorted(graph):
        if root in index:
            continue
        work = [(root, iter(sorted(graph[root])))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            v, children = work[-1]
            for w in children:
                if w not in index:
                    index[w] = low[w] = len(index)
                    stack.append(w)
                    on_stack.add(w)
                    work.append((w, iter(sorted(graph[w]))))
                    break
                if w in on_stack:
                    low[v] = min(low[v], index[w])
            else:
                work.pop()
                if work:
                    low[work[-1][0]] = min(low[work[-1][0]], low[v])
                if low[v] == index[v]:
                    component = []
                    while True:
                        w = stack.pop()
                        on_stack.discard(w)
                        component.append(w)
                        if w == v:
                            break
                    if len(component) > 1:
                        found.append(tuple(sorted(component)))
    return found


def test_no_import_cycle():
    """No cycle among the modules that run (imports under ``TYPE_CHECKING`` name types only)."""
    graph: dict[str, set[str]] = defaultdict(set)
    for importer, imported, _ in import_edges(type_only=False):
        if importer != imported and importer != "assembler_pin":
            graph[importer].add(imported)
            graph.setdefault(imported, set())
    cycles = set(_cycles(graph))
    assert cycles <= KNOWN_CYCLES, f"import cycles: {sorted(cycles - KNOWN_CYCLES)}"
    assert KNOWN_CYCLES <= cycles, f"remove from KNOWN_CYCLES: {sorted(KNOWN_CYCLES - cycles)}"


#: The package's reads of the environment that pick no code path: (module, why).
ENVIRONMENT_READS = {
    "assembler_pin/viz/server.py": "copies the environment for the viewer's server process",
}


def test_no_environment_variable_picks_a_code_path():
    """Nothing in the package reads ``os.environ`` / ``os.getenv`` to choose what to compute:
    every read is listed above with its reason (one engine per concern; a choice a user needs
    is one documented argument or configuration key)."""
    import ast
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    readers = set()
    for path in sorted((root / "assembler_pin").rglob("*.py")):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            name = node.attr if isinstance(node, ast.Attribute) else None
            if name in ("environ", "getenv") and isinstance(node.value, ast.Name) and node.value.id == "os":
                readers.add(path.relative_to(root).as_posix())
    assert readers <= set(ENVIRONMENT_READS), sorted(readers - set(ENVIRONMENT_READS))
