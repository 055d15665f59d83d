"""The paths of the ``assembler-pin`` options: an empty path is a usage error, every input path
is checked (a regular file) and every output path probed (writable, named as typed) before any
work, and before the heavy imports of a subcommand.

Nothing heavy is imported here: the checks run at once.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

from ..exceptions import CLIError


def path_argument(text: str) -> str:
    """The ``type`` of every option that takes a path: an empty path is a usage error (it
    names no file: ``--scene ""`` is refused, never read as "no scene")."""
    if not text:
        raise argparse.ArgumentTypeError("an empty path names no file; give a file name")
    return text


def _probe_directory(directory: Path, shown: str, what: str) -> None:
    """Create and remove an empty file in ``directory``: the one sure test that the output can
    be written there (``os.access`` says yes to root in ``/proc``). A CLIError naming the
    option's path as typed when it cannot."""
    try:
        fd, name = tempfile.mkstemp(prefix=".assembler-pin-probe.", suffix=".tmp", dir=directory)
    except OSError as exc:
        raise CLIError(f"{what} '{shown}': cannot write in directory '{directory}': {exc.strerror or exc}") from None
    os.close(fd)
    os.unlink(name)


def _existing_ancestor(path: Path) -> Path:
    """``path`` itself when it exists, else its nearest ancestor that does ('.' at worst)."""
    for candidate in (path, *path.parents):
        if os.path.lexists(candidate):
            return candidate
    return Path(".")


def _writable_existing_parent(parent: Path, path: str, what: str) -> None:
    """``parent`` (of ``path``, as typed) exists, is a directory and can be written in; else a
    CLIError naming ``path`` and what is wrong with it."""
    found = _existing_ancestor(parent)
    if not found.is_dir():
        raise CLIError(f"{what} '{path}': '{found}' is not a directory")
    if found != parent:
        raise CLIError(f"{what} '{path}': directory '{parent}' does not exist")
    _probe_directory(parent, path, what)


def writable_parent(path: str, what: str) -> Path:
    """``path`` of an output file, checked before any work: its directory exists, is a
    directory and can be written in (probed), and ``path`` is not a directory; else a
    CLIError naming ``path`` as typed and what is wrong with it."""
    target = Path(path)
    parent = target.parent
    if target.is_dir() and what.endswith("file"):
        raise CLIError(f"{what} '{path}' is a directory")
    _writable_existing_parent(parent, path, what)
    return target


def writable_directory(path: str, what: str) -> Path:
    """``path`` of an output directory, checked before any work: an existing directory that
    can be written in, or a new one whose parent is such a directory (a mistyped parent is
    not made); else a CLIError naming ``path`` as typed and what is wrong with it."""
    target = Path(path)
    if os.path.lexists(target):
        if not target.is_dir():
            raise CLIError(f"{what} '{path}' is not a directory")
        _probe_directory(target, path, what)
        return target
    parent = target.parent
    _writable_existing_parent(parent, path, what)
    return target


#: The input options (their ``dest``) and what their file is called in a refusal.
INPUT_FILES = {
    "config": "config file",
    "scene": "scene file",
    "plates": "plate file",
    "footholds": "footholds file",
    "waypoints": "waypoint file",
    "trajectory": "trajectory",
    "sweep": "config file",
}
#: The output options (their ``dest``); ``--out`` names a directory for these subcommands.
OUTPUT_OPTIONS = ("out", "html", "png", "plot")
OUTPUT_DIRECTORIES = frozenset({"walk", "map", "export", "reproduce"})


def check_paths_first(args: argparse.Namespace) -> None:
    """Every path of the parsed ``args``, before the subcommand imports or computes anything:
    an input path names a regular file (:func:`~assembler_pin.config.inputs.checked_input_path`:
    a FIFO, a device or a directory is refused without being opened; ``-`` is stdin), an
    output path can be written (:func:`writable_parent`, :func:`writable_directory`).

    Raises:
        CLIError: one line naming the option's path as typed.
    """
    from ..config.inputs import checked_input_path

    for dest, what in INPUT_FILES.items():
        value = getattr(args, dest, None)
        for path in value if isinstance(value, list) else [value]:
            if path is not None and path != "-":
                checked_input_path(path, what, CLIError)
    command = getattr(args, "command", "")
    for dest in OUTPUT_OPTIONS:
        path = getattr(args, dest, None)
        if path is None or not isinstance(path, str):
            continue
        if dest == "out" and command in OUTPUT_DIRECTORIES:
            writable_directory(path, "--out directory")
        else:
            writable_parent(path, f"--{dest} file")
