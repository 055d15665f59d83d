"""Shared argument groups, readers and text tables of the ``assembler-pin`` subcommands.

Nothing heavy is imported at module level: ``assembler-pin --help`` starts at once.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

from ..exceptions import CLIError
from .paths import path_argument
from .plate_file import plates_from_file

if TYPE_CHECKING:
    import numpy as np

    from ..config.schema import AssemblerConfig
    from ..model.assembler import AssemblerModel
    from ..state import StackState


def dumps(doc: object) -> str:
    """Strict JSON: a NaN or infinite number (a singular pose's forces) is written as null."""

    def clean(x: object) -> object:
        if isinstance(x, float):
            return x if math.isfinite(x) else None
        if isinstance(x, dict):
            return {k: clean(v) for k, v in x.items()}
        if isinstance(x, (list, tuple)):
            return [clean(v) for v in x]
        return x

    return json.dumps(clean(doc), allow_nan=False)


def config_from_args(args: argparse.Namespace) -> AssemblerConfig:
    from ..config.schema import load_config

    return load_config(args.config) if args.config else load_config()


def add_scene_argument(p: argparse.ArgumentParser, what: str) -> None:
    """``--scene FILE``: obstacles and a floor (read by :func:`scene_from_args`)."""
    p.add_argument(
        "--scene",
        type=path_argument,
        metavar="FILE",
        help=f"YAML scene of obstacles and a floor (docs/guides/collisions.md): {what}",
    )


def scene_from_args(args: argparse.Namespace):
    """The :class:`~assembler_pin.collision.scene.Scene` of ``--scene``, or None."""
    if not getattr(args, "scene", None):
        return None
    from ..collision.scene import read_scene

    return read_scene(args.scene)


def add_pose_source(
    p: argparse.ArgumentParser, home_help: str = "use the home pose", required: bool = False
) -> argparse._MutuallyExclusiveGroup:
    """The pose's source, ``--plates FILE`` or ``--home`` (read by :func:`plates_from_args`), as
    a mutually exclusive group the caller may add further sources to."""
    src = p.add_mutually_exclusive_group(required=required)
    src.add_argument(
        "--plates", type=path_argument, metavar="FILE", help='JSON {"plates": [n+1 4x4]} file, or - for stdin'
    )
    src.add_argument("--home", action="store_true", help=home_help)
    return src


def plates_from_args(args: argparse.Namespace, am: AssemblerModel, missing: str) -> list:
    """The pose of ``--home`` or ``--plates FILE``; a CLIError saying ``missing`` when neither."""
    if args.home:
        return am.home
    if args.plates is not None:
        return plates_from_file(args.plates)
    raise CLIError(missing)


#: The widest line the text answers print [characters].
TEXT_WIDTH = 100


def wrapped(text: str, width: int = TEXT_WIDTH) -> str:
    """``text`` folded at spaces into lines of at most ``width`` characters (a word longer
    than that stays whole), the lines after the first indented by four spaces."""
    import textwrap

    return textwrap.fill(text, width, subsequent_indent="    ", break_long_words=False, break_on_hyphens=False) or text


def format_state_table(state: StackState, title: str = "") -> str:
    """A readable table of a state: forces and lengths per actuator, then summary lines.

    Row ``i``, column ``SPj`` is leg ``i`` of platform ``j``, both 0-based
    (:mod:`~assembler_pin.common.labels`), the indices of ``forces[j, i]`` and of the JSON.
    """
    import numpy as np

    from ..common.labels import leg_label, platform_label

    n = state.forces.shape[0]
    lines = [title] if title else []
    for first in range(0, n, 4):  # four platforms a block: at most 83 characters wide
        block = range(first, min(n, first + 4))
        header = "leg | " + " | ".join(f"{platform_label(j)} F [N]  L [mm]" for j in block)
        lines += [header, "-" * len(header)]
        for i in range(6):
            cells = [f"{state.forces[j, i]:9.3f} {1e3 * state.leg_lengths[j, i]:7.2f}" for j in block]
            lines.append(f"{i:>3} | " + " | ".join(cells))
    j, i = np.unravel_index(np.abs(state.forces).argmax(), state.forces.shape)
    lines.append(
        f"max |F| = {state.max_abs_force:.3f} N ({leg_label(j, i)}), "
        f"mean |F| = {state.mean_abs_force:.3f} N   (tension positive)"
    )
    w = state.statics.base_wrench
    lines.append(
        f"base wrench [N, N·m]: f = ({w[0]:.3f}, {w[1]:.3f}, {w[2]:.3f}), m = ({w[3]:.3f}, {w[4]:.3f}, {w[5]:.3f})"
    )
    near = getattr(state, "clearance", None)  # None: not measured
    if near is not None and near.between[0]:
        a, b = near.between
        lines.append(f"clearance: {near.min_distance:.4f} m between {a} and {b} (at least {near.limit:g} m)")
    if state.feasible:
        lines.append("feasible: yes (every constraint holds)")
    else:
        lines.append(f"feasible: NO — {len(state.violations)} violation(s):")
        lines += [f"  - {v}" for v in state.violations]
    from ..common.messages import finite_text

    return finite_text("\n".join(lines))


def radians_checked(taa, flag: str, degrees_flag: str | None = None):
    """``taa`` (x y z rx ry rz) when its rotation vector is at most 2π rad long; a longer
    one is a rotation typed in degrees, refused pointing at the option in degrees."""
    rotation = [float(x) for x in taa[3:]]
    if not all(math.isfinite(x) for x in rotation):  # refused with its numbers where the pose is read
        return taa
    angle = math.hypot(*rotation)  # no overflow for finite components, however large
    if angle > 2 * math.pi:
        hint = f"use {degrees_flag} for degrees" if degrees_flag else "give the rotation vector in radians"
        raise CLIError(f"{flag}: the rotation vector is {angle:.4g} rad long, more than 2π (a turn): degrees? {hint}")
    return taa


def goal_from_args(args: argparse.Namespace):
    """The EE goal of ``solve``: ``--goal`` (rotation vector in rad) or ``--goal-deg`` (in deg)."""
    from ..kinematics import taa_to_se3

    if args.goal is not None:
        return taa_to_se3(radians_checked(args.goal, "--goal", "--goal-deg"), what="--goal")
    if args.goal_deg is not None:
        return taa_to_se3(args.goal_deg, degrees=True, what="--goal-deg")
    raise CLIError("give the EE goal: --goal X Y Z RX RY RZ (m, rad) or --goal-deg X Y Z RX RY RZ (m, deg)")


#: The optimizer's options as ``(attribute, option)``: None in the parsed arguments unless given.
OPTIMIZE_FLAGS = (
    ("method", "--method"),
    ("w1", "--w1"),
    ("w2", "--w2"),
    ("ee_tolerance", "--ee-tolerance"),
    ("max_iterations", "--max-iterations"),
    ("ftol", "--ftol"),
)


def given_flags(args: argparse.Namespace, flags: Sequence[tuple[str, str]]) -> list[str]:
    """The options of ``flags`` that were given (not None, not false) in ``args``."""
    return [flag for name, flag in flags if getattr(args, name, None) not in (None, False)]


def optimize_options(args: argparse.Namespace):
    from ..config.options import GoalTolerance
    from ..optimize import OptimizeOptions

    ee = None
    if args.ee_tolerance is not None:
        from ..config.bounds import check_bound

        pos, rot = args.ee_tolerance
        if not (pos > 0 and rot > 0):
            raise CLIError("--ee-tolerance POSITION ROTATION (ee_tolerance) must be finite numbers > 0 (m, rad)")
        check_bound("goal_tolerance.position", pos, "--ee-tolerance POSITION (ee_tolerance)", CLIError)
        check_bound("goal_tolerance.rotation", rot, "--ee-tolerance ROTATION (ee_tolerance)", CLIError)
        ee = GoalTolerance(position=pos, rotation=rot)
    try:
        d = OptimizeOptions()
        given = {name: getattr(args, name) for name in ("method", "w1", "w2", "max_iterations", "ftol")}
        return dataclasses.replace(d, ee_tolerance=ee, **{k: v for k, v in given.items() if v is not None})
    except ValueError as exc:
        raise CLIError(str(exc)) from None


def add_carrier_arguments(p: argparse.ArgumentParser, note: str = "") -> None:
    """``--carrier NAME``, ``--carrier-q`` and ``--mount``, read by :func:`carrier_from_args`."""
    from ..config.choices import CARRIER_NAMES

    p.add_argument(
        "--carrier",
        metavar="NAME",
        help=f"mount the stack on a carrier arm from example-robot-data: {', '.join(CARRIER_NAMES)}{note}",
    )
    p.add_argument(
        "--carrier-q",
        nargs="+",
        type=float,
        metavar="Q",
        help="the carrier's joint angles [rad] (default: its upright configuration)",
    )
    p.add_argument(
        "--mount",
        nargs=6,
        type=float,
        metavar=("X", "Y", "Z", "RX", "RY", "RZ"),
        help="base plate pose in the carrier's tool frame [m, rad] (default identity)",
    )


def carrier_from_args(args: argparse.Namespace):
    """(carrier, q) of ``--carrier``, or (None, None) without one."""
    if getattr(args, "carrier", None) is None:  # '' is a name given, and refused as a name
        if getattr(args, "carrier_q", None) or getattr(args, "mount", None):
            raise CLIError("--carrier-q and --mount need --carrier NAME")
        return None, None
    from ..carrier import Carrier
    from ..kinematics import taa_to_se3

    carrier = Carrier(args.carrier, None if args.mount is None else taa_to_se3(args.mount, what="--mount"))
    q = carrier.upright_q if args.carrier_q is None else carrier.check_q(args.carrier_q, "--carrier-q")
    return carrier, q


def format_carrier(carrier, statics) -> str:
    """The carrier's joint torques against their effort limits, and what binds."""
    lines = [f"carrier {carrier.name}: joint torques [N·m] (effort limit, use)"]
    for k, (tau, limit, ratio) in enumerate(
        zip(statics.torques, carrier.effort_limit, statics.torque_ratio, strict=True)
    ):
        lines.append(f"  joint {k}: {tau:9.3f}  ({limit:g}, {100 * ratio:5.1f} %)")
    lines.append(
        wrapped(
            f"stack at {100 * statics.stack_ratio:.1f} % of its force limit, carrier at "
            f"{100 * statics.carrier_ratio:.1f} % of its effort limit: {statics.binding} binds; "
            f"within every limit: {'yes' if statics.within_limits else 'NO'}"
        )
    )
    return "\n".join(lines)


def add_goal_arguments(group: argparse._MutuallyExclusiveGroup, note: str = "") -> None:
    """``--goal`` (rotation vector in rad) and ``--goal-deg``, read by :func:`goal_from_args`."""
    taa = ("X", "Y", "Z", "RX", "RY", "RZ")
    group.add_argument(
        "--goal",
        nargs=6,
        type=float,
        metavar=taa,
        help="EE goal: position [m] and rotation vector [rad], world frame" + note,
    )
    group.add_argument(
        "--goal-deg", nargs=6, type=float, metavar=taa, help="as --goal with the rotation vector in degrees"
    )


def add_optimize_arguments(p: argparse.ArgumentParser) -> None:
    """The optimizer's options; defaults and choices come from :class:`OptimizeOptions`. Each
    is None unless given (:data:`OPTIMIZE_FLAGS`), so that a command can refuse one that would
    have no effect; :func:`optimize_options` fills in the defaults."""
    from ..config.options import METHODS, OptimizeOptions

    d = OptimizeOptions()
    p.add_argument(
        "--method",
        choices=METHODS,
        help=f"slsqp: smooth epigraph form, SciPy SLSQP; ipopt: the same form by IPOPT on the sparse "
        f"Jacobian (CasADi); auto: ipopt from 12 platforms (finished by slsqp when it "
        f"stops unconverged), else slsqp; paper: the "
        f"paper's non-smooth objective with finite differences (default {d.method})",
    )
    p.add_argument("--w1", type=float, help=f"weight of max|F| [1/N] (default {d.w1:g})")
    p.add_argument("--w2", type=float, help=f"weight of the plate deviation term [1/rad] (default {d.w2:g})")
    p.add_argument(
        "--ee-tolerance",
        type=float,
        nargs=2,
        metavar=("POSITION", "ROTATION"),
        help="let the EE move this far from the goal [m, rad] (default: fixed at the goal)",
    )
    p.add_argument(
        "--max-iterations",
        type=int,
        help=f"solver iteration limit (default {d.max_iterations})",
    )
    p.add_argument("--ftol", type=float, help=f"solver tolerance on the objective (default {d.ftol:g})")


def add_helper_arm_arguments(p: argparse.ArgumentParser) -> None:
    """The helper arm's options; defaults come from :class:`HelperArmOptions`."""
    from ..config.options import HelperArmOptions

    d = HelperArmOptions()
    p.add_argument(
        "--d-step",
        type=float,
        default=d.d_step,
        metavar="M",
        help=f"helper-arm link-length scan step [m] (default {d.d_step:g})",
    )
    p.add_argument(
        "--max-attempts",
        type=int,
        default=d.max_attempts,
        metavar="N",
        help=f"helper-arm recursion limit: link lengths tried (default {d.max_attempts})",
    )


def finite_range(values: np.ndarray) -> list[float] | None:
    """[min, max] of the finite values, None without any."""
    import numpy as np

    ok = np.isfinite(values)
    return [float(values[ok].min()), float(values[ok].max())] if ok.any() else None


def progress_for(args: argparse.Namespace, label: str):
    """The progress display of a subcommand: on stderr when it is a terminal, unless ``--quiet``."""
    from ..common.progress import TerminalProgress

    return TerminalProgress(label, enabled=False if getattr(args, "quiet", False) else None)
