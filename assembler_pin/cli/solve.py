"""``assembler-pin solve``: internal poses for an EE goal."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from ..exceptions import CLIError

if TYPE_CHECKING:
    from ..model import AssemblerModel
from .common import (
    add_carrier_arguments,
    add_goal_arguments,
    add_helper_arm_arguments,
    add_optimize_arguments,
    carrier_from_args,
    config_from_args,
    dumps,
    format_carrier,
    format_state_table,
    goal_from_args,
    optimize_options,
)


def add_parser(add) -> None:
    """Register the ``solve`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("solve", "a valid pose of the whole stack for an end-effector goal")
    add_goal_arguments(p.add_mutually_exclusive_group())
    p.add_argument("--no-optimize", action="store_true", help="only the helper-arm initial condition")
    add_helper_arm_arguments(p)
    add_optimize_arguments(p)
    add_carrier_arguments(p, " (the goal is then in the world; the carrier's joints join the search)")
    p.add_argument("--fixed-carrier", action="store_true", help="with --carrier: hold it at --carrier-q")
    p.add_argument("--capacity", action="store_true",
                   help="also the largest payload [kg] some valid internal pose holds at the goal")  # fmt: skip
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Internal poses for an EE goal: helper-arm initial condition, then (by default) the
    force optimization. An unreachable goal is an answer (exit 0, success false)."""
    import numpy as np

    from ..helper_arm import HelperArmOptions
    from ..kinematics import se3_to_taa
    from ..model import AssemblerModel
    from ..solver import solve

    goal = goal_from_args(args)
    try:
        helper = HelperArmOptions(d_step=args.d_step, max_attempts=args.max_attempts)
    except ValueError as exc:
        raise CLIError(str(exc)) from None
    options = None if args.no_optimize else optimize_options(args)
    am = AssemblerModel.from_config(config_from_args(args))
    carrier, q = carrier_from_args(args)
    if carrier is not None:
        return _solve_on_carrier(args, am, carrier, q, goal)
    result = solve(am, goal, optimize=not args.no_optimize, options=options, helper_options=helper)
    capacity = None
    if args.capacity:
        from ..capacity import payload_capacity

        start = result.optimized.plates if result.success and result.optimized is not None else None
        capacity = payload_capacity(am, goal, start=start)
    if args.json:
        doc = result.to_dict()
        if capacity is not None:
            doc["capacity"] = capacity.to_dict()
        print(dumps(doc))
        return 0
    taa = se3_to_taa(result.goal)
    print(
        f"goal: p = ({', '.join(f'{x:.4f}' if abs(x) < 1e6 else f'{x:.4g}' for x in taa[:3])}) m, "
        f"rotation vector = ({np.rad2deg(taa[3]):.2f}, {np.rad2deg(taa[4]):.2f}, {np.rad2deg(taa[5]):.2f}) deg"
    )
    init = result.initial_result
    status = "valid" if init.success else "FAILED"
    print(f"initial condition (helper arm): {status} — {init.message} [{1e3 * init.time_s:.1f} ms]")
    title = "Initial condition" if init.success else "Home pose (no valid initial condition)"
    print(format_state_table(init.state, title))
    opt = result.optimization
    if opt is not None:
        print()
        print(f"optimization ({opt.method}): {'success' if result.success else 'FAILED'} — {result.message}; "
              f"{opt.iterations} iterations, {opt.evaluations} evaluations, {opt.time_s:.3f} s")  # fmt: skip
        starts = ", ".join(f"{name} {r.optimized.max_abs_force:.1f} N{'' if r.success else ' (failed)'}"
                           for name, r in result.runs.items())  # fmt: skip
        print(f"starts (max|F| reached): {starts}; kept: {result.start}")
        print(f"objective Ω = w1·max|F| + w2·sqrt(Σλ²): {opt.objective_initial:.3f} (start) -> "
              f"{opt.objective_optimized:.3f}")  # fmt: skip
        print(format_state_table(opt.optimized, "Optimized"))
    elif not args.no_optimize:
        print(f"\nno optimization: {result.message}")
    if capacity is not None:
        if capacity.success:
            print(f"\npayload capacity: {capacity.capacity_kg:.3f} kg ({capacity.binding} at its limit; "
                  f"{capacity.iterations} optimizations, {capacity.time_s:.2f} s)")  # fmt: skip
        else:
            print(f"\npayload capacity: none — {capacity.message}")
    return 0


def _solve_on_carrier(args: argparse.Namespace, am: AssemblerModel, carrier, q, goal) -> int:
    """``solve --carrier``: a world goal, the carrier moving unless ``--fixed-carrier``."""
    import numpy as np

    from ..carrier import solve_on_carrier

    result = solve_on_carrier(am, carrier, goal, q, move_carrier=not args.fixed_carrier)
    if args.json:
        print(dumps(result.to_dict()))
        return 0
    print(f"solve on {carrier.name} ({'carrier held' if args.fixed_carrier else 'carrier moving'}): "
          f"{'success' if result.success else 'FAILED'} — {result.message} [{result.time_s:.2f} s]")  # fmt: skip
    for t, cq, _score, note in result.candidates:
        print(f"  placement t = {t:.2f}: q = {np.round(cq, 3).tolist()}: {note}")
    if result.statics is not None:
        print(f"carrier q = {np.round(result.statics.q, 4).tolist()} rad")
        print(format_state_table(result.statics.state, "Optimized (world gravity)"))
        print(format_carrier(carrier, result.statics))
    return 0
