"""The compliant truss in the viewer: the loaded pose, exaggerated, and the EE's compliance ellipsoid.

* :func:`loaded_view` — the elastic equilibrium of the legs commanded to a pose's lengths
  (:func:`~assembler_pin.compliance.loaded.loaded_pose`: gravity, payload, an optional EE wrench),
  drawn with every plate moved ``factor`` times its displacement from the rigid pose
  (:func:`exaggerated_plates`).
* :func:`ellipsoid_view` — the translational block ``C_vv`` (3×3) [m/N] of the EE's compliance
  at the EE plate's origin (:func:`~assembler_pin.compliance.ee_stiffness.stiffness`, world axes), drawn
  as the ellipsoid whose semi-axes lie along its principal directions with length
  ``force × c_i`` [m]: the EE's sag under ``force`` newtons along each principal direction.

World frame O, metres, newtons.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import meshcat.geometry as mg
import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..compliance.ee_stiffness import stiffness
from ..compliance.loaded import LoadedPose, loaded_pose
from ..config.bounds import check_bound
from ..exceptions import ConvergenceError, ViewerError
from ..kinematics import PlateArrays, leg_state
from ..model.assembler import AssemblerModel
from .colors import material

__all__ = [
    "AUTO_EXAGGERATION_TARGET",
    "EllipsoidView",
    "LoadedView",
    "auto_exaggeration",
    "compliance_ellipsoid",
    "draw_ellipsoid",
    "ellipsoid_view",
    "exaggerated_plates",
    "loaded_view",
]

AUTO_EXAGGERATION_TARGET = 0.05
"""With no factor given, the largest plate displacement is drawn about this long [m]."""


def exaggerated_plates(rigid: PlateArrays, loaded: PlateArrays, factor: float) -> PlateArrays:
    """Plates moved ``factor`` times their displacement from ``rigid`` to ``loaded``:
    ``p = p_r + factor (p_l − p_r)``, ``R = exp3(factor log3(R_l R_rᵀ)) R_r`` (world axes)."""
    p = rigid.p + factor * (loaded.p - rigid.p)
    R = np.stack([pin.exp3(factor * pin.log3(Rl @ Rr.T)) @ Rr for Rr, Rl in zip(rigid.R, loaded.R, strict=True)])
    return PlateArrays(R, p)


def auto_exaggeration(displacement: float, target: float = AUTO_EXAGGERATION_TARGET) -> float:
    """The largest 1-2-5 factor (1, 2, 5, 10, ...) that draws ``displacement`` [m] at most
    ``target`` [m] long, within the ``view.exaggerate`` bound (1 for no displacement)."""
    if not displacement > 0:
        return 1.0
    raw = target / displacement
    decade = 10.0 ** math.floor(math.log10(raw))
    factor = max(m * decade for m in (1.0, 2.0, 5.0) if m * decade <= raw * (1 + 1e-12))
    return min(max(factor, 1.0), 1e4)


@dataclass(frozen=True)
class LoadedView:
    """A drawn loaded pose: ``loaded`` the equilibrium (:class:`~assembler_pin.compliance.loaded.LoadedPose`),
    ``factor`` the exaggeration, ``plates`` the plates as drawn, ``largest`` the largest plate
    displacement before exaggeration [m]."""

    loaded: LoadedPose
    factor: float
    plates: PlateArrays
    largest: float


def loaded_view(
    am: AssemblerModel, plates: PlateArrays, factor: float | None = None, wrench: npt.ArrayLike | None = None
) -> LoadedView:
    """The loaded pose of the legs commanded to ``plates``' lengths, exaggerated by ``factor``
    (default :func:`auto_exaggeration`; checked against the ``view.exaggerate`` bound).

    Raises:
        ViewerError: a factor out of bounds. ConvergenceError: no loaded equilibrium (why named).
    """
    if factor is not None:
        factor = check_bound("view.exaggerate", factor, "exaggeration factor", ViewerError)
    lp = loaded_pose(am, leg_state(am, plates).lengths, wrench, base=plates.se3(0))
    if not lp.success:
        raise ConvergenceError(f"no loaded pose to draw: {lp.message}", lp.iterations, lp.residual)
    largest = float(np.linalg.norm(lp.plates.p - lp.rigid.p, axis=1).max())
    factor = auto_exaggeration(largest) if factor is None else factor
    return LoadedView(lp, factor, exaggerated_plates(lp.rigid, lp.plates, factor), largest)


@dataclass(frozen=True)
class EllipsoidView:
    """A drawn compliance ellipsoid.

    Attributes:
        center: (3,) the EE plate's origin [m].
        directions: (3, 3) principal directions (columns, a rotation), largest semi-axis first.
        semi_axes: (3,) ``force × c_i`` [m], descending: the sag under ``force`` along each.
        force: the stated force [N]; compliance: (3, 3) the translational block [m/N].
    """

    center: np.ndarray
    directions: np.ndarray
    semi_axes: np.ndarray
    force: float
    compliance: np.ndarray

    @property
    def extent(self) -> np.ndarray:
        """(6, 3) the ends of the three semi-axes, both sides [m] (for framing)."""
        tips = self.center + (self.directions * self.semi_axes).T
        return np.vstack([tips, 2 * self.center - tips])

    @property
    def label(self) -> str:
        """The legend's text: the stated force and the largest sag."""
        return f"EE compliance ellipsoid: sag under {self.force:g} N (up to {1e3 * self.semi_axes[0]:.3g} mm)"

    @property
    def transform(self) -> np.ndarray:
        """4×4 pose of the ellipsoid: its axes the principal directions, at the EE origin."""
        T = np.eye(4)
        T[:3, :3], T[:3, 3] = self.directions, self.center
        return T


def draw_ellipsoid(node, view: EllipsoidView, rgba: npt.ArrayLike) -> None:
    """Draw ``view`` at the meshcat ``node``: meshcat's unit sphere scaled by the semi-axes
    (its ``intrinsic_transform``), then turned onto the principal directions and moved."""
    node.set_object(mg.Ellipsoid(view.semi_axes), material(rgba))
    node.set_transform(view.transform)


def compliance_ellipsoid(compliance: npt.ArrayLike, force: float, center: npt.ArrayLike) -> EllipsoidView:
    """The ellipsoid of a 3×3 translational compliance [m/N] under ``force`` [N] at ``center``.

    Raises:
        ViewerError: a force out of the ``view.ellipsoid_force`` bound, or a compliance that is
            not finite and positive definite.
    """
    force = check_bound("view.ellipsoid_force", force, "ellipsoid force", ViewerError)
    C = np.asarray(compliance, dtype=float)
    if C.shape != (3, 3) or not np.all(np.isfinite(C)):
        raise ViewerError(f"the translational compliance must be a finite 3x3 matrix, got shape {C.shape}")
    c, V = np.linalg.eigh(0.5 * (C + C.T))
    if not c[0] > 0:
        raise ViewerError(f"the translational compliance is not positive definite (eigenvalues {c.tolist()} m/N)")
    c, V = c[::-1], V[:, ::-1]
    if np.linalg.det(V) < 0:
        V[:, 2] = -V[:, 2]
    return EllipsoidView(np.asarray(center, dtype=float).copy(), V, force * c, force, C)


def ellipsoid_view(am: AssemblerModel, plates: PlateArrays, force: float = 100.0) -> EllipsoidView:
    """The EE's compliance ellipsoid at ``plates`` (legs commanded to their lengths), centred
    at the EE plate's origin of ``plates``.

    Raises:
        ViewerError: a force out of bounds. ConvergenceError: no stiffness (why named).
    """
    check_bound("view.ellipsoid_force", force, "ellipsoid force", ViewerError)
    result = stiffness(am, plates)
    if not result.success:
        raise ConvergenceError(f"no compliance ellipsoid to draw: {result.message}", result.iterations, math.nan)
    return compliance_ellipsoid(result.compliance[:3, :3], force, plates.p[-1])
