"""``assembler-pin export``: the model files."""

from __future__ import annotations

import argparse
from pathlib import Path

from .common import config_from_args
from .paths import path_argument, writable_directory


def add_parser(add) -> None:
    """Register the ``export`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("export", "write assembler.urdf, its closure sidecar assembler.yaml and the helper arm's URDF")
    p.add_argument("--out", type=path_argument, default="urdf", metavar="DIR", help="output directory (default: urdf)")
    p.add_argument("--mjcf", action="store_true", help="also write assembler.xml, the MuJoCo model (loops closed)")
    p.add_argument(
        "--hexapod",
        action="store_true",
        help="also write hexapod.xml: the config's hexapod in MuJoCo, its feet resting on a floor",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..export import export_model_files

    writable_directory(args.out, "--out directory")
    cfg = config_from_args(args)
    hexapod = hexapod_text(cfg) if args.hexapod else None  # refused before any file is written
    paths = export_model_files(cfg, args.out, mjcf=args.mjcf)
    if hexapod is not None:
        from ..common.files import write_atomic

        paths["hexapod"] = write_atomic(Path(args.out) / HEXAPOD_FILENAME, hexapod)
    for role, path in paths.items():
        print(f"wrote {role}: {path}")
    return 0


#: The hexapod's MJCF file name (``export --hexapod``).
HEXAPOD_FILENAME = "hexapod.xml"


def hexapod_text(cfg) -> str:
    """The text of ``hexapod.xml``: the configuration's hexapod
    (:func:`~assembler_pin.hexapod.configured_hexapod`, stacks without a tool: the body is the
    load) with resting feet (:func:`~assembler_pin.hexapod.mjcf.hexapod_mjcf`)."""
    from ..config.schema import PayloadConfig
    from ..hexapod import configured_hexapod
    from ..hexapod.mjcf import hexapod_mjcf
    from ..model.assembler import AssemblerModel

    am = AssemblerModel.from_config(cfg.replace(payload=PayloadConfig(mass=0.0)))
    stacks, mass, com = configured_hexapod(am)
    return hexapod_mjcf(am, stacks, mass, com, feet="resting")
