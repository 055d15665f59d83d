"""The README's Python examples run as written (so they cannot drift from the API)."""

from __future__ import annotations

import re
from pathlib import Path

README = Path(__file__).resolve().parents[1] / "README.md"


def test_readme_python_blocks_run():
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)
    assert blocks, "the README shows a Python example"
    namespaces = []
    for code in blocks:
        namespace: dict = {}
        exec(compile(code, str(README), "exec"), namespace)
        namespaces.append(namespace)
    # the API example: the statics of the default stack
    assert namespaces[0]["statics"].forces.shape == (4, 6)
    # the relaxed-limits example: optimizing on with relaxed limits never raises max|F|
    relaxed = next(ns for ns in namespaces if "relaxed" in ns)
    assert relaxed["more"].max_abs_force <= relaxed["ours"].max_abs_force + 1e-9


def test_readme_opens_with_the_two_setup_commands():
    text = README.read_text()
    first_blocks = re.findall(r"```bash\n(.*?)```", text, flags=re.S)[:2]
    assert first_blocks[0].strip().startswith("pip install -e .")
    assert first_blocks[1].strip() == 'pip install -e ".[test]" && python -m pytest'


def test_readme_picture_is_the_reproduce_figure():
    text = README.read_text()
    pictures = re.findall(r"!\[[^\]]*\]\(([^)]+)\)", text)
    assert pictures and pictures[0] == "docs/vertical_lift_views.png"
    assert (README.parent / pictures[0]).stat().st_size > 50_000
    assert "reproduce/vertical_lift_views.png" in text  # the command that makes it
    assert text.index("![") < text.index("```bash")  # the picture comes first
