"""One colour language, and figures that hide nothing: legends clear of the data, red only
for tension, every leg of the plan plot named, limits that do not squash the curves, and
the viewer's payload, ghost and carrier in their own colours.

The legend check renders the saved figure and compares, in display coordinates, every
legend box with every drawn vertex (a line's vertices, densified along its segments, and
a scatter's offsets) that lies inside its axes.
"""

from __future__ import annotations

import ast
import base64
import colorsys
import inspect
import re

import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PathCollection
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from assembler_pin import evaluate_state, palette, plots, scenario, stack_forward_kinematics, viz
from assembler_pin.labels import leg_label
from assembler_pin.motion.trajfile import MARGIN_KINDS, Trajectory


# ---------------------------------------------------------------------- helpers
def _densify(xy: np.ndarray, k: int = 24) -> np.ndarray:
    """Points along a polyline's segments (so a line crossing a box between two vertices counts)."""
    t = np.linspace(0.0, 1.0, k, endpoint=False)
    seg = xy[:-1, None, :] + t[None, :, None] * (xy[1:] - xy[:-1])[:, None, :]
    return np.vstack([seg.reshape(-1, 2), xy[-1:]])


def drawn_points(ax, renderer) -> list[tuple[str, np.ndarray]]:
    """(label, (N, 2) display points) of every visible line and scatter of ``ax``, clipped to the axes."""
    box = ax.get_window_extent(renderer)
    out = []
    for art in [*ax.lines, *(c for c in ax.collections if isinstance(c, PathCollection))]:
        if not art.get_visible():
            continue
        if isinstance(art, Line2D):
            xy = np.asarray(art.get_xydata(), dtype=float)
            if len(xy) >= 2 and art.get_linestyle() not in ("None", "none", "", " "):
                xy = _densify(xy)
            pts = art.get_transform().transform(xy)
        else:
            pts = art.get_offset_transform().transform(art.get_offsets())
        pts = pts[np.isfinite(pts).all(axis=1)]
        inside = (pts[:, 0] >= box.x0) & (pts[:, 0] <= box.x1) & (pts[:, 1] >= box.y0) & (pts[:, 1] <= box.y1)
        out.append((str(art.get_label()), pts[inside]))
    return out


def legend_overlaps(fig: Figure) -> list[str]:
    """What a legend box hides in the drawn figure: ``"<artist>: k points"`` per artist with
    drawn points inside any legend (axes legends and figure legends); empty when none."""
    FigureCanvasAgg(fig)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    legends = [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None] + list(fig.legends)
    assert legends, "the figure has no legend"
    boxes = [lg.get_window_extent(renderer) for lg in legends]
    hits = []
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        for label, pts in drawn_points(ax, renderer):
            for b in boxes:
                k = int(((pts[:, 0] > b.x0) & (pts[:, 0] < b.x1) & (pts[:, 1] > b.y0) & (pts[:, 1] < b.y1)).sum())
                if k:
                    hits.append(f"{label}: {k} points")
    return hits


def reddish(rgb) -> bool:
    """A colour a reader takes for red: hue within 25° of red, saturated and not dark."""
    h, s, v = colorsys.rgb_to_hsv(*to_rgb(rgb))
    return min(h, 1.0 - h) * 360.0 < 25.0 and s > 0.5 and v > 0.5


# ---------------------------------------------------------------------- fixtures
@pytest.fixture(scope="module")
def vertical_lift(am):
    """The vertical-lift goal's helper-arm state and arm (a stack lying over its floor line)."""
    from assembler_pin.helper_arm import initial_condition

    s = scenario("vertical_lift")
    res = initial_condition(am, s.goal)
    assert res.success
    return am, s, res


@pytest.fixture(scope="module")
def walk(am, bent_plates):
    """A smooth synthetic trajectory from home to a bent pose, with stack states at 7 samples."""
    home_lengths = np.full((am.n, 6), 0.275)
    bent = evaluate_state(am, bent_plates).leg_lengths
    T = 61
    t = np.linspace(0.0, 6.0, T)
    tau = t / t[-1]
    s = tau**3 * (10 - 15 * tau + 6 * tau**2)
    lengths = home_lengths[None] + s[:, None, None] * (bent - home_lengths)[None]
    idx = np.linspace(0, T - 1, 7).astype(int)
    states = [evaluate_state(am, stack_forward_kinematics(am, lengths[k]).raise_if_failed()) for k in idx]
    max_f = np.interp(t, t[idx], [st.max_abs_force for st in states])
    margins = {k: np.full(T, 0.01) for k in MARGIN_KINDS}
    traj = Trajectory(t, lengths, np.zeros((T, 6)), max_f, margins, np.ones(T, dtype=bool), am.n)
    return traj, states, t[idx]


@pytest.fixture(scope="module")
def plan_figure(am, walk):
    """The plan plot of :func:`walk`, drawn once: (figure, what its legends hide)."""
    traj, states, times = walk
    fig = plots.trajectory_plot(am, traj, states, times, "home → bent")
    return fig, legend_overlaps(fig)


# ---------------------------------------------------------------------- the palette
def test_palette_imports_nothing_heavy():
    tree = ast.parse(inspect.getsource(palette))
    top = {a.name for n in tree.body if isinstance(n, ast.Import) for a in n.names}
    top |= {n.module for n in tree.body if isinstance(n, ast.ImportFrom)}
    assert top <= {"__future__"}
    for name in ("TENSION", "COMPRESSION", "NEUTRAL", "INITIAL", "OPTIMIZED", "ARM", "CARRIER", "PAYLOAD"):
        rgb = getattr(palette, name)
        assert isinstance(rgb, tuple) and len(rgb) == 3 and all(0.0 <= c <= 1.0 for c in rgb), name
    assert palette.hex_color((1.0, 0.5, 0.0)) == "#ff8000"


def test_one_force_scale_in_figures_and_viewer(am):
    """The force table's colours are the viewer's leg colours at every force: blue ↔ grey ↔ red."""
    image = plots.force_heatmaps(evaluate_state(am, am.home), limit=150.0).axes[0].images[0]
    f = np.linspace(-150.0, 150.0, 301)
    figure = np.array(image.cmap(image.norm(f)))[:, :3]
    page = viz.force_color(f, 150.0, 150.0)
    np.testing.assert_allclose(figure, page, atol=2.5 / 255)
    assert reddish(figure[-1]) and not reddish(figure[0]) and figure[0, 2] > figure[0, 0]  # + red, − blue


def test_red_means_tension_only(vertical_lift, am):
    """No pose drawn in red: the optimized pose and every mark of the views take other colours."""
    _, s, res = vertical_lift
    fig = plots.pose_views(
        evaluate_state(am, am.home), res.state, arm_points=res.arm_points, goal=s.goal, floor_z=s.floor_z
    )
    colours = [line.get_color() for ax in fig.axes for line in ax.lines]
    colours += [p.get_facecolor() for ax in fig.axes for p in ax.patches]
    assert colours and not [c for c in colours if reddish(c[:3] if isinstance(c, tuple) else c)]
    assert not reddish(plots.OPTIMIZED_LEG_COLOR) and not reddish(plots.OPTIMIZED_PLATE_COLOR)
    bars = plots.force_bars(evaluate_state(am, am.home), res.state)
    assert not [p for p in bars.axes[0].patches if reddish(p.get_facecolor()[:3])]


# ---------------------------------------------------------------------- legends hide nothing
def test_pose_views_legend_hides_nothing(vertical_lift):
    _, s, res = vertical_lift
    fig = plots.pose_views(
        res.state, res.state, arm_points=res.arm_points, title="vertical_lift", goal=s.goal, floor_z=s.floor_z
    )
    assert legend_overlaps(fig) == []
    # the legend still names every mark
    labels = {t.get_text() for lg in fig.legends for t in lg.get_texts()}
    assert {"initial", "helper arm", "EE goal", "floor"} <= labels


def test_force_figures_legends_hide_nothing(vertical_lift, am):
    _, _, res = vertical_lift
    home = evaluate_state(am, am.home)
    leg = am.config.leg
    bars = plots.force_bars(home, res.state, limits=(leg.max_tension, leg.max_compression), leg=leg)
    assert legend_overlaps(bars) == []
    heat = plots.force_heatmaps(home, res.state, leg=leg)
    assert legend_overlaps(heat) == []


def test_the_overlap_check_sees_a_covering_legend():
    """The check itself: a legend placed on a line is reported, one placed beside it is not."""
    fig = Figure(figsize=(4, 3))
    ax = fig.subplots()
    ax.plot([0, 1], [0.9, 0.9], label="line at the top")
    ax.scatter([0.95], [0.05], label="dot")
    ax.legend(loc="upper right")
    assert any(h.startswith("line at the top") for h in legend_overlaps(fig))
    ax.get_legend().remove()
    ax.legend(loc="center left", bbox_to_anchor=(1.02, 0.5))
    assert legend_overlaps(fig) == []


# ---------------------------------------------------------------------- the plan plot
def _force_axes(fig: Figure) -> list:
    return [ax for ax in fig.axes if ax.get_visible() and "force" in ax.get_ylabel()]


def test_plan_plot_names_every_leg(am, plan_figure):
    fig, hidden = plan_figure
    labels = [t.get_text() for ax in fig.axes if ax.get_legend() for t in ax.get_legend().get_texts()]
    labels += [t.get_text() for lg in fig.legends for t in lg.get_texts()]
    expected = [leg_label(j, i) for j in range(am.n) for i in range(6)]
    assert sorted(set(labels) & set(expected)) == sorted(expected) and len(labels) == len(expected)
    # within a platform's panel, six different colours
    for ax in fig.axes:
        drawn = [ln for ln in ax.lines if ln.get_label() in expected]
        assert len({to_rgb(ln.get_color()) for ln in drawn}) == len(drawn)
    assert hidden == []


def test_plan_plot_limits_do_not_squash_the_forces(am, walk, plan_figure):
    """Forces of tens of newtons keep their own scale against ±limits of hundreds; the panel
    says how far the nearest limit is (the number checked against the forces themselves)."""
    _, states, _ = walk
    leg = am.config.leg
    fig, _ = plan_figure
    panels = _force_axes(fig)
    assert panels
    for ax in panels:
        ys = np.concatenate([ln.get_ydata() for ln in ax.lines if len(ln.get_ydata()) > 2])
        lo, hi = ax.get_ylim()
        assert (ys.max() - ys.min()) / (hi - lo) > 0.5, ax.get_title("left")
    forces = np.array([st.forces for st in states])  # (S, n, 6)
    for j, ax in enumerate(panels):
        f = forces[:, j, :]
        gap = min(f.min() + leg.max_compression, leg.max_tension - f.max())
        number = float(re.search(r"nearest limit ([0-9.e+-]+) N", ax.get_title("left")).group(1))
        assert number == pytest.approx(gap, rel=1e-3)  # written to 4 significant digits


def test_plan_plot_without_states_shows_the_stack_max_force(am, walk):
    traj, _, _ = walk
    fig = plots.trajectory_plot(am, traj, None, None, "no states")
    panels = _force_axes(fig)
    assert len(panels) == 1 and any(ln.get_label() == "max|F| (all legs)" for ln in panels[0].lines)


# ---------------------------------------------------------------------- viewer colours
def _page_commands(html: str) -> list[dict]:
    import umsgpack

    blobs = re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html)
    return [umsgpack.unpackb(base64.b64decode(blob)) for blob in blobs]


def _last_material(commands: list[dict], path: str) -> dict:
    objects = [c for c in commands if c.get("type") == "set_object" and c.get("path") == path]
    assert objects, path
    return objects[-1]["object"]["materials"][0]


def _rgb(material: dict) -> np.ndarray:
    c = int(material["color"])
    return np.array([(c >> 16) & 255, (c >> 8) & 255, c & 255]) / 255.0


def test_viewer_payload_stays_orange_beside_the_ghost(am, bent_plates, tmp_path):
    """The ghost's payload is an opaque orange wireframe: nothing translucent green lies over
    the payload to tint it olive. (Materials of the page's scene; headless Chromium is used
    by tests/test_viewer.py where installed.)"""
    from assembler_pin.carrier import Carrier

    with viz.StackViewer(am) as v:
        v.display(bent_plates)
        v.show_ghost(am.home)
        carrier = Carrier("ur3")
        v.show_carrier(carrier, carrier.upright_q)
        html = v.static_html(tmp_path / "page.html")
    cmds = _page_commands(html)
    solid = _last_material(cmds, "/meshcat/assembler/visuals/payload_0")
    ghost = _last_material(cmds, "/meshcat/assembler_initial/visuals/payload_0")
    for m in (solid, ghost):
        np.testing.assert_allclose(_rgb(m), palette.PAYLOAD, atol=1.5 / 255)
        assert m["opacity"] == 1.0 and not m["transparent"]
    assert ghost["wireframe"] and not solid["wireframe"]
    # the rest of the ghost is the translucent initial-pose green
    plate = _last_material(cmds, "/meshcat/assembler_initial/visuals/plate_0_0")
    np.testing.assert_allclose(_rgb(plate), palette.INITIAL, atol=1.5 / 255)
    assert plate["transparent"] and plate["opacity"] == pytest.approx(palette.GHOST_OPACITY)
    # the carrier is drawn in its slate, and its swatch differs from the zero-force grey
    meshes = [c for c in cmds if c.get("type") == "set_object" and c["path"].startswith("/meshcat/carrier/visuals/")]
    assert meshes and all(
        np.allclose(_rgb(_last_material(cmds, c["path"])), palette.CARRIER, atol=1.5 / 255) for c in meshes
    )
    swatches = dict((t.strip(), c) for c, t in re.findall(r"background:(#[0-9a-f]{6});[^>]*></span>([^<]+)<", html))
    carrier_rgb = np.array(to_rgb(swatches["carrier arm: ur3"]))
    zero_rgb = np.array(to_rgb(swatches["leg at 0 N"]))
    assert np.linalg.norm(carrier_rgb - zero_rgb) > 0.2
    np.testing.assert_allclose(np.array(to_rgb(swatches["payload 5 kg"])), palette.PAYLOAD, atol=1.5 / 255)
