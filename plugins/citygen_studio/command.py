"""CLI: ``citygen studio [SCENE] [--port N] [--no-browser]`` (as listed by ``citygen --help``; ``citygen studio``
itself starts early, through :func:`citygen_studio.serve.main`, before the plugins load)."""
from __future__ import annotations

import argparse

from citygen.registry import Command, Registry
from citygen_studio.serve import configure, serve


class StudioCommand(Command):
    name = "studio"
    help = "author rulesets live in the browser on a scene's buildings (local web app)"

    def configure(self, parser: argparse.ArgumentParser) -> None:
        configure(parser)

    def run(self, args: argparse.Namespace, registry: Registry) -> int:
        return serve(args.scene, args.port, not args.no_browser, registry)
