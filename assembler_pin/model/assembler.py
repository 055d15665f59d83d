"""Load the Assembler into Pinocchio: model, data, closure constraints, actuation map.

:class:`AssemblerModel` is built from the generated URDF + closure sidecar — the same
files a user gets from ``assembler-pin export`` — and holds everything that does not
change with the pose: the Pinocchio ``model``, the point-anchor closure constraints and
index maps. Per-pose computations live in :mod:`assembler_pin.kinematics` and
:mod:`assembler_pin.statics.pinocchio_statics`; they take an ``AssemblerModel`` and never write into a
``Data`` it holds: the statics run on per-platform models that own their ``Data``, or on a
whole-stack ``Data`` the caller creates (:meth:`AssemblerModel.create_data`) and passes.

The base (plate 0) is mounted by a free-flyer root joint: its pose in the world is a
coordinate of ``q`` and its generalized gravity is the wrench the mount must supply.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from ..common.naming import names
from ..config.schema import AssemblerConfig, PayloadConfig, load_config, load_yaml, read_text_file
from ..exceptions import ArgumentError, ConfigError, ModelFileError, short_repr
from .geometry import LEGS_PER_PLATFORM, LegGeometry, home_plates, leg_geometry
from .platform import PlatformModel, StackPlan
from .urdf import SIDECAR_FILENAME, URDF_FILENAME, assembler_urdf, closure_sidecar
from .urdf_check import parse_urdf, urdf_disagreements

__all__ = ["WHOLE_DATA_MAX_PLATFORMS", "AssemblerModel", "Closure", "checked_model"]

#: Largest stack whose whole-stack Pinocchio ``Data`` is created (its size grows as nv² and nv³).
WHOLE_DATA_MAX_PLATFORMS = 8

logger = logging.getLogger(__name__)


@dataclass(frozen=True)
class Closure:
    """One ball-joint loop closure read from the sidecar.

    Attributes:
        shaft_frame, anchor_frame: the two frame names the sidecar pairs.
        platform, leg: indices (j, i) of the leg it closes.
    """

    shaft_frame: str
    anchor_frame: str
    platform: int
    leg: int


@dataclass
class AssemblerModel:
    """The Pinocchio model of an Assembler and the index maps around it.

    Build with :meth:`from_config` or :meth:`from_files`. Attributes:

    * ``config``: the :class:`AssemblerConfig`; ``n``: number of platforms.
    * ``model``: the whole-stack Pinocchio model (free-flyer root), the exported format;
      :meth:`create_data` makes a ``Data`` of it for a caller (stacks up to 8 platforms),
      ``data`` is one kept for inspection (no computation uses it).
    * ``platform_models``: the per-platform models the statics run on
      (:mod:`~assembler_pin.model.platform`).
    * ``constraint_models`` / ``constraint_datas``: the 6n point-anchor closures as
      ``pin.StdVec_ConstraintModel`` / ``StdVec_ConstraintData``, ordered ``[j, i]``.
    * ``geometry``: :class:`~assembler_pin.model.geometry.LegGeometry`.
    * ``plate_joint_ids`` (n+1): joint of plate k (root free-flyer for plate 0).
    * ``plate_idx_q`` / ``plate_idx_v`` (n+1): first q / v index of each plate joint.
    * ``leg_idx_q`` / ``leg_idx_v`` (n, 6, 3): q / v indices of (ux, uy, actuator).
    * ``platform_rows_v`` (n, 24): v indices of SP j's leg joints then plate j+1's
      free-flyer — the rows of SP j's statics block.
    * ``plate_joint_placement`` (n+1): placement of each plate joint in its parent.
    * ``shaft_joint_ids`` (n, 6): joint carrying each shaft (the actuator joint).
    """

    config: AssemblerConfig
    model: pin.Model
    closures: list[Closure]
    urdf_text: str
    _data: pin.Data | None = field(default=None, init=False, repr=False)
    platform_models: tuple[PlatformModel, PlatformModel] = field(init=False, repr=False)
    """The models every computation runs on: (inner platforms, last platform with the payload)."""
    stack_plan: StackPlan = field(init=False, repr=False)
    """Their constants for this stack (:class:`~assembler_pin.model.platform.StackPlan`)."""
    physical: tuple[AssemblerModel, np.ndarray] | None = field(default=None, init=False, repr=False)
    """Set when this model is another stack seen from its other end
    (:func:`~assembler_pin.supports.turned.turned_model`): that stack, and the constant rotation
    of each of its plate frames into this model's (plate k here is plate n−k there). The
    bodies' sizes and their clearance are that stack's."""

    def __repr__(self) -> str:
        return (
            f"AssemblerModel({self.n} platforms, {6 * self.n} legs, nq={self.model.nq}, nv={self.model.nv}, "
            f"{len(self.closures)} closures, payload {self.config.payload.mass} kg)"
        )

    def __post_init__(self) -> None:
        cfg, model = self.config, self.model
        n = cfg.platforms
        self.n = n
        self.platform_models = (
            PlatformModel(cfg, PayloadConfig(mass=0.0, offset=cfg.payload.offset)),
            PlatformModel(cfg, cfg.payload),
        )
        self.stack_plan = StackPlan(*self.platform_models, n)
        self.geometry: LegGeometry = leg_geometry(cfg)
        # row map a ↦ [a, t × a] of each top anchor t (plate frame): (n, 6, 3, 6)
        self.top_line_map = np.concatenate(
            [
                np.broadcast_to(np.eye(3), (*self.geometry.top_in_plate.shape[:2], 3, 3)),
                np.array([[pin.skew(t).T for t in sp] for sp in self.geometry.top_in_plate]),
            ],
            axis=3,
        )
        self.top_anchor_homogeneous = np.concatenate(
            [self.geometry.top_in_plate, np.ones((*self.geometry.top_in_plate.shape[:2], 1))], axis=2
        )
        model.gravity.linear = np.array([0.0, 0.0, -cfg.gravity])

        def joint(name: str) -> int:
            if not model.existJointName(name):
                raise ModelFileError(f"the URDF has no joint '{name}'; is it an Assembler URDF?")
            return model.getJointId(name)

        self.plate_joint_ids = np.array([1] + [joint(names.plate_joint(j)) for j in range(n)])
        self.plate_idx_q = np.array([model.idx_qs[int(k)] for k in self.plate_joint_ids])
        self.plate_idx_v = np.array([model.idx_vs[int(k)] for k in self.plate_joint_ids])
        self.plate_joint_placement = [model.jointPlacements[int(k)].copy() for k in self.plate_joint_ids]
        self.plate_placement_R = np.array([m.rotation for m in self.plate_joint_placement[1:]])
        self.plate_placement_p = np.array([m.translation for m in self.plate_joint_placement[1:]])
        parts = ("ux", "uy", "actuator")
        leg_ids = np.array(
            [[[joint(names.leg(j, i, p)) for p in parts] for i in range(LEGS_PER_PLATFORM)] for j in range(n)]
        )
        self.leg_idx_q = np.vectorize(lambda k: model.idx_qs[int(k)])(leg_ids)
        self.leg_idx_v = np.vectorize(lambda k: model.idx_vs[int(k)])(leg_ids)
        self.shaft_joint_ids = leg_ids[:, :, 2]
        self.platform_rows_v = np.concatenate(
            [self.leg_idx_v.reshape(n, 18), self.plate_idx_v[1:, None] + np.arange(6)[None, :]], axis=1
        )
        self.plate_rows_ff = self.plate_idx_v[1:, None] + np.arange(6)
        self.fk_home_inverse_jacobian = self._home_inverse_jacobians()
        self.fk_jacobian_map = self._fk_jacobian_maps()
        self._check_order()
        self._build_constraints()
        self.home = home_plates(cfg)

    # ------------------------------------------------------------------ builders
    @classmethod
    def from_config(cls, config: AssemblerConfig | str | Path | dict | None = None) -> AssemblerModel:
        """Generate the URDF + sidecar of ``config`` in memory and load them.

        Args:
            config: an :class:`AssemblerConfig`, a YAML path, a mapping, or None (defaults).
        """
        cfg = load_config(config)
        return cls._from_texts(assembler_urdf(cfg), closure_sidecar(cfg), "<generated>", check=False)

    @classmethod
    def from_files(cls, urdf_path: str | Path, sidecar_path: str | Path | None = None) -> AssemblerModel:
        """Load an exported ``assembler.urdf`` and its closure sidecar.

        The two files must agree: every mass, inertia, centre of mass, joint origin, joint
        limit and the platform count of the URDF are compared with what the sidecar's
        ``assembler_config`` gives (:mod:`~assembler_pin.model.urdf_check`, relative tolerance 1e-9).

        Args:
            urdf_path: the URDF file, or a directory holding ``assembler.urdf``.
            sidecar_path: the sidecar; default ``assembler.yaml`` beside the URDF.

        Raises:
            ModelFileError: a file is missing, unreadable or malformed, does not describe an
                Assembler, or the two files disagree (one line naming the quantities and both values).
        """
        urdf_path = Path(urdf_path)
        if urdf_path.is_dir():
            urdf_path = urdf_path / URDF_FILENAME
        sidecar_path = Path(sidecar_path) if sidecar_path else urdf_path.with_name(SIDECAR_FILENAME)
        urdf_text = _read_model_file(urdf_path)
        sidecar_text = _read_model_file(sidecar_path)
        return cls._from_texts(urdf_text, sidecar_text, sidecar_path.name)

    @classmethod
    def _from_texts(cls, urdf_text: str, sidecar_text: str, origin: str, check: bool = True) -> AssemblerModel:
        sidecar, cfg = _read_sidecar(sidecar_text, origin)
        if check:
            given = parse_urdf(urdf_text, "the URDF")
            why = urdf_disagreements(given, parse_urdf(assembler_urdf(cfg), "the generated URDF"))
            if why is not None:
                raise ModelFileError(f"the URDF and the sidecar {origin} disagree: {why}")
        closures, name_mot = _sidecar_closures(sidecar, cfg, origin)
        try:
            model = pin.buildModelFromXML(urdf_text, pin.JointModelFreeFlyer())
        except (RuntimeError, ValueError) as exc:
            raise ModelFileError(f"Pinocchio cannot parse the URDF: {' '.join(str(exc).split())[:150]}") from None
        expected_mot = [names.leg(j, i, "actuator") for j in range(cfg.platforms) for i in range(6)]
        if name_mot != expected_mot:
            raise ModelFileError(
                f"closure sidecar {origin}: name_mot must list the {len(expected_mot)} actuators "
                f"{expected_mot[0]} .. {expected_mot[-1]} in order"
            )
        return cls(cfg, model, closures, urdf_text)

    def _home_inverse_jacobians(self) -> np.ndarray:
        """(n, 6, 6): home-pose twist of each top plate per unit leg-length change, in the
        bottom plate's frame (left perturbation): the inverse of the rows ``[u_i, b_i × u_i]``."""
        geo = self.geometry
        u = geo.home_direction
        rows = np.concatenate([u, np.cross(geo.bottom_in_plate, u)], axis=2)
        return np.linalg.inv(rows)

    def _fk_jacobian_maps(self) -> np.ndarray:
        """(n, 36, 18): per platform, the linear map from the leg vectors ``v`` (6, 3),
        flattened, to the FK Newton matrix ``2 [v_i, b_i × v_i]`` (6, 6), flattened."""
        out = np.zeros((self.n, 6, 6, 6, 3))
        for j, anchors in enumerate(self.geometry.bottom_in_plate):
            for i, b in enumerate(anchors):
                out[j, i, :3, i] = 2.0 * np.eye(3)
                out[j, i, 3:, i] = 2.0 * pin.skew(b)
        return out.reshape(self.n, 36, 18)

    def _check_order(self) -> None:
        """The configuration layout the kinematics rely on: the root free-flyer (7), then per
        platform j its legs' (ux, uy, actuator) for legs 0..5 and plate j+1's free-flyer
        (25 coordinates) — depth-first, legs before the next plate — and plate free-flyers
        whose home placement is a pure translation (plates parallel at home)."""
        for j in range(self.n):
            if self.leg_idx_v[j].max() > self.plate_idx_v[j + 1]:
                raise ModelFileError(
                    f"joint order: the legs of platform {j} must come before joint "
                    f"'{names.plate_joint(j)}' in the URDF (depth-first order)"
                )
        block = 7 + 25 * np.arange(self.n)
        expected_legs = block[:, None, None] + 3 * np.arange(6)[None, :, None] + np.arange(3)[None, None, :]
        if not (np.array_equal(self.leg_idx_q, expected_legs) and np.array_equal(self.plate_idx_q[1:], block + 18)):
            raise ModelFileError(
                "joint order: each platform's legs 0..5 (ux, uy, actuator) must be followed by the "
                "next plate's floating joint, depth-first from plate 0"
            )
        if not np.allclose(self.plate_placement_R, np.eye(3), atol=1e-12):
            raise ModelFileError("the plates' floating joints must have a pure translation as origin (home pose)")

    def _build_constraints(self) -> None:
        model = self.model
        self.constraint_models = pin.StdVec_ConstraintModel()
        self.anchor_frame_ids = np.zeros((self.n, 6), dtype=int)
        for c in self.closures:
            for frame in (c.shaft_frame, c.anchor_frame):
                if not model.existFrame(frame):
                    raise ModelFileError(f"closure frame '{frame}' is not in the URDF")
            shaft = model.frames[model.getFrameId(c.shaft_frame)]
            anchor_id = model.getFrameId(c.anchor_frame)
            anchor = model.frames[anchor_id]
            self.anchor_frame_ids[c.platform, c.leg] = anchor_id
            if shaft.parentJoint != self.shaft_joint_ids[c.platform, c.leg]:
                raise ModelFileError(f"closure frame '{c.shaft_frame}' is not the leg's shaft")
            if anchor.parentJoint != self.plate_joint_ids[c.platform + 1]:
                raise ModelFileError(f"closure frame '{c.anchor_frame}' is not on the top plate")
            cm = pin.PointAnchorConstraintModel(
                model, shaft.parentJoint, shaft.placement, anchor.parentJoint, anchor.placement
            )
            self.constraint_models.append(pin.ConstraintModel(cm))
        self.constraint_datas = pin.StdVec_ConstraintData()
        for cm in self.constraint_models:
            self.constraint_datas.append(cm.createData())

    # ------------------------------------------------------------------ helpers
    def create_data(self) -> pin.Data:
        """A new Pinocchio ``Data`` of the whole-stack model, owned by the caller (pass it to
        :func:`~assembler_pin.statics.engine.solve_statics` as ``data``, or use it to inspect the
        model). Refused above :data:`WHOLE_DATA_MAX_PLATFORMS` platforms, where it takes
        gigabytes.

        Raises:
            ConfigError: the stack has more than :data:`WHOLE_DATA_MAX_PLATFORMS` platforms.
        """
        if self.n > WHOLE_DATA_MAX_PLATFORMS:
            raise ConfigError(
                f"the whole-stack Pinocchio data of {self.n} platforms (nv = {self.model.nv}) would take "
                f"gigabytes; it is available up to {WHOLE_DATA_MAX_PLATFORMS} platforms"
            )
        return self.model.createData()

    @property
    def data(self) -> pin.Data:
        """A Pinocchio ``Data`` of the whole-stack model for interactive inspection, created on
        first use (:meth:`create_data`) and kept on the model.

        No computation of the package reads or writes it: they run on :attr:`platform_models`
        or on a ``Data`` their caller passes.

        Raises:
            ConfigError: the stack has more than :data:`WHOLE_DATA_MAX_PLATFORMS` platforms.
        """
        if self._data is None:
            self._data = self.create_data()
        return self._data

    @property
    def nq(self) -> int:
        return self.model.nq

    @property
    def nv(self) -> int:
        return self.model.nv

    def total_mass(self) -> float:
        """Mass of every body of the stack, payload included [kg]."""
        return float(sum(inertia.mass for inertia in self.model.inertias))


def checked_model(am: object, what: str = "am") -> AssemblerModel:
    """``am`` when it is an :class:`AssemblerModel`, else :class:`ArgumentError` naming ``what``."""
    if not isinstance(am, AssemblerModel):
        raise ArgumentError(
            f"{what} must be an AssemblerModel (AssemblerModel.from_config(...)), the first argument; "
            f"got {type(am).__name__}"
        )
    return am


#: Largest model file read [bytes] (the URDF of 64 platforms is about 2 MB).
MAX_MODEL_FILE_BYTES = 64 << 20


def _read_model_file(path: Path) -> str:
    """The UTF-8 text of a URDF or sidecar file (at most :data:`MAX_MODEL_FILE_BYTES`)."""
    return read_text_file(path, path.name, "model file", MAX_MODEL_FILE_BYTES, ModelFileError)


def _string_list(sidecar: dict, key: str, origin: str, pairs: bool = False) -> list:
    value = sidecar[key]
    item_ok = (
        (lambda x: isinstance(x, list) and len(x) == 2 and all(isinstance(y, str) for y in x))
        if pairs
        else (lambda x: isinstance(x, str))
    )
    if not isinstance(value, list) or not all(item_ok(x) for x in value):
        shape = "a list of [shaft frame, anchor frame] name pairs" if pairs else "a list of names"
        raise ModelFileError(f"closure sidecar {origin}: {key} must be {shape}, got {short_repr(value, 40)}")
    return value


def _read_sidecar(text: str, origin: str) -> tuple[dict, AssemblerConfig]:
    """The mapping of a closure sidecar's text and its configuration.

    Raises:
        ModelFileError: invalid YAML (aliases and duplicate keys included), a key missing,
            or an invalid assembler_config.
    """
    try:
        sidecar = load_yaml(text, f"closure sidecar {origin}")
    except ConfigError as exc:
        raise ModelFileError(str(exc)) from None
    required = ("closed_loop", "type", "name_mot", "assembler_config")
    if not isinstance(sidecar, dict) or not set(required[:3]) <= set(sidecar):
        raise ModelFileError(f"closure sidecar {origin} must have the keys {', '.join(required)}")
    if "assembler_config" not in sidecar or not isinstance(sidecar["assembler_config"], dict):
        raise ModelFileError(
            f"closure sidecar {origin}: assembler_config must be the mapping of the configuration the files were "
            "generated from (write both files with 'assembler-pin export')"
        )
    try:
        cfg = load_config(sidecar["assembler_config"])
    except ConfigError as exc:
        raise ModelFileError(f"closure sidecar {origin}: assembler_config: {exc}") from None
    return sidecar, cfg


def _sidecar_closures(sidecar: dict, cfg: AssemblerConfig, origin: str) -> tuple[list[Closure], list[str]]:
    """The closures and actuator names of a sidecar (ModelFileError: wrong types or counts,
    a closure that is not ``3d``)."""
    pairs = _string_list(sidecar, "closed_loop", origin, pairs=True)
    types = _string_list(sidecar, "type", origin)
    name_mot = _string_list(sidecar, "name_mot", origin)
    if len(pairs) != len(types) or len(pairs) != 6 * cfg.platforms:
        raise ModelFileError(
            f"closure sidecar {origin}: expected {6 * cfg.platforms} closures with one type "
            f"each, got {len(pairs)} pairs and {len(types)} types"
        )
    closures = []
    for c, (pair, kind) in enumerate(zip(pairs, types, strict=True)):
        if kind.lower() != "3d":
            raise ModelFileError(
                f"closure {short_repr(pair, 60)}: only type '3d' is supported, got {short_repr(kind, 20)}"
            )
        closures.append(Closure(pair[0], pair[1], c // 6, c % 6))
    return closures, name_mot
