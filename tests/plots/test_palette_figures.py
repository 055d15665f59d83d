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
import contextlib
import dataclasses
import inspect
import re
import shutil
import subprocess

import matplotlib.image as mpimg
import numpy as np
import pytest
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.collections import PathCollection
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from assembler_pin import AssemblerModel, evaluate_state, plots, scenario, stack_forward_kinematics, viz
from assembler_pin.common import palette
from assembler_pin.common.labels import leg_label
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
    # limits at the largest force, so that a leg is framed and the frames' legend is drawn
    peak = max(home.max_abs_force, res.state.max_abs_force)
    bound = dataclasses.replace(leg, max_tension=peak, max_compression=peak)
    heat = plots.force_heatmaps(home, res.state, leg=bound)
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
    by tests/viz/test_viewer.py where installed.)"""
    import dataclasses

    from assembler_pin.carrier import Carrier

    am = AssemblerModel.from_config(am.config.replace(payload=dataclasses.replace(am.config.payload, radius=0.05)))
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


# ---------------------------------------------------------------------- maps
def _map_table():
    """A 3 × 3 x–z slice: six reachable cells of capacities 1..6 kg, two unreachable cells,
    one cell missing (outside what was computed)."""
    import pyarrow as pa

    xs, zs = [0.2, 0.3, 0.4], [0.7, 0.8, 0.9]
    cells = [(x, z) for z in zs for x in xs][:-1]  # (0.4, 0.9) never computed
    reach = [1, 1, 1, 0, 1, 1, 0, 1]
    cap = [1.0, 2.0, 3.0, None, 4.0, 5.0, None, 6.0]
    force = [20.0 + 5 * k if r else None for k, r in enumerate(reach)]
    return pa.table(
        {
            "cell": list(range(len(cells))),
            "config": ["default"] * len(cells),
            "io": [0] * len(cells),
            "x": [c[0] for c in cells],
            "y": [0.0] * len(cells),
            "z": [c[1] for c in cells],
            "reachable": [bool(r) for r in reach],
            "max_abs_force": force,
            "capacity_kg": cap,
            "sag_m": [1e-5 * k if r else None for k, r in enumerate(reach)],
            "weakest_stiffness_n_per_m": [1e4 + 1e3 * k if r else None for k, r in enumerate(reach)],
            "clearance_m": [0.006 + 2e-3 * k if r else None for k, r in enumerate(reach)],
        }
    )


class _Viewer:
    """What the map page needs of a StackViewer, recorded."""

    def __init__(self) -> None:
        self.points: dict = {}
        self.title = ""

    def show_points(self, name, points, colors, size):
        self.points[name] = (np.asarray(points), np.asarray(colors), size)

    def set_title(self, title):
        self.title = title

    def static_html(self):
        return f"<html><body><div>{self.title}</div></body></html>"


@pytest.fixture(scope="module")
def map_png(am):
    """The heatmaps of :func:`_map_table`, drawn once: (figure, what its legends hide)."""
    from assembler_pin.maps import pictures

    fig = pictures.map_heatmaps(_map_table(), am)
    return fig, legend_overlaps(fig)


def _image_rgb(image, value: float) -> np.ndarray:
    return np.array(image.cmap(image.norm(value)))[:3]


def test_map_png_and_page_share_one_capacity_scale(map_png, tmp_path):
    """Low capacity dark, high yellow in the PNG and on the page alike (the page's point
    colours are the PNG's image colours at the same capacities), with a colour bar in kg."""
    from assembler_pin.maps import pictures

    table = _map_table()
    fig = map_png[0]
    cap_ax = next(ax for ax in fig.axes if ax.get_title().startswith("payload capacity"))
    image = cap_ax.images[0]
    assert image.cmap.name == palette.CAPACITY_CMAP
    low, high = _image_rgb(image, 1.0), _image_rgb(image, 6.0)
    assert sum(high) > sum(low) + 1.0  # yellow over dark purple
    assert any(ax.get_ylabel() == "payload capacity [kg]" for ax in fig.axes)  # its colour bar

    viewer = _Viewer()
    page = tmp_path / "map.html"
    lo, hi = pictures.write_map_page(viewer, table, page)
    assert (lo, hi) == (1.0, 6.0)
    _, colors, size = viewer.points["capability_map"]
    cap = np.array(table.column("capacity_kg").to_pylist(), dtype=float)
    for k in np.nonzero(np.isfinite(cap))[0]:
        np.testing.assert_allclose(colors[k], _image_rgb(image, cap[k]), atol=1e-6)
    for k in np.nonzero(~np.isfinite(cap))[0]:
        np.testing.assert_allclose(colors[k], palette.UNREACHABLE)
    assert size == pytest.approx(0.06)  # 0.6 of the 0.1 m spacing: points that read
    html = page.read_text()
    bar = html[html.index('id="assembler-map-colorbar"') :]
    assert "payload capacity [kg]" in bar and "1.00" in bar and "6.00" in bar and "not reachable" in bar
    stops = re.search(r"linear-gradient\(to right,([^)]*)\)", bar).group(1).split(",")
    assert stops[0] == palette.hex_color(_image_rgb(image, 1.0)) and stops[-1] == palette.hex_color(high)
    assert "(dark)" in viewer.title and "(yellow)" in viewer.title


def test_map_png_marks_unreachable_and_outside_cells_and_hides_nothing(map_png):
    """Unreachable cells dark grey with an x in every panel, where no cell was computed
    white and hatched, and a legend below the panels that covers no drawn point or line."""
    from matplotlib.patches import Rectangle

    fig, hidden = map_png
    legends = [ax for ax in fig.axes if ax.get_legend()]
    assert len(legends) == 1 and not legends[0].images and not legends[0].axison  # the sixth place
    assert hidden == []
    panels = [ax for ax in fig.axes if ax.images]
    assert len(panels) == 5  # clearance, max|F|, capacity, sag, weakest stiffness
    for ax in panels:
        marks = [c for c in ax.collections if isinstance(c, PathCollection) and c.get_label() == "not reachable"]
        assert marks and len(marks[0].get_offsets()) == 2
        grey = [im for im in ax.images if im.cmap.N == 1]
        assert grey and np.allclose(grey[0].cmap(0.5)[:3], palette.UNREACHABLE)
        hatched = [p for p in ax.patches if isinstance(p, Rectangle) and p.get_hatch() == palette.OUTSIDE_GRID_HATCH]
        assert hatched and np.allclose(hatched[0].get_facecolor()[:3], palette.OUTSIDE_GRID)
        assert np.allclose(to_rgb(ax.get_facecolor()), palette.OUTSIDE_GRID)


def test_map_png_reads_at_screen_size_and_yellow_is_better(map_png):
    """Panels in a grid (two rows), text of at least 10 pt inside the canvas, the sag in mm,
    yellow the better end of every colour scale, and the slice named in the title."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    fig = map_png[0]
    panels = [ax for ax in fig.axes if ax.images]
    rows = {round(ax.get_position().y0, 2) for ax in panels}
    assert len(rows) == 2 and fig.get_figwidth() * 150 <= 2000
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    for ax in fig.axes:
        box = ax.get_tightbbox(renderer)
        assert box.x0 >= -0.5 and box.y0 >= -0.5 and box.x1 <= fig.bbox.width + 0.5, ax.get_title()
        for label in (ax.xaxis.label, ax.yaxis.label, ax.title):
            assert not label.get_text() or label.get_fontsize() >= 10
    titles = {ax.get_title(): ax for ax in panels}
    sag = next(ax for name, ax in titles.items() if "sag" in name)
    assert "[mm]" in sag.get_title() and np.nanmax(sag.images[0].get_array()) == pytest.approx(1e3 * 7e-5)

    def yellowness(rgb):  # red + green - blue: yellow high, dark blue / purple / black low
        return rgb[0] + rgb[1] - rgb[2]

    better = {"max|F|": min, "sag": min, "capacity": max, "stiffness": max, "clearance": max}
    for name, ax in titles.items():
        pick = next((f for key, f in better.items() if key in name), None)
        if pick is None:
            continue
        image = ax.images[0]
        data = np.ma.compressed(image.get_array())
        good, bad = pick(data), (max if pick is min else min)(data)
        assert yellowness(_image_rgb(image, good)) > yellowness(_image_rgb(image, bad)), name
    title = fig._suptitle.get_text()
    assert "slice y = 0 m" in title and "config default" in title and "orientation 0" in title


def test_map_png_marks_the_clearance_limit_on_its_colour_bar(map_png, am):
    """The clearance panel [mm]: its scale reaches down to the configuration's limit, drawn
    dashed on its colour bar, whose label names it."""
    fig = map_png[0]
    bar = next(ax for ax in fig.axes if ax.get_ylabel().startswith("clearance [mm]"))
    limit = 1e3 * am.config.clearance
    dashed = [line for line in bar.lines if line.get_linestyle() == "--"]
    assert dashed and all(np.allclose(line.get_ydata(), limit) for line in dashed)
    lo, hi = sorted(bar.get_ylim())
    assert lo <= limit < hi and f"{limit:g} mm" in bar.get_ylabel()
    panel = next(ax for ax in fig.axes if ax.images and ax.get_title().startswith("clearance"))
    assert panel.get_title().endswith("[mm]") and panel.images[0].cmap.name == palette.CLEARANCE_CMAP


def test_map_pictures_name_no_colour_of_their_own():
    """Every colour and colormap of maps/pictures.py comes from the palette."""
    from assembler_pin.maps import pictures

    source = inspect.getsource(pictures)
    assert not re.search(r"#[0-9a-fA-F]{3,8}\b", source)
    assert not re.search(r"\"(magma|viridis|cividis|gray|grey|plasma|inferno)(_r)?\"", source)
    assert not re.search(r"rgba?\(\s*\d", source)


CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


def _screenshot(html, tmp_path, size=(900, 700)) -> np.ndarray:
    """The page as headless Chromium draws it, (H, W, 3) in [0, 1]."""
    png = html.with_suffix(".png")
    cmd = [
        CHROMIUM,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--enable-unsafe-swiftshader",
        "--no-first-run",
        f"--user-data-dir={tmp_path / 'chromium-profile'}",
        f"--screenshot={png}",
        f"--window-size={size[0]},{size[1]}",
        html.resolve().as_uri(),
    ]
    for _ in range(2):  # a stalled start can make one attempt fail
        with contextlib.suppress(subprocess.TimeoutExpired):
            subprocess.run(cmd, capture_output=True, timeout=120, check=False)
        if png.exists():
            break
    assert png.exists(), "chromium wrote no screenshot"
    return mpimg.imread(png)[..., :3]


def _has_colour(img: np.ndarray, rgb, tol: float = 0.08) -> bool:
    return bool((np.abs(img - np.asarray(rgb)[:3]).max(axis=-1) < tol).any())


@pytest.mark.skipif(CHROMIUM is None, reason="chromium not installed (.ci/run installs it)")
def test_map_page_in_a_real_browser(am, tmp_path):
    """The map page as a browser shows it: the colour bar at the bottom left with both ends
    of the capacity scale, and the cells drawn in the scale's colours above it."""
    from matplotlib import colormaps

    from assembler_pin.maps import pictures
    from assembler_pin.viz import StackViewer

    page = tmp_path / "map.html"
    with StackViewer(am) as v:
        v.display(am.home)
        pictures.write_map_page(v, _map_table(), page)
    img = _screenshot(page, tmp_path)
    h, w = img.shape[:2]
    cmap = colormaps[palette.CAPACITY_CMAP]
    corner = img[int(0.7 * h) :, : int(0.45 * w)]
    assert _has_colour(corner, cmap(0.0)) and _has_colour(corner, cmap(1.0)), "no capacity colour bar"
    scene = img[: int(0.7 * h)]
    assert _has_colour(scene, cmap(1.0), 0.15) and _has_colour(scene, palette.UNREACHABLE, 0.1), "no map cells"
