"""The curated hostile inputs: files for every reader, command lines for every subcommand.

Files are built once per session into a workspace directory (:func:`build_workspace`) from
a few valid originals — the home pose, a trajectory written by the planner, an exported
model — and their mutations. A command line refers to the workspace as ``{d}``.

Each :class:`CliCase` says what the contract expects: ``"refuse"`` (a malformed input: exit
status 2 with one line), ``"answer"`` (a valid input: answered, the answer re-checked) or
``"any"`` (hostile but possibly meaningful: refused in one line, or an answer that holds up).
``isolate`` runs the command as a memory-limited child process (absurd counts and sizes,
where a defect would exhaust the machine or block in C code).
"""

from __future__ import annotations

import csv
import importlib
import io
import json
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

# ---------------------------------------------------------------------- cases


@dataclass(frozen=True)
class CliCase:
    """One command line of the corpus.

    Attributes:
        id: the case id (the pytest id; :mod:`.known_failures` lists failing ones).
        argv: the arguments, ``{d}`` standing for the workspace directory and ``{case}``
            for the case id (an output directory of its own).
        expect: ``"refuse"``, ``"answer"`` or ``"any"``.
        isolate: run as a memory-limited child process.
        slow: takes more than a few seconds when answered (``@pytest.mark.slow``).
        check: extra re-check of an answer (see ``test_cli_corpus.CHECKS``).
    """

    id: str
    argv: tuple[str, ...]
    expect: str = "refuse"
    isolate: bool = False
    slow: bool = False
    check: str | None = None


def _case(id_: str, argv: str | list[str], expect: str = "refuse", **kw) -> CliCase:
    args = tuple(argv.split()) if isinstance(argv, str) else tuple(argv)
    return CliCase(id_, args, expect, **kw)


REACHABLE = "0.02 0.01 0.85 0 0 0"
UNREACHABLE = "10 0 0.9 0 0 0"
NEAR_HOME = "0 0 0.956 0 0 0"  # 1 cm below the home EE: a short, cheap plan
UNDER_FILE = "{d}/afile/out"  # a path whose parent is a regular file: unwritable, even as root


def _statics_config_cases() -> list[CliCase]:
    refuse = [
        "missing.yaml",
        "adir",
        "cfg_9_81.yaml",
        "cfg_sexagesimal.yaml",
        "cfg_octal_underscore.yaml",
        "cfg_bool.yaml",
        "cfg_nan.yaml",
        "cfg_inf.yaml",
        "cfg_overflow.yaml",
        "cfg_string.yaml",
        "cfg_null.yaml",
        "cfg_null_section.yaml",
        "cfg_dup.yaml",
        "cfg_alias.yaml",
        "cfg_alias_bomb_small.yaml",
        "cfg_deep_list.yaml",
        "cfg_deep_map.yaml",
        "cfg_toplist.yaml",
        "cfg_python_tag.yaml",
        "cfg_binary.yaml",
        "cfg_nonutf8.yaml",
        "cfg_long_value.yaml",
        "cfg_long_key.yaml",
        "cfg_platforms_huge.yaml",
        "cfg_platforms_float.yaml",
        "cfg_platforms_bool.yaml",
        "cfg_negative_mass.yaml",
        "cfg_multi_doc.yaml",
        "cfg_truncated.yaml",
        "cfg_unknown.yaml",
        "cfg_complex.yaml",
        "cfg_timestamp.yaml",
        "cfg_clearance_negative.yaml",
        "cfg_clearance_huge.yaml",
        "cfg_clearance_nan.yaml",
        "cfg_shaft_wider.yaml",
        "cfg_motor_longer.yaml",
        "cfg_node_zone_long.yaml",
        "cfg_plate_thick.yaml",
        "cfg_plate_radius_zero.yaml",
        "cfg_payload_radius_negative.yaml",
        "cfg_payload_radius_huge.yaml",
        "cfg_payload_radius_text.yaml",
        "cfg_payload_radius_nan.yaml",
        "cfg_bigint_motor_radius.yaml",
        "cfg_bigint_clearance.yaml",
        "cfg_typo_key.yaml",
        "fifo.yaml",
        "/dev/zero",
    ]
    cases = [
        _case(f"config.{Path(n).stem}", ["statics", "--home", "--json", "--config", n if n[0] == "/" else f"{{d}}/{n}"])
        for n in refuse
    ]
    cases += [
        _case("config.empty", "statics --home --json --config {d}/cfg_empty.yaml", "any", check="state"),
        _case("config.comment_only", "statics --home --json --config {d}/cfg_comment.yaml", "any", check="state"),
        _case("config.valid_other", "statics --home --json --config {d}/cfg_other.yaml", "answer", check="state"),
        _case("config.alias_bomb", "statics --home --json --config {d}/cfg_alias_bomb.yaml", isolate=True),
    ]
    return cases


PLATE_REFUSE = [
    "missing.json",
    "adir",
    "plates_empty.json",
    "plates_truncated.json",
    "plates_nonutf8.json",
    "plates_deep.json",
    "plates_dupkey.json",
    "plates_strings.json",
    "plates_one_string.json",
    "plates_bools.json",
    "plates_nan.json",
    "plates_infinity.json",
    "plates_overflow.json",
    "plates_bigint.json",
    "plates_complex.json",
    "plates_null.json",
    "plates_scaled.json",
    "plates_reflection.json",
    "plates_shear.json",
    "plates_lastrow.json",
    "plates_count.json",
    "plates_3x3.json",
    "plates_ragged.json",
    "plates_toplist.json",
    "plates_object.json",
    "plates_many.json",
    "plates_quaternion_zero.json",
    "plates_moved_1e15.json",
]


#: Scene files a command refuses in one line (:func:`assembler_pin.collision.read_scene`).
SCENE_FILES: dict[str, bytes] = {
    "scene_not_yaml.yaml": b"obstacles: [\n",
    "scene_unknown_key.yaml": b"walls: []\n",
    "scene_nan.yaml": b"obstacles:\n  - sphere: {radius: .nan, center: [0, 0, 1]}\n",
    "scene_huge.yaml": b"obstacles:\n  - sphere: {radius: 1.0e300, center: [0, 0, 1]}\n",
    "scene_two_kinds.yaml": (
        b"obstacles:\n  - {sphere: {radius: 1, center: [0, 0, 1]}, box: {size: [1, 1, 1], pose: [0, 0, 0, 0, 0, 0]}}\n"
    ),
    "scene_negative_box.yaml": b"obstacles:\n  - box: {size: [-1, 1, 1], pose: [0, 0, 0, 0, 0, 0]}\n",
    "scene_alias.yaml": b"a: &x {z: 0}\nfloor: *x\n",
    "scene_too_many.yaml": b"obstacles:\n" + b"  - sphere: {radius: 0.01, center: [5, 5, 5]}\n" * 300,
    "scene_duplicate_name.yaml": (
        b"obstacles:\n  - {name: a, sphere: {radius: 0.1, center: [5, 0, 1]}}\n"
        b"  - {name: a, sphere: {radius: 0.1, center: [6, 0, 1]}}\n"
    ),
    "scene_long_name.yaml": b"obstacles:\n  - {name: " + b"n" * 500 + b", sphere: {radius: 0.1, center: [5, 0, 1]}}\n",
    "scene_list.yaml": b"- 1\n- 2\n",
    # an integer of 400 digits (read exactly by YAML) where a number belongs
    "scene_bigint_box.yaml": b"obstacles:\n  - box: {size: [1" + b"0" * 400 + b", 1, 1], pose: [5, 0, 0, 0, 0, 0]}\n",
    "scene_bigint_pose.yaml": b"obstacles:\n  - box: {size: [1, 1, 1], pose: [1" + b"0" * 400 + b", 0, 0, 0, 0, 0]}\n",
    "scene_bigint_floor.yaml": b"floor: {z: 1" + b"0" * 400 + b"}\n",
    "scene_bigint_center.yaml": b"obstacles:\n  - sphere: {radius: 0.1, center: [5, 1" + b"0" * 400 + b", 1]}\n",
    "scene_typo_key.yaml": b"floor: {zz: 0.0}\n",
    "scene_long.yaml": b"obstacles:\n" + b"  - box: {size: [0.1, 0.1, 0.1], pose: [5, 0, 0.25, 0, 0, 0]}\n" * 10_000,
    "scene_ok.yaml": b"floor: {z: 0.0}\nobstacles:\n  - sphere: {radius: 0.05, center: [0.0, 0.0, 0.956]}\n",
}


def _scene_cases() -> list[CliCase]:
    refuse = [n for n in SCENE_FILES if n != "scene_ok.yaml"]
    cases = [
        _case(f"scene.statics.{Path(n).stem}", ["statics", "--home", "--json", "--scene", f"{{d}}/{n}"]) for n in refuse
    ]
    cases += [
        _case(f"scene.solve.{Path(n).stem}", [*f"solve --json --goal {REACHABLE}".split(), "--scene", f"{{d}}/{n}"])
        for n in refuse[:3]
    ]
    cases += [
        _case(f"scene.plan.{Path(n).stem}", [*f"plan --json --to {NEAR_HOME}".split(), "--scene", f"{{d}}/{n}"])
        for n in refuse[:3]
    ]
    cases += [
        _case(f"scene.view.{Path(n).stem}", ["view", "--home", "--html", "{d}/view.html", "--scene", f"{{d}}/{n}"])
        for n in refuse[:3]
    ]
    far_map = "map --json --workers 0 --no-progress --grid x=5,y=0,z=0.5 --out {d}/map_{case} --scene"
    cases += [_case(f"scene.map.{Path(n).stem}", [*far_map.split(), f"{{d}}/{n}"]) for n in refuse[:3]]
    cases += [
        _case("scene.view_missing", "view --home --html {d}/view.html --scene {d}/no_such_scene.yaml"),
        _case("scene.view_carrier", "view --home --carrier ur5 --html {d}/view.html --scene {d}/scene_ok.yaml"),
        _case("scene.missing", "statics --home --json --scene {d}/no_such_scene.yaml"),
        _case("scene.directory", "statics --home --json --scene {d}"),
        _case("scene.fifo", "statics --home --json --scene {d}/fifo.yaml"),
        _case("scene.dev_zero", "statics --home --json --scene /dev/zero"),
        _case("scene.statics_empty_path", ["statics", "--home", "--json", "--scene", ""]),
        _case("scene.solve_empty_path", [*f"solve --json --goal {REACHABLE}".split(), "--scene", ""]),
        _case("scene.plan_empty_path", [*f"plan --json --to {NEAR_HOME}".split(), "--scene", ""]),
        _case("statics.plates_fifo", "statics --json --plates {d}/fifo.yaml"),
        _case("solve.out_in_proc", f"solve --json --goal {REACHABLE} --out /proc/out.json"),
        # a sphere around the home EE plate: an answer, infeasible with a collision
        _case("scene.statics_collision", "statics --home --json --scene {d}/scene_ok.yaml", "answer", check="state"),
        _case("scene.solve_collision", f"solve --json --goal {NEAR_HOME} --scene {{d}}/scene_ok.yaml", "any"),
        _case("scene.with_carrier", "statics --home --carrier ur5 --scene {d}/scene_ok.yaml"),
        _case("scene.plan_compare", f"plan --compare --to {NEAR_HOME} --scene {{d}}/scene_ok.yaml"),
    ]
    return cases


def _statics_cases() -> list[CliCase]:
    cases = [_case(f"statics.{Path(n).stem}", ["statics", "--json", "--plates", f"{{d}}/{n}"]) for n in PLATE_REFUSE]
    cases += [
        _case("statics.home", "statics --home --json", "answer", check="state"),
        _case("statics.home_file", "statics --plates {d}/plates_home.json --json", "answer", check="state"),
        _case("statics.far", "statics --plates {d}/plates_far.json --json", "any", check="state"),
        _case(
            "statics.huge_translation", "statics --plates {d}/plates_huge_translation.json --json", "any", check="state"
        ),
        _case("statics.extra_key", "statics --plates {d}/plates_extra.json --json", "any", check="state"),
        _case("statics.no_source", "statics --json"),
        _case("statics.stdin_empty", "statics --plates - --json"),
        _case("statics.text", "statics --home", "answer"),
        _case("statics.carrier_bogus", "statics --home --carrier bogus"),
        _case("statics.carrier_q_nan", "statics --home --carrier ur5 --carrier-q nan 0 0 0 0 0"),
        _case("statics.carrier_q_count", "statics --home --carrier ur5 --carrier-q 0 0"),
        _case("statics.carrier_q_limits", "statics --home --carrier ur5 --carrier-q 100 0 0 0 0 0"),
        _case("statics.carrier_q_huge", "statics --home --carrier ur5 --carrier-q 1e308 0 0 0 0 0"),
        _case("statics.mount_nan", "statics --home --carrier ur5 --mount nan 0 0 0 0 0"),
        _case("statics.mount_huge", "statics --home --carrier ur5 --mount 0 0 0 1e9 0 0"),
        _case("statics.mount_without_carrier", "statics --home --mount 0 0 0 0 0 0"),
        _case("statics.carrier_home", "statics --home --carrier ur5 --json", "answer", slow=True, check="carrier"),
    ]
    return cases


def _solve_cases() -> list[CliCase]:
    s = "solve --json --goal " + REACHABLE
    cases = [
        _case("solve.goal_nan", "solve --json --goal nan 0 0.9 0 0 0"),
        _case("solve.goal_inf", "solve --json --goal 0 inf 0.9 0 0 0"),
        _case("solve.goal_overflow", "solve --json --goal 1e400 0 0.9 0 0 0"),
        _case("solve.goal_deg_huge", "solve --json --goal-deg 0 0 0.9 1e308 0 0"),
        _case("solve.goal_short", "solve --json --goal 0 0 0.9"),
        _case("solve.goal_text", "solve --json --goal a b c d e f"),
        _case("solve.no_goal", "solve --json"),
        _case("solve.both_goals", "solve --json --goal 0 0 0.9 0 0 0 --goal-deg 0 0 0.9 0 0 0"),
        _case("solve.ee_tolerance_nan", s + " --ee-tolerance nan 1e-3"),
        _case("solve.ee_tolerance_inf", s + " --ee-tolerance inf inf"),
        _case("solve.ee_tolerance_zero", s + " --ee-tolerance 0 0"),
        _case("solve.ee_tolerance_negative", s + " --ee-tolerance -1 1"),
        _case("solve.ee_tolerance_overflow", s + " --ee-tolerance 1e300 1e300"),
        _case("solve.ee_tolerance_rotation_huge", s + " --ee-tolerance 0.01 1e308"),
        _case("solve.goal_far", "solve --json --goal 1e308 0 0.9 0 0 0"),
        _case("solve.goal_far_below", "solve --json --goal 0 0 -1e15 0 0 0"),
        _case("solve.carrier_mount_far", s + " --carrier ur5 --mount 1e308 0 0 0 0 0"),
        _case("solve.carrier_empty", ["solve", "--json", "--goal", *REACHABLE.split(), "--carrier", ""]),
        # an option with no effect in the combination given is refused, never ignored
        *[
            _case(f"solve.no_optimize_with_{flag[2:].replace('-', '_')}", f"{s} --no-optimize {flag} {value}")
            for flag, value in (
                ("--method", "slsqp"),
                ("--starts", "all"),
                ("--w1", "1"),
                ("--w2", "1"),
                ("--max-iterations", "50"),
                ("--ftol", "1e-6"),
                ("--ee-tolerance", "0.01 0.01"),
                ("--objective", "sag"),
                ("--max-sag", "0.01"),
            )
        ],
        _case("stiffness.max_platforms_without_scaling", "stiffness --json --home --max-platforms 4"),
        _case("stiffness.compensated_with_scaling", "stiffness --json --scaling --compensated"),
        _case("stiffness.scaling_small", "stiffness --json --scaling --max-platforms 2", "answer", check="finite"),
        _case("solve.d_step_zero", s + " --d-step 0"),
        _case("solve.d_step_negative", s + " --d-step -1"),
        _case("solve.d_step_nan", s + " --d-step nan"),
        _case("solve.max_attempts_zero", s + " --max-attempts 0"),
        _case("solve.max_attempts_float", s + " --max-attempts 1e9"),
        _case("solve.max_iterations_zero", s + " --max-iterations 0"),
        _case("solve.ftol_zero", s + " --ftol 0"),
        _case("solve.ftol_nan", s + " --ftol nan"),
        _case("solve.weights_zero", s + " --w1 0 --w2 0"),
        _case("solve.w1_negative", s + " --w1 -1"),
        _case("solve.w2_inf", s + " --w2 inf"),
        _case("solve.method_bogus", s + " --method bogus"),
        _case("solve.fixed_carrier_without_carrier", s + " --fixed-carrier"),
        _case("solve.carrier_bogus", s + " --carrier bogus"),
        _case("solve.carrier_q_nan", s + " --carrier ur5 --carrier-q nan 0 0 0 0 0"),
        _case("solve.carrier_mount_nan", s + " --carrier ur5 --mount 0 0 nan 0 0 0"),
        _case(
            "solve.max_attempts_huge_tiny_step",
            "solve --json --goal " + UNREACHABLE + " --max-attempts 1000000000 --d-step 1e-9",
            isolate=True,
        ),
        _case("solve.max_iterations_huge", s + " --max-iterations 1000000000000", isolate=True),
        _case("solve.unreachable", "solve --json --no-optimize --goal " + UNREACHABLE, "answer", check="solve"),
        _case("solve.reachable", s, "answer", slow=True, check="solve"),
        _case("solve.reachable_no_optimize", s + " --no-optimize", "answer", slow=True, check="solve"),
        _case("solve.capacity", s + " --capacity", "answer", slow=True, check="solve"),
        _case("solve.ee_tolerance_huge", s + " --ee-tolerance 1e9 1e9", "any", slow=True, check="solve"),
        _case(
            "solve.carrier_capacity",
            "solve --json --carrier ur5 --capacity --goal 0.3 0.2 1.4 0 0 0",
            "any",
            slow=True,
            check="carrier_capacity",
        ),
    ]
    return cases


def _reproduce_cases() -> list[CliCase]:
    return [
        _case("reproduce.scenario_bogus", "reproduce --scenario bogus"),
        _case("reproduce.out_under_file", "reproduce --scenario translation --out " + UNDER_FILE),
        _case("reproduce.out_is_file", "reproduce --scenario translation --out {d}/afile"),
        _case("reproduce.w1_nan", "reproduce --scenario translation --w1 nan"),
        _case("reproduce.ee_tolerance_overflow", "reproduce --scenario translation --ee-tolerance 1e308 1e308"),
        _case("reproduce.max_iterations_negative", "reproduce --scenario translation --max-iterations -5"),
        _case("reproduce.method_bogus", "reproduce --method bogus"),
        _case("reproduce.config_bad", "reproduce --scenario translation --config {d}/cfg_9_81.yaml"),
        _case("reproduce.markdown_with_out", "reproduce --markdown --out {d}/{case}"),
        _case("reproduce.markdown_with_out_first", "reproduce --out {d}/{case} --scenario translation --markdown"),
        _case("reproduce.markdown_json", "reproduce --markdown --json"),
        _case("reproduce.markdown_value", "reproduce --markdown=yes"),
        _case("reproduce.markdown_scenario_bogus", "reproduce --markdown --scenario bogus"),
    ]


def _bench_cases() -> list[CliCase]:
    return [
        _case("bench.repeat_zero", "bench --repeat 0 --quick --no-optimize"),
        _case("bench.repeat_negative", "bench --repeat -1 --quick --no-optimize"),
        _case("bench.repeat_float", "bench --repeat 1e12 --quick --no-optimize"),
        _case("bench.repeat_huge", "bench --repeat 1000000000000 --quick --no-optimize --json", isolate=True),
        _case("bench.config_bad", "bench --quick --no-optimize --config {d}/cfg_nan.yaml"),
        _case("bench.map_cells_without_targets", "bench --quick --map-cells 100"),
        _case("bench.map_cells_negative", "bench --targets --quick --map-cells -1"),
        _case("bench.map_cells_tiny", "bench --targets --quick --map-cells 3"),
        _case("bench.map_cells_huge", "bench --targets --quick --map-cells 1000000000000", isolate=True),
        _case("bench.map_cells_float", "bench --targets --quick --map-cells 1e3"),
        _case("bench.quick", "bench --repeat 1 --quick --no-optimize --json", "answer", slow=True, check="finite"),
    ]


def _plan_cases() -> list[CliCase]:
    p = "plan --json --to " + NEAR_HOME
    cases = [
        _case("plan.rate_zero", p + " --rate 0"),
        _case("plan.rate_negative", p + " --rate -1"),
        _case("plan.rate_nan", p + " --rate nan"),
        _case("plan.rate_inf", p + " --rate inf"),
        _case("plan.rate_tiny", p + " --rate 1e-9"),
        _case("plan.rate_huge", p + " --rate 1e9 --out {d}/plan_rate.csv", isolate=True),
        _case("plan.w3_nan", p + " --w3 nan"),
        _case("plan.w3_negative", p + " --w3 -1"),
        _case("plan.to_nan", "plan --json --to nan 0 0.9 0 0 0"),
        _case("plan.to_overflow", "plan --json --to 0 0 1e400 0 0 0"),
        _case("plan.from_nan", p + " --from 0 0 nan 0 0 0"),
        _case("plan.to_far", "plan --json --to 1e308 0 0.9 0 0 0"),
        _case("plan.from_far", "plan --json --from 0 0 1e308 0 0 0 --to 0 0 0.9 0 0 0"),
        _case("plan.nothing", "plan --json"),
        _case("plan.out_under_file", p + " --out " + UNDER_FILE + ".csv"),
        _case("plan.out_is_dir", p + " --out {d}/adir"),
        _case("plan.plot_under_file", p + " --plot " + UNDER_FILE + ".png"),
        _case("plan.path_bogus", p + " --path bogus"),
        # --from then waypoints is a plan (since waypoints start at --to's start): answered, 0 or 1
        _case(
            "plan.from_with_waypoints",
            "plan --json --waypoints {d}/wp_valid.json --from 0 0 0.9 0 0 0",
            "any",
            slow=True,
        ),
        _case("plan.compare_rate_huge", "plan --compare --json --rate 1e9", isolate=True),
        _case(
            "plan.tiny_speed",
            p + " --config {d}/cfg_tiny_speed.yaml --out {d}/plan_slow.csv",
            "any",
            isolate=True,
            slow=True,
        ),
        _case(
            "plan.tiny_acceleration",
            p + " --config {d}/cfg_tiny_accel.yaml --out {d}/plan_slow2.csv",
            "any",
            isolate=True,
            slow=True,
        ),
        _case("plan.near_home", p + " --out {d}/plan_near.csv", "answer", slow=True, check="plan"),
        # the slowest allowed legs at 1000 Hz: over plan.row_checks, answered not possible at once
        _case(
            "plan.slowest_legs_rate_1000",
            p + " --rate 1000 --config {d}/cfg_slowest_legs.yaml --out {d}/plan_slowest.csv",
            "any",
            check="plan",
        ),
        _case(
            "plan.waypoints_valid",
            "plan --json --waypoints {d}/wp_valid.json --out {d}/plan_wp.csv",
            "answer",
            slow=True,
            check="plan_success",
        ),
        _case("plan.near_home_json_out", p + " --out {d}/plan_near.json", "answer", slow=True, check="plan"),
        _case(
            "plan.unreachable",
            # straight up past the stack's reach: a valid prefix, then "not possible" (the 1.5 rad
            # turn this case once used is now planned to its end, in about 70 s)
            "plan --json --to 0 0 1.6 0 0 0 --out {d}/plan_unreachable.csv",
            "answer",
            slow=True,
            check="plan",
        ),
        _case(
            "plan.waypoint_times",
            "plan --json --waypoints {d}/wp_times_given.json --out {d}/plan_times.csv",
            "any",
            slow=True,
            check="plan_times",
        ),
    ]
    for name in WAYPOINT_REFUSE:
        cases.append(_case(f"plan.{name.replace('.', '_')}", ["plan", "--json", "--waypoints", f"{{d}}/{name}"]))
    cases.append(_case("plan.wp_many", "plan --json --waypoints {d}/wp_many.json", isolate=True))
    return cases


WAYPOINT_REFUSE = [
    "wp_far.json",
    "missing.json",
    "adir",
    "wp_empty.json",
    "wp_nonutf8.json",
    "wp_deep.json",
    "wp_dup.json",
    "wp_toplist.json",
    "wp_degrees_string.json",
    "wp_degrees_int.json",
    "wp_times_nan.json",
    "wp_times_decreasing.json",
    "wp_times_count.json",
    "wp_times_strings.json",
    "wp_one.json",
    "wp_five.json",
    "wp_strings.json",
    "wp_bools.json",
    "wp_nan.json",
    "wp_unknown_key.json",
    "wp_header_only.csv",
    "wp_mixed.csv",
    "wp_nan.csv",
    "wp_nonutf8.csv",
    "wp_text.csv",
]


GRID_REFUSE = {
    "empty": "",
    "axis_empty": "x=",
    "count_zero": "x=0:1:0",
    "count_negative": "x=0:1:-1",
    "count_float": "x=0:1:2.5",
    "count_exp": "x=0:1:1e9",
    "nan": "x=nan",
    "inf": "x=inf",
    "overflow": "x=1e400",
    "stop_nan": "x=0:nan:3",
    "unknown_axis": "q=1",
    "twice": "x=0,x=1",
    "four_parts": "x=0:1:3:4",
    "semicolon": "x=0;y=0",
    "too_many_cells": "x=0:1:10000,y=0:1:10000",
    "axis_too_long": "x=0:1:100000",
    "overflowing_span": "x=1e308:-1e308:3",
}
ORIENTATION_REFUSE = {
    "nan": "nan 0 0",
    "two": "0 0",
    "overflow": "1e400 0 0",
    "text": "a b c",
    "too_many": "0 0 0;" * 20000,
}


def _walk_cases() -> list[CliCase]:
    """Walks whose work is over the plan.work bound are refused before planning."""
    return [
        _case("walk.floor_64_platforms", "walk --json --floor 0.5 2 --config {d}/cfg_platforms_64.yaml"),
        _case("walk.floor_count_huge", "walk --json --floor 0.5 1000000"),
        _case("walk.floor_step_nan", "walk --json --floor nan 2"),
    ]


def _hexapod_walk_cases() -> list[CliCase]:
    """A walk's goal, gait, step, samples and lift out of range are refused before any solve."""
    w = "hexapod walk --json "
    refused = [
        _case(f"hexapod.walk_{name}", w + args)
        for name, args in (
            ("without_to", ""),
            ("to_short", "--to 0.1 0"),
            ("to_nan", "--to nan 0 0"),
            ("to_inf", "--to 0 inf 0"),
            ("to_far", "--to 1e9 0 0"),
            ("yaw_past_pi", "--to 0 0 4"),
            ("too_many_steps", "--to 5 0 0 --step 0.01"),
            ("gait_unknown", "--to 0.1 0 0 --gait gallop"),
            ("step_zero", "--to 0.1 0 0 --step 0"),
            ("step_huge", "--to 0.1 0 0 --step 1e300"),
            ("step_nan", "--to 0.1 0 0 --step nan"),
            ("samples_zero", "--to 0.1 0 0 --samples 0"),
            ("samples_huge", "--to 0.1 0 0 --samples 1000000000"),
            ("samples_float", "--to 0.1 0 0 --samples 1.5"),
            ("lift_negative", "--to 0.1 0 0 --lift -0.1"),
            ("lift_nan", "--to 0.1 0 0 --lift nan"),
            ("with_scene", "--to 0.1 0 0 --scene {d}/missing.yaml"),
            ("with_html", "--to 0.1 0 0 --html {d}/w.html"),
        )
    ]
    return [
        *refused,
        _case("hexapod.stand_with_to", "hexapod stand --json --to 0.1 0 0"),
        _case("hexapod.walk_three_stacks", w + "--to 0.05 0 0 --samples 1 --stacks 3 --radius 0.4", "any"),
    ]


def _hexapod_cases() -> list[CliCase]:
    """Counts, sizes and masses of the hexapod out of range are refused before any solve."""
    h = "hexapod stand --json "
    cases = [
        _case(f"hexapod.{name}", h + args)
        for name, args in (
            ("stacks_zero", "--stacks 0"),
            ("stacks_huge", "--stacks 1000000000"),
            ("stacks_float", "--stacks 2.5"),
            ("radius_nan", "--radius nan"),
            ("radius_inf", "--radius inf"),
            ("radius_negative", "--radius -0.5"),
            ("radius_zero", "--radius 0"),
            ("body_mass_nan", "--body-mass nan"),
            ("body_mass_huge", "--body-mass 1e308"),
            ("feet_unknown", "--feet glued"),
            ("commands_unknown", "--commands best"),
            ("config_platforms_64", "--config {d}/cfg_platforms_64.yaml"),
            ("config_stacks_float", "--config {d}/cfg_hexapod_stacks_float.yaml"),
            ("config_com_short", "--config {d}/cfg_hexapod_com_short.yaml"),
            ("config_com_nan", "--config {d}/cfg_hexapod_com_nan.yaml"),
            ("config_unknown_key", "--config {d}/cfg_hexapod_unknown.yaml"),
            ("config_thick_body", "--config {d}/cfg_hexapod_thick_body.yaml"),
            ("scene_missing", "--scene {d}/missing.yaml"),
            ("html_unwritable", "--html " + UNDER_FILE + ".html"),
            ("plot_unwritable", "--plot " + UNDER_FILE + ".png"),
        )
    ]
    return [
        *cases,
        _case("hexapod.action_unknown", "hexapod gallop --json"),
        *_hexapod_walk_cases(),
        _case("hexapod.capacity_with_plot", "hexapod capacity --plot {d}/cap.png"),
        _case("hexapod.capacity_with_mass", "hexapod capacity --body-mass 5"),
        _case("hexapod.action_missing", "hexapod --json"),
        _case("hexapod.three_stacks", h + "--stacks 3 --radius 0.4", "answer"),
        _case("hexapod.resting_tipping", h + "--feet resting --config {d}/cfg_hexapod_tipping.yaml", "any"),
    ]


def _map_cases() -> list[CliCase]:
    m = "map --json --workers 0 --no-progress --grid x=0,y=0,z=0.85 --out "
    cases = [
        _case(f"map.grid_{k}", ["map", "--json", "--workers", "0", "--grid", v, "--out", "{d}/map_{case}"])
        for k, v in GRID_REFUSE.items()
    ]
    cases += [
        _case(
            f"map.orientations_{k}",
            [
                "map",
                "--json",
                "--workers",
                "0",
                "--grid",
                "x=0,y=0,z=0.85",
                "--orientations",
                v,
                "--out",
                "{d}/map_{case}",
            ],
        )
        for k, v in ORIENTATION_REFUSE.items()
    ]
    cases += [
        _case(
            "map.grid_axis_huge", "map --json --workers 0 --grid x=0:1:1000000000 --out {d}/map_{case}", isolate=True
        ),
        _case("map.workers_negative", m + "{d}/map_{case} --workers -1"),
        _case("map.workers_huge", m + "{d}/map_{case} --workers 1000000", isolate=True),
        _case("map.batch_zero", m + "{d}/map_{case} --batch-size 0"),
        _case("map.batch_huge", m + "{d}/map_{case} --batch-size 1000000000"),
        _case("map.scheduler_bogus", m + "{d}/map_{case} --scheduler not-an-address", isolate=True),
        _case("map.scheduler_closed_port", m + "{d}/map_{case} --scheduler tcp://127.0.0.1:1", isolate=True),
        _case("map.out_is_file", m + "{d}/afile"),
        _case("map.out_under_file", m + UNDER_FILE),
        _case("map.png_under_file", m + "{d}/map_{case} --png " + UNDER_FILE + ".png"),
        _case("map.html_under_file", m + "{d}/map_{case} --html " + UNDER_FILE + ".html"),
        _case("map.sweep_missing", m + "{d}/map_{case} --sweep {d}/missing.yaml"),
        _case("map.sweep_dir", m + "{d}/map_{case} --sweep {d}/adir"),
        _case("map.sweep_same_names", m + "{d}/map_{case} --sweep {d}/cfg_other.yaml {d}/sub/cfg_other.yaml"),
        _case("map.sweep_invalid", m + "{d}/map_{case} --sweep {d}/cfg_9_81.yaml"),
        _case("map.parts_junk", m + "{d}/map_junk"),
        _case("map.parts_empty", m + "{d}/map_empty_part"),
        _case("map.parts_wrong_schema", m + "{d}/map_wrong_schema"),
        _case("map.one_cell", m + "{d}/map_one", "answer", slow=True, check="map"),
        _case(
            "map.unreachable_cell",
            "map --json --workers 0 --no-progress --grid x=5,y=0,z=0.5 --out {d}/map_far",
            "answer",
            slow=True,
            check="map",
        ),
    ]
    return cases


def _simulate_cases() -> list[CliCase]:
    h = "simulate --home --json"
    cases = [
        _case("simulate.seconds_zero", h + " --seconds 0"),
        _case("simulate.seconds_negative", h + " --seconds -1"),
        _case("simulate.seconds_nan", h + " --seconds nan"),
        _case("simulate.seconds_inf", h + " --seconds inf"),
        _case("simulate.seconds_huge", h + " --seconds 1e9", isolate=True),
        _case("simulate.samples_zero", h + " --samples 0"),
        _case("simulate.samples_one", h + " --samples 1"),
        _case("simulate.samples_huge", h + " --samples 1000000000", isolate=True),
        _case("simulate.drift_nan", h + " --drift-tolerance nan"),
        _case("simulate.drift_negative", h + " --drift-tolerance -1"),
        _case("simulate.drift_inf", h + " --drift-tolerance inf"),
        _case("simulate.html_under_file", h + " --html " + UNDER_FILE + ".html"),
        _case("simulate.plates_scaled", "simulate --json --plates {d}/plates_scaled.json"),
        _case("simulate.no_source", "simulate --json"),
        _case("simulate.trajectory_with_html", "simulate --trajectory {d}/traj_valid.csv --html {d}/sim.html"),
        _case(
            "simulate.trajectory_seconds_nan", "simulate --json --trajectory {d}/traj_valid.csv --drift-tolerance nan"
        ),
        _case("simulate.home", h, "answer", slow=True, check="held"),
        _case(
            "simulate.trajectory_valid_csv",
            "simulate --json --trajectory {d}/traj_valid.csv",
            "answer",
            slow=True,
            check="followed",
        ),
        _case(
            "simulate.trajectory_valid_json",
            "simulate --json --trajectory {d}/traj_valid.json",
            "answer",
            slow=True,
            check="followed",
        ),
    ]
    for name, (expect, formats) in TRAJECTORY_MUTATIONS.items():
        if name == "valid":
            continue
        for fmt in formats:
            case = _case(
                f"simulate.traj_{name}.{fmt}",
                ["simulate", "--json", "--trajectory", f"{{d}}/traj_{name}.{fmt}"],
                expect,
                slow=expect != "refuse",
                isolate=name in HANG_PRONE_TRAJECTORIES,
            )
            cases.append(case)
    cases += [
        _case("simulate.traj_missing", "simulate --json --trajectory {d}/missing.csv"),
        _case("simulate.traj_dir", "simulate --json --trajectory {d}/adir"),
        _case(
            "simulate.traj_other_platforms",
            "simulate --json --trajectory {d}/traj_valid.csv --config {d}/cfg_three.yaml",
        ),
    ]
    return cases


def _view_cases() -> list[CliCase]:
    html = " --html {d}/view.html"
    cases = [
        _case("view.home", "view --home" + html, "answer", slow=True, check="html"),
        _case(
            "view.trajectory_valid", "view --trajectory {d}/traj_valid.csv" + html, "answer", slow=True, check="html"
        ),
        _case("view.frames_zero", "view --trajectory {d}/traj_valid.csv --frames 0" + html),
        _case("view.frames_one", "view --trajectory {d}/traj_valid.csv --frames 1" + html),
        _case("view.frames_huge", "view --trajectory {d}/traj_valid.csv --frames 1000000000" + html),
        _case("view.animate_negative", "view --goal " + REACHABLE + " --animate -1" + html),
        _case("view.animate_huge", "view --goal " + REACHABLE + " --animate 1000000000" + html, isolate=True),
        _case("view.goal_nan", "view --goal nan 0 0.9 0 0 0" + html),
        _case("view.plates_scaled", "view --plates {d}/plates_scaled.json" + html),
        _case("view.plates_strings", "view --plates {d}/plates_strings.json" + html),
        _case("view.html_under_file", "view --home --html " + UNDER_FILE + ".html"),
        _case("view.html_is_dir", "view --home --html {d}/adir"),
        _case("view.carrier_trajectory", "view --carrier ur5 --trajectory {d}/traj_valid.csv" + html),
        _case("view.scenario_bogus", "view --scenario bogus" + html),
        _case("view.force_scale_bogus", "view --home --force-scale bogus" + html),
        _case("view.host_bogus", "view --home --host 999.999.999.999", isolate=True),
        _case("view.carrier_q_nan", "view --home --carrier ur5 --carrier-q nan 0 0 0 0 0" + html),
        _case("view.unreachable", "view --goal " + UNREACHABLE + html, "any", slow=True, check="html"),
        _case("view.config_bad", "view --home --config {d}/cfg_alias.yaml" + html),
    ]
    for name in ("empty", "truncated_rows", "length_nudged", "time_huge", "nonutf8", "column_missing"):
        cases.append(
            _case(
                f"view.traj_{name}",
                ["view", "--trajectory", f"{{d}}/traj_{name}.csv", "--html", "{d}/view.html"],
                TRAJECTORY_MUTATIONS[name][0],
            )
        )
    return cases


def _export_cases() -> list[CliCase]:
    return [
        _case("export.out_is_file", "export --out {d}/afile"),
        _case("export.out_under_file", "export --out " + UNDER_FILE),
        _case("export.config_bad", "export --out {d}/export_bad --config {d}/cfg_dup.yaml"),
        _case("export.hexapod_massless", "export --hexapod --out {d}/export_hx --config {d}/cfg_hexapod_massless.yaml"),
        _case(
            "export.hexapod_bad_section", "export --hexapod --out {d}/export_hx --config {d}/cfg_hexapod_unknown.yaml"
        ),
        _case("export.ok", "export --mjcf --out {d}/export_ok", "answer", check="export"),
    ]


def _global_cases() -> list[CliCase]:
    return [
        _case("cli.nothing", [], "answer"),  # the help: the list of subcommands, exit 0
        _case("cli.only_flags", ["-q", "-v"], "answer"),
        _case("cli.unknown_command", "frobnicate"),
        _case("cli.unknown_option", "statics --home --bogus"),
        _case("cli.config_missing_value", "statics --home --config"),
    ]


# ---------------------------------------------------------------------- trajectory mutations
#: name -> (what the contract expects of a reader, formats it is written in)
TRAJECTORY_MUTATIONS: dict[str, tuple[str, tuple[str, ...]]] = {
    "valid": ("answer", ("csv", "json")),
    "empty": ("refuse", ("csv", "json")),
    "header_only": ("refuse", ("csv", "json")),
    "single_row": ("refuse", ("csv", "json")),
    "truncated_bytes": ("refuse", ("csv", "json")),
    "truncated_rows": ("refuse", ("csv", "json")),
    "time_nan": ("refuse", ("csv", "json")),
    "time_inf": ("refuse", ("csv", "json")),
    "time_huge": ("refuse", ("csv", "json")),
    "time_decreasing": ("refuse", ("csv", "json")),
    "time_duplicate": ("refuse", ("csv", "json")),
    "time_offset": ("refuse", ("csv",)),
    "length_nudged": ("refuse", ("csv", "json")),
    "length_nan": ("refuse", ("csv", "json")),
    "length_text": ("refuse", ("csv",)),
    "length_bool": ("refuse", ("json",)),
    "ee_nudged": ("refuse", ("csv", "json")),
    "force_nudged": ("refuse", ("csv", "json")),
    "column_missing": ("refuse", ("csv", "json")),
    "column_renamed": ("refuse", ("csv", "json")),
    "columns_swapped": ("refuse", ("csv", "json")),
    "ragged_row": ("refuse", ("csv", "json")),
    "nonutf8": ("refuse", ("csv", "json")),
    "deep": ("refuse", ("json",)),
    "dup_keys": ("refuse", ("json",)),
    "rows_not_list": ("refuse", ("json",)),
    "platforms_mismatch": ("refuse", ("json",)),
    "meta_base_bad": ("refuse", ("json",)),
    "toplist": ("refuse", ("json",)),
    "dynamic_force_nan": ("refuse", ("csv", "json")),
    "dynamic_force_nudged": ("refuse", ("csv", "json")),
    "time_law_unknown": ("refuse", ("json",)),
    "time_law_missing": ("refuse", ("json",)),
    "older_version": ("refuse", ("csv", "json")),
    "version_float": ("refuse", ("json",)),
    "feasible_flag_cleared": ("any", ("csv",)),
    "extra_column": ("any", ("csv",)),
}
#: mutations a reader that trusts the file turns into a near-endless simulation
HANG_PRONE_TRAJECTORIES = {"time_huge", "time_inf", "time_offset"}


def _parse_csv(text: str) -> tuple[list[str], list[list[str]], list[str]]:
    """(the comment lines before the header, the table from the header on, the comment lines
    after the rows): a v2 file's ``# assembler-pin trajectory v2`` and ``# meta:`` lines come
    first and its ``# end: N rows`` line last; they are kept as they are, so a damaged row
    must be refused by the checksum or the row checks."""
    lines = text.splitlines()
    head = next(k for k, line in enumerate(lines) if line.startswith("t,"))
    tail = next((k for k in range(head + 1, len(lines)) if lines[k].startswith("#")), len(lines))
    return lines[:head], [r for r in csv.reader(lines[head:tail]) if r], lines[tail:]


def _csv_text(pre: list[str], rows: list[list[str]], post: list[str] = ()) -> str:
    buf = io.StringIO()
    csv.writer(buf, lineterminator="\n").writerows(rows)
    return "".join(line + "\n" for line in pre) + buf.getvalue() + "".join(line + "\n" for line in post)


def mutate_trajectory(name: str, fmt: str, original: str) -> bytes:
    """The trajectory file ``original`` (written by the planner, CSV or JSON) mutated by ``name``."""
    if name == "empty":
        return b""
    if name == "nonutf8":
        return original.encode()[:200] + b"\xff\xfe\x80" + original.encode()[200:]
    if name == "truncated_bytes":
        return original.encode()[: len(original) // 2 + 7]
    if fmt == "json":
        return _mutate_json(name, original)
    pre, table, post = _parse_csv(original)
    if name == "older_version":
        pre = [pre[0].replace(" v3", " v2"), *pre[1:]]
    header, rows = table[0], table[1:]
    _mutate_table(name, header, rows)
    if name == "header_only":
        rows = []
    return _csv_text(pre, [header, *rows], post).encode()


def _mutate_table(name: str, header: list[str], rows: list[list]) -> None:
    """Mutate a trajectory's header and rows in place (rows of strings or numbers)."""
    mid = len(rows) // 2
    col = {c: k for k, c in enumerate(header)}
    leg = col["L_sp1_leg2"]
    num = repr if isinstance(rows[0][0], str) else float  # CSV cells are text, JSON cells numbers
    if name == "single_row":
        del rows[1:]
    elif name == "truncated_rows":
        del rows[max(2, len(rows) // 3) :]
    elif name == "time_nan":
        rows[mid][0] = num(float("nan"))
    elif name == "time_inf":
        rows[-1][0] = num(float("inf"))
    elif name == "time_huge":
        rows[-1][0] = num(1e6)
    elif name == "time_decreasing":
        rows[mid][0], rows[mid + 1][0] = rows[mid + 1][0], rows[mid][0]
    elif name == "time_duplicate":
        rows[mid + 1][0] = rows[mid][0]
    elif name == "time_offset":
        for r in rows[mid:]:
            r[0] = num(float(r[0]) + 1e5)
    elif name == "length_nudged":
        rows[mid][leg] = num(float(rows[mid][leg]) + 1e-3)
    elif name == "length_nan":
        rows[mid][leg] = num(float("nan"))
    elif name == "length_text":
        rows[mid][leg] = "abc"
    elif name == "length_bool":
        rows[mid][leg] = True
    elif name == "ee_nudged":
        rows[mid][col["ee_x"]] = num(float(rows[mid][col["ee_x"]]) + 1e-3)
    elif name == "force_nudged":
        rows[mid][col["max_abs_force"]] = num(0.5 * float(rows[mid][col["max_abs_force"]]))
    elif name == "column_missing":
        k = col["ee_rz"]
        del header[k]
        for r in rows:
            del r[k]
    elif name == "column_renamed":
        header[leg] = "L_sp1_legX"
    elif name == "columns_swapped":
        a, b = col["L_sp0_leg0"], col["L_sp0_leg3"]
        header[a], header[b] = header[b], header[a]
    elif name == "ragged_row":
        del rows[mid][-3:]
    elif name == "dynamic_force_nan":
        rows[mid][col["F_sp1_leg2"]] = num(float("nan"))
    elif name == "dynamic_force_nudged":
        rows[mid][col["F_sp1_leg2"]] = num(float(rows[mid][col["F_sp1_leg2"]]) + 1.0)
    elif name == "feasible_flag_cleared":
        rows[mid][col["feasible"]] = num(0.0)
    elif name == "extra_column":
        header.append("note")
        for r in rows:
            r.append(num(1.0))


def _mutate_json(name: str, original: str) -> bytes:
    doc = json.loads(original)
    if name == "deep":
        return ('{"columns": ' + "[" * 100_000 + "]" * 100_000 + "}").encode()
    if name == "dup_keys":
        body = original.strip()
        return (body[:-1] + ', "rows": [[0.0]]}').encode()
    if name == "rows_not_list":
        doc["rows"] = 5
    elif name == "platforms_mismatch":
        doc["meta"]["platforms"] = 3  # v2: the platform count is in the meta
    elif name == "meta_base_bad":
        doc.setdefault("meta", {})["base"] = [[1.0, 0.0], [0.0, "x"]]
    elif name == "toplist":
        return json.dumps([doc]).encode()
    elif name == "time_law_unknown":
        doc["meta"]["time_law"] = "fastest"
    elif name == "time_law_missing":
        del doc["meta"]["time_law"]
    elif name == "older_version":
        doc["version"] = 2
    elif name == "version_float":
        doc["version"] = float(doc["version"])  # 3.0: not what the writer writes
    elif name == "header_only":
        doc["rows"] = []
    else:
        _mutate_table(name, doc["columns"], doc["rows"])
    return json.dumps(doc).encode()


# ---------------------------------------------------------------------- files
def _dumps(doc) -> bytes:
    return json.dumps(doc).encode()


def plate_files(home: np.ndarray) -> dict[str, bytes]:
    """Plate files (``{"plates": [n+1 4x4]}``) from the home pose (n+1, 4, 4)."""
    h = home.tolist()
    text = json.dumps({"plates": h})

    def with_plate(k: int, matrix) -> list:
        out = [m for m in h]
        out[k] = matrix
        return out

    scaled = (home[1] * np.diag([2, 2, 2, 1])).tolist()
    reflection = (home[1] @ np.diag([1, 1, -1, 1])).tolist()
    shear = home[1].copy()
    shear[0, 1] += 1e-3
    last = home[1].copy()
    last[3] = [0, 0, 1, 1]
    far = home.copy()
    far[2:, 2, 3] += 1.0
    huge = home.copy()
    huge[3:, 0, 3] = 1e300
    moved = home.copy()
    moved[:, 0, 3] += 1e15  # the whole stack moved: beyond the pose.translation limit
    one_string = [m for m in h]
    one_string[1] = [[str(v) if (i, j) == (0, 0) else v for j, v in enumerate(row)] for i, row in enumerate(h[1])]
    return {
        "plates_home.json": text.encode(),
        "plates_empty.json": b"",
        "plates_truncated.json": text.encode()[: len(text) // 2],
        "plates_nonutf8.json": b'{"plates": \xff\xfe}',
        "plates_deep.json": ("[" * 100_000 + "]" * 100_000).encode(),
        "plates_dupkey.json": ('{"plates": ' + json.dumps(h) + ', "plates": ' + json.dumps(h) + "}").encode(),
        "plates_strings.json": _dumps({"plates": [[[str(v) for v in r] for r in m] for m in h]}),
        "plates_one_string.json": _dumps({"plates": one_string}),
        "plates_bools.json": _dumps({"plates": [[[bool(v) for v in r] for r in m] for m in h]}),
        "plates_nan.json": text.replace("0.0", "NaN", 1).encode(),
        "plates_infinity.json": text.replace("0.0", "Infinity", 1).encode(),
        "plates_overflow.json": text.replace("0.0", "1e400", 1).encode(),
        "plates_bigint.json": text.replace("0.0", "1" + "0" * 400, 1).encode(),
        "plates_complex.json": _dumps({"plates": [[[f"{v}+0j" for v in r] for r in m] for m in h]}),
        "plates_null.json": b'{"plates": null}',
        "plates_scaled.json": _dumps({"plates": with_plate(1, scaled)}),
        "plates_reflection.json": _dumps({"plates": with_plate(1, reflection)}),
        "plates_shear.json": _dumps({"plates": with_plate(1, shear.tolist())}),
        "plates_lastrow.json": _dumps({"plates": with_plate(1, last.tolist())}),
        "plates_count.json": _dumps({"plates": h[:-1]}),
        "plates_3x3.json": _dumps({"plates": [[r[:3] for r in m[:3]] for m in h]}),
        "plates_ragged.json": _dumps({"plates": with_plate(2, h[2][:3])}),
        "plates_toplist.json": _dumps([h]),
        "plates_object.json": _dumps({"plates": {str(k): m for k, m in enumerate(h)}}),
        "plates_many.json": _dumps({"plates": h * 20_000}),
        "plates_quaternion_zero.json": _dumps({"plates": [[0, 0, 0, 0, 0, 0, 0]] * len(h)}),
        "plates_far.json": _dumps({"plates": far.tolist()}),
        "plates_huge_translation.json": _dumps({"plates": huge.tolist()}),
        "plates_moved_1e15.json": _dumps({"plates": moved.tolist()}),
        "plates_extra.json": _dumps({"plates": h, "units": "m"}),
    }


def _alias_bomb(levels: int, width: int) -> str:
    lines = ["a0: &a0 [1.0]"]
    for k in range(1, levels):
        refs = ", ".join([f"*a{k - 1}"] * width)
        lines.append(f"a{k}: &a{k} [{refs}]")
    lines.append(f"payload: {{mass: *a{levels - 1}}}")
    return "\n".join(lines) + "\n"


CONFIG_FILES: dict[str, bytes] = {
    "cfg_bigint_motor_radius.yaml": b"leg: {motor_radius: 1" + b"0" * 400 + b"}\n",
    "cfg_bigint_clearance.yaml": b"clearance: -1" + b"0" * 400 + b"\n",
    "cfg_typo_key.yaml": b"leg: {motor_radious: 0.02}\n",
    "cfg_empty.yaml": b"",
    "cfg_comment.yaml": b"# defaults\n",
    "cfg_other.yaml": b"payload:\n  mass: 2.0\n",
    "cfg_three.yaml": b"platforms: 3\n",
    "cfg_9_81.yaml": b"gravity: 9_81\n",
    "cfg_sexagesimal.yaml": b"gravity: 1:30\n",
    "cfg_octal_underscore.yaml": b"platforms: 0_4\n",
    "cfg_bool.yaml": b"gravity: yes\n",
    "cfg_nan.yaml": b"gravity: .nan\n",
    "cfg_inf.yaml": b"payload:\n  mass: .inf\n",
    "cfg_overflow.yaml": b"gravity: 1.0e400\n",
    "cfg_string.yaml": b"payload:\n  mass: '5'\n",
    "cfg_null.yaml": b"payload:\n  mass: ~\n",
    "cfg_null_section.yaml": b"payload: ~\n",
    "cfg_dup.yaml": b"gravity: 9.81\ngravity: 1.62\n",
    "cfg_alias.yaml": b"plate: &p {mass: 1.0}\npayload: *p\n",
    "cfg_alias_bomb_small.yaml": _alias_bomb(6, 6).encode(),
    "cfg_alias_bomb.yaml": _alias_bomb(10, 10).encode(),
    "cfg_deep_list.yaml": ("gravity: " + "[" * 20_000 + "]" * 20_000 + "\n").encode(),
    "cfg_deep_map.yaml": "".join(" " * k + f"k{k}:\n" for k in range(3000)).encode(),
    "cfg_toplist.yaml": b"- 1\n- 2\n",
    "cfg_python_tag.yaml": b"!!python/object/apply:os.system ['true']\n",
    "cfg_binary.yaml": b"gravity: !!binary AAAA\n",
    "cfg_nonutf8.yaml": b"gravity: 9.81 \xff\xfe\n",
    "cfg_long_value.yaml": b"payload:\n  mass: '" + b"x" * 2_000_000 + b"'\n",
    "cfg_long_key.yaml": b"x" * 1_000_000 + b": 1\n",
    "cfg_platforms_huge.yaml": b"platforms: 100000000\n",
    "cfg_platforms_float.yaml": b"platforms: 2.5\n",
    "cfg_platforms_bool.yaml": b"platforms: true\n",
    "cfg_negative_mass.yaml": b"payload:\n  mass: -1.0\n",
    "cfg_multi_doc.yaml": b"gravity: 1.0\n---\ngravity: 2.0\n",
    "cfg_truncated.yaml": b"leg:\n  max_tension: [1.0, 2\n",
    "cfg_unknown.yaml": b"gravity: 9.81\nspeed: 3\n",
    "cfg_complex.yaml": b"gravity: !!python/complex 1+2j\n",
    "cfg_timestamp.yaml": b"gravity: 2001-12-14\n",
    "cfg_tiny_speed.yaml": b"leg:\n  max_speed: 1.0e-12\n",
    "cfg_tiny_accel.yaml": b"leg:\n  max_acceleration: 1.0e-12\n",
    "cfg_slowest_legs.yaml": b"leg:\n  max_speed: 1.0e-4\n  max_acceleration: 1.0e-4\n",
    "cfg_platforms_64.yaml": b"platforms: 64\n",
    "cfg_clearance_negative.yaml": b"clearance: -0.001\n",
    "cfg_clearance_huge.yaml": b"clearance: 1.0e30\n",
    "cfg_clearance_nan.yaml": b"clearance: .nan\n",
    "cfg_shaft_wider.yaml": b"leg:\n  motor_radius: 0.01\n  shaft_radius: 0.02\n",
    "cfg_motor_longer.yaml": b"leg:\n  motor_length: 0.5\n",
    "cfg_node_zone_long.yaml": b"leg:\n  node_zone: 0.15\n",
    "cfg_plate_thick.yaml": b"plate:\n  radius: 0.1\n  thickness: 0.2\n",
    "cfg_plate_radius_zero.yaml": b"plate:\n  radius: 0.0\n",
    "cfg_payload_radius_negative.yaml": b"payload:\n  radius: -0.01\n",
    "cfg_payload_radius_huge.yaml": b"payload:\n  radius: 1.5\n",
    "cfg_payload_radius_text.yaml": b"payload:\n  radius: big\n",
    "cfg_payload_radius_nan.yaml": b"payload:\n  radius: .nan\n",
    "cfg_hexapod_stacks_float.yaml": b"hexapod:\n  stacks: 2.5\n",
    "cfg_hexapod_com_short.yaml": b"hexapod:\n  body_com: [0.0, 0.1]\n",
    "cfg_hexapod_com_nan.yaml": b"hexapod:\n  body_com: [.nan, 0.0, 0.1]\n",
    "cfg_hexapod_unknown.yaml": b"hexapod:\n  legs: 6\n",
    "cfg_hexapod_thick_body.yaml": b"hexapod:\n  body_radius: 0.1\n  body_thickness: 0.5\n",
    "cfg_hexapod_massless.yaml": b"hexapod:\n  body_mass: 0.0\n",
    "cfg_hexapod_tipping.yaml": b"hexapod:\n  stacks: 3\n  radius: 0.4\n  body_com: [-0.9, 0.0, 0.1]\n",
}


def waypoint_files(start: list[float], goal: list[float]) -> dict[str, bytes]:
    """Waypoint files between two EE poses (TAA rows)."""
    wp = [start, goal]
    row = ",".join(map(repr, start))
    return {
        "wp_valid.json": _dumps({"waypoints": wp}),
        "wp_times_given.json": _dumps({"waypoints": wp, "times": [0.0, 30.0]}),
        "wp_empty.json": b"",
        "wp_nonutf8.json": b'{"waypoints": [\xff]}',
        "wp_deep.json": ('{"waypoints": ' + "[" * 100_000 + "]" * 100_000 + "}").encode(),
        "wp_dup.json": ('{"waypoints": ' + json.dumps(wp) + ', "waypoints": ' + json.dumps(wp[:1]) + "}").encode(),
        "wp_toplist.json": _dumps(wp),
        "wp_degrees_string.json": _dumps({"waypoints": wp, "degrees": "false"}),
        "wp_degrees_int.json": _dumps({"waypoints": wp, "degrees": 1}),
        "wp_times_nan.json": b'{"waypoints": ' + json.dumps(wp).encode() + b', "times": [0.0, NaN]}',
        "wp_times_decreasing.json": _dumps({"waypoints": wp, "times": [5.0, 1.0]}),
        "wp_times_count.json": _dumps({"waypoints": wp, "times": [0.0]}),
        "wp_times_strings.json": _dumps({"waypoints": wp, "times": ["0", "30"]}),
        "wp_one.json": _dumps({"waypoints": wp[:1]}),
        "wp_five.json": _dumps({"waypoints": [p[:5] for p in wp]}),
        "wp_strings.json": _dumps({"waypoints": [[str(v) for v in p] for p in wp]}),
        "wp_bools.json": _dumps({"waypoints": [[True] * 6, [False] * 6]}),
        "wp_nan.json": b'{"waypoints": [[NaN, 0, 0.9, 0, 0, 0], [0, 0, 0.9, 0, 0, 0]]}',
        "wp_far.json": b'{"waypoints": [[1e308, 0, 0.9, 0, 0, 0], [0, 0, 0.9, 0, 0, 0]]}',
        "wp_unknown_key.json": _dumps({"waypoints": wp, "speed": 0.01}),
        "wp_many.json": _dumps({"waypoints": [start, goal] * 10_001}),
        "wp_header_only.csv": b"x,y,z,rx,ry,rz\n",
        "wp_mixed.csv": (row + "\n" + row + ",1.0\n").encode(),
        "wp_nan.csv": (row + "\nnan,0,0.9,0,0,0\n").encode(),
        "wp_nonutf8.csv": b"x,y,z,rx,ry,rz\n\xff\xfe\n",
        "wp_text.csv": b"hello world\nfoo,bar\n",
    }


def map_dirs(root: Path) -> None:
    """Map directories holding parts that are not a map's."""
    (root / "map_junk").mkdir(exist_ok=True)
    (root / "map_junk" / "part-0.parquet").write_bytes(b"this is not parquet\x00\xff")
    (root / "map_empty_part").mkdir(exist_ok=True)
    (root / "map_empty_part" / "part-0.parquet").write_bytes(b"")
    (root / "map_wrong_schema").mkdir(exist_ok=True)
    import pyarrow as pa
    import pyarrow.parquet as pq

    pq.write_table(pa.table({"a": [1, 2]}), root / "map_wrong_schema" / "part-0.parquet")


@dataclass
class Workspace:
    """The session's hostile files and the originals they come from."""

    root: Path
    home: np.ndarray
    traj_csv: str
    traj_json: str
    model_dir: Path
    extra: dict = field(default_factory=dict)


def build_workspace(root: Path, am, plan: Callable[[], tuple[str, str]]) -> Workspace:
    """Write every corpus file into ``root``; ``plan()`` gives a valid trajectory (CSV, JSON text)."""
    import assembler_pin as ap

    root.mkdir(parents=True, exist_ok=True)
    (root / "adir").mkdir(exist_ok=True)
    (root / "sub").mkdir(exist_ok=True)
    (root / "afile").write_text("a regular file\n")
    if not (root / "fifo.yaml").exists():
        os.mkfifo(root / "fifo.yaml")  # a FIFO nobody writes: reading it would block forever
    home = am.home_matrices if hasattr(am, "home_matrices") else np.array([m.homogeneous for m in am.home])
    files: dict[str, bytes] = {}
    files |= plate_files(home)
    files |= CONFIG_FILES
    files |= SCENE_FILES
    files["sub/cfg_other.yaml"] = CONFIG_FILES["cfg_other.yaml"]
    start = ap.kinematics.se3_to_taa(am.home[-1]).tolist()
    goal = [float(v) for v in NEAR_HOME.split()]
    files |= waypoint_files(start, goal)
    traj_csv, traj_json = plan()
    for name, (_, formats) in TRAJECTORY_MUTATIONS.items():
        for fmt in formats:
            original = traj_csv if fmt == "csv" else traj_json
            files[f"traj_{name}.{fmt}"] = (
                original.encode() if name == "valid" else mutate_trajectory(name, fmt, original)
            )
    for name, content in files.items():
        (root / name).write_bytes(content)
    map_dirs(root)
    model_dir = root / "model"
    ap.export.export_model_files(am.config, model_dir)
    return Workspace(root, home, traj_csv, traj_json, model_dir)


CLI_CASES: list[CliCase] = [
    *_global_cases(),
    *_statics_config_cases(),
    *_statics_cases(),
    *_scene_cases(),
    *_solve_cases(),
    *_reproduce_cases(),
    *_bench_cases(),
    *_plan_cases(),
    *_walk_cases(),
    *_hexapod_cases(),
    *_map_cases(),
    *_simulate_cases(),
    *_view_cases(),
    *_export_cases(),
]
assert len({c.id for c in CLI_CASES}) == len(CLI_CASES), "case ids must be unique"


# ---------------------------------------------------------------------- API calls
@dataclass(frozen=True)
class ApiCase:
    """One call of the public API with hostile arguments.

    Attributes:
        id: the case id (``api.`` first).
        call: the call, given the :class:`ApiContext`.
        expect: ``"refuse"`` (an AssemblerError subclass), ``"answer"`` or ``"any"``.
        verdict: a result that is returned must not claim this (``"success"``,
            ``"feasible"``): the call was given something it cannot have achieved.
        isolate: run in a memory-limited child process.
        slow: more than a few seconds.
        fk_lengths: the leg length [m] every leg was given (a successful FK is held to it).
    """

    id: str
    call: Callable
    expect: str = "refuse"
    verdict: str | None = None
    isolate: bool = False
    slow: bool = False
    fk_lengths: float | None = None


class ApiContext:
    """What API calls are built from: the default model, the workspace, a carrier."""

    def __init__(self, am, ws: Workspace) -> None:
        self.am, self.ws = am, ws
        self._carrier = None

    @property
    def carrier(self):
        from assembler_pin.carrier import Carrier

        if self._carrier is None:
            self._carrier = Carrier("ur5")
        return self._carrier

    def model_files(self, name: str, urdf: str | bytes | None = None, sidecar: str | bytes | None = None) -> Path:
        """A copy of the exported model with the URDF and/or sidecar text replaced."""
        d = self.ws.root / "models" / name
        d.mkdir(parents=True, exist_ok=True)
        for fname, text in (("assembler.urdf", urdf), ("assembler.yaml", sidecar)):
            content = (self.ws.model_dir / fname).read_bytes() if text is None else text
            (d / fname).write_bytes(content.encode() if isinstance(content, str) else content)
        return d / "assembler.urdf"

    def sidecar(self) -> str:
        return (self.ws.model_dir / "assembler.yaml").read_text()

    def urdf(self) -> str:
        return (self.ws.model_dir / "assembler.urdf").read_text()


def _se3(R=None, p=(0.0, 0.0, 0.9)):
    import pinocchio as pin

    return pin.SE3(np.eye(3) if R is None else np.asarray(R, dtype=float), np.asarray(p, dtype=float))


NAN_GOAL_P = (float("nan"), 0.0, 0.9)
REACH_P = (0.02, 0.01, 0.85)


def _plates_with(c: ApiContext, k: int, matrix) -> list:
    mats = [m.homogeneous.copy() for m in c.am.home]
    mats[k] = np.asarray(matrix, dtype=float)
    return mats


def _nonrotation_arrays(c: ApiContext):
    import assembler_pin as ap

    R = np.array([m.rotation for m in c.am.home])
    R[2] *= 2.0
    return ap.PlateArrays(R, np.array([m.translation for m in c.am.home]))


def _sidecar_with(c: ApiContext, old: str, new: str) -> str:
    text = c.sidecar()
    assert old in text, f"{old!r} not in the exported sidecar"
    return text.replace(old, new, 1)


def _api_cases() -> list[ApiCase]:
    import assembler_pin as ap
    from assembler_pin.carrier import Carrier, carrier_statics, solve_on_carrier
    from assembler_pin.kinematics import plates_from_q, sp_forward_kinematics
    from assembler_pin.maps import parse_grid, parse_orientations, run_map
    from assembler_pin.solver import solve  # the function: ``ap.solve`` (see api.solve.name_is_callable)
    from assembler_pin.statics import solve_statics_batch

    GT = ap.constraints.GoalTolerance
    home = lambda c: c.am.home  # noqa: E731
    cases = [
        # states and statics
        ApiCase("api.evaluate_state.nonrotation_arrays", lambda c: ap.evaluate_state(c.am, _nonrotation_arrays(c))),
        ApiCase("api.solve_statics.nonrotation_arrays", lambda c: ap.solve_statics(c.am, _nonrotation_arrays(c))),
        ApiCase(
            "api.evaluate_state.nan_arrays",
            lambda c: ap.evaluate_state(
                c.am, ap.PlateArrays(np.full((c.am.n + 1, 3, 3), np.nan), np.zeros((c.am.n + 1, 3)))
            ),
        ),
        ApiCase(
            "api.evaluate_state.wrong_shape_arrays",
            lambda c: ap.evaluate_state(c.am, ap.PlateArrays(np.zeros((c.am.n + 1, 2, 2)), np.zeros((c.am.n + 1, 3)))),
        ),
        ApiCase(
            "api.evaluate_state.reflection",
            lambda c: ap.evaluate_state(
                c.am, _plates_with(c, 1, np.diag([1.0, 1.0, -1.0, 1.0]) @ c.am.home[1].homogeneous)
            ),
        ),
        ApiCase("api.evaluate_state.string", lambda c: ap.evaluate_state(c.am, "home")),
        ApiCase("api.evaluate_state.dict", lambda c: ap.evaluate_state(c.am, {"plates": []})),
        ApiCase(
            "api.evaluate_state.complex",
            lambda c: ap.evaluate_state(c.am, np.array([m.homogeneous for m in c.am.home], dtype=complex)),
        ),
        ApiCase(
            "api.evaluate_state.object_array",
            lambda c: ap.evaluate_state(c.am, np.array([m.homogeneous for m in c.am.home], dtype=object)),
        ),
        ApiCase(
            "api.evaluate_state.goal_nan",
            lambda c: ap.evaluate_state(c.am, home(c), goal=_se3(p=NAN_GOAL_P)),
            "any",
            verdict="feasible",
        ),
        ApiCase(
            "api.evaluate_state.goal_matrix_nan",
            lambda c: ap.evaluate_state(c.am, home(c), goal=np.full((4, 4), np.nan)),
            "any",
            verdict="feasible",
        ),
        ApiCase(
            "api.evaluate_state.tolerance_nan",
            lambda c: ap.evaluate_state(
                c.am,
                home(c),
                goal=_se3(p=c.am.home[-1].translation + np.array([0.3, 0, 0])),
                tolerance=GT(np.nan, np.nan),
            ),
            "any",
            verdict="feasible",
        ),
        ApiCase(
            "api.evaluate_state.tolerance_negative",
            lambda c: ap.evaluate_state(c.am, home(c), goal=c.am.home[-1], tolerance=GT(-1.0, -1.0)),
            "any",
            verdict="feasible",
        ),
        ApiCase(
            "api.evaluate_state.tolerance_string",
            lambda c: ap.evaluate_state(c.am, home(c), goal=c.am.home[-1], tolerance="tight"),
        ),
        ApiCase(
            "api.solve_statics_batch.nan",
            lambda c: solve_statics_batch(c.am, np.full((2, c.am.n + 1, 4, 4), np.nan)),
        ),
        ApiCase(
            "api.solve_statics_batch.empty",
            lambda c: solve_statics_batch(c.am, np.zeros((0, c.am.n + 1, 4, 4))),
            "any",
        ),
        ApiCase("api.solve_statics_batch.wrong_shape", lambda c: solve_statics_batch(c.am, np.zeros((3, 4, 4)))),
        ApiCase("api.plates_from_q.zero_quaternions", lambda c: plates_from_q(c.am, np.zeros(c.am.nq))),
        ApiCase("api.plates_from_q.nan", lambda c: plates_from_q(c.am, np.full(c.am.nq, np.nan))),
        ApiCase("api.q_from_plates.nonrotation", lambda c: ap.kinematics.q_from_plates(c.am, _nonrotation_arrays(c))),
        ApiCase("api.leg_state.nonrotation", lambda c: ap.kinematics.leg_state(c.am, _nonrotation_arrays(c))),
        ApiCase("api.to_se3.bools", lambda c: ap.kinematics.to_se3(np.eye(4, dtype=bool))),
        ApiCase("api.taa_to_se3.strings", lambda c: ap.kinematics.taa_to_se3(["0", "0", "0.9", "0", "0", "0"])),
        ApiCase("api.taa_to_se3.bools", lambda c: ap.kinematics.taa_to_se3([True, False, True, False, False, False])),
        # forward kinematics
        ApiCase("api.fk.lengths_nan", lambda c: ap.stack_forward_kinematics(c.am, np.full((c.am.n, 6), np.nan))),
        ApiCase("api.fk.lengths_shape", lambda c: ap.stack_forward_kinematics(c.am, np.full((c.am.n, 5), 0.27))),
        ApiCase("api.fk.lengths_strings", lambda c: ap.stack_forward_kinematics(c.am, [["0.27"] * 6] * c.am.n)),
        ApiCase("api.fk.lengths_bools", lambda c: ap.stack_forward_kinematics(c.am, np.ones((c.am.n, 6), bool))),
        ApiCase(
            "api.fk.lengths_huge",
            lambda c: ap.stack_forward_kinematics(c.am, np.full((c.am.n, 6), 1e300)),
            "any",
            verdict="success",
        ),
        ApiCase(
            "api.fk.lengths_negative",
            lambda c: ap.stack_forward_kinematics(c.am, np.full((c.am.n, 6), -0.27)),
            "any",
            verdict="success",
        ),
        ApiCase(
            "api.fk.tol_nan",
            lambda c: ap.stack_forward_kinematics(c.am, np.full((c.am.n, 6), 0.27), tol=np.nan),
            fk_lengths=0.27,
        ),
        ApiCase(
            "api.fk.tol_negative",
            lambda c: ap.stack_forward_kinematics(c.am, np.full((c.am.n, 6), 0.27), tol=-1.0),
            fk_lengths=0.27,
        ),
        ApiCase(
            "api.fk.max_iterations_negative",
            lambda c: ap.stack_forward_kinematics(c.am, np.full((c.am.n, 6), 0.27), max_iterations=-1),
            fk_lengths=0.27,
        ),
        ApiCase(
            "api.fk.max_iterations_bool",
            lambda c: ap.stack_forward_kinematics(c.am, np.full((c.am.n, 6), 0.27), max_iterations=True),
            fk_lengths=0.27,
        ),
        ApiCase(
            "api.fk.max_iterations_huge",
            lambda c: ap.stack_forward_kinematics(c.am, np.full((c.am.n, 6), 0.9), max_iterations=10**12),
            "refuse",
            isolate=True,
            fk_lengths=0.9,
        ),
        ApiCase(
            "api.fk.guess_garbage",
            lambda c: ap.stack_forward_kinematics(c.am, np.full((c.am.n, 6), 0.27), guess="home"),
            fk_lengths=0.27,
        ),
        ApiCase(
            "api.fk.guess_nonrotation",
            lambda c: ap.stack_forward_kinematics(c.am, np.full((c.am.n, 6), 0.27), guess=_nonrotation_arrays(c)),
            fk_lengths=0.27,
        ),
        ApiCase(
            "api.fk.base_nonrotation",
            lambda c: ap.stack_forward_kinematics(c.am, np.full((c.am.n, 6), 0.27), base=np.diag([2.0, 2.0, 2.0, 1.0])),
            fk_lengths=0.27,
        ),
        ApiCase(
            "api.fk.base_nan",
            lambda c: ap.stack_forward_kinematics(c.am, np.full((c.am.n, 6), 0.27), base=np.full((4, 4), np.nan)),
            fk_lengths=0.27,
        ),
        ApiCase("api.sp_fk.lengths_nan", lambda c: sp_forward_kinematics(c.am, 0, np.full(6, np.nan))),
        # solve, initial condition, optimizer, capacity
        ApiCase(
            "api.solve.goal_nan", lambda c: solve(c.am, _se3(p=NAN_GOAL_P), optimize=False), "any", verdict="success"
        ),
        ApiCase("api.solve.goal_matrix_nan", lambda c: solve(c.am, np.full((4, 4), np.nan)), "any", verdict="success"),
        ApiCase("api.solve.goal_nonrotation", lambda c: solve(c.am, np.diag([2.0, 2.0, 2.0, 1.0]))),
        ApiCase("api.solve.goal_string", lambda c: solve(c.am, "goal")),
        ApiCase("api.solve.options_wrong_type", lambda c: solve(c.am, _se3(p=REACH_P), options="slsqp")),
        ApiCase("api.solve.options_dict", lambda c: solve(c.am, _se3(p=REACH_P), options={"w1": 1.0})),
        ApiCase(
            "api.solve.helper_options_wrong_type",
            lambda c: solve(c.am, _se3(p=REACH_P), optimize=False, helper_options=ap.OptimizeOptions()),
        ),
        ApiCase("api.solve.model_wrong_type", lambda c: solve("model", _se3(p=REACH_P))),
        ApiCase(
            "api.solve.name_is_callable",
            lambda c: (
                importlib.import_module("assembler_pin.solver.pipeline"),
                ap.solve(c.am, _se3(p=(10.0, 0, 0.9)), optimize=False),
            )[1],
            "any",
            verdict="success",
        ),
        ApiCase(
            "api.initial_condition.goal_nan",
            lambda c: ap.initial_condition(c.am, _se3(p=NAN_GOAL_P)),
            "any",
            verdict="success",
        ),
        ApiCase(
            "api.initial_condition.options_wrong_type",
            lambda c: ap.initial_condition(c.am, _se3(p=REACH_P), options={"d_step": 0.01}),
        ),
        ApiCase(
            "api.optimize.goal_nan",
            lambda c: ap.optimize_internal_poses(c.am, home(c), goal=_se3(p=NAN_GOAL_P)),
            "any",
            verdict="success",
        ),
        ApiCase(
            "api.optimize.goal_far_nan_tolerance",
            lambda c: ap.optimize_internal_poses(
                c.am,
                home(c),
                goal=_se3(p=c.am.home[-1].translation + np.array([0.3, 0, 0])),
                options=ap.OptimizeOptions(goal_tolerance=GT(np.nan, np.nan)),
            ),
        ),
        ApiCase("api.optimize.options_wrong_type", lambda c: ap.optimize_internal_poses(c.am, home(c), options=5)),
        ApiCase("api.optimize.initial_garbage", lambda c: ap.optimize_internal_poses(c.am, "home")),
        ApiCase("api.optimize_options.w1_nan", lambda c: ap.OptimizeOptions(w1=np.nan)),
        ApiCase("api.optimize_options.method_int", lambda c: ap.OptimizeOptions(method=5)),
        ApiCase("api.optimize_options.max_iterations_bool", lambda c: ap.OptimizeOptions(max_iterations=True)),
        ApiCase("api.optimize_options.max_iterations_huge", lambda c: ap.OptimizeOptions(max_iterations=10**12)),
        ApiCase("api.optimize_options.max_iterations_float", lambda c: ap.OptimizeOptions(max_iterations=10.5)),
        ApiCase("api.optimize_options.ftol_string", lambda c: ap.OptimizeOptions(ftol="1e-7")),
        ApiCase("api.optimize_options.ee_tolerance_string", lambda c: ap.OptimizeOptions(ee_tolerance="loose")),
        ApiCase("api.optimize_options.ee_tolerance_nan", lambda c: ap.OptimizeOptions(ee_tolerance=GT(np.nan, 1.0))),
        ApiCase("api.optimize_options.goal_tolerance_inf", lambda c: ap.OptimizeOptions(goal_tolerance=GT(np.inf, 1))),
        ApiCase(
            "api.helper_options.tiny_step_huge_attempts", lambda c: ap.HelperArmOptions(d_step=1e-9, max_attempts=10**9)
        ),
        ApiCase("api.helper_options.d_step_nan", lambda c: ap.HelperArmOptions(d_step=np.nan)),
        ApiCase("api.helper_options.max_attempts_bool", lambda c: ap.HelperArmOptions(max_attempts=True)),
        ApiCase("api.helper_options.tolerance_wrong_type", lambda c: ap.HelperArmOptions(tolerance=1e-9)),
        ApiCase(
            "api.capacity.goal_nan", lambda c: ap.payload_capacity(c.am, _se3(p=NAN_GOAL_P)), "any", verdict="success"
        ),
        ApiCase("api.capacity.rtol_nan", lambda c: ap.payload_capacity(c.am, _se3(p=REACH_P), rtol=np.nan)),
        ApiCase(
            "api.capacity.max_iterations_negative",
            lambda c: ap.payload_capacity(c.am, _se3(p=REACH_P), max_iterations=-1),
        ),
        ApiCase(
            "api.capacity.max_iterations_huge",
            lambda c: ap.payload_capacity(c.am, _se3(p=REACH_P), max_iterations=10**9),
            isolate=True,
        ),
        ApiCase("api.capacity.start_garbage", lambda c: ap.payload_capacity(c.am, _se3(p=REACH_P), start="home")),
        # motion
        ApiCase(
            "api.plan.rate_nan",
            lambda c: ap.plan_trajectory(
                c.am, ap.EEPath((c.am.home[-1], c.am.home[-1] * _se3(p=(0, 0, -0.01)))), c.am.home, rate=np.nan
            ),
        ),
        ApiCase(
            "api.plan.rate_huge",
            lambda c: ap.plan_trajectory(
                c.am, ap.EEPath((c.am.home[-1], c.am.home[-1] * _se3(p=(0, 0, -0.01)))), c.am.home, rate=1e9
            ),
            isolate=True,
        ),
        ApiCase(
            "api.plan.refinements_negative",
            lambda c: ap.plan_trajectory(
                c.am, ap.EEPath((c.am.home[-1], c.am.home[-1] * _se3(p=(0, 0, -0.01)))), c.am.home, refinements=-1
            ),
        ),
        ApiCase("api.plan.path_wrong_type", lambda c: ap.plan_trajectory(c.am, [c.am.home[-1]], c.am.home)),
        ApiCase(
            "api.plan.options_wrong_type",
            lambda c: ap.plan_trajectory(
                c.am, ap.EEPath((c.am.home[-1], c.am.home[-1] * _se3(p=(0, 0, -0.01)))), c.am.home, options="fast"
            ),
        ),
        ApiCase(
            "api.plan.start_garbage",
            lambda c: ap.plan_trajectory(
                c.am, ap.EEPath((c.am.home[-1], c.am.home[-1] * _se3(p=(0, 0, -0.01)))), start="home"
            ),
        ),
        ApiCase("api.eepath.nan_waypoint", lambda c: ap.EEPath((c.am.home[-1], _se3(p=NAN_GOAL_P)))),
        ApiCase("api.eepath.matrix_waypoints", lambda c: ap.EEPath((np.eye(4), np.eye(4)))),
        ApiCase("api.eepath.times_bools", lambda c: ap.EEPath((c.am.home[-1], c.am.home[-1]), times=(False, True))),
        ApiCase("api.eepath.between_nan", lambda c: ap.EEPath.between(np.eye(4), np.full((4, 4), np.nan))),
        ApiCase("api.read_trajectory.dir", lambda c: ap.read_trajectory(c.ws.root / "adir")),
        ApiCase("api.read_trajectory.missing", lambda c: ap.read_trajectory(c.ws.root / "missing.csv")),
        ApiCase("api.read_trajectory.int", lambda c: ap.read_trajectory(5)),
        # configs and model files
        ApiCase("api.load_config.int", lambda c: ap.load_config(5)),
        ApiCase("api.load_config.bytes", lambda c: ap.load_config(b"gravity: 1.0")),
        ApiCase("api.load_config.dir", lambda c: ap.load_config(c.ws.root / "adir")),
        ApiCase("api.load_config.list", lambda c: ap.load_config([("gravity", 1.0)])),
        ApiCase(
            "api.load_config.alias_bomb", lambda c: ap.load_config(c.ws.root / "cfg_alias_bomb.yaml"), isolate=True
        ),
        ApiCase("api.load_config.nested_numpy", lambda c: ap.load_config({"payload": {"mass": np.float64("nan")}})),
        ApiCase("api.load_config.numpy_bool", lambda c: ap.load_config({"gravity": np.bool_(True)})),
        ApiCase("api.load_config.complex", lambda c: ap.load_config({"gravity": 9.81 + 0j})),
        ApiCase("api.load_config.decimal_string", lambda c: ap.load_config({"gravity": "9.81"})),
        ApiCase("api.load_config.tiny_speed", lambda c: ap.load_config({"leg": {"max_speed": 1e-12}})),
        ApiCase("api.from_config.int", lambda c: ap.AssemblerModel.from_config(5)),
        ApiCase("api.from_config.missing", lambda c: ap.AssemblerModel.from_config(c.ws.root / "missing.yaml")),
        ApiCase("api.from_files.missing", lambda c: ap.AssemblerModel.from_files(c.ws.root / "missing.urdf")),
        ApiCase("api.from_files.empty_dir", lambda c: ap.AssemblerModel.from_files(c.ws.root / "adir")),
        ApiCase("api.from_files.roundtrip", lambda c: ap.AssemblerModel.from_files(c.ws.model_dir), "answer"),
        ApiCase(
            "api.from_files.urdf_garbage",
            lambda c: ap.AssemblerModel.from_files(c.model_files("urdf_garbage", urdf="<robot name='x'><link")),
        ),
        ApiCase(
            "api.from_files.urdf_empty", lambda c: ap.AssemblerModel.from_files(c.model_files("urdf_empty", urdf=""))
        ),
        ApiCase(
            "api.from_files.urdf_nonutf8",
            lambda c: ap.AssemblerModel.from_files(c.model_files("urdf_nonutf8", urdf=b"<robot \xff\xfe>")),
        ),
        ApiCase(
            "api.from_files.sidecar_empty",
            lambda c: ap.AssemblerModel.from_files(c.model_files("sidecar_empty", sidecar="")),
        ),
        ApiCase(
            "api.from_files.sidecar_nonutf8",
            lambda c: ap.AssemblerModel.from_files(c.model_files("sidecar_nonutf8", sidecar=b"closed_loop: \xff\n")),
        ),
        ApiCase(
            "api.from_files.sidecar_list",
            lambda c: ap.AssemblerModel.from_files(c.model_files("sidecar_list", sidecar="- 1\n- 2\n")),
        ),
        ApiCase(
            "api.from_files.sidecar_closed_loop_int",
            lambda c: ap.AssemblerModel.from_files(
                c.model_files("sidecar_int", sidecar="closed_loop: 5\ntype: 5\nname_mot: 5\n")
            ),
        ),
        ApiCase(
            "api.from_files.sidecar_pairs_strings",
            lambda c: ap.AssemblerModel.from_files(
                c.model_files(
                    "sidecar_str",
                    sidecar="closed_loop: "
                    + json.dumps(["ab"] * 24)
                    + "\ntype: "
                    + json.dumps(["3d"] * 24)
                    + "\nname_mot: []\n",
                )
            ),
        ),
        ApiCase(
            "api.from_files.sidecar_alias_bomb",
            lambda c: ap.AssemblerModel.from_files(
                c.model_files(
                    "sidecar_bomb", sidecar=_alias_bomb(10, 10) + "closed_loop: *a9\ntype: *a9\nname_mot: *a9\n"
                )
            ),
            isolate=True,
        ),
        ApiCase(
            "api.from_files.sidecar_9_81",
            lambda c: ap.AssemblerModel.from_files(
                c.model_files("sidecar_9_81", sidecar=_sidecar_with(c, "gravity: 9.81", "gravity: 9_81"))
            ),
        ),
        ApiCase(
            "api.from_files.sidecar_payload_disagrees",
            lambda c: ap.AssemblerModel.from_files(
                c.model_files("sidecar_payload", sidecar=_sidecar_with(c, "mass: 5.0", "mass: 50.0"))
            ),
        ),
        ApiCase(
            "api.from_files.sidecar_platforms_disagree",
            lambda c: ap.AssemblerModel.from_files(
                c.model_files("sidecar_platforms", sidecar=_sidecar_with(c, "platforms: 4", "platforms: 3"))
            ),
        ),
        ApiCase(
            "api.from_files.sidecar_dup_keys",
            lambda c: ap.AssemblerModel.from_files(
                c.model_files("sidecar_dup", sidecar=c.sidecar() + "closed_loop: []\n")
            ),
        ),
        ApiCase(
            "api.from_files.sidecar_is_dir",
            lambda c: ap.AssemblerModel.from_files(c.ws.model_dir / "assembler.urdf", c.ws.root / "adir"),
        ),
        # maps
        ApiCase("api.parse_grid.none", lambda c: parse_grid(None)),
        ApiCase("api.parse_grid.int", lambda c: parse_grid(5)),
        ApiCase("api.parse_grid.axis_huge", lambda c: parse_grid("x=0:1:1000000000"), isolate=True),
        ApiCase("api.parse_grid.axis_astronomic", lambda c: parse_grid("x=0:1:10000000000000")),
        ApiCase("api.parse_orientations.int", lambda c: parse_orientations(5)),
        ApiCase(
            "api.run_map.workers_negative",
            lambda c: run_map(parse_grid("x=0,y=0,z=0.85"), [("d", c.am.config)], c.ws.root / "api_map_w", workers=-1),
            isolate=True,
        ),
        ApiCase(
            "api.run_map.batch_negative",
            lambda c: run_map(
                parse_grid("x=0,y=0,z=0.85"), [("d", c.am.config)], c.ws.root / "api_map_b", workers=0, batch_size=-1
            ),
        ),
        ApiCase(
            "api.run_map.workers_string",
            lambda c: run_map(parse_grid("x=0,y=0,z=0.85"), [("d", c.am.config)], c.ws.root / "api_map_s", workers="2"),
        ),
        ApiCase(
            "api.run_map.configs_wrong",
            lambda c: run_map(parse_grid("x=0,y=0,z=0.85"), ["default"], c.ws.root / "api_map_c", workers=0),
        ),
        ApiCase(
            "api.run_map.grid_wrong", lambda c: run_map("x=0", [("d", c.am.config)], c.ws.root / "api_map_g", workers=0)
        ),
        ApiCase(
            "api.run_map.out_is_file",
            lambda c: run_map(parse_grid("x=0,y=0,z=0.85"), [("d", c.am.config)], c.ws.root / "afile", workers=0),
        ),
        # carrier
        ApiCase("api.carrier.bogus", lambda c: Carrier("bogus")),
        ApiCase("api.carrier.name_int", lambda c: Carrier(5)),
        ApiCase("api.carrier.mount_nan", lambda c: Carrier("ur5", mount=np.full((4, 4), np.nan))),
        ApiCase("api.carrier.mount_nonrotation", lambda c: Carrier("ur5", mount=np.diag([2.0, 2.0, 2.0, 1.0]))),
        ApiCase("api.carrier.mount_string", lambda c: Carrier("ur5", mount="flange")),
        ApiCase("api.carrier.check_q_nan", lambda c: c.carrier.check_q(np.full(6, np.nan))),
        ApiCase("api.carrier.check_q_strings", lambda c: c.carrier.check_q(["0"] * 6)),
        ApiCase("api.carrier.base_pose_wrong_count", lambda c: c.carrier.base_pose(np.zeros(3))),
        ApiCase(
            "api.carrier.ik_target_nan",
            lambda c: c.carrier.ik(_se3(p=NAN_GOAL_P), c.carrier.upright_q),
            "any",
            verdict="success",
        ),
        ApiCase(
            "api.carrier.ik_iterations_negative",
            lambda c: c.carrier.ik(_se3(p=REACH_P), c.carrier.upright_q, max_iterations=-1),
        ),
        ApiCase(
            "api.carrier_statics.q_nan",
            lambda c: carrier_statics(c.am, c.carrier, np.full(6, np.nan), c.am.home),
        ),
        ApiCase(
            "api.carrier_statics.plates_nonrotation",
            lambda c: carrier_statics(c.am, c.carrier, c.carrier.upright_q, _nonrotation_arrays(c)),
        ),
        ApiCase(
            "api.carrier_statics.carrier_wrong_type",
            lambda c: carrier_statics(c.am, "ur5", np.zeros(6), c.am.home),
        ),
        ApiCase(
            "api.solve_on_carrier.goal_nan",
            lambda c: solve_on_carrier(c.am, c.carrier, _se3(p=NAN_GOAL_P), move_carrier=False),
            "any",
            verdict="success",
        ),
        ApiCase(
            "api.solve_on_carrier.blends_zero",
            lambda c: solve_on_carrier(c.am, c.carrier, _se3(p=(0.3, 0.2, 1.4)), blends=0),
        ),
        ApiCase(
            "api.solve_on_carrier.blends_huge",
            lambda c: solve_on_carrier(c.am, c.carrier, _se3(p=(0.3, 0.2, 1.4)), blends=10**9),
            isolate=True,
        ),
        ApiCase(
            "api.solve_on_carrier.w_carrier_nan",
            lambda c: solve_on_carrier(c.am, c.carrier, _se3(p=(0.3, 0.2, 1.4)), w_carrier=np.nan),
        ),
        ApiCase(
            "api.solve_on_carrier.max_iterations_negative",
            lambda c: solve_on_carrier(c.am, c.carrier, _se3(p=(0.3, 0.2, 1.4)), max_iterations=-1),
        ),
        ApiCase(
            "api.solve_on_carrier.q0_wrong_count",
            lambda c: solve_on_carrier(c.am, c.carrier, _se3(p=(0.3, 0.2, 1.4)), q0=np.zeros(2)),
        ),
        # bounds before arithmetic: motions, tolerances, positions
        *[
            ApiCase(
                f"api.inverse_dynamics.{name}",
                lambda c, v=v: ap.inverse_dynamics(c.am, c.am.home, np.full((c.am.n + 1, 6), v), np.zeros((c.am.n, 6))),
            )
            for name, v in (("twists_1e308", 1e308), ("twists_1e200", 1e200), ("twists_1e5", 1e5))
        ],
        ApiCase(
            "api.inverse_dynamics.accelerations_huge",
            lambda c: ap.inverse_dynamics(c.am, c.am.home, np.zeros((c.am.n, 6)), np.full((c.am.n, 6), 1e300)),
        ),
        ApiCase("api.goal_tolerance.position_huge", lambda c: GT(1e300, 1e-3)),
        ApiCase("api.goal_tolerance.rotation_huge", lambda c: GT(1e-3, 1e308)),
        ApiCase("api.goal_tolerance.bool", lambda c: GT(True, 1e-3)),
        ApiCase(
            "api.evaluate_state.moved_1e15",
            lambda c: ap.evaluate_state(c.am, [m.homogeneous + _shift(1e15) for m in c.am.home]),
        ),
        # payload_capacity: a start that is not a valid pose at the goal, wrong types
        ApiCase(
            "api.payload_capacity.start_off_goal",
            lambda c: ap.payload_capacity(c.am, _se3(p=REACH_P), start=c.am.home),
        ),
        ApiCase(
            "api.payload_capacity.start_off_unreachable_goal",
            lambda c: ap.payload_capacity(c.am, _se3(p=(10.0, 0.0, 0.9)), start=c.am.home),
        ),
        ApiCase("api.payload_capacity.rtol_string", lambda c: ap.payload_capacity(c.am, _se3(p=REACH_P), rtol="0.1")),
        ApiCase("api.payload_capacity.rtol_nan", lambda c: ap.payload_capacity(c.am, _se3(p=REACH_P), rtol=np.nan)),
        ApiCase("api.payload_capacity.models_wrong", lambda c: ap.payload_capacity(c.am, _se3(p=REACH_P), models="x")),
        ApiCase("api.payload_capacity.model_string", lambda c: ap.payload_capacity("am", _se3(p=REACH_P))),
        *[
            ApiCase(
                f"api.two_point_statics.max_iterations_{name}",
                lambda c, v=v: ap.two_point_statics(c.am, c.am.home, max_iterations=v),
            )
            for name, v in (("zero", 0), ("huge", 10**9), ("bool", True), ("float", 5.0), ("string", "5"))
        ],
        ApiCase("api.two_point_statics.model_string", lambda c: ap.two_point_statics("am", c.am.home)),
        ApiCase("api.walk_options.floor_nan", lambda c: ap.walk.WalkOptions(floor_z=float("nan"))),
        ApiCase("api.walk_options.floor_bool", lambda c: ap.walk.WalkOptions(floor_z=True)),
        # one argument check at every public entry: a specific AssemblerError, never a bare one
        *[
            ApiCase(
                f"api.macro_statics.{name}",
                lambda c, m=m, com=com: ap.walk.macro_statics(c.am, [c.am.home, c.am.home], m, com),
            )
            for name, m, com in (
                ("mass_string", "5", [0, 0, 1]),
                ("mass_none", None, [0, 0, 1]),
                ("mass_complex", 1 + 2j, [0, 0, 1]),
                ("mass_huge", 1e308, [0, 0, 1]),
                ("mass_bool", True, [0, 0, 1]),
                ("com_string", 5.0, "abc"),
                ("com_none", 5.0, None),
                ("com_complex", 5.0, [1j, 0, 1]),
                ("com_huge", 5.0, [1e308, 0, 0]),
            )
        ],
        ApiCase("api.macro_capacity.com_none", lambda c: ap.walk.macro_capacity(c.am, [c.am.home], None)),
        *_hexapod_api_cases(),
        ApiCase("api.macro_statics.model_string", lambda c: ap.walk.macro_statics("am", [c.am.home], 1.0, [0, 0, 1])),
        ApiCase(
            "api.loaded_pose.max_iterations_negative", lambda c: ap.loaded_pose(c.am, c.am.home, max_iterations=-1)
        ),
        ApiCase("api.loaded_pose.max_iterations_string", lambda c: ap.loaded_pose(c.am, c.am.home, max_iterations="5")),
        ApiCase("api.stiffness.model_string", lambda c: ap.stiffness("am", c.am.home)),
        ApiCase("api.plan_walk.model_string", lambda c: ap.plan_walk("am", [])),
        ApiCase("api.turned_model.model_string", lambda c: ap.walk.turned_model("am")),
        ApiCase(
            "api.plan_walk.progress_int",
            lambda c: ap.plan_walk(c.am, ap.walk.footholds.floor_footholds(0.3, 2), progress=5),
        ),
        ApiCase(
            "api.plan_trajectory.progress_int",
            lambda c: ap.plan_trajectory(c.am, ap.EEPath.between(c.am.home[-1], c.am.home[-1]), progress=5),
        ),
        ApiCase(
            "api.stiffness_scaling.progress_int",
            lambda c: importlib.import_module("assembler_pin.compliance.scaling").stiffness_scaling(progress=5),
        ),
        ApiCase("api.read_walk_csv.none", lambda c: ap.walk.read_walk_csv(None)),
        ApiCase("api.read_walk_csv.bytes", lambda c: ap.walk.read_walk_csv(b"walk.csv")),
        ApiCase("api.parse_walk_csv.none", lambda c: ap.walk.parse_walk_csv(None)),
        ApiCase("api.parse_walk_csv.bytes", lambda c: ap.walk.parse_walk_csv(b"sample\n")),
        ApiCase("api.read_footholds.none", lambda c: ap.walk.footholds.read_footholds(None)),
        ApiCase("api.read_trajectory.dev_zero", lambda c: ap.read_trajectory("/dev/zero")),
        ApiCase("api.export_model_files.none", lambda c: ap.export.export_model_files(None, c.ws.root / "exp_none")),
        ApiCase("api.export_model_files.out_none", lambda c: ap.export.export_model_files(c.am.config, None)),
        *[
            ApiCase(
                f"api.sp_forward_kinematics.index_{name}",
                lambda c, j=j: sp_forward_kinematics(c.am, j, np.full(6, 0.27)),
            )
            for name, j in (("float", 1.0), ("bool", True), ("half", 1.5), ("string", "1"), ("negative", -1))
        ],
        ApiCase(
            "api.ee_jacobian.coinciding_joints",
            lambda c: ap.kinematics.jacobian.ee_jacobian_wrt_lengths(c.am, [_se3(p=(0, 0, 0))] * (c.am.n + 1)),
        ),
    ]
    return cases


def _hexapod_api_cases() -> list[ApiCase]:
    """The hexapod's entries: each hostile argument refused by a HexapodError (or the config's,
    the pose's own), a machine that cannot stand answered infeasible, never claimed feasible."""
    import assembler_pin as ap
    from assembler_pin import hexapod as hx

    def stand(c, **kw):
        args = {"stacks": [c.am.home] * 3, "body_mass": 1.0, "body_com": [0, 0, 1.0]} | kw
        return hx.stand(c.am, **args)

    shape = (3, 4, 6)
    cases = [
        ApiCase(f"api.hexapod_stand.{name}", lambda c, kw=kw: stand(c, **kw))
        for name, kw in (
            ("mass_string", {"body_mass": "5"}),
            ("mass_none", {"body_mass": None}),
            ("mass_nan", {"body_mass": float("nan")}),
            ("mass_bool", {"body_mass": True}),
            ("mass_huge", {"body_mass": 1e308}),
            ("com_none", {"body_com": None}),
            ("com_complex", {"body_com": [1j, 0, 1]}),
            ("com_inf", {"body_com": [0, float("inf"), 1]}),
            ("feet_int", {"feet": 1}),
            ("feet_unknown", {"feet": "glued"}),
            ("friction_nan", {"friction": float("nan")}),
            ("friction_negative", {"friction": -1.0}),
            ("min_margin_string", {"min_margin": "0"}),
            ("lengths_string", {"lengths": "abc"}),
            ("lengths_shape", {"lengths": np.full((2, 4, 6), 0.27)}),
            ("lengths_nan", {"lengths": np.full(shape, float("nan"))}),
            ("lengths_negative", {"lengths": np.full(shape, -0.27)}),
            ("lengths_huge", {"lengths": np.full(shape, 1e308)}),
            ("stacks_empty", {"stacks": []}),
            ("stacks_string", {"stacks": "stacks"}),
            ("stacks_too_many", {"stacks": [np.eye(4)] * 17}),
            ("stacks_short", {"stacks": [[np.eye(4)] * 2]}),
            ("scene_int", {"scene": 5}),
        )
    ]
    far = np.full(shape, 0.5)  # every leg commanded far beyond its stroke: an answer, infeasible
    cases += [
        ApiCase("api.hexapod_stand.lengths_far", lambda c: stand(c, lengths=far), "any", verdict="feasible"),
        ApiCase(
            "api.hexapod_stand.resting_tipping",
            lambda c: stand(c, body_mass=50.0, body_com=[3.0, 0, 1.0], feet="resting"),
            "any",
            verdict="feasible",
        ),
        ApiCase("api.hexapod_stand.scene_missing", lambda c: stand(c, scene=c.ws.root / "missing.yaml")),
        ApiCase("api.hexapod_stand.model_string", lambda c: hx.stand("am", [c.am.home], 1.0, [0, 0, 1])),
        ApiCase(
            "api.hexapod_stand.platforms_64",
            lambda c: hx.stand(ap.AssemblerModel.from_config({"platforms": 64}), [c.am.home], 1.0, [0, 0, 1]),
        ),
        ApiCase(
            "api.hexapod_capacity.rtol_zero", lambda c: hx.hexapod_capacity(c.am, [c.am.home], [0, 0, 1], rtol=0.0)
        ),
        ApiCase(
            "api.hexapod_capacity.rtol_string", lambda c: hx.hexapod_capacity(c.am, [c.am.home], [0, 0, 1], rtol="1")
        ),
        ApiCase("api.hexapod_capacity.com_nan", lambda c: hx.hexapod_capacity(c.am, [c.am.home], [np.nan, 0, 1])),
        ApiCase("api.ring_stacks.count_zero", lambda c: hx.ring_stacks(c.am, 0, 0.5)),
        ApiCase("api.ring_stacks.count_float", lambda c: hx.ring_stacks(c.am, 2.5, 0.5)),
        ApiCase("api.ring_stacks.count_huge", lambda c: hx.ring_stacks(c.am, 10**9, 0.5)),
        ApiCase("api.ring_stacks.radius_nan", lambda c: hx.ring_stacks(c.am, 3, float("nan"))),
        ApiCase(
            "api.force_optimal_commands.mass_nan",
            lambda c: hx.force_optimal_commands(c.am, [c.am.home], np.nan, [0, 0, 1]),
        ),
        ApiCase("api.length_sensitivity.result_string", lambda c: hx.length_sensitivity(c.am, "result")),
        ApiCase(
            "api.hexapod_clearance.scene_missing",
            lambda c: hx.hexapod_clearance(c.am, stand(c), c.ws.root / "missing.yaml"),
        ),
    ]
    cases += [
        ApiCase(f"api.load_config.hexapod_{name}", lambda c, section=section: ap.load_config({"hexapod": section}))
        for name, section in (
            ("none", None),
            ("list", [6]),
            ("stacks_string", {"stacks": "6"}),
            ("stacks_numpy_nan", {"stacks": np.float64("nan")}),
            ("stacks_bool", {"stacks": True}),
            ("com_bool", {"body_com": [True, 0, 0]}),
            ("com_nested", {"body_com": [[0, 0, 0]]}),
            ("com_huge", {"body_com": [1e308, 0, 0]}),
            ("friction_complex", {"friction": 1 + 1j}),
            ("radius_negative", {"radius": -1.0}),
            ("min_margin_nan", {"min_margin": float("nan")}),
            ("min_margin_huge", {"min_margin": 1e9}),
            ("min_margin_string", {"min_margin": "0.05"}),
            ("min_margin_bool", {"min_margin": True}),
        )
    ]
    cases += [
        ApiCase(f"api.hexapod_walk.{name}", lambda c, kw=kw: hx.walk(c.am, **({"to": (0.05, 0.0, 0.0)} | kw)))
        for name, kw in (
            ("to_none", {"to": None}),
            ("to_string", {"to": "forward"}),
            ("to_nan", {"to": (np.nan, 0.0, 0.0)}),
            ("to_complex", {"to": (1j, 0.0, 0.0)}),
            ("yaw_past_pi", {"to": (0.0, 0.0, 3.5)}),
            ("gait_none", {"gait": None}),
            ("step_negative", {"step": -0.1}),
            ("step_string", {"step": "0.1"}),
            ("samples_numpy_float", {"samples": np.float64(2.0)}),
            ("lift_huge", {"lift": 1e308}),
            ("min_margin_nan", {"min_margin": float("nan")}),
            ("too_many_cycles", {"to": (50.0, 0.0, 0.0), "step": 0.01}),
            ("model_string", {"am": "am"}),
        )
        if "am" not in kw
    ]
    cases += [
        ApiCase("api.hexapod_walk.model_string", lambda c: hx.walk("am", (0.05, 0.0, 0.0))),
        ApiCase("api.hexapod_stand.hanging_short", lambda c: stand(c, hanging=[True])),
        ApiCase("api.hexapod_stand.hanging_ints", lambda c: stand(c, hanging=[1, 0, 0])),
        ApiCase("api.hexapod_stand.hanging_all", lambda c: stand(c, feet="resting", hanging=[True] * 3)),
        ApiCase("api.read_walk.missing", lambda c: hx.read_walk(c.ws.root / "missing.json")),
        ApiCase("api.read_walk.directory", lambda c: hx.read_walk(c.ws.root)),
        ApiCase("api.read_walk.int", lambda c: hx.read_walk(5)),
    ]
    return cases


def _shift(d: float) -> np.ndarray:
    """A 4x4 matrix adding ``d`` [m] to a pose's x."""
    out = np.zeros((4, 4))
    out[0, 3] = d
    return out


API_CASES: list[ApiCase] = _api_cases()
assert len({c.id for c in API_CASES}) == len(API_CASES), "API case ids must be unique"
