"""Exceptions raised by assembler_pin.

Every error the package raises on purpose derives from :class:`AssemblerError`, so a
caller can catch one type. Messages say what was wrong and what is allowed.
"""

from __future__ import annotations

#: Longest repr of a user's value quoted in a message [characters].
REPR_LIMIT = 60


def short_repr(value: object, limit: int = REPR_LIMIT) -> str:
    """``repr(value)`` on one line, cut to ``limit`` characters (a huge value never makes a
    huge message)."""
    try:
        text = repr(value)
    except Exception:
        text = f"<{type(value).__name__}>"
    text = " ".join(text.split())
    return text if len(text) <= limit else text[: limit - 1] + "…"


class AssemblerError(Exception):
    """Root of every error raised on purpose by assembler_pin."""


class ConfigError(AssemblerError, ValueError):
    """A configuration value, key or file is invalid."""


class PoseError(AssemblerError, ValueError):
    """A pose, a list of plate poses or a vector of leg lengths is malformed."""


class ArgumentError(AssemblerError, TypeError):
    """An API argument of the wrong type (the message names the argument and what is allowed)."""


class ModelFileError(AssemblerError):
    """A URDF or closure sidecar file is missing or does not describe an Assembler."""


class ConvergenceError(AssemblerError, RuntimeError):
    """A numerical solve (e.g. forward kinematics) did not converge.

    Attributes:
        iterations: iterations spent.
        residual: final residual norm, in the units of the solve ([m] for FK).
    """

    def __init__(self, message: str, iterations: int = 0, residual: float = float("nan")):
        super().__init__(message)
        self.iterations = iterations
        self.residual = residual


class SingularConfigurationError(AssemblerError, RuntimeError):
    """The statics of a pose cannot be solved reliably (a near-singular platform).

    Attributes:
        condition_number: the largest condition number of the per-platform systems.
        platform: index of the worst platform.
    """

    def __init__(self, message: str, condition_number: float, platform: int):
        super().__init__(message)
        self.condition_number = condition_number
        self.platform = platform


class ViewerError(AssemblerError, RuntimeError):
    """The viewer's meshcat server cannot start (unusable host or port, or it exited)."""


class OptionsError(AssemblerError, ValueError):
    """An option of a solver (optimizer, helper arm, planner) is out of its allowed range."""


class UnknownScenarioError(AssemblerError, KeyError):
    """No scenario has the given name."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class CLIError(AssemblerError):
    """A command-line input problem (reported as one line, exit status 2)."""


class UnknownCarrierError(AssemblerError, ValueError):
    """A carrier name that is not supported."""


class SimulationError(AssemblerError):
    """MuJoCo is missing, or a simulation request is invalid."""


class PathError(AssemblerError, ValueError):
    """An EE path that cannot be built (bad waypoints, file or settings)."""


class TrajectoryError(AssemblerError, ValueError):
    """A trajectory that cannot be built, written or read."""


class GridError(AssemblerError, ValueError):
    """A grid or orientation SPEC that cannot be read."""


class LoadError(AssemblerError, ValueError):
    """An external load (a wrench on the end effector) that is malformed, not finite or absurd."""


class SceneError(AssemblerError, ValueError):
    """A scene of obstacles (:func:`assembler_pin.collision.read_scene`) that is malformed or out of range."""


class SingularIterateError(AssemblerError, RuntimeError):
    """The optimizer's solver accepted an iterate whose statics (or their derivatives) are
    singular: raised by the problem's evaluations and caught by the optimizer, which ends the
    run with the reason (it never reaches a caller of :mod:`assembler_pin.optimize`)."""


class SupportError(AssemblerError, ValueError):
    """A support that is not one of the known ones (``base``, ``ee``, ``both``, ``none``)."""


class WalkError(AssemblerError, ValueError):
    """Footholds that cannot start a walk: malformed, overlapping, off the declared floor."""


class HexapodError(AssemblerError, ValueError):
    """A hexapod that cannot be built or stood: malformed stacks, body, feet or lengths."""


class MapError(AssemblerError, ValueError):
    """A capability map that cannot be run, resumed or read (arguments, directory, parts, cluster)."""
