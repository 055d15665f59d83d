"""Reproduce the paper's §V: the representative scenarios, initial vs optimized.

:func:`run_scenarios` solves every scenario goal (helper-arm initial condition, then the
force optimization) and :func:`write_report` writes a markdown report with PNG figures:
side and top views of the initial (green) and optimized poses, per-actuator force bars,
force heatmaps. :func:`summary_table` and :func:`force_tables` give the text the
``assembler-pin reproduce`` command prints — the summary the paper gives in prose and
its Tables I–II layout — beside the paper's own figures. :func:`sag_table` sets the
force-optimal pose beside the sag-optimal one (``OptimizeOptions(objective="sag")``): max|F|
and the EE's sag under its own load of each, the trade-off a user chooses from.
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin

from .common.files import atomic_path
from .common.labels import leg_label, platform_label
from .common.progress import ProgressCallback, checked_progress
from .constraints import STROKE_END_TOLERANCE, at_stroke_end
from .helper_arm import perturbed_plates, repair_stack
from .model.assembler import AssemblerModel
from .optimize import OptimizeOptions, optimize_internal_poses
from .optimize.objective import state_sag
from .scenarios import SCENARIOS, Scenario
from .solver.pipeline import SolveResult, solve
from .state import StackState, evaluate_state

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from .config.schema import LegConfig

__all__ = [
    "ScenarioOutcome",
    "findings",
    "force_tables",
    "results_markdown",
    "run_scenarios",
    "sag_table",
    "summary_table",
    "write_report",
]

logger = logging.getLogger(__name__)


#: Random valid poses drawn per goal for the reference columns, and the seed.
REFERENCE_SAMPLES = 8
REFERENCE_SEED = 0


@dataclass
class Reference:
    """What our optimum is measured against, beside our own start: random valid poses for
    the same goal, and the best optimum reached from each of them (a multistart).

    Attributes:
        sample_max_forces: max|F| of each random valid pose [N].
        multistart_best: smallest max|F| of the feasible optima from those poses and ours [N].
    """

    sample_max_forces: np.ndarray
    multistart_best: float

    @property
    def median(self) -> float:
        return float(np.median(self.sample_max_forces))

    @property
    def worst(self) -> float:
        return float(np.max(self.sample_max_forces))


@dataclass
class ScenarioOutcome:
    """One scenario solved: the scenario, its :class:`~assembler_pin.solver.pipeline.SolveResult`, the
    leg stroke it was solved with and the :class:`Reference` poses (None when not solved)."""

    scenario: Scenario
    result: SolveResult
    stroke: tuple[float, float]
    """(min_length, max_length) of the legs [m]."""
    reference: Reference | None = None
    sag_result: SolveResult | None = None
    """The same goal solved with the sag objective (None when not asked for)."""

    @property
    def initial(self) -> StackState | None:
        return self.result.initial

    @property
    def optimized(self) -> StackState | None:
        return self.result.optimized

    @property
    def reduction(self) -> float | None:
        """Relative reduction of max |F| [fraction], None when not solved."""
        if self.initial is None or self.optimized is None:
            return None
        return 1.0 - self.optimized.max_abs_force / self.initial.max_abs_force


def run_scenarios(
    am: AssemblerModel,
    names: Sequence[str] | None = None,
    options: OptimizeOptions | None = None,
    progress: ProgressCallback | None = None,
    sag: bool = True,
) -> list[ScenarioOutcome]:
    """Solve the named scenarios (default: all, in the paper's order) with the force
    objective and, with ``sag``, with the sag objective too (the same options otherwise);
    ``progress`` is called ``(done, total, scenario name)`` after each."""
    progress = checked_progress(progress)
    chosen = list(SCENARIOS) if names is None else list(names)
    base = options if options is not None else OptimizeOptions()
    force_options = dataclasses.replace(base, objective="force")
    outcomes = []
    for name in chosen:
        scn = SCENARIOS[name]
        result = solve(am, scn.goal, optimize=True, options=force_options)
        logger.info("scenario %s: %s", name, result.message)
        solved = result.initial is not None and result.optimized is not None
        ref = reference(am, result, force_options) if solved else None
        stroke = (am.config.leg.min_length, am.config.leg.max_length)
        sag_result = solve(am, scn.goal, options=dataclasses.replace(base, objective="sag")) if sag else None
        outcomes.append(ScenarioOutcome(scn, result, stroke, ref, sag_result))
        if progress is not None:
            progress(len(outcomes), len(chosen), name)
    return outcomes


def random_valid_poses(
    am: AssemblerModel, goal: pin.SE3, around: StackState, count: int, seed: int = REFERENCE_SEED
) -> list[StackState]:
    """Up to ``count`` random feasible poses for ``goal``: the internal plates of ``around``
    moved by seeded random twists (±5 cm, ±0.3 rad per axis), repaired onto the leg limits,
    and kept when every constraint (forces included) holds; at most ``3·count`` draws."""
    poses = []
    for plates in perturbed_plates(around.plates.as_se3(), 3 * count, seed=seed):
        repaired, violation = repair_stack(am, plates)
        if violation > 0.0:
            continue
        state = evaluate_state(am, repaired, goal=goal)
        if state.feasible:
            poses.append(state)
            if len(poses) == count:
                break
    return poses


def reference(am: AssemblerModel, result: SolveResult, options: OptimizeOptions | None = None) -> Reference | None:
    """The :class:`Reference` of a solved goal: :data:`REFERENCE_SAMPLES` random valid poses
    around the helper arm's initial pose, each also optimized (the multistart)."""
    assert result.initial is not None and result.optimized is not None, "a reference needs a solved goal"
    poses = random_valid_poses(am, result.goal, result.initial, REFERENCE_SAMPLES)
    if not poses:
        return None
    best = result.optimized.max_abs_force
    for start in poses:
        opt = optimize_internal_poses(am, start, result.goal, options)
        if opt.optimized.feasible:
            best = min(best, opt.optimized.max_abs_force)
    return Reference(np.array([p.max_abs_force for p in poses]), best)


#: Legs whose |F| is within this fraction of the largest are tied with it: an optimum of the
#: max|F| objective holds several legs at the maximum, equal to ~1e-8 N, the next one N below.
TIE_RTOL = 1e-5


def _argmax_label(state: StackState) -> str:
    """``SPj leg i`` of the largest |F| (0-based, :mod:`~assembler_pin.common.labels`); among legs
    tied with it (:data:`TIE_RTOL`) the first by platform, then leg, so that the label does
    not depend on the last bits of the forces (which differ between BLAS kernels)."""
    magnitude = np.abs(state.forces)
    first = np.flatnonzero(magnitude.ravel() >= (1.0 - TIE_RTOL) * magnitude.max())[0]
    j, i = np.unravel_index(first, magnitude.shape)
    return leg_label(j, i)


def _legs_at_stroke_end(state: StackState, stroke: tuple[float, float]) -> int:
    """Legs at a stroke end (:func:`~assembler_pin.constraints.at_stroke_end`): the limits that bind."""
    return int(np.sum(at_stroke_end(state.leg_lengths, *stroke)))


def _paper_reduction(scn: Scenario) -> float:
    return 1.0 - scn.paper_optimized_max_force / scn.paper_initial_max_force


def figure_title(s: Scenario) -> str:
    """A scenario's figure title: its name and goal (position [m], rotation vector [deg])."""
    taa = s.goal_taa
    return (
        f"{s.name}: goal ({', '.join(f'{x:.2f}' for x in taa[:3])}) m, "
        f"rotation vector ({', '.join(f'{np.rad2deg(x):.0f}' for x in taa[3:])})°"
    )


def summary_table(outcomes: Sequence[ScenarioOutcome], markdown: bool = False, times: bool = True) -> str:
    """Initial vs optimized max |F| (which leg: ``SPj leg i``, 0-based), reduction, mean |F|
    and time, beside the paper's figures; ``times=False`` leaves out the time column (the
    one figure that depends on the machine)."""
    header = [
        "scenario",
        "initial max|F| [N]",
        "optimized max|F| [N]",
        "reduction",
        "paper",
        "mean |F| init → opt [N]",
        "paper mean [N]",
        "legs at stroke end",
        "vs median / worst random valid pose",
        "gap to multistart",
        "time [s]",
    ]
    rows = []
    for o in outcomes:
        s = o.scenario
        reduction = 100 * _paper_reduction(s)
        paper = f"{s.paper_initial_max_force:.1f} → {s.paper_optimized_max_force:.1f} ({reduction:.0f}%)"
        paper_mean = f"{s.paper_initial_mean_force:.1f} → {s.paper_optimized_mean_force:.1f}"
        if o.initial is None or o.optimized is None:
            rows.append([s.name, "—", "—", "—", paper, "—", paper_mean, "—", "—", "—", "—"])
            continue
        time_s = sum(o.result.timing_s.values())
        rows.append(
            [
                s.name,
                f"{o.initial.max_abs_force:.1f} ({_argmax_label(o.initial)})",
                f"{o.optimized.max_abs_force:.1f} ({_argmax_label(o.optimized)})",
                "—" if o.reduction is None else f"{100 * o.reduction:.0f}%",
                paper,
                f"{o.initial.mean_abs_force:.1f} → {o.optimized.mean_abs_force:.1f}",
                paper_mean,
                f"{_legs_at_stroke_end(o.initial, o.stroke)} → {_legs_at_stroke_end(o.optimized, o.stroke)}",
                *_reference_cells(o),
                f"{time_s:.2f}",
            ]
        )
    if not times:
        header, rows = header[:-1], [r[:-1] for r in rows]
    if markdown:
        return _markdown_table(header, rows)
    return "\n\n".join(_text_table(header, rows, [c for c in cols if c < len(header)]) for cols in TEXT_GROUPS)


def _markdown_table(header: list[str], rows: list[list[str]]) -> str:
    """A markdown table, ``|`` in a cell escaped."""

    def md(cells: list[str]) -> str:
        return "| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |"

    return "\n".join([md(header), "|" + "---|" * len(header)] + [md(r) for r in rows])


#: The summary's columns in the terminal: three tables, each under 100 characters, each
#: led by the scenario's name (the markdown report keeps one table).
TEXT_GROUPS = ((0, 1, 2, 3, 4), (0, 5, 6, 7, 10), (0, 8, 9))


def _text_table(header: list[str], rows: list[list[str]], cols: Sequence[int]) -> str:
    """The columns ``cols`` of a table as aligned text, a dashed rule under the header."""
    picked = [[str(r[c]) for c in cols] for r in [header, *rows]]
    widths = [max(len(r[k]) for r in picked) for k in range(len(cols))]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths)
    lines = [fmt.format(*picked[0]), fmt.format(*["-" * w for w in widths])] + [fmt.format(*r) for r in picked[1:]]
    return "\n".join(line.rstrip() for line in lines)


def _reference_cells(o: ScenarioOutcome) -> list[str]:
    """ "-37% / -52% (n = 8)" and "+0.4%": our optimum against the reference poses."""
    ref = o.reference
    if ref is None or o.optimized is None:
        return ["—", "—"]
    ours = o.optimized.max_abs_force
    vs = (
        f"{100 * (1 - ours / ref.median):.0f}% / {100 * (1 - ours / ref.worst):.0f}% (n = {ref.sample_max_forces.size})"
    )
    return [vs, f"{100 * (ours / ref.multistart_best - 1):+.1f}%"]


def _sag_cells(am: AssemblerModel, result: SolveResult | None) -> list[str]:
    """max|F| [N], EE sag [mm] and optimizer time [s] of a solve's optimum ("—" when none)."""
    if result is None or result.optimized is None or not result.success:
        return ["—", "—", "—"]
    state = result.optimized
    return [f"{state.max_abs_force:.1f}", f"{1e3 * state_sag(am, state):.3f}", f"{result.timing_s['optimize']:.2f}"]


def _sag_change(force: list[str], sag: list[str]) -> float | None:
    """The sag's change from the force-optimal to the sag-optimal pose [%], from the table's
    cells (:func:`_sag_cells`), None when either is missing."""
    if "—" in (force[1], sag[1]):
        return None
    return 100 * (float(sag[1]) / float(force[1]) - 1)


def sag_table(
    am: AssemblerModel, outcomes: Sequence[ScenarioOutcome], markdown: bool = False, times: bool = True
) -> str:
    """The force-optimal and the sag-optimal pose side by side: max|F| [N], the EE's linear
    sag under its own load [mm] (:func:`~assembler_pin.compliance.loaded.sag_and_gradient`) and the
    optimizer's time ``t`` [s] (every start it ran) of each, and the sag's change; the text
    is under 100 characters wide. ``times=False`` leaves out the two time columns."""
    header = ["scenario", "force-opt max|F|", "sag [mm]", "t [s]", "sag-opt max|F|", "sag [mm]", "t [s]", "sag"]
    rows = []
    for o in outcomes:
        force, sag = _sag_cells(am, o.result), _sag_cells(am, o.sag_result)
        change = _sag_change(force, sag)
        rows.append([o.scenario.name, *force, *sag, "—" if change is None else f"{change:+.0f}%"])
    if not times:
        keep = [k for k, h in enumerate(header) if h != "t [s]"]
        header, rows = [header[k] for k in keep], [[r[k] for k in keep] for r in rows]
    if markdown:
        return _markdown_table(header, rows)
    return _text_table(header, rows, range(len(header)))


def results_markdown(am: AssemblerModel, outcomes: Sequence[ScenarioOutcome]) -> str:
    """What ``assembler-pin reproduce --markdown`` prints and ``docs/results.md`` holds between
    its markers: the summary table and the sag table in markdown without their time columns,
    and the ranges the page's prose rests on (:func:`findings`), all from ``outcomes``.

    Nothing in it depends on the machine: the times are left out, every figure is rounded as
    the tables round it, and a leg tied at the maximum is named by a fixed rule.
    """
    cfg = am.config
    parts = [
        f"The paper's scenarios on {am.n} platforms, payload {cfg.payload.mass:g} kg at "
        f"{cfg.payload.offset:g} m (forces in N, tension positive; `SPj leg i` 0-based):",
        summary_table(outcomes, markdown=True, times=False),
    ]
    if any(o.sag_result is not None for o in outcomes):
        parts += [
            "Force-optimal and sag-optimal poses: max|F| [N], the EE's sag under its own load [mm] "
            f"(legs of {cfg.leg.stiffness:g} N/m):",
            sag_table(am, outcomes, markdown=True, times=False),
        ]
    parts.append(findings(am, outcomes))
    return "\n\n".join(parts)


def _span(values: Sequence[float], fmt: str = "{:.0f}", unit: str = "%") -> str:
    """``"18–45%"``: the smallest and largest of ``values`` as the tables round them."""
    lo, hi = fmt.format(min(values)), fmt.format(max(values))
    return f"{lo}{unit}" if lo == hi else f"{lo}–{hi}{unit}"


def findings(am: AssemblerModel, outcomes: Sequence[ScenarioOutcome]) -> str:
    """The ranges over the solved scenarios that ``docs/results.md`` quotes, as a markdown
    list: reductions (ours and the paper's), the reference columns, the legs at a stroke end,
    where the mean |F| rises, and the sag-optimal poses against the force-optimal ones."""
    solved = [o for o in outcomes if o.initial is not None and o.optimized is not None]
    if not solved:
        return "- No scenario was solved."
    count = "all " + str(len(outcomes)) if len(solved) == len(outcomes) else f"{len(solved)} of {len(outcomes)}"
    lines = [
        f"- Solved: {count} scenarios. max|F| falls from our start by "
        f"{_span([100 * (o.reduction or 0.0) for o in solved])}; in the paper, from its start, by "
        f"{_span([100 * _paper_reduction(o.scenario) for o in solved])}."
    ]
    refs = [(o, o.reference) for o in solved if o.reference is not None]
    if refs:
        ours = [(o.optimized.max_abs_force, r) for o, r in refs if o.optimized is not None]
        sizes = _span([r.sample_max_forces.size for _, r in ours], unit="")
        gaps = [100 * (f / r.multistart_best - 1) for f, r in ours]
        gap = _span(gaps, "{:+.1f}")
        lines += [
            f"- The optimum is below the median random valid pose for the same goal by "
            f"{_span([100 * (1 - f / r.median) for f, r in ours])}, below the worst by "
            f"{_span([100 * (1 - f / r.worst) for f, r in ours])} (n = {sizes} poses per goal).",
            f"- Gap to the multistart: {gap} "
            + (f"on all {len(refs)}." if len(refs) == len(solved) else f"on {len(refs)} of the {len(solved)} solved."),
        ]
    starts = [_legs_at_stroke_end(o.initial, o.stroke) for o in solved if o.initial is not None]
    ends = [_legs_at_stroke_end(o.optimized, o.stroke) for o in solved if o.optimized is not None]
    lines.append(
        f"- Legs at an end of their stroke (within {STROKE_END_TOLERANCE:g} m of it, where the limit binds): "
        f"{_span(starts, '{:d}', '')} of {6 * am.n} at the start, {_span(ends, '{:d}', '')} at the optimum."
    )
    rising = [o.scenario.name for o in solved if o.optimized.mean_abs_force > o.initial.mean_abs_force]  # type: ignore[union-attr]
    lines.append(
        f"- The mean |F| rises while max|F| falls in {len(rising)} of {len(solved)}"
        + (f": {', '.join(rising)}." if rising else ".")
    )
    cells = [(_sag_cells(am, o.result), _sag_cells(am, o.sag_result)) for o in solved]
    pairs = [(force, sag, change) for force, sag in cells if (change := _sag_change(force, sag)) is not None]
    if pairs:
        more = [100 * (float(sag[0]) / float(force[0]) - 1) for force, sag, _ in pairs]
        lines.append(
            f"- The sag-optimal pose sags {_span([-c for _, _, c in pairs])} less than the force-optimal "
            f"one, for {_span(more)} more max|F|"
            + ("." if len(pairs) == len(solved) else f" ({len(pairs)} of the {len(solved)} solved have both).")
        )
    return "\n".join(lines)


def force_tables(outcome: ScenarioOutcome, markdown: bool = False) -> str:
    """The 6×n initial and optimized force tables side by side (paper Tables I–II) [N].

    Row ``i``, column ``SPj``: leg ``i`` of platform ``j``, both 0-based (:mod:`~assembler_pin.common.labels`).
    """
    if outcome.initial is None or outcome.optimized is None:
        return f"{outcome.scenario.name}: not solved ({outcome.result.message})"
    n = outcome.initial.forces.shape[0]
    sps = [platform_label(j) for j in range(n)]
    # one row per actuator: its force in every platform, initial then optimized
    rows = np.concatenate([outcome.initial.forces.T, outcome.optimized.forces.T], axis=1)  # (6, 2n)
    if markdown:
        header = ["leg"] + [f"initial {s}" for s in sps] + [f"optimized {s}" for s in sps]
        lines = ["| " + " | ".join(header) + " |", "|" + "---|" * (2 * n + 1)]
        lines += [f"| {i} | " + " | ".join(f"{f:.2f}" for f in row) + " |" for i, row in enumerate(rows)]
        return "\n".join(lines)

    def half(values: Sequence) -> str:
        return "".join(f"{v:>9}" if isinstance(v, str) else f"{v:9.2f}" for v in values)

    lines = [
        f"{outcome.scenario.title}: initial and optimized forces [N] (tension +)",
        "leg " + half(sps) + "   |" + half(sps),
    ]
    lines += [f"{i:>3} " + half(row[:n]) + "   |" + half(row[n:]) for i, row in enumerate(rows)]
    return "\n".join(lines)


def write_report(am: AssemblerModel, outcomes: Sequence[ScenarioOutcome], out_dir: str | Path) -> Path:
    """Write ``report.md`` and its PNG figures into ``out_dir``; returns the report path.

    Every file is first written to a temporary file beside it; they are moved into place
    together once all are written, ``report.md`` last, so an interrupted run leaves the
    previous report (or none) and never a partial one.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with contextlib.ExitStack() as files:
        report = files.enter_context(atomic_path(out / "report.md"))  # entered first: replaced last

        def target(name: str) -> Path:
            """A temporary path that becomes ``out/name`` with the report."""
            return files.enter_context(atomic_path(out / name))

        text = _report_text(am, outcomes, target)
        report.write_text(text, encoding="utf-8")
    return out / "report.md"


def _report_text(am: AssemblerModel, outcomes: Sequence[ScenarioOutcome], target: Callable[[str], Path]) -> str:
    """The markdown of the report; each figure is saved to ``target(file name)``."""
    from . import plots  # delays matplotlib

    leg = am.config.leg
    parts = [
        "# Internal-pose optimization: the paper's scenarios",
        "",
        f"{am.n} platforms, payload {am.config.payload.mass:g} kg at {am.config.payload.offset:g} m, "
        f"force limits {leg.max_tension:g} N tension / {leg.max_compression:g} N compression. "
        "Forces in newtons, tension positive. Initial pose: helper-arm initial condition; "
        "optimized: smooth SLSQP with analytic gradients.",
        "",
        summary_table(outcomes, markdown=True),
        "",
    ]
    if any(o.sag_result is not None for o in outcomes):
        parts += [
            "## Force-optimal and sag-optimal poses",
            "",
            f"max|F| [N] and the EE's sag under its own load [mm] (legs of {am.config.leg.stiffness:g} N/m,",
            "linear in their compliance) of the force-optimal pose (objective Ω) and of the sag-optimal",
            "pose (objective: the sag, every limit kept); t: the optimizer's time over its starts [s].",
            "",
            sag_table(am, outcomes, markdown=True),
            "",
        ]
    for o in outcomes:
        s = o.scenario
        parts += [f"## {s.title}", "", s.description, ""]
        if o.initial is None or o.optimized is None:
            parts += [f"Not solved: {o.result.message}", ""]
            continue
        for kind, fig in _figures(o, leg):
            name = f"{s.name}_{kind}.png"
            plots.save(fig, target(name))
            parts += [f"![{s.name} {kind}]({name})", ""]
        parts += [force_tables(o, markdown=True), "", f"Result: {o.result.message}.", ""]
    return "\n".join(parts)


def _figures(o: ScenarioOutcome, leg: LegConfig) -> Iterator[tuple[str, Figure]]:
    """A solved scenario's figures, one at a time: (kind, figure) for its views, force bars
    and force heatmaps."""
    from . import plots  # delays matplotlib

    s, heading = o.scenario, figure_title(o.scenario)
    arm = o.result.initial_result.arm_points
    yield "views", plots.pose_views(o.initial, o.optimized, arm, title=heading, goal=s.goal, floor_z=s.floor_z)
    limits = (leg.max_tension, leg.max_compression)
    yield "forces", plots.force_bars(o.initial, o.optimized, limits=limits, leg=leg, title=heading)
    yield "heatmap", plots.force_heatmaps(o.initial, o.optimized, leg=leg, title=heading)
