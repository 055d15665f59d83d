"""Model loading from the URDF + sidecar: structure, order, errors."""

from __future__ import annotations

import numpy as np
import pytest

from assembler_pin import AssemblerModel, load_config
from assembler_pin.exceptions import ModelFileError
from assembler_pin.export import export_model_files


def test_model_structure(am):
    assert am.model.check(am.data)
    assert am.nq == 7 + am.n * (7 + 18) and am.nv == 6 + am.n * 24
    # depth-first: each platform's 18 leg coordinates, then the next plate's free-flyer
    for j in range(am.n):
        rows = am.platform_rows_v[j]
        assert np.array_equal(rows, np.arange(6 + 24 * j, 6 + 24 * (j + 1)))
    assert am.total_mass() == pytest.approx(9.36, rel=1e-12)


def test_from_files_equals_from_config(tmp_path):
    cfg = load_config({"platforms": 3, "payload": {"mass": 2.0}})
    export_model_files(cfg, tmp_path)
    a = AssemblerModel.from_files(tmp_path)
    b = AssemblerModel.from_config(cfg)
    assert a.config == cfg
    assert a.model.nq == b.model.nq
    for ia, ib in zip(a.model.inertias, b.model.inertias, strict=True):
        assert np.allclose(ia.toDynamicParameters(), ib.toDynamicParameters())


def test_bad_files(tmp_path):
    with pytest.raises(ModelFileError, match="cannot read"):
        AssemblerModel.from_files(tmp_path / "nothing.urdf")
    export_model_files(load_config(), tmp_path)
    side = tmp_path / "assembler.yaml"
    text = side.read_text()
    side.write_text(text.replace("type: [3d,", "type: [6d,", 1))
    with pytest.raises(ModelFileError, match="only type '3d'"):
        AssemblerModel.from_files(tmp_path)
    side.write_text("closed_loop: []\n")
    with pytest.raises(ModelFileError, match="must have the keys"):
        AssemblerModel.from_files(tmp_path)
    side.write_text(text.replace("sp1_leg2_top", "sp1_leg2_nowhere"))
    with pytest.raises(ModelFileError, match="not in the URDF"):
        AssemblerModel.from_files(tmp_path)
