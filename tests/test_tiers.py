"""The test tiers: the slow list names real tests, test file names are unique (the list names a
file without its folder), and every tier marker is registered."""

from __future__ import annotations

import ast
from pathlib import Path
from types import SimpleNamespace

import pytest
from conftest import SLOW_LIST, read_slow_list, tier_markers

ROOT = Path(__file__).parents[1]
TIERS = ("slow", "browser", "mujoco", "dask", "notebook")


def _test_names(path: Path) -> set[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"))
    return {n.name for n in ast.walk(tree) if isinstance(n, ast.FunctionDef) and n.name.startswith("test_")}


def _test_files() -> dict[str, list[Path]]:
    """Test file name -> the files of tests/ with that name."""
    files: dict[str, list[Path]] = {}
    for path in sorted((ROOT / "tests").rglob("test_*.py")):
        files.setdefault(path.name, []).append(path)
    return files


def test_test_file_names_are_unique():
    twice = {name: [str(p.relative_to(ROOT)) for p in paths] for name, paths in _test_files().items() if len(paths) > 1}
    assert not twice, f"test file names must be unique across tests/ (the slow list names files by name): {twice}"


def test_every_slow_entry_names_a_test_that_exists():
    entries = read_slow_list()
    assert entries, f"{SLOW_LIST} is empty"
    files = _test_files()
    names: dict[str, set[str]] = {}
    for entry in sorted(entries):
        file, _, test = entry.partition("::")
        assert test and "/" not in file, f"{entry}: expected <file>.py::<test> (the file name without its folder)"
        assert file in files, f"{entry}: no file {file} under tests/"
        names.setdefault(file, _test_names(files[file][0]))
        assert test.split("[", 1)[0] in names[file], f"{entry}: no such test in {file}"


def test_tier_markers_are_registered_and_applied(request):
    registered = {line.split(":", 1)[0].strip() for line in request.config.getini("markers")}
    assert set(TIERS) <= registered
    assert "--strict-markers" in (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    # this very item went through the hook: a fast test of tests/, no tier of its own
    assert not {m.name for m in request.node.iter_markers()} & set(TIERS)


@pytest.mark.parametrize(
    ("nodeid", "expected"),
    [
        ("tests/simulate/test_mujoco.py::test_x", ["mujoco"]),
        ("tests/maps/test_maps.py::test_map_on_dask[2]", ["dask"]),
        ("tests/maps/test_maps.py::test_grid", []),
        ("tests/viz/test_viewer.py::test_page_in_a_real_browser", ["browser"]),
        ("notebooks/quickstart.ipynb", ["notebook", "slow"]),
    ],
)
def test_markers_by_module_and_name(nodeid, expected):
    file, _, name = nodeid.partition("::")
    item = SimpleNamespace(path=ROOT / file, nodeid=nodeid, name=name or file)
    assert tier_markers(item, set()) == expected
    # the slow list marks by file name and test name, a bare name every parametrization, in
    # whichever folder the file is
    entry = f"{Path(file).name}::{name}" if name else Path(file).name
    assert "slow" in tier_markers(item, {entry}) and "slow" in tier_markers(item, {entry.split("[")[0]})
    moved = SimpleNamespace(path=ROOT / "tests" / "elsewhere" / Path(file).name, nodeid=nodeid, name=item.name)
    assert "slow" in tier_markers(moved, {entry})
