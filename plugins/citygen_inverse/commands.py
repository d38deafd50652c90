"""CLI: ``citygen layout import-cmp`` and ``citygen grammar extract|cost``."""
from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

from citygen.errors import CitygenError
from citygen.registry import Command, Registry


def write_text(path: str | None, text: str) -> None:
    """Write ``text`` to ``path`` through a temporary file and a rename (stdout when ``path`` is None or -)."""
    if path in (None, "-"):
        sys.stdout.write(text)
        return
    target = Path(path)
    fd, tmp = tempfile.mkstemp(dir=target.parent or ".", prefix=f".{target.name}.")
    with os.fdopen(fd, "w") as handle:
        handle.write(text)
    os.replace(tmp, target)


class LayoutCommand(Command):
    name = "layout"
    help = "layout tools: import annotated facades as FacadeLayout JSON"

    def configure(self, parser: argparse.ArgumentParser) -> None:
        sub = parser.add_subparsers(dest="layout_command", required=True)
        cmp = sub.add_parser("import-cmp", help="CMP facade annotation (XML) -> layout JSON")
        cmp.add_argument("xml", help="CMP annotation file (*.xml)")
        cmp.add_argument("--png", help="label map of the photo (default: the .png beside the XML)")
        scale = cmp.add_mutually_exclusive_group()
        scale.add_argument("--width", type=float, help="facade width in metres")
        scale.add_argument("--floor-height", type=float, default=3.0,
                           help="metres per row of windows/doors/shops (default 3.0)")
        cmp.add_argument("-o", "--output", help="output JSON file (default stdout)")

    def run(self, args: argparse.Namespace, registry: Registry) -> int:
        from citygen_inverse.cmp import import_cmp
        try:
            layout = import_cmp(args.xml, png=args.png, width=args.width, floor_height=args.floor_height)
        except (CitygenError, OSError) as exc:
            print(f"error: {exc}", file=sys.stderr)
            return 2
        write_text(args.output, layout.dumps() + "\n")
        meta = layout.meta
        print(f"{args.xml}: {len(layout.terminals())} terminals, {layout.width:.2f} x {layout.height:.2f} m "
              f"({meta['scale_from']}), {meta['pinwheel_blocks']} pinwheel blocks", file=sys.stderr)
        return 0
