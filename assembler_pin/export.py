"""Write the model files of a configuration: the stack URDF, its closure sidecar, the
helper arm's URDF and, on request, the MuJoCo MJCF (``assembler-pin export``)."""

from __future__ import annotations

import os
from pathlib import Path

from .common.files import write_atomic
from .config.schema import AssemblerConfig
from .exceptions import ArgumentError
from .helper_arm import HELPER_ARM_URDF_FILENAME, helper_arm_urdf
from .model.mjcf import MJCF_FILENAME, assembler_mjcf
from .model.urdf import SIDECAR_FILENAME, URDF_FILENAME, assembler_urdf, closure_sidecar

__all__ = ["export_model_files"]


def export_model_files(cfg: AssemblerConfig, out_dir: str | Path, mjcf: bool = False) -> dict[str, Path]:
    """Write the stack URDF, its closure sidecar and the helper arm's URDF into ``out_dir``;
    with ``mjcf``, also the MuJoCo model ``assembler.xml`` (:mod:`assembler_pin.model.mjcf`).

    Each file is written atomically (:func:`~assembler_pin.common.files.write_atomic`): an
    interrupted export leaves every file either as it was or complete.

    Returns:
        A mapping from file role (``urdf``, ``sidecar``, ``helper_arm``, ``mjcf``) to the
        written path.
    """
    if not isinstance(cfg, AssemblerConfig):
        raise ArgumentError(f"cfg must be an AssemblerConfig (load_config(...)), got {type(cfg).__name__}")
    if isinstance(out_dir, bytes) or not isinstance(out_dir, (str, os.PathLike)) or not str(out_dir):
        raise ArgumentError(f"out_dir must be a non-empty str or path, got {type(out_dir).__name__}")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = {
        "urdf": out / URDF_FILENAME,
        "sidecar": out / SIDECAR_FILENAME,
        "helper_arm": out / HELPER_ARM_URDF_FILENAME,
    }
    texts = {"urdf": assembler_urdf(cfg), "sidecar": closure_sidecar(cfg), "helper_arm": helper_arm_urdf(cfg)}
    if mjcf:
        paths["mjcf"] = out / MJCF_FILENAME
        texts["mjcf"] = assembler_mjcf(cfg)
    for role, text in texts.items():  # every text built first, then each file written atomically
        write_atomic(paths[role], text)
    return paths
