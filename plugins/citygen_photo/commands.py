"""CLI: ``citygen layout from-photo PHOTO [--width M | --floor-height M] [--crop ...] [--labels PNG] [--png PNG]``."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from citygen.errors import CitygenError, LayoutError
from citygen.registry import LayoutSource
from citygen_inverse.commands import report, write_text
from citygen_photo import PARSERS


class FromPhoto(LayoutSource):
    name = "from-photo"
    help = "rectified facade photo -> layout JSON (mueller2007 with a learned facade parser)"

    def configure(self, parser: argparse.ArgumentParser) -> None:
        parser.add_argument("photo", help="facade photo (JPEG, PNG, ...), rectified")
        scale = parser.add_mutually_exclusive_group()
        scale.add_argument("--width", type=float, help="facade (crop) width in metres")
        scale.add_argument("--floor-height", type=float, default=3.0,
                           help="metres per detected floor period (default 3.0)")
        parser.add_argument("--crop", type=float, nargs=4, metavar=("X0", "Y0", "X1", "Y1"),
                            help="facade box in pixels, y down (default the whole photo)")
        parser.add_argument("--parser", choices=PARSERS, default="learned",
                            help="learned (default): the trained facade parser under the regular structure; "
                                 "contrast: mueller2007's intensity contrast test and element library")
        parser.add_argument("--labels", type=Path, metavar="PNG",
                            help="also write the parser's predicted label map (CMP colours) of the crop")
        parser.add_argument("--png", type=Path, metavar="PNG", help="also draw the layout over the photo")
        parser.add_argument("-o", "--output", help="output JSON file (default stdout)")

    def run(self, args: argparse.Namespace) -> int:
        from citygen_photo.overlay import save_labels, save_overlay
        from citygen_photo.photo import layout_from_photo
        for name in ("width", "floor_height"):
            value = getattr(args, name)
            if value is not None and not 0 < value < float("inf"):
                return report(LayoutError(f"--{name.replace('_', '-')} must be a finite positive number of metres, "
                                          f"got {value:g}", where=args.photo))
        try:
            result = layout_from_photo(args.photo, width=args.width, floor_height=args.floor_height,
                                       crop=tuple(args.crop) if args.crop else None, parser=args.parser)
            if args.labels:
                save_labels(result, args.labels)
            if args.png:
                save_overlay(result, args.photo, tuple(args.crop) if args.crop else None, args.png)
        except (CitygenError, OSError) as exc:
            return report(exc)
        layout = result.layout
        write_text(args.output, layout.dumps() + "\n")
        print(f"{args.photo}: {layout.meta['floors']} floors x {layout.meta['tiles_per_floor']} tiles, "
              f"{layout.count('window')} windows, {layout.count('door')} doors, {len(layout.terminals())} "
              f"terminals, {layout.width:.2f} x {layout.height:.2f} m ({layout.meta['scale_from']})",
              file=sys.stderr)
        return 0
