"""Serving a studio: its command-line options, the loopback socket, and the server that answers the page at once
while the library and the scene load behind it (:class:`PendingSession`).

Nothing here imports the library beyond its errors: ``citygen studio`` starts through :func:`main` before the
plugins load (the ``citygen.early`` entry point), so the page paints while they do.
"""
from __future__ import annotations

import argparse
import socket
import sys
import threading
import time
import webbrowser
from collections.abc import Callable
from pathlib import Path
from typing import Any

#: The studio listens on the loopback only: it reads and writes files for whoever can reach it.
HOST = "127.0.0.1"


def configure(parser: argparse.ArgumentParser) -> None:
    """The options of ``citygen studio``."""
    parser.add_argument("scene", nargs="?", help="scene TOML file (default: only the rulesets of this folder)")
    parser.add_argument("--port", type=_port, default=0, help="port on 127.0.0.1 (default: a free one)")
    parser.add_argument("--no-browser", action="store_true", help="print the URL, do not open a browser")


def _port(text: str) -> int:
    if not text.isdigit() or int(text) > 65535:
        raise argparse.ArgumentTypeError(f"a port is a whole number from 0 to 65535, got {text!r}")
    return int(text)


def listen(port: int) -> socket.socket:
    """A listening socket on the loopback (``port`` 0: a free one the system picks)."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.bind((HOST, port))
    sock.listen(64)
    return sock


class PendingSession:
    """A :class:`~citygen_studio.session.Session` being made in a background thread (the plugins imported, the
    scene loaded): its ``scene_ready`` and ``loaded`` events exist at once, so the app can be served before it; any
    other attribute waits until the session exists. ``make(events)`` builds the session on those events."""

    def __init__(self, make: Callable[[tuple[threading.Event, threading.Event]], Any]) -> None:
        self.scene_ready, self.loaded = threading.Event(), threading.Event()
        self._made = threading.Event()
        self._session: Any = None
        self._error: str | None = None
        threading.Thread(target=self._make, args=(make,), daemon=True).start()

    def _make(self, make: Callable[[tuple[threading.Event, threading.Event]], Any]) -> None:
        try:
            self._session = make((self.scene_ready, self.loaded))
        except BaseException as exc:  # (the page says so instead of waiting for ever)
            self._error = f"the studio could not start: {type(exc).__name__}: {exc}"
            print(f"citygen: error: {self._error}", file=sys.stderr, flush=True)
            self.scene_ready.set()
            self.loaded.set()
        finally:
            self._made.set()

    def __getattr__(self, name: str) -> Any:
        self._made.wait()
        if self._session is None:
            from citygen_studio.confinement import StudioError
            raise StudioError(self._error or "the studio could not start", 500)
        return getattr(self._session, name)


def serve(scene: str | None, port: int, browser: bool, registry: Any = None) -> int:
    """Listen, print the URL, open the browser (``browser``) and serve until Ctrl+C; the session is made in the
    background (with ``registry``, or the default one, loaded there)."""
    try:
        import uvicorn

        from citygen_studio.app import create_app
    except ImportError as exc:
        print(f"error: the studio needs {exc.name}: pip install 'citygen[studio]'", file=sys.stderr)
        return 2
    try:
        sock = listen(port)
    except OSError as exc:
        print(f"error: cannot listen on {HOST}:{port}: {exc.strerror}", file=sys.stderr)
        return 2

    def make(events: tuple[threading.Event, threading.Event]) -> Any:
        from citygen.registry import default_registry
        from citygen_studio.session import Session
        return Session(registry or default_registry(), Path(scene) if scene else None, background=True,
                       events=events)

    url = f"http://{HOST}:{sock.getsockname()[1]}/"
    server = uvicorn.Server(uvicorn.Config(create_app(PendingSession(make)), log_level="warning", lifespan="off"))
    print(f"citygen studio on {url} (Ctrl+C to stop)", flush=True)
    if browser:
        threading.Thread(target=_open_when_started, args=(server, url), daemon=True).start()
    server.run(sockets=[sock])
    return 0


def main(argv: list[str]) -> int:
    """``citygen studio ...`` started before the plugins load (the ``citygen.early`` entry point)."""
    parser = argparse.ArgumentParser(prog="citygen studio",
                                     description="author rulesets live in the browser on a scene's buildings")
    configure(parser)
    args = parser.parse_args(argv)
    return serve(args.scene, args.port, not args.no_browser)


def _open_when_started(server: Any, url: str) -> None:
    for _ in range(100):
        if server.started:
            webbrowser.open(url)
            return
        time.sleep(0.05)
