"""CPU per SAFE (dang2014) preview as the studio makes it: an edited ``.safe`` text parsed and its facade generated.

    .venv/bin/python benchmarks/safe_preview_cpu.py [--repeats 7] [--sizes 20x15 10x12 30x18 60x30]

For every shipped ``.safe`` ruleset and size, prints the median process CPU milliseconds of parsing a text the
process has not seen (a comment with a new number appended: the studio's keystroke) plus ``SafeKind.generate`` at
the size (floor height 3.3 m, as the studio's default face), of ``generate`` alone on that freshly parsed ruleset,
and of ``generate`` in a process that remembers nothing (*cold*: :func:`citygen_safe.memory.forget` first, as for
a ruleset whose layout or grids were just changed). The machine is shared: CPU time, not wall time, is the figure.
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

from citygen.request import FacadeRequest
from citygen_safe.memory import forget
from citygen_safe.plugin import SafeKind

RULESETS = Path(__file__).resolve().parents[1] / "rulesets"
SIZES = ("20x15", "10x12", "30x18", "60x30")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--sizes", nargs="*", default=SIZES, metavar="WxH", help="target sizes in m")
    args = parser.parse_args()
    kind = SafeKind()
    print(f"{'ruleset':<16} {'size':>7} {'parse+generate':>15} {'generate':>9} {'cold':>7}  "
          f"(median CPU ms of {args.repeats})")
    for path in sorted(RULESETS.glob("*.safe")):
        text = path.read_text(encoding="utf-8")
        kind.generate(kind.loads(text, path), FacadeRequest.preview(20.0, 15.0, 3.3))  # imports, first-use caches
        for spec in args.sizes:
            width, height = (float(v) for v in spec.split("x"))
            request = FacadeRequest.preview(width, height, 3.3)
            total, gen, cold = [], [], []
            for k in range(args.repeats):
                c0 = time.process_time()
                ruleset = kind.loads(f"{text}\n# edit {k} {spec}\n", path)
                c1 = time.process_time()
                kind.generate(ruleset, request)
                c2 = time.process_time()
                total.append(1000 * (c2 - c0))
                gen.append(1000 * (c2 - c1))
                ruleset = kind.loads(f"{text}\n# cold {k} {spec}\n", path)
                forget()
                c3 = time.process_time()
                kind.generate(ruleset, request)
                cold.append(1000 * (time.process_time() - c3))
            print(f"{path.name:<16} {spec:>7} {statistics.median(total):>15.1f} {statistics.median(gen):>9.1f} "
                  f"{statistics.median(cold):>7.1f}")


if __name__ == "__main__":
    main()
