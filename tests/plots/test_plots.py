"""Figures: the numbers drawn are the states' numbers, in the package's conventions."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from matplotlib.colors import to_rgb

from assembler_pin import evaluate_state, plots
from assembler_pin.exceptions import AssemblerError


@pytest.fixture(scope="module")
def two_states(am, bent_plates):
    return evaluate_state(am, am.home), evaluate_state(am, bent_plates)


def test_force_heatmaps_show_the_forces(two_states):
    initial, optimized = two_states
    fig = plots.force_heatmaps(initial, optimized)
    axes = [ax for ax in fig.axes if ax.images]
    assert len(axes) == 2
    for ax, state in zip(axes, two_states, strict=True):
        image = ax.images[0]
        assert np.array_equal(image.get_array(), state.forces.T)  # actuator × platform
        norm = image.norm
        assert norm(0.0) == pytest.approx(0.5)  # diverging, centred at zero
        texts = [float(t.get_text()) for t in ax.texts]
        assert np.allclose(sorted(texts), sorted(np.round(state.forces.ravel(), 1)), atol=0.051)
        # tension (positive) is drawn red, compression blue
        hot = image.cmap(norm(abs(state.forces).max()))
        cold = image.cmap(norm(-abs(state.forces).max()))
        assert hot[0] > hot[2] and cold[2] > cold[0]
    # one shared, symmetric scale
    vmax = max(np.abs(s.forces).max() for s in two_states)
    assert axes[0].images[0].norm.vmax == pytest.approx(vmax) and axes[0].images[0].norm.vmin == pytest.approx(-vmax)
    with pytest.raises(AssemblerError):
        plots.force_heatmaps(None, None)


def test_pose_views_draw_the_legs_at_their_joint_centres(two_states):
    initial, optimized = two_states
    arm = np.vstack([np.zeros(3), optimized.plates.p[1:-1], optimized.plates.p[-1]])
    fig = plots.pose_views(initial, optimized, arm_points=arm)
    side, front, top = fig.axes[:3]
    for ax, (a, b) in ((side, (0, 2)), (front, (1, 2)), (top, (0, 1))):
        for state, color in ((initial, plots.INITIAL_COLOR), (optimized, plots.OPTIMIZED_LEG_COLOR)):
            segments = [
                np.column_stack(line.get_data())
                for line in ax.lines
                if to_rgb(line.get_color()) == to_rgb(color) and len(line.get_xdata()) == 2
            ]
            expected = [
                np.array([[bp[a], bp[b]], [tp[a], tp[b]]])
                for bp, tp in zip(
                    state.legs.bottom_points.reshape(-1, 3), state.legs.top_points.reshape(-1, 3), strict=True
                )
            ]
            assert len(segments) >= len(expected)
            for seg in expected:
                assert any(np.allclose(seg, s, atol=1e-12) for s in segments)
    assert side.get_xlabel() == "x [m]" and side.get_ylabel() == "z [m]" and top.get_ylabel() == "y [m]"


def test_force_bars_heights(two_states, tmp_path):
    initial, optimized = two_states
    fig = plots.force_bars(initial, optimized, limits=(200.0, 150.0))
    ax = fig.axes[0]
    heights = np.array([p.get_height() for p in ax.patches])
    n = initial.forces.size
    assert np.allclose(heights[:n], initial.forces.ravel())
    assert np.allclose(heights[n:], optimized.forces.ravel())
    assert {line.get_ydata()[0] for line in ax.lines if line.get_linestyle() == "--"} == {200.0, -150.0}
    path = plots.save(fig, tmp_path / "sub" / "bars.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_workspace_slice_with_a_user_callable(am):
    calls = []

    def state_fn(goal: pin.SE3):
        calls.append(goal.translation.copy())
        if goal.translation[0] > 0.05:
            return None  # "unreachable"
        return evaluate_state(am, am.home)

    fig, ws = plots.workspace_slice(
        am, state_fn, plane="xz", u_range=(-0.1, 0.1), v_range=(0.8, 1.0), resolution=(3, 2), fixed=0.02
    )
    assert ws.max_abs_force.shape == (2, 3)
    assert np.array_equal(ws.reachable, np.array([[True, True, False], [True, True, False]]))
    assert np.allclose(ws.max_abs_force[ws.reachable], evaluate_state(am, am.home).max_abs_force)
    goals = np.array(calls)
    assert np.allclose(goals[:, 1], 0.02)  # the third axis is held fixed
    assert np.allclose(sorted(set(np.round(goals[:, 0], 9))), [-0.1, 0.0, 0.1])
    assert np.allclose(sorted(set(np.round(goals[:, 2], 9))), [0.8, 1.0])
    assert fig.axes[0].get_xlabel() == "x [m]"
    with pytest.raises(AssemblerError):
        plots.compute_workspace_slice(am, state_fn, plane="xx")


def test_workspace_slice_default_solver(am):
    ws = plots.compute_workspace_slice(am, plane="xz", u_range=(0.2, 0.2), v_range=(0.9, 0.9), resolution=(1, 1))
    assert ws.reachable.all() and ws.max_abs_force[0, 0] > 0


def test_figures_say_what_they_show(am):
    """Titles, legend entries for every mark, the goal, the floor, and the legs at a limit."""
    import dataclasses

    from matplotlib.patches import Rectangle

    from assembler_pin import stack_forward_kinematics

    leg = am.config.leg
    lengths = np.full((am.n, 6), 0.275)
    lengths[0, 1] = leg.min_length  # at a stroke end
    lengths[2, 4] = leg.max_length
    state = evaluate_state(am, stack_forward_kinematics(am, lengths).raise_if_failed())
    # the flags, held to the lengths set above and to a force limit placed at one leg's force
    stroke, bound = plots.leg_flags(state, leg)
    assert {tuple(x) for x in np.argwhere(stroke)} == {(0, 1), (2, 4)}
    assert not bound.any()
    j, i = np.unravel_index(np.abs(state.forces).argmax(), state.forces.shape)
    tight = dataclasses.replace(leg, max_tension=abs(state.forces[j, i]), max_compression=abs(state.forces[j, i]))
    assert plots.leg_flags(state, tight)[1][j, i]

    fig = plots.force_heatmaps(state, leg=leg, title="my scenario")
    frames = [p for ax in fig.axes for p in ax.patches if isinstance(p, Rectangle) and not p.get_fill()]
    assert len(frames) == 2 and fig.get_suptitle() == "my scenario"
    # the legend names the frames drawn, no other: no leg is at its force bound here
    assert [t.get_text() for lg in fig.legends for t in lg.get_texts()] == ["at a stroke end"]
    fig = plots.force_heatmaps(state, leg=tight)
    assert sorted(t.get_text() for lg in fig.legends for t in lg.get_texts()) == [
        "at a stroke end",
        "at the force bound",
    ]
    bars = plots.force_bars(state, limits=(leg.max_tension, leg.max_compression), leg=leg, title="my scenario")
    labels = [t.get_text() for t in bars.axes[0].get_legend().get_texts()]
    assert "initial: at a stroke end" in labels and {"tension limit", "compression limit"} <= set(labels)

    goal = pin.SE3(state.plates.R[-1], state.plates.p[-1])
    arm = np.linspace([0, 0, 0], state.plates.p[-1], am.n + 2)
    views = plots.pose_views(state, state, arm_points=arm, title="my scenario", goal=goal, floor_z=0.0)
    assert views.get_suptitle().startswith("my scenario") and f"{state.max_abs_force:.1f} N" in views.get_suptitle()
    assert [ax.get_title() for ax in views.axes] == ["side view (x–z)", "front view (y–z)", "top view (x–y)"]
    assert views.axes[0].get_legend() is None  # one legend, below the views
    labels = {t.get_text() for t in views.legends[0].get_texts()}
    assert {
        "initial",
        "optimized legs",
        "optimized plates",
        "plate centres",
        "helper arm",
        "helper arm joints",
        "EE goal",
        "EE goal's z axis (to the payload)",
        "floor",
    } <= labels
    # every entry of the legend names something drawn in the views
    drawn = {ln.get_label() for ax in views.axes for ln in ax.lines if len(ln.get_xdata())}
    drawn |= {"EE goal's z axis (to the payload)"} if any(ax.texts for ax in views.axes) else set()
    drawn |= {"plate centres", "optimized plates"}  # drawn unlabelled in the plates' colours, named once
    assert labels <= drawn, labels - drawn
    star = next(ln for ln in views.axes[0].lines if ln.get_label() == "EE goal")
    assert np.allclose([star.get_xdata()[0], star.get_ydata()[0]], goal.translation[[0, 2]])


def test_one_definition_of_a_leg_at_a_stroke_end(am):
    """The figures' flags and the results table count the same legs: those within
    ``STROKE_END_TOLERANCE`` of an end of the stroke (a leg 0.5 mm inside is not at it, one
    within the optimizer's margin is), and the pages state that tolerance."""
    from pathlib import Path

    from assembler_pin.config.options import OptimizeOptions
    from assembler_pin.constraints import STROKE_END_TOLERANCE, at_stroke_end

    leg = am.config.leg
    lo, hi = leg.min_length, leg.max_length
    lengths = np.array([lo, lo + 1e-7, lo + 5e-4, 0.5 * (lo + hi), hi - 5e-4, hi - 1e-7, hi])
    assert at_stroke_end(lengths, lo, hi).tolist() == [True, True, False, False, False, True, True]
    assert STROKE_END_TOLERANCE > OptimizeOptions().limit_margin  # beyond the optimizer's margin
    docs = Path(__file__).resolve().parents[2] / "docs"
    for page in ("guides/viewer.md", "results.md"):
        text = " ".join((docs / page).read_text(encoding="utf-8").split())
        assert f"within {STROKE_END_TOLERANCE:g} m of it, where the limit binds" in text, page
