"""The package's one colour language: every colour a figure, page or viewer scene draws with.

One meaning per colour, the same in the matplotlib figures (:mod:`~assembler_pin.plots.figures`),
the Meshcat pages (:mod:`~assembler_pin.viz`) and the maps:

==========================  ===========  =====================================================
what                        colour       where
==========================  ===========  =====================================================
leg force > 0 (tension)     red          force tables, bars, viewer legs; saturates at the limit
leg force < 0 (compression) blue         same scale, mirrored
leg force = 0               mid grey     centre of the diverging force scale
initial condition / ghost   green        pose views; translucent ghost in the viewer
optimized pose              charcoal     pose views (legs and plates); never red
helper arm                  violet       links; dark violet joint clusters
carrier arm                 slate        viewer; a darker, bluish grey than zero force
payload                     orange       cube and rod in the viewer
loaded pose (exaggerated)   teal         translucent ghost in the viewer (``view --loaded``)
EE compliance ellipsoid     magenta      translucent ellipsoid at the EE (``view --ellipsoid``)
violation / at a bound      yellow       viewer balls, figure frames and rings
obstacle (scene)            stone        translucent boxes, cylinders, spheres (``view --scene``)
closest pair                cyan         segment and end balls between two witness points
EE goal                     gold star    pose views
capacity (maps)             viridis      dark purple = low, yellow = high, in PNG and HTML alike
max|F| (maps)               cividis_r    yellow = low (better), dark blue = high (a magnitude, no sign)
reachable (maps)            teal         a grid cell where a valid state was found
home pose, for scale        dark grey    drawn over the map panels
not reachable (maps)        dark grey    a grid cell inside the grid with no state found
outside the grid (maps)     white        hatched, light grey edge: no cell was computed there
==========================  ===========  =====================================================

Colours are plain ``(r, g, b)`` tuples in [0, 1] (``rgba`` adds the opacity), so this
module imports nothing heavy; :func:`hex_color` gives the CSS form and
:func:`force_cmap` the matplotlib colormap of the force scale, built from the same three
anchors as the viewer's leg colours (blue ↔ grey ↔ red, linear in each half).
"""

from __future__ import annotations

__all__ = [
    "ARM",
    "ARM_JOINT",
    "BACKGROUND_BOTTOM",
    "BACKGROUND_TOP",
    "CAPACITY_CMAP",
    "CARRIER",
    "CLEARANCE_CMAP",
    "CLOSEST_PAIR",
    "COMPLIANCE",
    "COMPRESSION",
    "FLOOR",
    "FORCE_MAGNITUDE_CMAP",
    "GHOST_OPACITY",
    "GOAL_EDGE",
    "GOAL_FACE",
    "INITIAL",
    "LEG_CYCLE",
    "LIMIT",
    "LOADED",
    "NEUTRAL",
    "OBSTACLE",
    "OBSTACLE_OPACITY",
    "OPTIMIZED",
    "OUTSIDE_GRID",
    "OUTSIDE_GRID_EDGE",
    "OUTSIDE_GRID_HATCH",
    "PAGE_EDGE",
    "PAGE_INK",
    "PAGE_PANEL",
    "PAYLOAD",
    "REACHABLE",
    "SAG_CMAP",
    "SCALE_POSE",
    "SCALE_POSE_PLATE",
    "STIFFNESS_CMAP",
    "TENSION",
    "UNREACHABLE",
    "UNREACHABLE_MARK",
    "VIOLATION",
    "force_cmap",
    "hex_color",
    "rgba",
]

RGB = tuple[float, float, float]

TENSION: RGB = (0.95, 0.12, 0.10)
"""Red: a leg in tension (force > 0), at or beyond the scale's tension end."""
COMPRESSION: RGB = (0.12, 0.30, 0.95)
"""Blue: a leg in compression (force < 0), at or beyond the scale's compression end."""
NEUTRAL: RGB = (0.62, 0.62, 0.62)
"""Mid grey: zero force, the centre of the diverging force scale."""

INITIAL: RGB = (0.17, 0.63, 0.17)
"""Green: the initial condition (the paper's §V figures); the viewer's ghost pose."""
GHOST_OPACITY = 0.3
"""Opacity of the viewer's ghost pose (the initial condition beside the optimized one)."""
OPTIMIZED: RGB = (0.13, 0.13, 0.15)
"""Charcoal: the optimized pose's legs and plates in the figures (red is tension only)."""

ARM: RGB = (0.60, 0.25, 0.80)
"""Violet: the helper arm's links (a colour no leg takes: legs run blue ↔ grey ↔ red)."""
ARM_JOINT: RGB = (0.40, 0.10, 0.55)
"""Dark violet: the helper arm's joint clusters."""
CARRIER: RGB = (0.33, 0.37, 0.43)
"""Slate: a carrier arm (darker and bluer than the zero-force grey)."""
PAYLOAD: RGB = (0.85, 0.55, 0.10)
"""Orange: the payload cube and its rod."""
LOADED: RGB = (0.0, 0.58, 0.60)
"""Teal: the loaded pose (the legs' elastic equilibrium, displacements exaggerated), a ghost."""
COMPLIANCE: RGB = (0.85, 0.25, 0.60)
"""Magenta: the EE's compliance ellipsoid (semi-axes the sag under a stated force)."""
BACKGROUND_TOP: RGB = (0.97, 0.97, 0.96)
"""The viewer's neutral background, top."""
BACKGROUND_BOTTOM: RGB = (0.86, 0.87, 0.88)
"""The viewer's neutral background, bottom."""

VIOLATION: RGB = (1.0, 0.85, 0.0)
"""Yellow: a leg violating a limit (viewer), a state violating one (figures)."""
OBSTACLE: RGB = (0.72, 0.68, 0.58)
"""Stone: a scene's obstacles in the viewer (translucent; the floor plane is :data:`FLOOR`)."""
OBSTACLE_OPACITY = 0.45
"""Opacity of the viewer's obstacles and floor plane (the stack stays visible behind them)."""
CLOSEST_PAIR: RGB = (0.0, 0.80, 1.0)
"""Cyan: the segment between the witness points of the closest pair of bodies."""
LIMIT: RGB = (0.25, 0.25, 0.25)
"""Dark grey: dashed limit lines that are not a force sign (stroke, speed, acceleration)."""
GOAL_FACE: RGB = (1.0, 0.84, 0.0)
"""Gold: the EE goal star's face (black edge)."""
GOAL_EDGE: RGB = (0.0, 0.0, 0.0)
"""Black: the EE goal star's edge and its z-axis arrow."""
FLOOR: RGB = (0.55, 0.27, 0.07)
"""Brown: the floor line; the viewer's translucent floor plane."""

LEG_CYCLE: tuple[RGB, ...] = (
    (0.106, 0.620, 0.467),
    (0.851, 0.373, 0.008),
    (0.459, 0.439, 0.702),
    (0.906, 0.161, 0.541),
    (0.400, 0.651, 0.118),
    (0.651, 0.463, 0.114),
)
"""Legs 0..5 of a platform where one line per leg is drawn (no pure red or blue: those are
force signs). Platforms are told apart by panels, not colours."""

CAPACITY_CMAP = "viridis"
"""Sequential colormap of the maps' capacity: low = dark purple, high = yellow, in the PNG
and the HTML point cloud alike, with a colour bar."""
FORCE_MAGNITUDE_CMAP = "cividis_r"
"""Sequential colormap of the maps' optimized max|F| [N] (unsigned: not the force scale):
yellow = low. In every map panel yellow is the better end."""
SAG_CMAP = "magma_r"
"""Sequential colormap of the maps' EE sag [mm] under gravity and payload: yellow = small."""
STIFFNESS_CMAP = "plasma"
"""Sequential colormap of the maps' weakest EE stiffness [N/m]: yellow = stiff."""
CLEARANCE_CMAP = "inferno"
"""Sequential colormap of the maps' clearance [mm]: black = close to a collision, pale
yellow = far from one."""
REACHABLE: RGB = (0.10, 0.60, 0.55)
"""Teal: a grid cell where a valid state was found (the maps' reachability panel)."""
SCALE_POSE: RGB = (0.27, 0.27, 0.27)
"""Dark grey: the home pose's legs drawn over a map for scale."""
SCALE_POSE_PLATE: RGB = (0.13, 0.13, 0.13)
"""Near black: the home pose's plates drawn over a map for scale."""
UNREACHABLE: RGB = (0.40, 0.40, 0.40)
"""Dark grey: a grid cell where no valid state was found (drawn with a ``x`` marker)."""
UNREACHABLE_MARK: RGB = (1.0, 1.0, 1.0)
"""White: the ``x`` drawn on each unreachable cell (legible on its dark grey)."""
OUTSIDE_GRID: RGB = (1.0, 1.0, 1.0)
"""White: where no cell was computed (outside the grid); hatched with :data:`OUTSIDE_GRID_HATCH`."""
OUTSIDE_GRID_EDGE: RGB = (0.80, 0.80, 0.80)
"""Light grey: the hatch lines of the area outside the grid."""
OUTSIDE_GRID_HATCH = "//"
"""Matplotlib hatch of the area outside the grid."""


PAGE_INK: RGB = (0.13, 0.13, 0.13)
"""Near black: the text of a page's overlay boxes (legend, colour bars)."""
PAGE_EDGE: RGB = (0.33, 0.33, 0.33)
"""Dark grey: the thin border of a page's swatches and colour bars."""
PAGE_PANEL: RGB = (1.0, 1.0, 1.0)
"""White: the background of a page's overlay boxes (drawn at 85 % opacity)."""


def rgba(rgb: RGB, alpha: float = 1.0) -> tuple[float, float, float, float]:
    """``rgb`` with opacity ``alpha`` (both in [0, 1])."""
    return (float(rgb[0]), float(rgb[1]), float(rgb[2]), float(alpha))


def hex_color(rgb: tuple[float, ...]) -> str:
    """CSS ``#rrggbb`` of an RGB(A) triple in [0, 1] (the opacity, if any, is dropped)."""
    return "#" + "".join(f"{round(255 * min(max(float(c), 0.0), 1.0)):02x}" for c in rgb[:3])


def force_cmap():
    """The force scale as a matplotlib colormap: 0 → :data:`COMPRESSION`, 0.5 →
    :data:`NEUTRAL`, 1 → :data:`TENSION`, linear in between (the viewer's leg colours).
    Use it with a norm centred at zero force (e.g. ``TwoSlopeNorm(0)``)."""
    from matplotlib.colors import LinearSegmentedColormap

    return LinearSegmentedColormap.from_list("assembler_force", [COMPRESSION, NEUTRAL, TENSION], N=512)
