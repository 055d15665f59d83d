"""The compliant truss in the viewer: the loaded pose drawn exaggerated, the compliance ellipsoid.

Both are read back from the meshcat commands of the standalone page and held to computations
written here: the drawn plates to ``rigid + factor × (loaded − rigid)`` from the plates of
:func:`~assembler_pin.compliance.loaded_pose` (rotations scaled with SciPy's rotation vectors),
and the ellipsoid's semi-axes to the EE's sag in a second nonlinear equilibrium with a small
force added along each drawn axis (no use of the stiffness matrix).
"""

from __future__ import annotations

import re

import numpy as np
import pinocchio as pin
import pytest
from pages import page_commands, page_end_transforms
from scipy.spatial.transform import Rotation

from assembler_pin import loaded_pose
from assembler_pin.cli import main
from assembler_pin.common.naming import names
from assembler_pin.exceptions import ViewerError
from assembler_pin.kinematics import leg_state
from assembler_pin.viz import StackViewer, auto_exaggeration, compliance_ellipsoid

FACTOR = 200.0
FORCE = 100.0  # [N]


@pytest.fixture(scope="module")
def viewer(am):
    with StackViewer(am) as v:
        yield v


@pytest.fixture(scope="module")
def page(viewer, bent_plates):
    """The bent pose with its loaded pose (× FACTOR) and its ellipsoid (FORCE), as a page."""
    viewer.display(bent_plates)
    loaded = viewer.show_loaded(exaggerate=FACTOR)
    ellipsoid = viewer.show_ellipsoid(force=FORCE)
    return viewer.static_html(), loaded, ellipsoid


def _plate_visual_placements(am) -> dict[int, np.ndarray]:
    """Each plate disc's placement in its plate frame, from an independent parse of the URDF."""
    gmodel = pin.buildGeomFromUrdfString(am.model, am.urdf_text, pin.GeometryType.VISUAL)
    out = {}
    for g in gmodel.geometryObjects:
        frame = am.model.frames[g.parentFrame].name
        for k in range(am.n + 1):
            if frame == names.plate(k) and k not in out:
                out[k] = (g.name, g.placement.homogeneous)
    return out


def test_drawn_loaded_plates_are_rigid_plus_factor_times_the_displacement(am, bent_plates, page):
    html, _, _ = page
    rest = leg_state(am, bent_plates).lengths
    lp = loaded_pose(am, rest, base=bent_plates.se3(0))
    assert lp.success
    rigid, loaded = lp.rigid, lp.plates
    expected_p = rigid.p + FACTOR * (loaded.p - rigid.p)
    turn = Rotation.from_matrix(np.matmul(loaded.R, np.swapaxes(rigid.R, 1, 2))).as_rotvec()
    expected_R = np.matmul(Rotation.from_rotvec(FACTOR * turn).as_matrix(), rigid.R)
    drawn = page_end_transforms(html)
    for k, (geom, local) in _plate_visual_placements(am).items():
        T = drawn[f"/meshcat/assembler_loaded/visuals/{geom}"] @ np.linalg.inv(local)
        np.testing.assert_allclose(T[:3, 3], expected_p[k], atol=1e-9)
        np.testing.assert_allclose(T[:3, :3], expected_R[k], atol=1e-9)
    # the exaggeration shows: the EE plate is drawn millimetres away from the rigid one
    assert np.linalg.norm(expected_p[-1] - rigid.p[-1]) > 1e-3
    # and the rigid pose is the one drawn solid
    T_rigid = drawn[f"/meshcat/assembler/visuals/{_plate_visual_placements(am)[am.n][0]}"]
    np.testing.assert_allclose(T_rigid[:3, 3], bent_plates.p[-1], atol=1e-9)


def test_ellipsoid_semi_axes_are_the_sag_under_the_force(am, bent_plates, page):
    html, _, view = page
    (obj,) = [
        c["object"]
        for c in page_commands(html)
        if c["type"] == "set_object" and c["path"] == "/meshcat/assembler_compliance/ellipsoid"
    ]
    (place,) = [
        c["matrix"]
        for c in page_commands(html)
        if c["type"] == "set_transform" and c["path"] == "/meshcat/assembler_compliance/ellipsoid"
    ]
    shape = np.array(obj["object"]["matrix"]).reshape(4, 4).T  # column-major: the unit sphere's scaling
    T = np.array(place).reshape(4, 4).T
    semi = (T @ shape)[:3, :3]  # columns: the three semi-axis vectors [m], world axes
    np.testing.assert_allclose(T[:3, 3], bent_plates.p[-1], atol=1e-12)  # at the EE plate's origin
    np.testing.assert_allclose(np.linalg.norm(semi, axis=0), view.semi_axes, rtol=1e-12)  # as returned
    rest = leg_state(am, bent_plates).lengths
    base = loaded_pose(am, rest, base=bent_plates.se3(0))
    probe = 5.0  # [N]: small, so the response is linear
    for a in semi.T:
        u = a / np.linalg.norm(a)
        pushed = loaded_pose(am, rest, wrench=np.r_[probe * u, 0.0, 0.0, 0.0], base=bent_plates.se3(0))
        assert pushed.success
        sag = (pushed.translation - base.translation) * (FORCE / probe)  # the sag under FORCE along u
        np.testing.assert_allclose(np.linalg.norm(a), sag @ u, rtol=1e-3)
        assert np.linalg.norm(sag - (sag @ u) * u) < 1e-3 * np.linalg.norm(sag)  # a principal direction
    assert f"sag under {FORCE:g} N" in html and f"× {FACTOR:g}" in html


def test_cli_view_loaded_and_ellipsoid(tmp_path, capsys):
    page = tmp_path / "loaded.html"
    args = ["view", "--home", "--loaded", "--exaggerate", "300", "--ellipsoid", "--ellipsoid-force", "500"]
    assert main([*args, "--html", str(page)]) == 0
    err = capsys.readouterr().err
    assert "displacements × 300" in err and "sag under 500 N" in err
    html = page.read_text()
    paths = {c.get("path") for c in page_commands(html)}
    assert "/meshcat/assembler_compliance/ellipsoid" in paths
    assert any(str(p).startswith("/meshcat/assembler_loaded/visuals/") for p in paths)
    legend = re.findall(r"</span>([^<]+)<", html)
    assert any("loaded pose, displacements × 300" in t for t in legend)
    assert any("EE compliance ellipsoid: sag under 500 N" in t for t in legend)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (["--loaded", "--exaggerate", "0"], "--exaggerate must be a number in"),
        (["--loaded", "--exaggerate", "nan"], "--exaggerate must be a number in"),
        (["--loaded", "--exaggerate", "1e5"], "--exaggerate must be a number in"),
        (["--exaggerate", "10"], "--exaggerate needs --loaded"),
        (["--ellipsoid", "--ellipsoid-force", "-5"], "--ellipsoid-force must be a number in"),
        (["--ellipsoid", "--ellipsoid-force", "inf"], "--ellipsoid-force must be a number in"),
        (["--ellipsoid", "--ellipsoid-force", "1e7"], "--ellipsoid-force must be a number in"),
        (["--ellipsoid-force", "100"], "--ellipsoid-force needs --ellipsoid"),
    ],
)
def test_cli_view_refuses_bad_factors(tmp_path, capsys, extra, message):
    assert main(["view", "--home", *extra, "--html", str(tmp_path / "x.html")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err
    assert not (tmp_path / "x.html").exists()


def test_library_refuses_bad_factors_and_matrices(viewer, page):
    for bad in (0.0, -1.0, float("nan"), 1e9):
        with pytest.raises(ViewerError, match="exaggeration factor"):
            viewer.show_loaded(exaggerate=bad)
        with pytest.raises(ViewerError, match="ellipsoid force"):
            viewer.show_ellipsoid(force=bad)
    with pytest.raises(ViewerError, match="not positive definite"):
        compliance_ellipsoid(np.diag([1e-5, 1e-5, -1e-7]), 100.0, np.zeros(3))
    with pytest.raises(ViewerError, match="finite 3x3"):
        compliance_ellipsoid(np.full((3, 3), np.nan), 100.0, np.zeros(3))


def test_automatic_exaggeration_is_a_stated_round_factor():
    # 0.05 m / 6e-5 m = 833: the largest 1-2-5 number below it
    assert auto_exaggeration(6e-5) == 500.0
    assert auto_exaggeration(0.05) == 1.0 and auto_exaggeration(0.0) == 1.0
    assert auto_exaggeration(1e-12) == 1e4  # capped at the bound's upper end
    for d in np.geomspace(1e-7, 1e-2, 23):
        f = auto_exaggeration(d)
        assert f * d <= 0.05 * (1 + 1e-12) and f in {m * 10.0**e for m in (1, 2, 5) for e in range(5)}
