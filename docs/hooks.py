"""MkDocs hooks: pages made at build time from the repository, so they cannot go stale.

- ``notebooks/<name>.md``: each notebook of ``notebooks/`` rendered as its markdown and code
  cells (the notebooks are stored without outputs; the test suite executes them).
- ``api/<module>.md``: one page per module or subpackage of ``assembler_pin``, each a
  mkdocstrings ``::: assembler_pin.<module>`` block (the docstrings are the reference).
- ``api/index.md``: the names ``import assembler_pin as ap`` offers, read from the package's
  ``__init__.py``, each with the module that defines it.

The nav entries ``Notebooks`` and ``API reference`` of mkdocs.yml are filled with these pages.
"""

from __future__ import annotations

import ast
import json
import re
from pathlib import Path

from mkdocs.structure.files import File, Files

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = "assembler_pin"
NOTEBOOKS = ROOT / "notebooks"
REPO_NOTEBOOKS = "notebooks"  # as a path in the repository


def notebook_markdown(path: Path) -> str:
    """A notebook as markdown: its markdown cells as they are, its code cells as Python blocks."""
    nb = json.loads(path.read_text(encoding="utf-8"))
    parts = []
    for cell in nb["cells"]:
        source = "".join(cell["source"]).strip()
        if not source:
            continue
        parts.append(f"```python\n{source}\n```" if cell["cell_type"] == "code" else source)
    note = (
        f"!!! note\n    Rendered from `{REPO_NOTEBOOKS}/{path.name}`, stored without outputs: open it in Jupyter"
        f" to see them. The test suite executes it (`python -m pytest {REPO_NOTEBOOKS}/{path.name}`)."
    )
    # the notebook's own title first, then the note
    if parts and parts[0].startswith("# "):
        title, _, rest = parts[0].partition("\n")
        return "\n\n".join([title, note, rest.strip(), *parts[1:]]).rstrip() + "\n"
    return "\n\n".join([f"# {path.stem}", note, *parts]).rstrip() + "\n"


def api_modules() -> dict[str, list[str]]:
    """Top-level module or subpackage of the package -> the dotted modules its page shows."""
    pkg = ROOT / PACKAGE
    groups: dict[str, list[str]] = {}
    for path in sorted(pkg.iterdir()):
        if path.name.startswith("_") or path.name.startswith("."):
            continue
        if path.suffix == ".py":
            groups[path.stem] = [f"{PACKAGE}.{path.stem}"]
        elif path.is_dir() and (path / "__init__.py").exists():
            subs = sorted(
                ".".join((PACKAGE, *p.relative_to(pkg).with_suffix("").parts))
                for p in path.rglob("*.py")
                if not p.name.startswith("_")
            )
            groups[path.name] = [f"{PACKAGE}.{path.name}", *subs]
    return groups


def api_page(name: str, modules: list[str]) -> str:
    """The API page of one module, or of a subpackage and each of its modules."""
    head, *subs = modules
    lines = [f"# `{head}`", ""]
    if not subs:
        lines += [f"::: {head}", "    options:", "      show_root_heading: false", ""]
        return "\n".join(lines)
    lines += [f"::: {head}", "    options:", "      show_root_heading: false", "      members: false", ""]
    for mod in subs:
        lines += [f"::: {mod}", "    options:", "      show_root_heading: true", "      heading_level: 2", ""]
    return "\n".join(lines)


def public_names() -> list[tuple[str, str]]:
    """(name, defining module) for each name imported into the package's ``__init__.py``."""
    tree = ast.parse((ROOT / PACKAGE / "__init__.py").read_text(encoding="utf-8"))
    listed: set[str] | None = None
    found: dict[str, str] = {}
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.level == 1 and node.module:
            for alias in node.names:
                if not (alias.asname or alias.name).startswith("_"):
                    found[alias.asname or alias.name] = f"{PACKAGE}.{node.module}"
        if isinstance(node, ast.Assign) and any(isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets):
            try:
                listed = set(ast.literal_eval(node.value))
            except ValueError:
                listed = None  # computed at import time: every imported name counts
    return sorted((n, m) for n, m in found.items() if listed is None or n in listed)


def _describe(package, module: str, name: str, page_of: dict[str, str]) -> tuple[str, str]:
    """A link to where ``module.name`` is documented, and its docstring's first line."""
    import griffe

    try:
        obj = package[f"{module.removeprefix(PACKAGE + '.')}.{name}"]
        canonical = obj.canonical_path
        doc = obj.docstring.value.strip().splitlines()[0] if obj.docstring else ""
        doc = re.sub(r":\w+:`~?([^`]+)`", r"`\1`", doc)  # Sphinx roles as code
    except (KeyError, AttributeError, griffe.AliasResolutionError):
        canonical, doc = f"{module}.{name}", ""
    owner = canonical.rpartition(".")[0]
    top = next((page_of[m] for m in (owner, module) if m in page_of), None)
    if top is None:
        return f"`{canonical}`", doc
    anchor = f"#{canonical}" if doc else ""
    return f"[<code>{dotted_breaks(canonical)}</code>]({top}.md{anchor})", doc


def dotted_breaks(path: str) -> str:
    """A dotted name with a line-break opportunity (``<wbr>``) after each dot: a narrow column
    breaks it between its parts, never inside one (docs/stylesheets/extra.css)."""
    return path.replace(".", ".<wbr>")


def api_index(groups: dict[str, list[str]]) -> str:
    """The API reference's first page: the top-level names and the module pages."""
    import griffe

    package = griffe.load(PACKAGE, search_paths=[str(ROOT)])
    page_of = {mod: name for name, mods in groups.items() for mod in mods}
    rows = ["| name | defined in | what it is |", "| --- | --- | --- |"]
    for name, module in public_names():
        where, doc = _describe(package, module, name, page_of)
        doc = doc.replace("|", r"\|")
        rows.append(f"| `{name}` | {where} | {doc} |")
    pages = "\n".join(f"- [`{PACKAGE}.{name}`]({name}.md)" for name in groups)
    return (
        "# API reference\n\n"
        "Generated from the docstrings (mkdocstrings). Units and frames are given in each\n"
        "docstring; the conventions they share are on the [Conventions](../conventions.md) page.\n\n"
        "## The top-level names\n\n"
        "`import assembler_pin as ap` offers these names (imported on first use, so that\n"
        "`import assembler_pin` stays light); everything else is one level down.\n\n"
        + "\n".join(rows)
        + "\n\n## Modules\n\n"
        + pages
        + "\n"
    )


def _generated(config, files: Files, uri: str, content: str) -> None:
    files.append(File.generated(config, uri, content=content))


def on_files(files: Files, config) -> Files:
    groups = api_modules()
    _generated(config, files, "api/index.md", api_index(groups))
    for name, modules in groups.items():
        _generated(config, files, f"api/{name}.md", api_page(name, modules))
    for path in sorted(NOTEBOOKS.glob("*.ipynb")):
        _generated(config, files, f"notebooks/{path.stem}.md", notebook_markdown(path))
    return files


def on_config(config):
    """Fill the ``Notebooks`` and ``API reference`` nav sections with the generated pages."""
    groups = api_modules()
    fill = {
        "API reference": ["api/index.md", *(f"api/{name}.md" for name in groups)],
        "Notebooks": [f"notebooks/{p.stem}.md" for p in sorted(NOTEBOOKS.glob("*.ipynb"))],
    }
    for item in config["nav"] or []:
        if isinstance(item, dict):
            for key in item:
                if key in fill:
                    item[key] = fill[key]
    return config
