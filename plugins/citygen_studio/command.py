"""CLI: ``citygen studio [SCENE] [--port N] [--no-browser]``."""
from __future__ import annotations

import argparse
import socket
import sys
import threading
import time
import webbrowser
from pathlib import Path

from citygen.cliargs import whole
from citygen.registry import Command, Registry

#: The studio listens on the loopback only: it reads and writes files for whoever can reach it.
HOST = "127.0.0.1"


def listen(port: int) -> socket.socket:
    """A listening socket on the loopback (``port`` 0: a free one the system picks)."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    sock.bind((HOST, port))
    sock.listen(64)
    return sock


class StudioCommand(Command):
    name = "studio"
    help = "author rulesets live in the browser on a scene's buildings (local web app)"

    def configure(self, parser: argparse.ArgumentParser) -> None:
        parser.add_argument("scene", nargs="?", help="scene TOML file (default: only the rulesets of this folder)")
        parser.add_argument("--port", type=whole(0), default=0, help="port on 127.0.0.1 (default: a free one)")
        parser.add_argument("--no-browser", action="store_true", help="print the URL, do not open a browser")

    def run(self, args: argparse.Namespace, registry: Registry) -> int:
        try:
            import uvicorn

            from citygen_studio.app import create_app
        except ImportError as exc:
            print(f"error: the studio needs {exc.name}: pip install 'citygen[studio]'", file=sys.stderr)
            return 2
        from citygen_studio.session import Session

        session = Session(registry, Path(args.scene) if args.scene else None, background=True)
        try:
            sock = listen(args.port)
        except OSError as exc:
            print(f"error: cannot listen on {HOST}:{args.port}: {exc.strerror}", file=sys.stderr)
            return 2
        url = f"http://{HOST}:{sock.getsockname()[1]}/"
        server = uvicorn.Server(uvicorn.Config(create_app(session), log_level="warning", lifespan="off"))
        print(f"citygen studio on {url} (Ctrl+C to stop)", flush=True)
        if not args.no_browser:
            threading.Thread(target=_open_when_started, args=(server, url), daemon=True).start()
        server.run(sockets=[sock])
        return 0


def _open_when_started(server, url: str) -> None:
    for _ in range(100):
        if server.started:
            webbrowser.open(url)
            return
        time.sleep(0.05)
