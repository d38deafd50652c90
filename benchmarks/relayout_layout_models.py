"""Relayout models built from imported CMP facades alone (``layout "file.json"``, no constraints) on building faces.

Each CMP annotation is imported (``citygen_inverse.cmp.import_cmp``), turned into a layout-only model, and dressed
on preview faces (3.0 m storeys, 4.0 m ground floor) at multiples of its own size; each outcome is classified as
``citygen facade`` does (dressed / fell-back / implausible / constraints-broken).

    python benchmarks/relayout_layout_models.py [--cmp ../shared/data/cmp_facade/base] [--names cmp_b0002 ...]
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from collections import Counter
from pathlib import Path

from citygen.cli import facade_outcome
from citygen.errors import CitygenError
from citygen.request import FacadeRequest
from citygen_inverse.cmp import import_cmp
from citygen_relayout import parse_model
from citygen_relayout.building import generate_face

NAMES = ("cmp_b0002", "cmp_b0010", "cmp_b0035", "cmp_b0092", "cmp_b0150", "cmp_b0213")
#: target sizes as (width, height) multiples of the input facade
SCALES = ((1.0, 1.0), (1.5, 1.0), (1.0, 1.6), (2.2, 1.3), (0.7, 1.0))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cmp", type=Path, help="directory of CMP annotations (base/*.xml)",
                        default=Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "cmp_facade" / "base")
    parser.add_argument("--names", nargs="*", default=list(NAMES))
    args = parser.parse_args(argv)
    tally: Counter = Counter()
    with tempfile.TemporaryDirectory() as tmp:
        base = Path(tmp)
        for name in args.names:
            layout = import_cmp(args.cmp / f"{name}.xml")
            (base / f"{name}.layout.json").write_text(layout.dumps())
            try:
                model = parse_model(f'model {name}\nlayout "{name}.layout.json" tolerance 0.15\n',
                                    str(base / f"{name}.relayout"), base=base)
            except CitygenError as exc:
                print(f"{name}: not a model: {exc}")
                tally["not segmentable"] += 1
                continue
            outcomes = []
            for fw, fh in SCALES:
                request = FacadeRequest.preview(round(layout.width * fw, 1), round(layout.height * fh, 1),
                                                floor_height=3.0, ground_height=4.0)
                outcome, _ = facade_outcome(generate_face(model, request), request)
                tally[outcome] += 1
                outcomes.append(outcome)
            print(f"{name} {layout.width:.1f} x {layout.height:.1f} m, {len(model.symbols)} symbols, "
                  f"{model.terminal_count()} terminals: {' '.join(outcomes)}", flush=True)
    print(", ".join(f"{v} {k}" for k, v in sorted(tally.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
