"""The EE's sag of a solve's answer: the ``sag`` block of ``assembler-pin solve --json``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ..compliance.loaded import sag_and_gradient
from ..config.options import OptimizeOptions
from ..exceptions import SingularConfigurationError
from ..model.assembler import AssemblerModel
from ..state import StackState

__all__ = ["SagReport", "pose_sag", "sag_report"]


def pose_sag(am: AssemblerModel, state: StackState | None) -> dict[str, Any] | None:
    """The EE's linear sag of one pose under its own load (legs of stiffness
    ``leg.stiffness``, :func:`~assembler_pin.compliance.loaded.sag_and_gradient`):
    ``{"sag_m", "translation_m"}`` [m, world axes]; both None with a ``message`` where a
    platform is singular; None without a pose."""
    if state is None:
        return None
    try:
        s = sag_and_gradient(am, state.plates)
    except SingularConfigurationError as exc:
        return {"sag_m": None, "translation_m": None, "message": str(exc)}
    return {"sag_m": s.sag, "translation_m": s.translation.tolist()}


@dataclass(frozen=True)
class SagReport:
    """The EE's sag of a solve.

    Attributes:
        objective: the optimizer's objective (None without optimization).
        max_sag_m: its sag limit [m] (None: no limit or no optimization).
        stiffness_n_per_m: the legs' stiffness the sag is computed with [N/m].
        initial, answer: :func:`pose_sag` of the helper arm's pose and of the returned pose.
    """

    objective: str | None
    max_sag_m: float | None
    stiffness_n_per_m: float
    initial: dict[str, Any] | None
    answer: dict[str, Any] | None

    def to_dict(self) -> dict[str, Any]:
        """JSON: ``{"objective", "max_sag_m", "stiffness_n_per_m", "initial", "answer"}``."""
        return {
            "objective": self.objective,
            "max_sag_m": self.max_sag_m,
            "stiffness_n_per_m": self.stiffness_n_per_m,
            "initial": self.initial,
            "answer": self.answer,
        }


def sag_report(
    am: AssemblerModel, initial: StackState | None, answer: StackState | None, options: OptimizeOptions | None
) -> SagReport:
    """The :class:`SagReport` of the helper arm's pose ``initial`` and the returned pose
    ``answer`` (each None when there is none); ``options`` None without optimization."""
    first = pose_sag(am, initial)
    return SagReport(
        objective=options.objective if options is not None else None,
        max_sag_m=options.max_sag if options is not None else None,
        stiffness_n_per_m=float(am.config.leg.stiffness),
        initial=first,
        answer=first if answer is initial else pose_sag(am, answer),
    )
