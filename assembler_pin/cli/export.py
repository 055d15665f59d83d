"""``assembler-pin export``: the model files."""

from __future__ import annotations

import argparse

from .common import config_from_args
from .paths import path_argument, writable_directory


def add_parser(add) -> None:
    """Register the ``export`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("export", "write assembler.urdf, its closure sidecar assembler.yaml and the helper arm's URDF")
    p.add_argument("--out", type=path_argument, default="urdf", metavar="DIR", help="output directory (default: urdf)")
    p.add_argument("--mjcf", action="store_true", help="also write assembler.xml, the MuJoCo model (loops closed)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from ..export import export_model_files

    writable_directory(args.out, "--out directory")
    cfg = config_from_args(args)
    paths = export_model_files(cfg, args.out, mjcf=args.mjcf)
    for role, path in paths.items():
        print(f"wrote {role}: {path}")
    return 0
