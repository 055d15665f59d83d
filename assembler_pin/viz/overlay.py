"""The page's overlay: title, a legend of every colour and marker drawn, the leg-force colour bar.

The same HTML is embedded in a standalone page and served to the live page by the viewer's
meshcat server (:data:`~assembler_pin.viz.server.SET_OVERLAY`).
"""

from __future__ import annotations

import html as html_lib
from collections.abc import Iterable

import meshcat
import numpy.typing as npt

from .colors import COMPRESSION_RGB, NEUTRAL_RGB, TENSION_RGB, css
from .server import SET_OVERLAY

__all__ = ["LegendItem", "force_items", "overlay_html", "send_overlay"]

LegendItem = tuple[npt.ArrayLike, str]
"""A legend entry: its RGB(A) colour in [0, 1] and its text."""


def force_items() -> list[LegendItem]:
    """The legend entries of the leg-force colours (tension, compression, zero)."""
    return [
        (TENSION_RGB, "leg in tension (+)"),
        (COMPRESSION_RGB, "leg in compression (−)"),
        (NEUTRAL_RGB, "leg at 0 N"),
    ]


def _legend(items: Iterable[LegendItem]) -> str:
    return "".join(
        f'<div><span style="display:inline-block;width:12px;height:12px;background:{css(c)};margin-right:6px;'
        f'border:1px solid #555"></span>{html_lib.escape(t)}</div>'
        for c, t in items
    )


def _color_bar(tension: float, compression: float) -> str:
    blue, gray, red = (css(rgb) for rgb in (COMPRESSION_RGB, NEUTRAL_RGB, TENSION_RGB))
    return (
        f'<div id="assembler-colorbar" style="margin-top:8px">leg force [N]'
        f'<div style="height:12px;width:220px;background:linear-gradient(to right,{blue},{gray},{red});'
        f'border:1px solid #555"></div><div style="display:flex;justify-content:space-between;width:222px">'
        f"<span>−{compression:.0f}</span><span>0</span><span>+{tension:.0f}</span></div></div>"
    )


#: The legend's line for meshcat's world axes, drawn at the world origin.
AXES_HTML = (
    '<div id="assembler-axes">world axes at the origin: <b style="color:#d62728">x</b> '
    '<b style="color:#2ca02c">y</b> <b style="color:#1f5fd6">z</b> (thin lines)</div>'
)


def overlay_html(title: str, items: Iterable[LegendItem], force_range: tuple[float, float] | None) -> str:
    """The overlay's HTML: ``title``, the legend ``items``, the world axes and the colour bar
    of the leg forces, saturating at ``force_range`` = (tension, compression) [N] (no bar when
    None: the legs carry no force colours)."""
    bar = "" if force_range is None else _color_bar(*force_range)
    return (
        '<div id="assembler-overlay" style="position:absolute;top:8px;left:8px;z-index:10;'
        "max-width:330px;background:rgba(255,255,255,0.8);padding:6px 8px;border-radius:4px;font:12px sans-serif;"
        f'color:#222;pointer-events:none"><div id="assembler-title" style="font-weight:bold;'
        f'margin-bottom:6px">{html_lib.escape(title or "Assembler")}</div>'
        f'<div id="assembler-legend">{_legend(items)}{AXES_HTML}</div>{bar}</div>'
    )


def send_overlay(vis: meshcat.Visualizer, html: str) -> None:
    """Set the overlay of the live page served by this package's meshcat server."""
    socket = vis.window.zmq_socket
    socket.send_multipart([SET_OVERLAY, html.encode("utf-8")])
    socket.recv()
