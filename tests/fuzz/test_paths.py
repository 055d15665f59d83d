"""Every path a command or a reader takes, hostile: empty, a FIFO nobody writes, a device, a
directory; an output under a regular file, in a missing directory or in ``/proc``.

Each is refused in one line (exit status 2 at the command line, an
:class:`~assembler_pin.exceptions.AssemblerError` through the API), naming the path as typed.
An input that is not a regular file is refused before it is opened (a FIFO never blocks the
read); an output path is checked before any work (the model is never built).
"""

from __future__ import annotations

import argparse
import os
import stat
from pathlib import Path

import pytest

import assembler_pin as ap
from assembler_pin.cli.app import build_parser
from assembler_pin.cli.paths import path_argument
from assembler_pin.collision.scene import read_scene

from .harness import judge_cli, run_cli, watchdog

#: Seconds a refusal may take before the watchdog calls it a hang (a blocked FIFO read).
REFUSAL_TIMEOUT = 20.0
#: The metavars of the options that name a file or a directory.
PATH_METAVARS = {"FILE", "DIR", "PNG", "PAGE", "FILE.png"}


def _subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(sub.choices)


def _path_options() -> list[tuple[str, str]]:
    """(subcommand, option) of every option read as a path, from the parser itself."""
    return [
        (name, action.option_strings[-1])
        for name, p in _subparsers().items()
        for action in p._actions
        if action.type is path_argument
    ]


PATH_OPTIONS = _path_options()


def test_every_option_naming_a_file_or_directory_is_read_as_a_path():
    """An option whose metavar names a file or directory has ``type=path_argument`` (its
    empty value is refused), and there are some of every kind."""
    missing = [
        f"{name} {action.option_strings[-1]}"
        for name, p in _subparsers().items()
        for action in p._actions
        if action.metavar in PATH_METAVARS and action.type is not path_argument
    ]
    assert not missing, missing
    options = {option for _, option in PATH_OPTIONS}
    assert {"--config", "--scene", "--plates", "--out", "--html", "--png", "--plot", "--sweep"} <= options


@pytest.mark.parametrize(("command", "option"), PATH_OPTIONS, ids=[f"{c}{o}" for c, o in PATH_OPTIONS])
def test_an_empty_path_is_a_usage_error(command, option):
    outcome = run_cli([command, option, ""], timeout=REFUSAL_TIMEOUT)
    judge_cli(outcome, "refuse", f"{command} {option} ''")
    assert f"argument {option}" in outcome.err and "an empty path names no file" in outcome.err, outcome.err


@pytest.mark.parametrize("read", [ap.load_config, read_scene])
def test_an_empty_path_is_refused_by_the_api_too(read):
    with pytest.raises(ap.AssemblerError, match="must not be empty"):
        read("")


# ---------------------------------------------------------------------- inputs that are not files


@pytest.fixture(scope="module")
def odd_files(tmp_path_factory) -> dict[str, Path]:
    """A FIFO nobody writes, a device and a directory."""
    root = tmp_path_factory.mktemp("odd")
    fifo = root / "fifo.yaml"
    if not hasattr(os, "mkfifo"):
        pytest.skip("no named pipes here")
    os.mkfifo(fifo)
    assert stat.S_ISFIFO(fifo.stat().st_mode)
    return {"fifo": fifo, "device": Path("/dev/zero"), "directory": root}


#: Every input option, its subcommand's arguments before it, and the file kind it names.
INPUTS = [
    ("statics --home --config", "config file"),
    ("statics --home --scene", "scene file"),
    ("statics --json --plates", "plate file"),
    ("support --plates", "plate file"),
    ("walk --footholds", "footholds file"),
    ("plan --waypoints", "waypoint file"),
    ("simulate --trajectory", "trajectory"),
    ("view --trajectory", "trajectory"),
    ("map --workers 0 --grid x=5,y=0,z=0.5 --out {d}/map --sweep", "config file"),
]


@pytest.mark.parametrize("kind", ["fifo", "device", "directory"])
@pytest.mark.parametrize(("argv", "what"), INPUTS, ids=[a.split(" -")[0] + a.rsplit(" ", 1)[-1] for a, _ in INPUTS])
def test_an_input_that_is_not_a_regular_file_is_refused_before_it_is_opened(odd_files, tmp_path, argv, what, kind):
    path = odd_files[kind]
    args = [a.replace("{d}", str(tmp_path)) for a in argv.split()] + [str(path)]
    outcome = run_cli(args, timeout=REFUSAL_TIMEOUT)
    judge_cli(outcome, "refuse", " ".join(args))
    assert "not a regular file" in outcome.err and what in outcome.err, outcome.err


def _api_readers(tmp_path: Path) -> dict[str, object]:
    from assembler_pin.cli.plate_file import plates_from_file
    from assembler_pin.maps.store import read_manifest
    from assembler_pin.motion.paths import read_waypoints
    from assembler_pin.walk.footholds import read_footholds
    from assembler_pin.walk.samples import read_walk_csv

    return {
        "load_config": ap.load_config,
        "read_scene": read_scene,
        "read_footholds": read_footholds,
        "read_waypoints": read_waypoints,
        "read_trajectory": ap.read_trajectory,
        "read_walk_csv": read_walk_csv,
        "plates_from_file": plates_from_file,
        "model sidecar": lambda p: ap.AssemblerModel.from_files(tmp_path / "model", sidecar_path=p),
        "model urdf": ap.AssemblerModel.from_files,
        "map manifest": lambda p: read_manifest(_map_dir_with_manifest(tmp_path, p)),
    }


def _map_dir_with_manifest(tmp_path: Path, manifest: Path) -> Path:
    """A map directory whose map.json is a link to ``manifest``."""
    d = tmp_path / "map"
    d.mkdir(exist_ok=True)
    link = d / "map.json"
    if link.is_symlink():
        link.unlink()
    link.symlink_to(manifest)
    return d


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_every_reader_refuses_a_fifo_or_a_device_without_blocking(odd_files, tmp_path, kind):
    """Through the API: a FIFO nobody writes would block ``open`` forever; each reader refuses
    it (and ``/dev/zero``, endless) in one line instead, under the watchdog."""
    ap.export.export_model_files(ap.load_config(), tmp_path / "model")
    for name, read in _api_readers(tmp_path).items():
        with watchdog(REFUSAL_TIMEOUT), pytest.raises(ap.AssemblerError) as info:
            read(odd_files[kind])  # type: ignore[operator]
        line = str(info.value)
        assert "not a regular file" in line and "\n" not in line and len(line) < 400, (name, line)


def test_a_file_swapped_for_a_fifo_after_the_check_is_refused_on_its_descriptor(odd_files, monkeypatch):
    """The door checks the opened descriptor again (a FIFO opened without blocking)."""
    from assembler_pin.config import inputs

    monkeypatch.setattr(inputs, "checked_input_path", lambda path, what, error, shown=None: Path(path))
    with watchdog(REFUSAL_TIMEOUT), pytest.raises(ap.exceptions.ConfigError, match="FIFO"):
        inputs.read_input_bytes(odd_files["fifo"], "config file", ap.exceptions.ConfigError, 1000)


# ---------------------------------------------------------------------- outputs

#: (the subcommand's arguments, the output option, the name it writes, a file or a directory)
OUTPUTS = [
    ("solve --goal 0.02 0.01 0.85 0 0 0", "--out", "x.json", "file"),
    ("plan --to 0 0 0.956 0 0 0", "--out", "x.csv", "file"),
    ("plan --to 0 0 0.956 0 0 0", "--plot", "x.png", "file"),
    ("walk --floor 0.3 3", "--out", "w", "directory"),
    ("walk --floor 0.3 3", "--html", "x.html", "file"),
    ("walk --floor 0.3 3", "--plot", "x.png", "file"),
    ("map --workers 0 --grid x=5,y=0,z=0.5", "--out", "m", "directory"),
    ("map --workers 0 --grid x=5,y=0,z=0.5 --out {d}/map", "--png", "x.png", "file"),
    ("map --workers 0 --grid x=5,y=0,z=0.5 --out {d}/map", "--html", "x.html", "file"),
    ("view --home", "--html", "x.html", "file"),
    ("simulate --home", "--html", "x.html", "file"),
    ("export", "--out", "e", "directory"),
    ("reproduce --scenario translation", "--out", "r", "directory"),
    ("stiffness --scaling", "--out", "x.png", "file"),
    ("hexapod stand", "--html", "x.html", "file"),
    ("hexapod stand", "--plot", "x.png", "file"),
    ("hexapod walk --to 0.05 0 0", "--out", "w.json", "file"),
]


def test_every_output_option_has_its_cases():
    outputs = {(c, o) for c, o in PATH_OPTIONS if o in ("--out", "--html", "--png", "--plot")}
    assert outputs == {(a.split()[0], o) for a, o, _, _ in OUTPUTS}


@pytest.fixture
def no_work(monkeypatch):
    """Building a model is the work: a refusal must come before it (exit 70 otherwise)."""

    def refuse(*args, **kwargs):
        raise AssertionError("the work started before the output path was checked")

    monkeypatch.setattr(ap.AssemblerModel, "from_config", refuse)


def _places(tmp_path: Path, name: str, kind: str) -> dict[str, tuple[str, str]]:
    """place -> (the path typed, the words its refusal must hold)."""
    (tmp_path / "afile").write_text("a regular file\n")
    (tmp_path / "adir").mkdir()
    (tmp_path / "adir" / name).mkdir()
    places = {
        "under_a_file": (f"{tmp_path}/afile/{name}", f"'{tmp_path}/afile' is not a directory"),
        "missing_directory": (f"{tmp_path}/nodir/{name}", f"directory '{tmp_path}/nodir' does not exist"),
    }
    if os.path.isdir("/proc"):
        places["proc"] = (f"/proc/{name}", "cannot write in directory '/proc'")
    if kind == "file":
        places["a_directory"] = (f"{tmp_path}/adir/{name}", f"'{tmp_path}/adir/{name}' is a directory")
    else:
        places["a_file"] = (f"{tmp_path}/afile", f"'{tmp_path}/afile' is not a directory")
    return places


@pytest.mark.parametrize(
    ("argv", "option", "name", "kind"), OUTPUTS, ids=[f"{a.split()[0]}{o}" for a, o, *_ in OUTPUTS]
)
def test_an_unwritable_output_is_refused_before_the_work_named_as_typed(tmp_path, no_work, argv, option, name, kind):
    for place, (typed, words) in _places(tmp_path, name, kind).items():
        args = [a.replace("{d}", str(tmp_path)) for a in argv.split()] + [option, typed]
        outcome = run_cli(args, timeout=REFUSAL_TIMEOUT)
        judge_cli(outcome, "refuse", f"{place}: {' '.join(args)}")
        assert f"'{typed}'" in outcome.err and words in outcome.err and ".tmp" not in outcome.err, (place, outcome.err)


def test_a_failed_atomic_write_names_the_target_not_its_temporary_file(tmp_path):
    from assembler_pin.common.files import write_atomic

    target = tmp_path / "afile" / "x.json"
    (tmp_path / "afile").write_text("")
    with pytest.raises(OSError) as info:
        write_atomic(target, "{}")
    assert info.value.filename == str(target)
