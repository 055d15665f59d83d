"""``assembler-pin walk``: the inchworm walk between footholds (reach, transfer, swing, ...)."""

from __future__ import annotations

import argparse
from pathlib import Path

from ..exceptions import CLIError
from .common import add_scene_argument, config_from_args, dumps, progress_for, scene_from_args
from .paths import path_argument, writable_directory, writable_parent

DEFAULT_FPS = 10.0
"""``walk --html``: samples of the walk shown per second, by default."""


def add_parser(add) -> None:
    """Register the ``walk`` subcommand (``add`` makes a subparser with ``--config``)."""
    p = add("walk", "the inchworm walk: the feet (plate 0, the EE plate) land on footholds in turn")
    src = p.add_mutually_exclusive_group()
    src.add_argument(
        "--footholds",
        type=path_argument,
        metavar="FILE",
        help='JSON {"footholds": [[x, y, z, rx, ry, rz] or 4x4, ...]}',
    )
    src.add_argument(
        "--floor",
        nargs=2,
        metavar=("STEP", "COUNT"),
        help="COUNT footholds STEP metres apart along +x on the floor z = 0, the first at the origin",
    )
    p.add_argument("--clearance", type=float, default=0.03, help="lift and pre-contact height [m] (default 0.03)")
    p.add_argument(
        "--payload",
        type=float,
        default=0.0,
        metavar="KG",
        help="a tool of this mass on the EE plate, at the config's payload.offset (default 0: a walking "
        "stack carries no tool; the config's payload.mass is not used)",
    )
    p.add_argument(
        "--out", type=path_argument, metavar="DIR", help="write walk.json and walk.csv (one row per sample) into DIR"
    )
    p.add_argument(
        "--plot", type=path_argument, metavar="PNG", help="write max|F| over the walk with its phases marked"
    )
    p.add_argument(
        "--html",
        type=path_argument,
        metavar="PAGE",
        help="write a standalone page animating every sample (legs by force, held feet, footholds)",
    )
    p.add_argument("--fps", type=float, help="with --html: samples shown per second (default 10)")
    add_scene_argument(
        p, "every reach and swing keeps its clearance at and between samples; the footholds on its floor"
    )
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=run)


def _number(text: str, what: str, kind: type) -> float:
    try:
        return kind(text)
    except ValueError:
        raise CLIError(f"{what} must be {'an integer' if kind is int else 'a number'}, got {text[:30]!r}") from None


def _footholds(args: argparse.Namespace):
    """(footholds, floor height or None) from ``--footholds`` or ``--floor``."""
    from ..walk.footholds import floor_footholds, read_footholds

    if args.footholds:
        got = read_footholds(args.footholds)
        return got.footholds, got.floor_z
    if args.floor:
        step = _number(args.floor[0], "--floor STEP", float)
        count = int(_number(args.floor[1], "--floor COUNT", int))
        return floor_footholds(step, count), 0.0
    raise CLIError("give --footholds FILE or --floor STEP COUNT")


def walking_config(cfg, payload: float):
    """``cfg`` carrying ``payload`` [kg] on its EE plate (the config's own payload mass is the
    tool of ``solve``; a walking stack carries a tool only when asked). A mass out of range
    is refused by the configuration's own check (``payload.mass``)."""
    import dataclasses

    from ..exceptions import ConfigError

    try:
        return cfg.replace(payload=dataclasses.replace(cfg.payload, mass=payload))
    except ConfigError:
        raise CLIError(f"--payload must be a finite mass >= 0 [kg], at most 1e5, got {payload:g}") from None


def run(args: argparse.Namespace) -> int:
    """Exit 0 when the walk reaches its last foothold, 1 when it cannot (the valid prefix is
    still printed and written), 2 for refused input."""
    from ..config.bounds import check_bound
    from ..model.assembler import AssemblerModel
    from ..walk import WalkOptions, plan_walk

    out = Path(args.out) if args.out else None
    if out is not None:  # every output checked before any work
        writable_directory(args.out, "--out directory")
    if args.html:
        writable_parent(args.html, "--html file")
    if args.plot:
        writable_parent(args.plot, "--plot file")
    scene = scene_from_args(args)  # read before the model is built: a bad scene is refused at once
    am = AssemblerModel.from_config(walking_config(config_from_args(args), args.payload))
    feet, floor_z = _footholds(args)
    options = WalkOptions(clearance=args.clearance, floor_z=floor_z)
    if args.fps is not None:
        if not args.html:
            raise CLIError("--fps needs --html (it sets the page's samples per second)")
        check_bound("walk.fps", args.fps, "--fps", CLIError)
    prog = progress_for(args, "walk")
    try:
        walk = plan_walk(am, feet, options=options, progress=prog, scene=scene)
    finally:
        prog.close()
    doc = walk.to_dict()
    written: list[Path] = []
    if out is not None:
        write_walk(am, walk, out)
        written += [out / "walk.json", out / "walk.csv"]
    if args.plot:
        plot_walk(am, walk, args.plot)
        written.append(Path(args.plot))
    if args.html and view_walk(am, walk, args.html, DEFAULT_FPS if args.fps is None else args.fps):
        written.append(Path(args.html))
    print(dumps(doc) if args.json else format_walk(walk))
    if not args.json:
        for path in written:
            print(f"wrote {path}")
    return 0 if walk.success else 1


def walk_rows(am, walk) -> tuple[list[str], list[list[object]]]:
    """The CSV header and rows (:func:`assembler_pin.walk.samples.walk_rows`)."""
    from ..walk.samples import walk_rows as rows

    return rows(am, walk)


def write_walk(am, walk, out: Path) -> None:
    """``walk.json`` (the answer) and ``walk.csv`` (the samples, read back by
    :func:`~assembler_pin.walk.samples.read_walk_csv`) in ``out``, each atomically."""
    from ..common.files import write_atomic
    from ..walk.samples import walk_csv

    out.mkdir(parents=True, exist_ok=True)
    write_atomic(out / "walk.json", dumps(walk.to_dict()) + "\n")
    write_atomic(out / "walk.csv", walk_csv(am, walk))


def view_walk(am, walk, path: str, fps: float) -> bool:
    """The standalone page animating the walk (:meth:`~assembler_pin.viz.StackViewer.show_walk`)
    among its scene's obstacles and floor, written atomically; a walk without a sample writes
    none and says so on stderr. Returns whether the page was written."""
    import sys

    from ..viz import StackViewer

    if not any(len(p.plates) for p in walk.phases):
        print(f"walk: no sample to animate, {path} not written", file=sys.stderr)
        return False
    with StackViewer(am, scene=walk.scene) as viewer:  # the obstacles and floor it walked among
        viewer.show_walk(walk, fps=fps)
        viewer.static_html(path)
    return True


def walk_times(am, walk):
    """(m,) the time [s] of each sample of the walk when every step runs at the legs' top
    speed: a step takes its largest commanded length change over ``leg.max_speed``."""
    import numpy as np

    commanded = [p.commanded for p in walk.phases if len(p.plates)]
    if not commanded:
        return np.zeros(0)
    lengths = np.concatenate(commanded).reshape(-1, am.n * 6)
    steps = np.abs(np.diff(lengths, axis=0)).max(axis=1) / am.config.leg.max_speed
    return np.concatenate([[0.0], np.cumsum(steps)])


def plot_walk(am, walk, path: str):
    """max|F| [N] over the walk against time at the legs' top speed, each phase shaded and
    named, the force limits dashed. Returns the figure (closed once saved)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..common import palette
    from ..plots.figures import save

    times = walk_times(am, walk)
    fig, ax = plt.subplots(figsize=(8, 3.6), layout="constrained")
    start = 0
    shades = {"reach": "#dce9f5", "transfer": "#f3e3c3", "swing": "#dcefdc"}
    for phase in walk.phases:
        m = len(phase.plates)
        if not m:
            continue
        t = times[start : start + m]
        t0 = times[start - 1] if start else 0.0
        ax.axvspan(t0, t[-1], color=shades[phase.kind], lw=0)
        ax.plot(t, phase.max_abs_forces, color="#333333", lw=1.2)
        ax.text((t0 + t[-1]) / 2, 0.02, phase.kind, transform=ax.get_xaxis_transform(), ha="center", size=8)
        start += m
    leg = am.config.leg
    ax.axhline(leg.max_tension, color=palette.hex_color(palette.TENSION), ls="--", lw=1)
    ax.text(
        0.005,
        leg.max_tension,
        f" force limit {leg.max_tension:g} N",
        transform=ax.get_yaxis_transform(),
        va="bottom",
        size=8,
    )
    if leg.max_compression != leg.max_tension:
        ax.axhline(leg.max_compression, color=palette.hex_color(palette.COMPRESSION), ls="--", lw=1)
    top = max(leg.max_tension, leg.max_compression)
    ax.set_ylim(0, 1.12 * top)
    ax.set_xlabel(f"time at the legs' top speed ({leg.max_speed:g} m/s) [s]")
    ax.set_ylabel("max |F| [N]")
    verdict = "valid" if walk.success else walk.reason[:70]
    tool = f"{am.config.payload.mass:g} kg tool" if am.config.payload.mass > 0 else "no tool"
    ax.set_title(f"walk over {len(walk.footholds)} footholds, {tool}: {verdict}", size=10)
    save(fig, path)
    plt.close(fig)
    return fig


#: The phase table's columns: (heading, width); each row's cell is right-aligned under it.
WALK_COLUMNS = (("phase", 5), ("kind", 8), ("support", 7), ("foothold", 8), ("samples", 7), ("peak max|F| [N]", 15))


def format_walk(walk) -> str:
    """A compact text report: the verdict, then one row per phase under a header (lines ≤ 100
    characters)."""
    import textwrap

    lines = [f"walk over {len(walk.footholds)} footholds: {'success' if walk.success else 'not possible'}"]
    if not walk.success:
        lines += textwrap.wrap(walk.reason, 96, initial_indent="  ", subsequent_indent="    ")
    lines.append(
        "  " + "  ".join(f"{h:>{w}s}" if k in (0, 3, 4, 5) else f"{h:{w}s}" for k, (h, w) in enumerate(WALK_COLUMNS))
    )
    (_, w0), (_, w1), (_, w2), (_, w3), (_, w4), (_, w5) = WALK_COLUMNS
    for k, p in enumerate(walk.phases):
        peak = f"{p.max_abs_forces.max():.2f}" if len(p.plates) else "-"
        state = "  (incomplete)" if not p.complete else ""
        cells = f"{k:{w0}d}  {p.kind:{w1}s}  {p.support:{w2}s}  {p.step:{w3}d}  {len(p.plates):{w4}d}"
        lines.append(f"  {cells}  {peak:>{w5}s}{state}")
        if p.clearance is not None and walk.scene is not None:
            a, b = p.clearance.between
            lines.append(f"         clearance {p.clearance.min_distance:.4f} m ({a} and {b})")
    return "\n".join(line[:100] for line in lines)
