"""The Meshcat viewer: colors, drawn geometry, animation, CLI, and a real browser rendering.

The browser test renders the standalone page of ``assembler-pin view --html`` in headless
Chromium and checks the pixels: the stack must be drawn where the camera model says it
is, and two different poses must give different pictures.
"""

from __future__ import annotations

import contextlib
import math
import os
import select
import shutil
import signal
import subprocess
import sys
import time
import urllib.request
from pathlib import Path

import matplotlib.image as mpimg
import numpy as np
import pinocchio as pin
import pytest
from pages import page_commands, page_end_transforms

import assembler_pin as ap
from assembler_pin import evaluate_state, stack_forward_kinematics
from assembler_pin.exceptions import AssemblerError, ConvergenceError, ViewerError
from assembler_pin.kinematics import StackFKResult
from assembler_pin.model import WHOLE_DATA_MAX_PLATFORMS
from assembler_pin.viz import (
    ARM_LINK_RGBA,
    CAMERA_FOV_DEG,
    COMPRESSION_RGB,
    NEUTRAL_RGB,
    TENSION_RGB,
    StackViewer,
    camera_for_points,
    force_color,
    interpolate_states,
    placements,
)

WIDTH, HEIGHT = 800, 600
CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.fixture(scope="module")
def bent(bent_plates):
    return bent_plates


@pytest.fixture(scope="module")
def viewer(am):
    v = StackViewer(am)
    yield v
    v.close()


# ---------------------------------------------------------------------- colors
def test_force_colors_monotone_and_saturating():
    f = np.linspace(-400.0, 400.0, 801)
    c = force_color(f, max_tension=200.0, max_compression=100.0)
    assert c.shape == (801, 3) and c.min() >= 0 and c.max() <= 1
    assert np.all(np.diff(c[:, 0]) >= -1e-15)  # red grows with the force
    assert np.all(np.diff(c[:, 2]) <= 1e-15)  # blue falls with the force
    assert np.allclose(force_color(0.0, 200, 100), NEUTRAL_RGB)
    assert np.allclose(force_color(200.0, 200, 100), TENSION_RGB)
    assert np.allclose(force_color(1e4, 200, 100), TENSION_RGB)
    assert np.allclose(force_color(-100.0, 200, 100), COMPRESSION_RGB)
    assert np.allclose(force_color(-1e4, 200, 100), COMPRESSION_RGB)
    # half the tension limit is half-way between gray and red
    assert np.allclose(force_color(100.0, 200, 100), 0.5 * (NEUTRAL_RGB + TENSION_RGB))
    with pytest.raises(AssemblerError):
        force_color(1.0, 0.0, 100.0)


# ---------------------------------------------------------------------- drawing
def test_drawn_legs_join_the_joint_centres(am, viewer, bent):
    state = viewer.display(bent)
    bottom, top = viewer.drawn_leg_endpoints()
    assert np.allclose(bottom, state.legs.bottom_points, atol=1e-12)
    assert np.allclose(top, state.legs.top_points, atol=1e-12)
    # every motor and shaft is drawn, and their geometry sits on the leg axis
    assert sorted(viewer._leg_geoms) == [(j, i) for j in range(am.n) for i in range(6)]
    vdata, vmodel = viewer.viz.visual_data, viewer.visual_model
    for (j, i), gids in viewer._leg_geoms.items():
        for gid in gids:
            centre = vdata.oMg[gid].translation
            b, t = state.legs.bottom_points[j, i], state.legs.top_points[j, i]
            u = (t - b) / np.linalg.norm(t - b)
            off_axis = (centre - b) - ((centre - b) @ u) * u
            assert np.linalg.norm(off_axis) < 1e-12, vmodel.geometryObjects[gid].name


def test_violations_are_marked(am, viewer):
    lengths = np.full((am.n, 6), 0.275)
    lengths[0, 0] = 0.36  # beyond max_length
    fk = stack_forward_kinematics(am, lengths)
    assert fk.success
    state = evaluate_state(am, fk.plates)
    assert (0, 0) in StackViewer.violating_legs(state)
    assert viewer.display(state, mark_violations=True) is state


def test_helper_arm_input_checked(viewer):
    with pytest.raises(AssemblerError):
        viewer.show_helper_arm(np.zeros((3, 2)))
    with pytest.raises(AssemblerError):
        viewer.show_helper_arm(np.full((6, 3), np.nan))


def test_camera_frames_every_point():
    pts = np.random.default_rng(0).uniform([-0.3, -0.2, 0.0], [0.4, 0.2, 1.3], (200, 3))
    cam = camera_for_points(pts)
    px = project(cam, pts)
    assert np.all((px[:, 0] > 0) & (px[:, 0] < WIDTH) & (px[:, 1] > 0) & (px[:, 1] < HEIGHT))
    # side view: the camera is on the -y side, z up, looking at the box centre
    assert cam.position[1] < cam.target[1] and abs(cam.position[0] - cam.target[0]) < 1e-9


# ---------------------------------------------------------------------- animation
def test_interpolation_runs_stack_fk_each_step(am, bent):
    states = interpolate_states(am, am.home, bent, steps=7)
    assert len(states) == 7
    assert np.allclose(states[0].plates.p, np.array([m.translation for m in am.home]), atol=1e-9)
    assert np.allclose(states[-1].plates.p, bent.p, atol=1e-9)
    L0 = states[0].leg_lengths
    L1 = states[-1].leg_lengths
    for k, s in enumerate(states):
        assert np.allclose(s.leg_lengths, L0 + k / 6 * (L1 - L0), atol=1e-10)


def test_interpolation_stops_on_fk_failure(am, bent, monkeypatch):
    import assembler_pin.viz.animation as animation_mod

    real = animation_mod.stack_forward_kinematics
    calls = {"n": 0}

    def failing(*args, **kwargs):
        calls["n"] += 1
        res = real(*args, **kwargs)
        if calls["n"] == 4:
            return StackFKResult(res.plates, False, res.platforms, "did not converge (test)")
        return res

    monkeypatch.setattr(animation_mod, "stack_forward_kinematics", failing)
    with pytest.raises(ConvergenceError, match=r"animation step 3/9 .*did not converge \(test\)"):
        interpolate_states(am, am.home, bent, steps=10)
    with pytest.raises(AssemblerError):
        interpolate_states(am, am.home, bent, steps=1)


def test_animation_in_static_html(am, viewer, bent, tmp_path):
    states = interpolate_states(am, am.home, bent, steps=5)
    viewer.animate(states, fps=5)
    html = viewer.static_html(tmp_path / "anim.html")
    cmds = page_commands(html)
    anims = [c for c in cmds if c["type"] == "set_animation"]
    assert len(anims) == 1
    tracks = anims[0]["animations"]
    assert len(tracks) == viewer.visual_model.ngeoms + 1  # one clip per drawn body, and the payload rod
    times = [k["time"] for k in tracks[0]["clip"]["tracks"][0]["keys"]]
    assert times == list(range(5))
    assert (tmp_path / "anim.html").stat().st_size > 100_000


def _leg_geometry_offsets(viewer: StackViewer, transforms: dict[str, np.ndarray], state) -> np.ndarray:
    """Distance [m] of each drawn motor and shaft centre from its leg's axis in ``state``."""
    out = []
    for (j, i), gids in viewer._leg_geoms.items():
        b, t = state.legs.bottom_points[j, i], state.legs.top_points[j, i]
        u = (t - b) / np.linalg.norm(t - b)
        for gid in gids:
            path = viewer.viz.getViewerNodeName(viewer.visual_model.geometryObjects[gid], pin.GeometryType.VISUAL)
            c = transforms["/meshcat/" + path][:3, 3] - b  # node frames are world frames under the root
            out.append(np.linalg.norm(c - (c @ u) * u))
    return np.array(out)


def test_a_pose_shown_after_an_animation_is_what_the_page_ends_on(am, bent, tmp_path):
    lengths = np.full((am.n, 6), 0.275)
    lengths[2, ::2] = 0.31
    lengths[3, 1::2] = 0.24
    other = evaluate_state(am, stack_forward_kinematics(am, lengths).raise_if_failed())
    bent_state = evaluate_state(am, bent)
    with StackViewer(am) as v:
        v.animate(interpolate_states(am, am.home, bent, steps=4))
        animated = page_end_transforms(v.static_html(tmp_path / "animated.html"))
        # the reading of the page is right: an animation ends on its last frame (the bent pose)
        assert _leg_geometry_offsets(v, animated, bent_state).max() < 1e-9
        v.show_comparison(evaluate_state(am, am.home), other)
        html = v.static_html(tmp_path / "comparison.html")
        shown = page_end_transforms(html)
        offsets_other = _leg_geometry_offsets(v, shown, other)
        offsets_bent = _leg_geometry_offsets(v, shown, bent_state)
    assert offsets_other.max() < 1e-9, "the page does not end on the pose shown last"
    assert offsets_bent.max() > 1e-3
    played = [c for c in page_commands(html) if c["type"] == "set_animation" and c["options"]["play"]]
    assert all(not c["animations"] for c in played)


def test_notebook_inline_cell(viewer, bent):
    viewer.display(bent)
    cell = viewer.jupyter_static(height=300)
    assert "srcdoc" in cell.data and "MeshCat" in cell.data


# ---------------------------------------------------------------------- CLI
def run_cli(*args: str, timeout: float = 120):
    return subprocess.run(
        [sys.executable, "-m", "assembler_pin.cli", *args], capture_output=True, text=True, timeout=timeout
    )


def test_cli_view_errors(tmp_path):
    out = run_cli("view", "--plates", str(tmp_path / "missing.json"), "--html", str(tmp_path / "x.html"))
    assert out.returncode == 2 and out.stderr.count("\n") == 1 and "cannot read" in out.stderr
    out = run_cli("view", "--html", str(tmp_path / "x.html"))
    assert out.returncode == 2  # argparse: one source is required
    for host in ("256.1.1.1", "no-such-host.invalid"):
        out = run_cli("view", "--home", "--host", host)
        assert out.returncode == 2 and out.stderr.count("\n") == 1 and f"viewer host '{host}'" in out.stderr


def test_server_host_and_port_checked():
    from assembler_pin.exceptions import ViewerError
    from assembler_pin.viz.server import start_server

    for host, port in (("", None), ("8.8.8.8", None), ("127.0.0.1", 0), ("127.0.0.1", 70000), ("127.0.0.1", "80")):
        with pytest.raises(ViewerError, match=r"viewer (host|port)"):
            start_server(host, port)
    first = start_server()
    try:
        port = int(first.web_url.split(":")[2].split("/")[0])
        with pytest.raises(ViewerError, match=r"did not start.*Address already in use"):
            start_server(port=port)  # a port asked for explicitly is not moved
    finally:
        first.stop()


# ---------------------------------------------------------------------- the live server's lifetime
def _proc_stat(pid: int) -> tuple[str, int] | None:
    """(state letter, parent pid) of a process from /proc, None when it no longer exists."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2 :].split()  # after "pid (comm) "
    return fields[0], int(fields[1])


def _running(pid: int) -> bool:
    """The process exists and is not a zombie (a dead child nobody reaped yet)."""
    stat = _proc_stat(pid)
    return stat is not None and stat[0] not in "ZX"


def _children(pid: int) -> list[int]:
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            stat = _proc_stat(int(entry.name))
            if stat is not None and stat[1] == pid and stat[0] not in "ZX":
                out.append(int(entry.name))
    return out


def _listening(port: int) -> dict[int, str]:
    """TCP sockets listening on ``port``: socket inode -> local address (IPv4 dotted, IPv6 hex)."""
    found = {}
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        with contextlib.suppress(OSError):
            for line in Path(table).read_text().splitlines()[1:]:
                fields = line.split()
                address, port_hex = fields[1].rsplit(":", 1)
                if fields[3] == "0A" and int(port_hex, 16) == port:  # 0A: LISTEN
                    if len(address) == 8:  # IPv4, little-endian hex
                        address = ".".join(str(b) for b in reversed(bytes.fromhex(address)))
                    found[int(fields[9])] = address
    return found


def _wait_for(predicate, timeout: float) -> bool:
    """Poll ``predicate`` until true or ``timeout`` [s] passes (a deadline, not a measurement)."""
    deadline = time.monotonic() + timeout
    while not predicate():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.2)
    return True


def _start_live_view(*extra: str) -> tuple[subprocess.Popen, str]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "assembler_pin.cli", "view", "--home", *extra],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    ready, _, _ = select.select([proc.stdout], [], [], 180)  # generous: a loaded 2-core machine
    url = proc.stdout.readline().strip() if ready else ""
    return proc, url


@pytest.mark.skipif(not Path("/proc/net/tcp").exists(), reason="reads processes and sockets from Linux's /proc")
@pytest.mark.parametrize("sig", ["SIGINT", "SIGTERM", "SIGHUP", "SIGKILL"])
def test_cli_view_server_stops_with_the_command(sig):
    """Whatever ends ``view`` — Ctrl-C, kill, a closed terminal, even SIGKILL — its meshcat
    server ends too, and while it runs its page listens on this machine only."""
    proc, url = _start_live_view()
    try:
        assert url.startswith("http://127.0.0.1:"), (url, proc.stderr.read() if proc.poll() is not None else "")
        port = int(url.split(":")[2].split("/")[0])
        servers = _children(proc.pid)
        assert len(servers) == 1, servers
        server = servers[0]  # the meshcat server
        sockets = _listening(port)
        assert list(sockets.values()) == ["127.0.0.1"]  # not 0.0.0.0, not [::]
        with urllib.request.urlopen(url, timeout=30) as page:
            assert page.status == 200 and b"MeshCat" in page.read()

        proc.send_signal(getattr(signal, sig))
        code = proc.wait(timeout=120)
        assert code == (-signal.SIGKILL if sig == "SIGKILL" else 0), proc.stderr.read()
        assert "Traceback" not in proc.stderr.read()
        assert _wait_for(lambda: not _running(server), timeout=60), f"meshcat server {server} still running"
        # its socket is closed (the port itself may be taken again by another program meanwhile)
        assert _wait_for(lambda: not set(sockets) & set(_listening(port)), timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()


def test_cli_view_stopped_before_it_is_ready(monkeypatch, capsys):
    """A SIGTERM while the pose is being computed ends ``view`` with one line and status
    128 + 15, its server stopped and reaped, the previous signal handlers back."""
    from assembler_pin.cli import main

    servers = []
    real_display = StackViewer.display

    def display_then_terminated(self, *args, **kwargs):
        servers.append(self.server)
        os.kill(os.getpid(), signal.SIGTERM)  # the handler raises at the next bytecode
        time.sleep(30)  # not reached; a sleep is interrupted by the handler anyway
        return real_display(self, *args, **kwargs)

    before = {sig: signal.getsignal(sig) for sig in (signal.SIGTERM, signal.SIGHUP)}
    monkeypatch.setattr(StackViewer, "display", display_then_terminated)
    assert main(["view", "--home"]) == 128 + signal.SIGTERM
    assert capsys.readouterr().err.splitlines() == ["assembler-pin view: stopped by SIGTERM before the view was ready"]
    assert len(servers) == 1 and servers[0].process.returncode is not None  # stopped and reaped
    assert {sig: signal.getsignal(sig) for sig in before} == before


def test_viewer_close_stops_its_server(am):
    v = StackViewer(am)
    server = v.server
    assert server is not None and server.running()
    assert server.web_url.startswith("http://127.0.0.1:") and server.zmq_url.startswith("tcp://127.0.0.1:")
    v.close()
    assert server.process.returncode is not None  # reaped: close() waits for it
    v.close()  # twice is fine


@pytest.mark.skipif(
    not __import__("importlib").util.find_spec("assembler_pin.solver"), reason="assembler_pin.solver not available"
)
def test_cli_view_goal_writes_comparison(tmp_path):
    page = tmp_path / "goal.html"
    out = run_cli("view", "--goal", "0.1", "0", "0.9", "0", "0", "0", "--html", str(page), timeout=300)
    assert out.returncode == 0, out.stderr
    assert "solve: success" in out.stderr
    paths = page_paths(page.read_text())
    assert any(p.startswith("/meshcat/assembler/visuals/") for p in paths)  # optimized, solid
    assert any(p.startswith("/meshcat/assembler_initial/visuals/") for p in paths)  # initial, ghost
    clusters = [p for p in paths if p.startswith("/meshcat/helper_arm/cluster")]
    assert len(clusters) == 4  # n joint clusters of the helper arm


def page_paths(html: str) -> set[str]:
    """Meshcat paths of every drawing command embedded in a static page."""
    return {cmd["path"] for cmd in page_commands(html) if cmd.get("path")}


# ---------------------------------------------------------------------- real browser
def project(cam, points: np.ndarray) -> np.ndarray:
    """Pixel coordinates of world points seen by meshcat's perspective camera (fov 75°,
    looking from ``cam.position`` at ``cam.target``, z up)."""
    fwd = cam.target - cam.position
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, fwd)
    rel = np.asarray(points) - cam.position
    depth = rel @ fwd
    f = (HEIGHT / 2) / math.tan(math.radians(CAMERA_FOV_DEG) / 2)
    u = WIDTH / 2 + f * (rel @ right) / depth
    v = HEIGHT / 2 - f * (rel @ up) / depth
    return np.stack([u, v], axis=1)


def screenshot(html: Path, tmp_path: Path, virtual_time_ms: int | None = None) -> np.ndarray:
    """The page as headless Chromium draws it; ``virtual_time_ms`` lets animations run
    that long (in the browser's virtual time) before the picture is taken."""
    png = html.with_suffix(".png")
    cmd = [
        CHROMIUM,
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--enable-unsafe-swiftshader",
        "--disable-background-networking",
        "--disable-component-update",
        "--disable-sync",
        "--no-first-run",
        f"--user-data-dir={tmp_path / 'chromium-profile'}",
        f"--screenshot={png}",
        f"--window-size={WIDTH},{HEIGHT}",
        html.resolve().as_uri(),
    ]
    if virtual_time_ms is not None:
        cmd.insert(1, f"--virtual-time-budget={virtual_time_ms}")
    for _ in range(2):  # a profile still held by the previous run (or a stalled start) can make one attempt fail
        with contextlib.suppress(subprocess.TimeoutExpired):
            subprocess.run(cmd, capture_output=True, timeout=120, check=False)
        if png.exists():
            break
    assert png.exists(), "chromium wrote no screenshot"
    img = mpimg.imread(png)[..., :3]
    assert img.shape[:2] == (HEIGHT, WIDTH)
    return img


@pytest.mark.skipif(CHROMIUM is None, reason="chromium not installed (.ci/run installs it)")
def test_html_page_draws_the_stack_in_a_real_browser(am, bent, tmp_path):
    import json

    plates_file = tmp_path / "bent.json"
    plates_file.write_text(json.dumps({"plates": bent.as_matrices().tolist()}))
    pages = {"home": tmp_path / "home.html", "bent": tmp_path / "bent.html"}
    out = run_cli("view", "--home", "--html", str(pages["home"]))
    assert out.returncode == 0, out.stderr
    out = run_cli("view", "--plates", str(plates_file), "--html", str(pages["bent"]))
    assert out.returncode == 0, out.stderr

    # the same scene without the stack: the background seen by the same camera
    with StackViewer(am) as v:
        v.display(am.home)
        cam = v.frame()
        for root in v._roots:
            v.meshcat[root].set_property("visible", False)
        v.static_html(tmp_path / "background.html", frame=False)
        stack_points = placements.stack_points(am, evaluate_state(am, am.home))

    home = screenshot(pages["home"], tmp_path)
    bent_img = screenshot(pages["bent"], tmp_path)
    background = screenshot(tmp_path / "background.html", tmp_path)

    # where the stack must appear: its projected bounding box, padded
    px = project(cam, stack_points)
    pad = 25
    u0, v0 = np.floor(px.min(axis=0)).astype(int) - pad
    u1, v1 = np.ceil(px.max(axis=0)).astype(int) + pad
    inside = np.zeros((HEIGHT, WIDTH), dtype=bool)
    inside[max(v0, 0) : v1, max(u0, 0) : u1] = True
    inside_px = inside.sum()
    assert 0.05 * WIDTH * HEIGHT < inside_px < 0.6 * WIDTH * HEIGHT  # framed: neither tiny nor clipped

    changed = np.abs(home - background).max(axis=2) > 0.12
    assert changed[inside].mean() > 0.15, f"only {changed[inside].mean():.1%} of the stack region is drawn"
    assert changed[~inside].mean() < 0.01, "pixels changed outside the region the stack projects to"
    # the stack spans the frame vertically: drawn rows from near the top to near the bottom of its box
    rows = np.flatnonzero(changed[inside.any(axis=1)].any(axis=1))
    assert rows.size > 0.6 * (min(v1, HEIGHT) - max(v0, 0))

    # a different pose gives a different picture
    differ = np.abs(home - bent_img).max(axis=2) > 0.12
    assert differ.mean() > 0.01

    # the overlay (title, legend, color bar) is drawn at the top left, and nowhere else
    html = pages["home"].read_text()
    start, end = html.index('<div id="assembler-overlay"'), html.index("</body>")
    bare = tmp_path / "bare.html"
    bare.write_text(html[:start] + html[end:])
    overlay = np.abs(home - screenshot(bare, tmp_path)).max(axis=2) > 0.12
    corner = np.zeros_like(overlay)
    corner[: HEIGHT // 2, : WIDTH // 2] = True
    assert overlay[:60, :200].mean() > 0.05, "no overlay text at the top left"
    assert overlay[~corner].mean() < 0.01


@pytest.mark.skipif(CHROMIUM is None, reason="chromium not installed (.ci/run installs it)")
def test_pose_shown_after_an_animation_in_a_real_browser(am, bent, tmp_path):
    """The browser lets the animation run out, then shows the page: after animate() and
    show_comparison(), it is the picture of show_comparison() alone."""
    lengths = np.full((am.n, 6), 0.275)
    lengths[2, ::2] = 0.35
    lengths[3, 1::2] = 0.21
    other = evaluate_state(am, stack_forward_kinematics(am, lengths).raise_if_failed())
    home = evaluate_state(am, am.home)
    motion = interpolate_states(am, am.home, bent, steps=5)
    pages = {name: tmp_path / f"{name}.html" for name in ("still", "played", "after", "plain")}
    with StackViewer(am) as v:
        v.animate(motion, fps=10, play=False)
        v.static_html(pages["still"])
        v.animate(motion, fps=10, play=True)
        v.static_html(pages["played"])
        v.show_comparison(home, other)
        v.static_html(pages["after"])
    with StackViewer(am) as v:
        v.show_comparison(home, other)
        v.static_html(pages["plain"])
    img = {name: screenshot(page, tmp_path, virtual_time_ms=5000) for name, page in pages.items()}

    def changed(a: str, b: str) -> float:
        return float((np.abs(img[a] - img[b]).max(axis=2) > 0.12).mean())

    assert changed("still", "played") > 0.01  # the animation does run in the browser before the picture
    assert changed("after", "plain") < 1e-3  # and a pose shown afterwards is not replayed over


def test_page_overlay_names_what_is_drawn_and_the_color_scale_follows_the_option(am, bent, tmp_path):
    state = evaluate_state(am, bent)
    peak = float(np.abs(state.forces).max())
    leg = am.config.leg
    with StackViewer(am, force_scale="limit") as v:
        v.display(state)
        assert v.force_range == (leg.max_tension, leg.max_compression)
        v.display(state, force_scale="max")
        assert v.force_range == pytest.approx((peak, peak))
        # the drawn leg colors saturate at the chosen scale: the strongest leg is at a pure end color
        j, i = np.unravel_index(np.abs(state.forces).argmax(), state.forces.shape)
        end = TENSION_RGB if state.forces[j, i] > 0 else COMPRESSION_RGB
        assert np.allclose(force_color(state.forces[j, i], *v.force_range), end)
        v.display(am.home, force_scale="auto")  # max|F| but at least 10 % of the smaller limit
        assert v.force_range[0] == pytest.approx(
            max(evaluate_state(am, am.home).max_abs_force, 0.1 * min(leg.max_tension, leg.max_compression))
        )
        v.show_ghost(bent)
        v.show_helper_arm(np.array([[0, 0, 0], [0.1, 0, 0.3], [0.2, 0, 0.6]]))
        v.set_title("Scenario test — max|F| initial 1 → optimized 2 N")
        html = v.static_html(tmp_path / "page.html")
        with pytest.raises(ViewerError, match="force_scale"):
            v.display(am.home, force_scale="huge")
    for element in (
        'id="assembler-overlay"',
        'id="assembler-title"',
        'id="assembler-legend"',
        'id="assembler-colorbar"',
        "Scenario test",
        "initial pose (ghost)",
        "helper arm",
        "leg in tension",
        "leg in compression",
        "payload 5 kg",
    ):
        assert element in html, element
    low, high = v.force_range
    assert f"−{low:.0f}" in html and f"+{high:.0f}" in html
    # the helper arm's color is none a leg can take (legs run blue ↔ gray ↔ red)
    legs = force_color(np.linspace(-1, 1, 2001), 1.0, 1.0)
    assert np.abs(legs - ARM_LINK_RGBA[:3]).max(axis=1).min() > 0.15
    # the payload is joined to the EE plate by a rod
    rod = [c for c in page_commands(html) if c.get("path") == "/meshcat/assembler_payload_rod/rod"]
    assert rod and rod[-1]["type"] == "set_transform"
    # the rod runs from the EE plate's centre to the payload: its middle is half the offset up the EE's z
    T = np.array(rod[-1]["matrix"]).reshape(4, 4).T
    ee = evaluate_state(am, am.home).plates
    expected_mid = ee.p[-1] + 0.5 * am.config.payload.offset * ee.R[-1][:, 2]
    np.testing.assert_allclose(T[:3, 3], expected_mid, atol=1e-9)


def test_live_page_shows_the_overlay(am):
    import urllib.request

    with StackViewer(am) as v:
        v.display(am.home)
        v.set_title("Live page title")
        page = urllib.request.urlopen(v.url, timeout=10).read().decode()
        overlay = urllib.request.urlopen(v.url.replace("/static/", "/overlay"), timeout=10).read().decode()
        script = urllib.request.urlopen(v.url + "main.min.js", timeout=10)
        assert script.status == 200  # meshcat's own files are still served
    assert 'id="assembler-live-overlay"' in page and 'fetch("/overlay"' in page
    assert overlay == v.overlay_html()
    for element in ("Live page title", 'id="assembler-legend"', 'id="assembler-colorbar"'):
        assert element in overlay


def test_closed_form_placements_match_pinocchio_and_draw_any_number_of_platforms(am, bent, tmp_path):
    with StackViewer(am) as v:
        exact = v.placements(evaluate_state(am, bent))  # Pinocchio's kinematics of the whole stack
        v.whole_stack_kinematics = False
        closed = v.placements(evaluate_state(am, bent))
        frames = v._geometry_frames
    for (body, _, _), A, B in zip(frames, exact, closed, strict=True):
        np.testing.assert_allclose(B[:3, 3], A[:3, 3], atol=1e-12)  # every visual at the same place
        if body in ("plate", "payload"):
            np.testing.assert_allclose(B, A, atol=1e-12)
        else:  # cylinders about the leg axis: the same axis (the turn about it does not show)
            np.testing.assert_allclose(B[:3, 2], A[:3, 2], atol=1e-12)
    big = ap.AssemblerModel.from_config({"platforms": 12})
    assert big.n > WHOLE_DATA_MAX_PLATFORMS
    lengths = np.full((12, 6), 0.275)
    lengths[5, ::2] = 0.31
    state = evaluate_state(big, stack_forward_kinematics(big, lengths).raise_if_failed())
    with StackViewer(big) as v:
        v.display(state)
        bottom, _ = v.drawn_leg_endpoints()
        np.testing.assert_allclose(bottom, state.legs.bottom_points)
        v.animate(interpolate_states(big, big.home, state.plates, steps=3), fps=5)
        html = v.static_html(tmp_path / "twelve.html")
    paths = page_paths(html)
    assert any(p.startswith("/meshcat/assembler/visuals/sp11_leg5_shaft") for p in paths)
