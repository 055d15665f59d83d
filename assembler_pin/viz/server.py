"""A meshcat server bound to one interface and tied to the lifetime of the process that started it.

meshcat 0.3.2 starts its server (``python -m meshcat.servers.zmqserver``) in a new session,
binds its ZMQ socket to 127.0.0.1 but its web server to *every* interface (tornado's
``listen(port)`` without an address), and stops it only from an ``atexit`` hook — which
never runs when the Python process dies from SIGTERM, SIGHUP or SIGKILL, so the server
outlives it, reachable from the network.

This module runs the same ZMQ–WebSocket bridge with:

* the web server bound to ``host`` (default ``127.0.0.1``; ``0.0.0.0`` serves every
  interface, on request only), the ZMQ socket always on 127.0.0.1;
* a lifeline: the server reads its stdin, a pipe from the parent, and stops when that
  pipe closes — which the kernel does whenever the parent ends, however it ends;
* a clean stop on SIGTERM, SIGHUP and SIGINT.

:func:`start_server` runs this file as a script in a subprocess and returns a
:class:`ServerProcess` with its URLs; :meth:`ServerProcess.stop` ends it. The script is
run by path, not as part of the package, so the server imports only meshcat's server
modules (not Pinocchio): it starts in a fraction of a second and stays small.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib.util
import operator
import os
import signal
import socket
import subprocess
import sys
import tempfile
import threading
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import IO

__all__ = ["DEFAULT_HOST", "SET_OVERLAY", "ServerProcess", "connect", "main", "start_server"]

DEFAULT_HOST = "127.0.0.1"
"""Interface the web server listens on unless asked otherwise: this machine only."""
ZMQ_HOST = "127.0.0.1"
"""The ZMQ command socket is only for the local Python process: always loopback."""
SET_OVERLAY = b"set_overlay"
"""ZMQ command of this server (not meshcat's): frames ``[SET_OVERLAY, html]`` set the
HTML the live page shows over the scene (title, legend, color bar)."""
OVERLAY_SCRIPT = """<div id="assembler-live-overlay"></div>
<script>
(function () {
  var box = document.getElementById("assembler-live-overlay"), last = null;
  function refresh() {
    fetch("/overlay", {cache: "no-store"}).then(function (r) { return r.text(); }).then(function (t) {
      if (t !== last) { box.innerHTML = t; last = t; }
    }).catch(function () {});
  }
  refresh();
  setInterval(refresh, 1000);
})();
</script>
"""


@dataclass
class ServerProcess:
    """A running meshcat server subprocess.

    Attributes:
        process: the subprocess (its stdin is the lifeline: closing it stops the server).
        zmq_url: where the drawing commands go (``tcp://127.0.0.1:PORT``).
        web_url: the page a browser opens (``http://HOST:PORT/static/``).
    """

    process: subprocess.Popen
    zmq_url: str
    web_url: str
    _stderr: IO[bytes] | None = field(default=None, repr=False)

    @property
    def pid(self) -> int:
        return self.process.pid

    def running(self) -> bool:
        return self.process.poll() is None

    def stop(self, timeout: float = 10.0) -> None:
        """Stop the server and reap it: close the lifeline, then SIGTERM, then SIGKILL.

        Safe to call more than once; returns when the process has ended.
        """
        with contextlib.suppress(OSError, ValueError):
            if self.process.stdin is not None:
                self.process.stdin.close()
        for escalate in (None, self.process.terminate, self.process.kill):
            if escalate is not None and self.process.poll() is None:
                with contextlib.suppress(OSError):
                    escalate()
            try:
                self.process.wait(timeout=timeout)
                break
            except subprocess.TimeoutExpired:
                continue
        for stream in (self.process.stdout, self._stderr):
            with contextlib.suppress(Exception):
                if stream is not None:
                    stream.close()


def connect(host: str = DEFAULT_HOST, port: int | None = None):
    """Start a server (:func:`start_server`) and a ``meshcat.Visualizer`` talking to it; the
    server is stopped again if the visualizer cannot be made. Returns (server, visualizer)."""
    import io

    import meshcat

    server = start_server(host, port)
    try:
        with contextlib.redirect_stdout(io.StringIO()):  # meshcat prints its URL
            return server, meshcat.Visualizer(zmq_url=server.zmq_url)
    except BaseException:
        server.stop()
        raise


def _url_host(host: str) -> str:
    """``host`` as written in a URL: IPv6 addresses in brackets."""
    return f"[{host}]" if ":" in host and not host.startswith("[") else host


def start_server(host: str = DEFAULT_HOST, port: int | None = None, timeout: float = 60.0) -> ServerProcess:
    """Start a meshcat server subprocess whose web server listens on ``host``.

    Args:
        host: interface of the web server (``127.0.0.1``: this machine only; ``0.0.0.0``:
            every IPv4 interface).
        port: web server port; default the first free one from 7000.
        timeout: how long to wait for the server to announce its URLs [s].

    Raises:
        ViewerError: ``host`` is not an interface of this machine, ``port`` is out of
            range, or the server exited before announcing its URLs (its stderr is quoted).
    """
    _check_host_and_port(host, port)
    script = os.path.abspath(__file__)
    run = f"import runpy, sys; sys.argv[0] = {script!r}; runpy.run_path({script!r}, run_name='__main__')"
    args = [sys.executable, "-u", "-c", run, "--host", host]
    if port is not None:
        args += ["--port", str(operator.index(port))]
    env = dict(os.environ)
    spec = importlib.util.find_spec("meshcat")  # found by this process: let the server find it too
    if spec is not None and spec.origin:
        meshcat_root = os.path.dirname(os.path.dirname(spec.origin))
        env["PYTHONPATH"] = os.pathsep.join(p for p in (meshcat_root, env.get("PYTHONPATH", "")) if p)
    stderr = tempfile.TemporaryFile()  # not a pipe: nobody reads it while the server runs
    proc = subprocess.Popen(
        args,
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=stderr,
        env=env,
        start_new_session=True,  # a Ctrl-C meant for a notebook cell must not reach it
    )
    server = ServerProcess(proc, "", "", stderr)
    urls: dict[str, str] = {}
    reader = threading.Thread(target=_read_urls, args=(proc, urls), daemon=True)
    reader.start()
    try:
        reader.join(timeout)
    except BaseException:  # interrupted while waiting: do not leave it behind
        server.stop()
        raise
    if "zmq_url" not in urls or "web_url" not in urls:
        from ..exceptions import ViewerError  # script: run without its package (runpy), see main()

        server._stderr = None  # read it once the server has ended, then close it here
        server.stop()
        with stderr:
            stderr.seek(0)
            tail = stderr.read().decode("utf-8", "replace").strip().splitlines()[-1:]  # the error itself
        raise ViewerError(
            f"the meshcat server did not start (exit code {proc.returncode}): {''.join(tail) or 'no output'}"
        )
    server.zmq_url, server.web_url = urls["zmq_url"], urls["web_url"]
    return server


def _check_host_and_port(host: str, port: int | None) -> None:
    """Refuse a host this machine cannot listen on, or a port out of range (ViewerError)."""
    from ..exceptions import ViewerError  # script: run without its package (runpy), see main()

    allowed = "e.g. 127.0.0.1 (this machine only) or 0.0.0.0 (every interface)"
    if port is not None:
        try:
            number = None if isinstance(port, bool) else operator.index(port)  # numpy integers too
        except TypeError:
            number = None
        if number is None or not 1 <= number <= 65535:
            raise ViewerError(f"viewer port must be an integer in 1..65535, got {port!r}")
    if not isinstance(host, str) or not host or "\x00" in host:
        raise ViewerError(f"viewer host must be an interface address, {allowed}; got {host!r}")
    try:
        family, kind, proto, _, address = socket.getaddrinfo(host, 0, type=socket.SOCK_STREAM)[0]
        with socket.socket(family, kind, proto) as probe:
            probe.bind(address)
    except (OSError, UnicodeError) as exc:
        reason = getattr(exc, "strerror", None) or exc
        raise ViewerError(
            f"cannot listen on viewer host {host!r} ({reason}): give an address of this machine, {allowed}"
        ) from None


def _read_urls(proc: subprocess.Popen, urls: dict[str, str]) -> None:
    assert proc.stdout is not None  # started with stdout=PIPE
    for raw in proc.stdout:
        key, _, value = raw.decode("utf-8", "replace").strip().partition("=")
        if key in ("zmq_url", "web_url"):
            urls[key] = value
        if len(urls) == 2:
            return


# ---------------------------------------------------------------------- the server side
def _make_bridge(host: str, port: int | None):
    import tornado.routing
    import tornado.web
    from meshcat.servers.zmqserver import VIEWER_HTML, VIEWER_ROOT, ZMQWebSocketBridge

    class OverlayHandler(tornado.web.RequestHandler):
        """The overlay's current HTML (title, legend, color bar), as last set by the viewer."""

        def initialize(self, bridge) -> None:
            self.bridge = bridge

        def get(self) -> None:
            self.set_header("Cache-Control", "no-store")
            self.set_header("Content-Type", "text/html; charset=utf-8")
            self.write(self.bridge.overlay)

    class IndexHandler(tornado.web.RequestHandler):
        """meshcat's page with a box that shows the overlay, refreshed every second."""

        def get(self, _name: str | None = None) -> None:
            with open(os.path.join(VIEWER_ROOT, VIEWER_HTML), encoding="utf-8") as fh:
                page = fh.read()
            self.set_header("Cache-Control", "no-store")
            self.write(page.replace("</body>", OVERLAY_SCRIPT + "</body>", 1))

    class Bridge(ZMQWebSocketBridge):
        """meshcat's bridge with the web server on ``web_host`` and ZMQ on loopback, and
        the page's overlay (set with the ZMQ command ``set_overlay``)."""

        def __init__(self) -> None:
            self.web_host = host
            self.overlay = ""
            super().__init__(host=ZMQ_HOST, port=port)
            self.web_url = f"http://{_url_host(host)}:{self.fileserver_port}/static/"

        def handle_zmq(self, frames):
            if frames[0] == SET_OVERLAY:
                self.overlay = frames[1].decode("utf-8") if len(frames) > 1 else ""
                self.zmq_socket.send(b"ok")
                return
            super().handle_zmq(frames)

        def make_app(self):
            app = super().make_app()
            app.wildcard_router.rules[:0] = tornado.routing.RuleRouter(
                [(r"/static/(index\.html)?", IndexHandler), (r"/overlay", OverlayHandler, {"bridge": self})]
            ).rules
            listen = app.listen

            def listen_on_host(port: int, **kwargs):
                return listen(port, address=self.web_host, **kwargs)

            app.listen = listen_on_host
            return app

    return Bridge()


def _watch_lifeline(loop) -> None:
    """Block on stdin; at end of file (the parent closed the pipe or ended), stop the loop."""
    with contextlib.suppress(Exception):
        while sys.stdin.buffer.read(1024):
            pass
    loop.add_callback(loop.stop)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description="meshcat server bound to one interface, stopped with its parent")
    parser.add_argument("--host", default=DEFAULT_HOST, help="web server interface (default 127.0.0.1)")
    parser.add_argument("--port", type=int, default=None, help="web server port (default: first free from 7000)")
    args = parser.parse_args(argv)

    bridge = _make_bridge(args.host, args.port)
    loop = bridge.ioloop
    for name in ("SIGTERM", "SIGINT", "SIGHUP"):
        sig = getattr(signal, name, None)
        if sig is None:
            continue
        try:
            loop.asyncio_loop.add_signal_handler(sig, loop.stop)
        except (NotImplementedError, AttributeError):  # no asyncio signal handlers (Windows)
            signal.signal(sig, lambda *_: loop.add_callback(loop.stop))
    print(f"zmq_url={bridge.zmq_url}", flush=True)
    print(f"web_url={bridge.web_url}", flush=True)
    sys.stdout = open(os.devnull, "w")  # nobody reads the pipe from here on
    threading.Thread(target=_watch_lifeline, args=(loop,), daemon=True).start()
    bridge.run()
    return 0


if __name__ == "__main__":
    sys.exit(main())
