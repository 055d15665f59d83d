"""The stack turned around: modelled from its EE plate, so that plate n is the foothold.

The design is the same seen from either end: each plate carries the same three nodes, and a
platform turned upside down (``Rx(π)``, a node at angle α going to −α) is again a platform of
the design, up to a turn of its plate frames about z by a multiple of 60°. So the turned stack
is an :class:`~assembler_pin.model.AssemblerModel` of the package's own kind (its URDF, FK,
statics, helper arm and optimizer work unchanged) with:

* plate k of the turned model at the world pose of plate n−k of the original, times one
  constant ``flip = Rx(π) Rz(ψ)`` (ψ found by matching the joint centres, see
  :func:`turned_model`): the turned base is the physical EE plate, the turned EE the physical
  base plate;
* platform j' of the turned model = platform n−1−j' of the original, its legs in another order
  (:attr:`TurnedModel.permutation`), the motor and the shaft exchanged (a leg's motor now sits
  at its upper joint): the configuration's ``motor_mass``/``motor_com`` and
  ``shaft_mass``/``shaft_com`` exchanged;
* no payload: the payload stays on the physical EE plate, which the turned model holds (its
  weight goes straight into that support and loads no leg).

Held at its base, the turned model gives the leg forces of the original stack held at its EE
plate alone (support ``ee``), for the same physical pose and gravity.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from ..config.schema import AssemblerConfig, LegConfig, PayloadConfig
from ..constraints import Violation
from ..kinematics import PlateArrays, leg_vectors, plate_arrays
from ..model.assembler import AssemblerModel, checked_model

__all__ = ["TurnedModel", "turned_config", "turned_model"]

_EXCHANGED = {"deflection_bottom": "deflection_top", "deflection_top": "deflection_bottom"}

#: Largest distance [m] between a turned joint centre and the original one it stands for.
MATCH_TOLERANCE = 1e-9


def turned_config(cfg: AssemblerConfig) -> AssemblerConfig:
    """The configuration of the stack modelled from its EE plate: the same geometry, limits
    and plates, motor and shaft exchanged, no payload (module doc)."""
    leg: LegConfig = dataclasses.replace(
        cfg.leg,
        motor_mass=cfg.leg.shaft_mass,
        shaft_mass=cfg.leg.motor_mass,
        motor_com=cfg.leg.shaft_com,
        shaft_com=cfg.leg.motor_com,
    )
    return dataclasses.replace(cfg, leg=leg, payload=PayloadConfig(mass=0.0, offset=cfg.payload.offset))


@dataclass(frozen=True)
class TurnedModel:
    """The stack modelled from its EE plate (module doc).

    Attributes:
        model: the turned :class:`AssemblerModel` (its plate 0 is the original's plate n).
        original: the model it was turned from.
        flip: turned plate k's frame in original plate n−k's frame (a turn of π about x, then
            ψ about z).
        permutation: (n, 6) turned leg i' of turned platform j' is leg ``permutation[j', i']``
            of original platform n−1−j'.
    """

    model: AssemblerModel
    original: AssemblerModel
    flip: pin.SE3
    permutation: np.ndarray

    @property
    def n(self) -> int:
        return self.original.n

    def plates(self, plates: PlateArrays | Sequence | np.ndarray) -> PlateArrays:
        """Original plate poses (world) → the turned model's plates (the same bodies)."""
        pa = plate_arrays(self.original, plates)
        F = self.flip.rotation
        return PlateArrays(np.matmul(pa.R[::-1], F), pa.p[::-1].copy())

    def original_plates(self, turned: PlateArrays | Sequence | np.ndarray) -> PlateArrays:
        """The turned model's plate poses → the original's (the inverse of :meth:`plates`)."""
        ta = plate_arrays(self.model, turned)
        return PlateArrays(np.matmul(ta.R[::-1], self.flip.rotation.T), ta.p[::-1].copy())

    def original_legs(self, values: npt.ArrayLike) -> np.ndarray:
        """Per-leg values (..., n, 6) in the turned model's order → the original's order."""
        v = np.asarray(values, dtype=float)
        out = np.empty_like(v)
        for jp in range(self.n):
            out[..., self.n - 1 - jp, self.permutation[jp]] = v[..., jp, :]
        return out

    def original_violation(self, v: Violation) -> Violation:
        """A constraint violation of the turned model, named for the original's platform and
        leg (its bottom joint is the turned model's top joint)."""
        if v.platform is None:
            return v
        leg = None if v.leg is None else int(self.permutation[v.platform, v.leg])
        kind = _EXCHANGED.get(v.kind, v.kind)
        return dataclasses.replace(v, kind=kind, platform=self.n - 1 - v.platform, leg=leg)

    def turned_legs(self, values: npt.ArrayLike) -> np.ndarray:
        """Per-leg values (..., n, 6) in the original's order → the turned model's order."""
        v = np.asarray(values, dtype=float)
        out = np.empty_like(v)
        for jp in range(self.n):
            out[..., jp, :] = v[..., self.n - 1 - jp, self.permutation[jp]]
        return out


def _flip(psi: float) -> pin.SE3:
    return pin.SE3(pin.exp3(np.array([math.pi, 0.0, 0.0])) @ pin.exp3(np.array([0.0, 0.0, psi])), np.zeros(3))


def _permutation(original: AssemblerModel, turned: AssemblerModel, flip: pin.SE3) -> np.ndarray | None:
    """The legs' order in the turned model when ``flip`` maps every joint centre onto one of
    the original's (bottom onto top and top onto bottom), else None."""
    n = original.n
    pa = plate_arrays(original, original.home)
    ta = PlateArrays(np.matmul(pa.R[::-1], flip.rotation), pa.p[::-1].copy())
    bottom, top = leg_vectors(original, pa)[:2]
    t_bottom, t_top = leg_vectors(turned, ta)[:2]
    perm = np.empty((n, 6), dtype=int)
    for jp in range(n):
        j = n - 1 - jp
        gap = np.linalg.norm(t_bottom[jp][:, None] - top[j][None], axis=-1)
        gap += np.linalg.norm(t_top[jp][:, None] - bottom[j][None], axis=-1)
        best = gap.argmin(axis=1)
        if len(set(best.tolist())) < 6 or gap[np.arange(6), best].max() > MATCH_TOLERANCE:
            return None
        perm[jp] = best
    return perm


@lru_cache(maxsize=8)
def _turned_stack(cfg: AssemblerConfig) -> AssemblerModel:
    return AssemblerModel.from_config(turned_config(cfg))


def _turned(original: AssemblerModel) -> TurnedModel:
    model = _turned_stack(original.config)
    for k in range(6):
        flip = _flip(k * math.pi / 3.0)
        perm = _permutation(original, model, flip)
        if perm is not None:
            model.physical = (original, flip.rotation)  # its bodies are the original's (collisions)
            return TurnedModel(model, original, flip, perm)
    raise AssertionError("no turn of the plates about z maps the design onto itself")  # the design guarantees one


def turned_model(am: AssemblerModel) -> TurnedModel:
    """The stack ``am`` modelled from its EE plate (module doc); built once per model.

    The turn ψ about z is the multiple of 60° that maps every joint centre of the turned
    model, at the original's home pose, onto the original's own to :data:`MATCH_TOLERANCE`.
    """
    am = checked_model(am)
    key = id(am)
    held = _BUILT.get(key)
    if held is None or held.original is not am:
        if len(_BUILT) >= 8:
            _BUILT.pop(next(iter(_BUILT)))
        held = _BUILT[key] = _turned(am)
    return held


_BUILT: dict[int, TurnedModel] = {}
