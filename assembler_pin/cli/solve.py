"""``assembler-pin solve``: internal poses for an EE goal."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from ..exceptions import CLIError

if TYPE_CHECKING:
    from ..model.assembler import AssemblerModel
from .common import (
    OPTIMIZE_FLAGS,
    add_carrier_arguments,
    add_goal_arguments,
    add_helper_arm_arguments,
    add_optimize_arguments,
    add_scene_argument,
    carrier_from_args,
    config_from_args,
    dumps,
    format_carrier,
    format_state_table,
    given_flags,
    goal_from_args,
    optimize_options,
    progress_for,
    scene_from_args,
    wrapped,
)
from .paths import path_argument, writable_parent


def add_parser(add) -> None:
    """Register the ``solve`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("solve", "a valid pose of the whole stack for an end-effector goal")
    add_goal_arguments(p.add_mutually_exclusive_group())
    p.add_argument("--no-optimize", action="store_true", help="only the helper-arm initial condition")
    add_helper_arm_arguments(p)
    add_optimize_arguments(p)
    add_sag_arguments(p)
    _add_starts_argument(p)
    add_carrier_arguments(p, " (the goal is then in the world; the carrier's joints join the search)")
    p.add_argument("--fixed-carrier", action="store_true", help="with --carrier: hold it at --carrier-q")
    p.add_argument(
        "--capacity",
        action="store_true",
        help="also the largest payload [kg] some valid internal pose holds at the goal",
    )
    p.add_argument(
        "--out",
        type=path_argument,
        metavar="FILE",
        help='write the pose found as a plate file {"plates": [...]} for statics, view, simulate, stiffness',
    )
    add_scene_argument(p, "every optimizer run keeps its clearance from it (not with --carrier)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def _add_starts_argument(p: argparse.ArgumentParser) -> None:
    """``--starts first|all`` (:data:`~assembler_pin.config.choices.SOLVE_STARTS`), passed to ``solve(starts=...)``."""
    from ..config.choices import SOLVE_STARTS

    p.add_argument(
        "--starts",
        choices=SOLVE_STARTS,
        help=f"the optimizer's starts: {SOLVE_STARTS[0]} (default): the starts in order (helper arm, screw, "
        "home), stopping at the second when both reach one optimum; all: every start; the best optimum is "
        "kept (not with --carrier)",
    )


def add_sag_arguments(p: argparse.ArgumentParser) -> None:
    """``--objective``, ``--sag-weight`` and ``--max-sag`` (:class:`~assembler_pin.config.options.OptimizeOptions`)."""
    from ..config.choices import OBJECTIVES
    from ..config.options import OptimizeOptions

    d = OptimizeOptions()
    p.add_argument(
        "--objective",
        choices=OBJECTIVES,
        help="what the optimizer minimizes: force: Ω = w1·max|F| + w2·sqrt(Σλ²) (default); sag: the EE's "
        "sag under its own load (legs of stiffness leg.stiffness), every limit kept; weighted: "
        "Ω + W·sag/sag_home (sag_home: the home pose's sag)",
    )
    p.add_argument(
        "--sag-weight",
        type=float,
        metavar="W",
        help=f"weight W of the sag in --objective weighted (default {d.sag_weight:g})",
    )
    p.add_argument(
        "--max-sag",
        type=float,
        metavar="M",
        help="largest EE sag of the answer [m] (a constraint; success false with 'sag limit' when not met)",
    )


def sag_options(args: argparse.Namespace, options):
    """``options`` with ``--objective``, ``--sag-weight`` and ``--max-sag``, each checked
    (one line naming the option when refused)."""
    import dataclasses

    from ..config.bounds import check_bound
    from ..exceptions import OptionsError

    if args.sag_weight is not None:
        check_bound("optimize.sag_weight", args.sag_weight, "--sag-weight", CLIError)
        if args.objective != "weighted":
            raise CLIError("--sag-weight weighs the sag in --objective weighted; give --objective weighted")
    if args.max_sag is not None:
        check_bound("optimize.max_sag", args.max_sag, "--max-sag [m]", CLIError)
    changes = {"objective": args.objective, "sag_weight": args.sag_weight, "max_sag": args.max_sag}
    changes = {k: v for k, v in changes.items() if v is not None}
    if not changes:
        return options
    try:
        return dataclasses.replace(options, **changes)
    except OptionsError as exc:
        raise CLIError(str(exc)) from None


def run(args: argparse.Namespace) -> int:
    """Internal poses for an EE goal: helper-arm initial condition, then (by default) the
    force optimization. Exit 0 when solved; an unreachable goal is an answer too (printed,
    success false), with exit status 1, as is ``--capacity`` finding no capacity."""
    from ..config.bounds import check_bound
    from ..config.choices import SOLVE_STARTS
    from ..model.assembler import AssemblerModel
    from ..solver.pipeline import solve

    goal = goal_from_args(args)
    _refuse_carrier_options(args)
    _refuse_optimizer_options_without_optimizing(args)
    if args.out:
        writable_parent(args.out, "--out file")
    if args.max_iterations is not None:
        check_bound("optimize.max_iterations", args.max_iterations, "--max-iterations", CLIError)
    helper = helper_options(args)
    options = None if args.no_optimize else sag_options(args, optimize_options(args))
    scene = scene_from_args(args)  # read before the model is built: a bad scene is refused at once
    am = AssemblerModel.from_config(config_from_args(args))
    _check_scan_length(am, helper)
    carrier, q = carrier_from_args(args)
    if carrier is not None:
        return _solve_on_carrier(args, am, carrier, q, goal, helper)
    starts = args.starts or SOLVE_STARTS[0]
    result = solve(
        am,
        goal,
        optimize=not args.no_optimize,
        options=options,
        helper_options=helper,
        starts=starts,
        scene=scene,
    )
    capacity = None
    if args.capacity:
        from ..solver.capacity import payload_capacity

        start = result.optimized.plates if result.success and result.optimized is not None else None
        capacity = payload_capacity(am, goal, start=start, scene=scene)  # every pose clear of the scene
    written = _write_plates(args.out, result) if args.out else None
    if args.json:
        doc = result.to_dict()
        if capacity is not None:
            doc["capacity"] = capacity.to_dict()
        if args.out:
            doc["out"] = written
        print(dumps(doc))
    else:
        _print_result(args, result, capacity)
        if result.sag is not None:
            _print_sag(result.sag.to_dict())
        if args.out:
            print(f"wrote {written}" if written else f"no pose to write to {args.out}: the goal was not solved")
    return 0 if result.success and (capacity is None or capacity.success) else 1


def _refuse_optimizer_options_without_optimizing(args: argparse.Namespace) -> None:
    """``--no-optimize`` skips the optimizer: an option that only sets it is refused (it would
    be silently ignored), naming the first one given. With ``--carrier`` the options still
    score the carrier's placements."""
    if not args.no_optimize or args.carrier is not None:
        return
    flags = (
        *OPTIMIZE_FLAGS,
        ("starts", "--starts"),
        ("objective", "--objective"),
        ("sag_weight", "--sag-weight"),
        ("max_sag", "--max-sag"),
    )
    given = given_flags(args, flags)
    if given:
        raise CLIError(
            f"{given[0]} sets the optimizer, which --no-optimize skips (only the helper arm's pose): drop one of them"
        )


def _write_plates(path: str, result) -> str | None:
    """Write the solved pose (optimized, else the helper arm's) as a plate file, atomically;
    nothing when the goal was not solved (a file holds valid content only)."""
    from ..common.files import write_atomic

    state = result.optimized if result.optimized is not None else result.initial
    if not result.success or state is None:
        return None
    write_atomic(path, dumps({"plates": state.to_dict()["plates"]}) + "\n")
    return path


def helper_options(args: argparse.Namespace):
    """The helper arm's options of ``--d-step`` and ``--max-attempts``, bounds checked."""
    from ..config.bounds import check_bound
    from ..config.options import HelperArmOptions

    check_bound("helper.max_attempts", args.max_attempts, "--max-attempts", CLIError)
    check_bound("helper.d_step", args.d_step, "--d-step", CLIError)
    try:
        return HelperArmOptions(d_step=args.d_step, max_attempts=args.max_attempts)
    except ValueError as exc:
        raise CLIError(str(exc)) from None


def _check_scan_length(am: AssemblerModel, helper) -> None:
    """The helper arm's scan, (height range) / ``--d-step`` link lengths, within its bound."""
    import math

    from ..config.bounds import check_bound
    from ..helper_arm import height_range

    lo, hi = height_range(am.config)
    values = max(1, math.ceil((hi - lo) / helper.d_step)) if math.isfinite(hi - lo) else hi - lo
    check_bound("helper.scan_values", values, f"the scan of --d-step {helper.d_step:g} over {hi - lo:.4g} m", CLIError)


def _refuse_carrier_options(args: argparse.Namespace) -> None:
    """One line for an option that cannot apply with (or without) ``--carrier``."""
    if args.fixed_carrier and not args.carrier:
        raise CLIError("--fixed-carrier needs --carrier NAME")
    if args.carrier and args.starts:
        raise CLIError("--starts chooses the starts of the fixed-base solve and is not available with --carrier")
    sag_given = [name for name in ("objective", "sag_weight", "max_sag") if getattr(args, name) is not None]
    if sag_given and (args.carrier or args.no_optimize):
        flag = "--" + sag_given[0].replace("_", "-")
        raise CLIError(
            f"{flag} sets the fixed-base optimizer's objective and is not available with --carrier or --no-optimize"
        )
    if args.carrier and args.scene:
        raise CLIError("--scene is checked on a fixed base and is not available with --carrier")
    if args.carrier and args.out:
        raise CLIError("--out writes a fixed-base plate file and is not available with --carrier")
    if args.carrier and args.capacity:
        raise CLIError(
            "--capacity is computed on a fixed base and is not available with --carrier; "
            "run 'solve --capacity' without --carrier for the goal seen from the base"
        )


def _print_result(args: argparse.Namespace, result, capacity) -> None:
    """The text answer of ``solve``: the goal, the initial condition, the optimization."""
    import numpy as np

    from ..kinematics import se3_to_taa

    taa = se3_to_taa(result.goal)
    print(
        f"goal: p = ({', '.join(f'{x:.4f}' if abs(x) < 1e6 else f'{x:.4g}' for x in taa[:3])}) m, "
        f"rotation vector = ({np.rad2deg(taa[3]):.2f}, {np.rad2deg(taa[4]):.2f}, {np.rad2deg(taa[5]):.2f}) deg"
    )
    init = result.initial_result
    status = ("valid" if init.state.feasible else "valid, not feasible") if init.success else "none found"
    print(wrapped(f"initial condition (helper arm): {status} — {init.message} [{1e3 * init.time_s:.1f} ms]"))
    title = "Initial condition" if init.success else "Home pose (no valid initial condition)"
    print(format_state_table(init.state, title))
    opt = result.optimization
    if opt is not None:
        print()
        print(
            wrapped(
                f"optimization ({opt.method}): {_verdict(result)} — {result.message}; "
                f"{opt.iterations} iterations, {opt.evaluations} evaluations, {opt.time_s:.3f} s"
            )
        )
        starts = ", ".join(f"{name} {r.optimized.max_abs_force:.1f} N{_run_note(r)}" for name, r in result.runs.items())
        print(wrapped(f"starts (max|F| reached): {starts}; kept: {result.start}"))
        what = {"force": "Ω = w1·max|F| + w2·sqrt(Σλ²)", "sag": "sag/sag_home", "weighted": "Ω + W·sag/sag_home"}
        print(
            f"objective {what.get(opt.objective, opt.objective)}: {opt.objective_initial:.3f} (start) -> "
            f"{opt.objective_optimized:.3f}"
        )
        print(format_state_table(opt.optimized, "Optimized"))
    elif not args.no_optimize:
        print("\n" + wrapped(f"optimization: FAILED — {result.message}"))
    if capacity is not None:
        if capacity.success:
            print(
                f"\npayload capacity: {capacity.capacity_kg:.3f} kg ({capacity.binding} at its limit; "
                f"{capacity.iterations} optimizations, {capacity.time_s:.2f} s)"
            )
        else:
            print("\n" + wrapped(f"payload capacity: none — {capacity.message}"))


def _verdict(result) -> str:
    """The word of a solve's optimization: an optimum, a valid pose not proven optimal, or none."""
    if not result.success:
        return "FAILED"
    return "optimum" if result.optimal else "valid, not proven optimal"


def _run_note(run) -> str:
    """What a start's run reached, after its max|F|: nothing for an optimum."""
    if run.optimal:
        return ""
    return " (valid, not proven optimal)" if run.success else " (failed)"


def _print_sag(block: dict) -> None:
    """One line: the EE's linear sag of the answer (and of the helper arm's pose)."""

    def mm(entry: dict | None) -> str:
        return "—" if entry is None or entry["sag_m"] is None else f"{1e3 * entry['sag_m']:.4g} mm"

    limit = f", limit {1e3 * block['max_sag_m']:.4g} mm" if block["max_sag_m"] is not None else ""
    print(
        "\n"
        + wrapped(
            f"EE sag under its own load (legs {block['stiffness_n_per_m']:g} N/m, objective "
            f"{block['objective'] or '—'}{limit}): initial {mm(block['initial'])} -> answer {mm(block['answer'])}"
        )
    )


def _solve_on_carrier(args: argparse.Namespace, am: AssemblerModel, carrier, q, goal, helper) -> int:
    """``solve --carrier``: a world goal, the carrier moving unless ``--fixed-carrier``; every
    optimizer and helper-arm option applies (the joint optimization is always SLSQP)."""
    import numpy as np

    from ..carrier import solve_on_carrier

    prog = progress_for(args, f"solve on {carrier.name}")
    options = optimize_options(args)  # its weights score the placements even with --no-optimize
    moving, optimize = not args.fixed_carrier, not args.no_optimize
    result = solve_on_carrier(
        am,
        carrier,
        goal,
        q,
        move_carrier=moving,
        options=options,
        helper_options=helper,
        optimize=optimize,
        progress=prog,
    )
    prog.close()
    if args.json:
        print(dumps(result.to_dict()))
        return 0 if result.success else 1
    print(
        wrapped(
            f"solve on {carrier.name} ({'carrier held' if args.fixed_carrier else 'carrier moving'}): "
            f"{'success' if result.success else 'FAILED'} — {result.message} [{result.time_s:.2f} s]"
        )
    )
    for t, cq, _score, note in result.candidates:
        where = "joint optimization (carrier joints and plates together)" if np.isnan(t) else f"placement t = {t:.2f}"
        print(wrapped(f"  {where}: q = {np.round(cq, 3).tolist()}: {note}"))
    if result.statics is not None:
        print(f"carrier q = {np.round(result.statics.q, 4).tolist()} rad")
        title = "Optimized" if optimize else "Helper-arm pose (not optimized)"
        print(format_state_table(result.statics.state, f"{title} (world gravity)"))
        print(format_carrier(carrier, result.statics))
    return 0 if result.success else 1
