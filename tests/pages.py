"""Reading the viewer's standalone pages back: the meshcat commands they embed, and where each
animated object ends (shared by the viewer, walk, motion and compliance-view tests)."""

from __future__ import annotations

import base64
import re

import numpy as np
import pinocchio as pin
import umsgpack


def page_end_transforms(html: str) -> dict[str, np.ndarray]:
    """The 4×4 transform of every meshcat path once a static page has run its commands
    and played its animation to the end.

    As meshcat's viewer does: a ``set_animation`` replaces the previous one, an animation
    with ``play`` runs once and stays on its last frame (``clampWhenFinished``), and its
    ``position``/``quaternion`` tracks then override the node's last ``set_transform``.
    """
    transforms: dict[str, np.ndarray] = {}
    animation = None
    for cmd in page_commands(html):
        if cmd["type"] == "set_transform":
            transforms[cmd["path"]] = np.array(cmd["matrix"], dtype=float).reshape(4, 4).T  # column-major
        elif cmd["type"] == "set_animation":
            animation = cmd
        elif cmd["type"] == "delete":
            transforms = {p: T for p, T in transforms.items() if not (p + "/").startswith(cmd["path"] + "/")}
    if animation is not None and animation["options"]["play"]:
        for clip in animation["animations"]:
            last = {track["name"]: track["keys"][-1]["value"] for track in clip["clip"]["tracks"]}
            T = transforms.get(clip["path"], np.eye(4)).copy()
            if ".position" in last:
                T[:3, 3] = last[".position"]
            if ".quaternion" in last:
                x, y, z, w = last[".quaternion"]
                T[:3, :3] = pin.Quaternion(w, x, y, z).toRotationMatrix()
            transforms[clip["path"]] = T
    return transforms


def page_commands(html: str) -> list[dict]:
    """The meshcat drawing commands embedded in a static page (msgpack, base64)."""

    blobs = re.findall(r"data:application/octet-binary;base64,([A-Za-z0-9+/=]+)", html)
    return [umsgpack.unpackb(base64.b64decode(blob)) for blob in blobs]
