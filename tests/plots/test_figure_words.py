"""The figures a command writes say what they show: every text inside the canvas, margins
in millimetres, the force limits drawn, the time-optimal law's bang-bang acceleration named,
and a walk's time in seconds with no tool unless asked."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg


def texts_outside_the_canvas(fig) -> list[str]:
    """What of ``fig`` leaves its canvas: each axes with its labels, ticks and title (as
    drawn), and the figure's title."""
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    renderer = canvas.get_renderer()
    fig.draw(renderer)
    width, height = fig.bbox.width, fig.bbox.height
    boxes = [(ax.get_ylabel() or ax.get_xlabel() or "axes", ax.get_tightbbox(renderer)) for ax in fig.axes]
    texts = [t for t in (fig._suptitle, *fig.texts) if t is not None and t.get_text().strip()]
    boxes += [(t.get_text(), t.get_window_extent(renderer)) for t in texts]
    return [
        what
        for what, box in boxes
        if box is not None and (box.x0 < -0.5 or box.y0 < -0.5 or box.x1 > width + 0.5 or box.y1 > height + 0.5)
    ]


@pytest.fixture(scope="module")
def short_motion(am):
    import assembler_pin as ap
    from assembler_pin.motion import EEPath

    start = ap.kinematics.taa_to_se3([0, 0, 0.95, 0, 0, 0])
    goal = ap.kinematics.taa_to_se3([0.01, 0, 0.95, 0, 0, 0])
    first = ap.solve(am, start).optimized
    motion = ap.plan_trajectory(am, EEPath((start, goal)), first.plates, time_law="optimal")
    assert motion.success, motion.reason
    return motion


def test_plan_plot_titles_in_mm_force_limits_drawn_and_bang_bang_named(am, short_motion):
    from assembler_pin.motion.timing import trajectory_states
    from assembler_pin.plots.trajectory import trajectory_plot

    traj = short_motion.trajectory
    times, states = trajectory_states(am, traj, 20)
    fig = trajectory_plot(am, traj, states, times, "home → goal")
    assert "bang-bang" in fig._suptitle.get_text()
    assert not texts_outside_the_canvas(fig)
    leg = am.config.leg
    for row in fig.axes[: am.n * 5 : 5]:
        assert " mm (leg " in row.get_title(loc="left"), row.get_title(loc="left")  # length margin in millimetres
    forces = [ax for ax in fig.axes if ax.get_ylabel().startswith("force")]
    assert len(forces) == 2 * am.n
    # the five columns, as docs/colours.md names them
    columns = [ax.get_ylabel().split(" [")[0] for ax in fig.axes[:5]]
    assert columns == ["length", "speed", "acceleration", "force", "force static+dynamic"]
    assert len(fig.axes) == 5 * am.n and all(ax.get_ylabel() for ax in fig.axes)
    page = (Path(__file__).parents[2] / "docs" / "colours.md").read_text(encoding="utf-8")
    assert "one column each for leg length, speed, acceleration, force (statics) and force" in " ".join(page.split())
    for ax in forces:  # each force limit is drawn on the scale, or named at the panel's edge
        low, high = ax.get_ylim()
        named = " ".join(text.get_text() for text in ax.texts)
        for value, name in ((leg.max_tension, "tension"), (-leg.max_compression, "compression")):
            assert low <= value <= high or f"{name} limit {value:g} N" in named, (ax.get_title(loc="left"), named)


def _fake_walk(am, success=True):
    """A two-phase walk (reach, then transfer) of plausible samples, for the figure alone."""
    rng = np.random.default_rng(0)
    phases = []
    for kind, m in (("reach", 12), ("transfer", 4)):
        commanded = 0.275 + 0.01 * np.cumsum(rng.normal(size=(m, am.n, 6)), axis=0) / m
        phases.append(
            SimpleNamespace(kind=kind, plates=[None] * m, commanded=commanded, max_abs_forces=rng.uniform(5, 60, m))
        )
    return SimpleNamespace(phases=phases, footholds=[None, None], success=success, reason="")


def test_walk_plot_time_in_seconds_limits_drawn_labels_inside(am, tmp_path):
    from assembler_pin import AssemblerModel
    from assembler_pin.cli.walk import plot_walk, walk_times, walking_config

    am = AssemblerModel.from_config(walking_config(am.config, 0.0))
    walk = _fake_walk(am)
    fig = plot_walk(am, walk, str(tmp_path / "walk.png"))
    (ax,) = fig.axes
    assert ax.get_xlabel().endswith("[s]") and "sample" not in ax.get_xlabel()
    times = walk_times(am, walk)
    lengths = np.concatenate([p.commanded for p in walk.phases]).reshape(len(times), -1)
    expected = np.abs(np.diff(lengths, axis=0)).max(axis=1).sum() / am.config.leg.max_speed
    assert times[-1] == pytest.approx(expected)
    limits = [line.get_ydata()[0] for line in ax.get_lines() if line.get_linestyle() == "--"]
    assert am.config.leg.max_tension in limits and ax.get_ylim()[1] > am.config.leg.max_tension
    assert "no tool" in ax.get_title()
    assert not texts_outside_the_canvas(fig)


def test_a_walk_carries_no_tool_unless_asked():
    from assembler_pin.cli.walk import walking_config
    from assembler_pin.config import load_config

    cfg = load_config()
    assert cfg.payload.mass > 0
    assert walking_config(cfg, 0.0).payload.mass == 0.0
    assert walking_config(cfg, 2.5).payload == cfg.payload.__class__(mass=2.5, offset=cfg.payload.offset)


def test_scaling_figure_puts_one_unit_on_each_axis_and_labels_its_ticks():
    """``stiffness --scaling --out``: the N/m stiffnesses, the N·m/rad one and the sag each on
    their own axis, with at least three labelled ticks within the drawn range."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from assembler_pin.compliance.scaling import ScalingTable, scaling_figure

    n = np.array([1, 2, 4, 8, 16])
    table = ScalingTable(
        platforms=n,
        lateral=5.5e5 / n**3,
        axial=4.6e6 / n,
        torsional=2.5e4 / n,
        sag=1.2e-5 * n**1.5,
        elastic={"lateral": 5.6e5 / n**3, "axial": 4.6e6 / n, "torsional": 2.5e4 / n},
        stable=np.ones(5, dtype=bool),
        message=[""] * 5,
        leg_stiffness=1e6,
    )
    fig = scaling_figure(table)
    FigureCanvasAgg(fig).draw()
    units = {ax.get_ylabel().rsplit("[", 1)[-1].rstrip("]"): ax for ax in fig.axes}
    assert sorted(units) == ["N/m", "N·m/rad", "mm"]
    assert {ln.get_label() for ln in units["N·m/rad"].lines} == {
        "torsional (about z), loaded",
        "torsional (about z), legs' springs alone",
    }
    assert all("torsional" not in ln.get_label() for ln in units["N/m"].lines)
    for unit, ax in units.items():
        low, high = ax.get_ylim()
        ticks = [*ax.yaxis.get_major_ticks(), *ax.yaxis.get_minor_ticks()]
        shown = [t for t in ticks if t.label1.get_visible() and t.label1.get_text() and low <= t.get_loc() <= high]
        assert len(shown) >= 3, (unit, [t.label1.get_text() for t in shown])
    assert not texts_outside_the_canvas(fig)


#: The width a documentation page shows a wide figure at [px] (the site's content column).
PAGE_WIDTH_PX = 760


def test_the_pose_views_legend_reads_at_page_scale(am, bent_plates):
    """The home page's picture (docs/vertical_lift_views.png, the pose views at 150 dpi): its
    legend's letters stay at least 8 px tall when the figure is shown a page wide."""
    import struct

    from assembler_pin import evaluate_state
    from assembler_pin.plots import pose_views

    state = evaluate_state(am, bent_plates)
    fig = pose_views(evaluate_state(am, am.home), state, title="t")
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    (legend,) = fig.legends
    scale = PAGE_WIDTH_PX / fig.bbox.width
    heights = [scale * t.get_window_extent(renderer).height for t in legend.get_texts()]
    assert min(heights) >= 8.0, heights
    with (Path(__file__).resolve().parents[2] / "docs" / "vertical_lift_views.png").open("rb") as png:
        size = struct.unpack(">II", png.read(24)[16:24])
    assert size == (round(fig.get_figwidth() * 150), round(fig.get_figheight() * 150))
