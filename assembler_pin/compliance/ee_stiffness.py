"""The end effector's stiffness: the Assembler as a compliant truss (legs as springs).

:func:`stiffness` answers, for plate poses commanded by their leg lengths, how far gravity and
the payload make the EE sag and how stiff it is there: the 6×6 tangent stiffness of the EE
plate, the Hessian of the total potential (:mod:`assembler_pin.compliance.elastic`) at the loaded
equilibrium, with the intermediate plates' 6(n−1) coordinates condensed out (static
condensation: the EE loaded, every other plate free).

Conventions: twists and wrenches ``[v, ω]`` / ``[f, m]`` in world axes at the EE plate's
origin; stiffness [N/m, N/rad; N·m/m, N·m/rad], compliance its inverse; the sag is the EE's
loaded pose against its rigid pose (the pose the lengths give with rigid legs): translation
[m] and rotation vector ``log3(R_loaded R_rigidᵀ)`` [rad], world axes.

Split: ``elastic`` is the condensed ``Σ k ∇L ∇Lᵀ`` (the legs' axial springs alone, exactly the
serial sum of the platforms' compliances ``Jⱼ⁻¹ Jⱼ⁻ᵀ / k`` moved to the EE); ``geometric`` =
``stiffness − elastic`` is what the loads add: the legs' preload times the curvature of their
lengths, the legs' own weight, and the lever arms of the payload and leg forces.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..common.linalg import skew
from ..common.validation import as_float_array
from ..config.bounds import check_bound
from ..exceptions import LoadError, PoseError
from ..kinematics import PlateArrays, plate_arrays
from ..model.assembler import AssemblerModel, checked_model
from ..statics.closed_form import CONDITION_LIMIT
from .elastic import Equilibrium, elastic_terms, line_conditions, solve_equilibrium

__all__ = ["StiffnessResult", "elastic_compliance", "platform_compliances", "stiffness", "stiffness_from_equilibrium"]

_AXES = ("x", "y", "z")


@dataclass(frozen=True)
class StiffnessResult:
    """The EE's stiffness at the loaded equilibrium of a commanded pose (module docstring).

    Attributes:
        stiffness, compliance: (6, 6) tangent stiffness and its inverse, ``[v, ω]`` order.
        elastic, geometric: (6, 6) the legs' springs alone, and what the loads add.
        platform_compliance: (n, 6, 6) each platform's elastic compliance moved to the EE
            (they sum to ``inv(elastic)``).
        platform_share: (n,) each platform's part of the elastic compliance along the
            weakest direction (sums to 1).
        translational_stiffness: (3,) principal stiffnesses under a pure force [N/m],
            ascending; translational_directions: (3, 3) their unit directions (columns).
        rotational_stiffness: (3,) under a pure moment [N·m/rad]; rotational_axes (3, 3).
        sag_translation, sag_rotation: (3,) the EE's loaded pose from its rigid pose [m, rad].
        plates: the loaded plate poses; forces: (n, 6) leg forces there [N, tension positive].
        condition: (n,) 1-norm condition number of each platform's leg lines (as the statics).
        leg_stiffness: k [N/m]; iterations: Newton steps of the loaded equilibrium.
        success: the equilibrium converged, is stable and no platform is singular;
            message: "ok" or why not (then every matrix is NaN).
    """

    stiffness: np.ndarray
    compliance: np.ndarray
    elastic: np.ndarray
    geometric: np.ndarray
    platform_compliance: np.ndarray
    platform_share: np.ndarray
    translational_stiffness: np.ndarray
    translational_directions: np.ndarray
    rotational_stiffness: np.ndarray
    rotational_axes: np.ndarray
    sag_translation: np.ndarray
    sag_rotation: np.ndarray
    plates: PlateArrays
    forces: np.ndarray
    condition: np.ndarray
    leg_stiffness: float
    iterations: int
    success: bool
    message: str

    @property
    def weakest_stiffness(self) -> float:
        """The smallest principal stiffness under a pure force [N/m]."""
        return float(self.translational_stiffness[0])

    @property
    def weakest_direction(self) -> np.ndarray:
        """Its unit direction, world axes (the sign puts its largest component positive)."""
        return self.translational_directions[:, 0]

    @property
    def weakest_name(self) -> str:
        """``lateral`` (within 10° of the xy plane), ``vertical`` (within 10° of z) or ``oblique``,
        with the nearest world axis, e.g. ``lateral (x)``; ``lateral (any direction)`` when the
        two weakest are equal (to 1e-6) and span the xy plane (the home pose's symmetry)."""
        d = self.weakest_direction
        if not np.all(np.isfinite(d)):
            return "undefined"
        t, dirs = self.translational_stiffness, self.translational_directions
        if t[1] <= t[0] * (1 + 1e-6) and abs(float(np.cross(dirs[:, 0], dirs[:, 1])[2])) > math.cos(math.radians(10)):
            return "lateral (any direction)"
        tilt = math.degrees(math.asin(min(1.0, abs(float(d[2])))))
        kind = "lateral" if tilt < 10.0 else "vertical" if tilt > 80.0 else "oblique"
        return f"{kind} ({_AXES[int(np.argmax(np.abs(d)))]})"

    def __repr__(self) -> str:
        if not self.success:
            return f"StiffnessResult(success=False, message={self.message!r})"
        return (
            f"StiffnessResult({len(self.forces)} platforms, weakest {self.weakest_stiffness:.4g} N/m "
            f"{self.weakest_name}, sag {1e3 * float(np.linalg.norm(self.sag_translation)):.4f} mm, "
            f"{self.iterations} Newton steps)"
        )

    def to_dict(self) -> dict:
        """The JSON of ``assembler-pin stiffness --json`` (NaN as null through ``dumps``)."""
        return {
            "success": self.success,
            "message": self.message,
            "leg_stiffness": self.leg_stiffness,
            "stiffness": self.stiffness.tolist(),
            "compliance": self.compliance.tolist(),
            "elastic": self.elastic.tolist(),
            "geometric": self.geometric.tolist(),
            "sag": {"translation": self.sag_translation.tolist(), "rotation": self.sag_rotation.tolist()},
            "principal": {
                "translational": {
                    "stiffness": self.translational_stiffness.tolist(),
                    "directions": self.translational_directions.T.tolist(),
                },
                "rotational": {
                    "stiffness": self.rotational_stiffness.tolist(),
                    "axes": self.rotational_axes.T.tolist(),
                },
            },
            "weakest": {
                "stiffness": self.weakest_stiffness,
                "direction": self.weakest_direction.tolist(),
                "name": self.weakest_name,
            },
            "platform_share": self.platform_share.tolist(),
            "leg_forces": self.forces.tolist(),
            "loaded_plates": self.plates.as_matrices().tolist(),
            "condition": self.condition.tolist(),
            "iterations": self.iterations,
            "units": {
                "stiffness": "[v, w] order, world axes at the EE origin: N/m, N/rad; N m/m, N m/rad",
                "sag": "translation m, rotation rad (rotation vector), world axes",
            },
        }


def _principal(C: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Principal stiffnesses (ascending) and unit directions (columns) of the translation and
    rotation blocks of a 6×6 compliance; each direction's largest component is positive."""
    blocks = np.stack([C[:3, :3], C[3:, 3:]])
    w, v = np.linalg.eigh(0.5 * (blocks + np.swapaxes(blocks, 1, 2)))  # compliance ascending
    w, v = w[:, ::-1], v[:, :, ::-1]
    big = np.take_along_axis(v, np.abs(v).argmax(axis=1)[:, None, :], axis=1)
    v = v * np.where(big < 0, -1.0, 1.0)
    with np.errstate(divide="ignore"):
        k = np.where(w > 0, 1.0 / np.where(w > 0, w, 1.0), np.inf)
    return k[0], v[0], k[1], v[1]


def _failed(am: AssemblerModel, pa: PlateArrays, k: float, cond: np.ndarray, its: int, message: str) -> StiffnessResult:
    n = am.n
    nan6, nan3, nan33 = np.full((6, 6), np.nan), np.full(3, np.nan), np.full((3, 3), np.nan)
    return StiffnessResult(
        nan6,
        nan6,
        nan6,
        nan6,
        np.full((n, 6, 6), np.nan),
        np.full(n, np.nan),
        nan3,
        nan33,
        nan3,
        nan33,
        nan3,
        nan3,
        pa,
        np.full((n, 6), np.nan),
        cond,
        k,
        its,
        False,
        message,
    )


def _transport(p_from: np.ndarray, p_ee: np.ndarray) -> np.ndarray:
    """(m, 6, 6) maps of small plate motions ``(δp, δθ)`` at ``p_from`` (m, 3) to the EE's."""
    X = np.zeros((p_from.shape[0], 6, 6))
    X[:, :3, :3] = X[:, 3:, 3:] = np.eye(3)
    X[:, :3, 3:] = -skew(p_ee - p_from)
    return X


def platform_compliances(lines: np.ndarray, J_inv: np.ndarray, p: np.ndarray, k: float) -> np.ndarray:
    """(n, 6, 6) each platform's elastic compliance ``J⁻¹ J⁻ᵀ / k`` at its top plate, moved to
    the EE origin (world axes, ``[v, ω]``): ``lines`` (n, 6, 6) the legs' lines, ``J_inv`` their
    inverses, ``p`` (n+1, 3) the plate origins [m], ``k`` [N/m]. They sum to the stack's."""
    XJ = np.matmul(_transport(p[1:], p[-1]), J_inv)
    return np.matmul(XJ, np.swapaxes(XJ, 1, 2)) / k


def elastic_compliance(am: AssemblerModel, plates: PlateArrays | Sequence | np.ndarray) -> np.ndarray:
    """(6, 6) the EE's compliance of the legs' springs alone at the pose ``plates`` (no loads,
    no equilibrium: ``Σ k ∇L ∇Lᵀ`` condensed), world axes at the EE origin, ``[v, ω]`` [m/N,
    rad/N; m/(N·m), rad/(N·m)]; NaN when a platform is singular."""
    pa = plate_arrays(am, plates)
    k = float(am.config.leg.stiffness)
    lines = elastic_terms(am, pa.R, pa.p, None, k, hessian=False).lines
    J_inv, cond = line_conditions(lines)
    if not cond.max() <= CONDITION_LIMIT:
        return np.full((6, 6), np.nan)
    return platform_compliances(lines, J_inv, pa.p, k).sum(axis=0)


def stiffness(
    am: AssemblerModel,
    plates: PlateArrays | Sequence | np.ndarray,
    lengths: npt.ArrayLike | None = None,
    tol: float = 1e-12,
) -> StiffnessResult:
    """The EE's tangent stiffness at the loaded equilibrium of the legs commanded to ``plates``.

    ``plates``: world poses of plates 0..n, or a state carrying them (``result.optimized``).
    The legs (springs of ``leg.stiffness``) are commanded to the lengths of ``plates`` (or to
    ``lengths`` [m], e.g. :func:`~assembler_pin.compliance.loaded.compensated_lengths`, whose loaded
    equilibrium is ``plates`` itself); gravity and the payload load them; Newton finds the
    loaded equilibrium from ``plates`` and the Hessian there is condensed onto the EE.

    Returns:
        A :class:`StiffnessResult`; ``success`` false (NaN matrices) when a platform is singular
        (leg-line condition number above :data:`~assembler_pin.statics.closed_form.CONDITION_LIMIT`), the
        equilibrium does not converge or is not stable.

    Raises:
        PoseError: malformed plates or lengths. LoadError: ``tol`` out of bounds (``elastic.tol``).
    """
    if not all(hasattr(am, a) for a in ("config", "n", "geometry", "home")):  # the truss of scaling passes
        checked_model(am)
    check_bound("elastic.tol", tol, "tol", LoadError)
    pa = plate_arrays(am, plates)
    k = float(am.config.leg.stiffness)
    rest = None if lengths is None else _checked_lengths(am, lengths)
    eq = solve_equilibrium(am, pa.R, pa.p, rest, k, tol=tol, condition_limit=CONDITION_LIMIT)
    return stiffness_from_equilibrium(am, pa, eq, k)


def _checked_lengths(am: AssemblerModel, lengths: npt.ArrayLike) -> np.ndarray:
    arr = as_float_array(lengths, "commanded leg lengths", (am.n, 6))
    if not np.all(np.isfinite(arr)) or not arr.min() > 0:
        raise PoseError("commanded leg lengths must be finite and > 0 [m]")
    return arr


def stiffness_from_equilibrium(am: AssemblerModel, rigid: PlateArrays, eq: Equilibrium, k: float) -> StiffnessResult:
    """The :class:`StiffnessResult` of a solved equilibrium ``eq`` of the commanded pose ``rigid``."""
    loaded = PlateArrays(eq.R, eq.p)
    terms = eq.terms
    J_inv, cond = line_conditions(terms.lines)
    why = eq.message
    if why is None and not cond.max() <= CONDITION_LIMIT:
        j = int(np.argmax(cond))
        why = f"the loaded pose puts platform {j} at a singular configuration (condition number {cond[j]:.3g})"
    if why is None and not eq.stable:
        why = "the loaded equilibrium is not stable (its tangent stiffness is not positive definite): the stack buckles"
    if why is not None:
        return _failed(am, loaded, k, cond, eq.iterations, why)
    C = 0.5 * (eq.compliance + eq.compliance.T)
    K = np.linalg.inv(C)
    K = 0.5 * (K + K.T)
    platform_c = platform_compliances(terms.lines, J_inv, eq.p, k)
    K_el = np.linalg.inv(platform_c.sum(axis=0))
    K_el = 0.5 * (K_el + K_el.T)
    t_stiff, t_dirs, r_stiff, r_axes = _principal(C)
    weak = t_dirs[:, 0]
    along = np.einsum("a,jab,b->j", weak, platform_c[:, :3, :3], weak)
    sag = (eq.p[-1] - rigid.p[-1], pin.log3(eq.R[-1] @ rigid.R[-1].T))
    parts = (K, C, K_el, K - K_el, platform_c, along / along.sum(), t_stiff, t_dirs, r_stiff, r_axes, *sag)
    return StiffnessResult(*parts, loaded, terms.tension.copy(), cond, k, eq.iterations, True, "ok")
