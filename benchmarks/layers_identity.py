"""Digests of layer-stack layouts, to check that a solver change is exact (byte-identical layout JSON).

Run: python benchmarks/layers_identity.py OUT.json [--random N]   (then diff two OUT files)

Covers the cases of ``layers_solve.py``, the shipped ``.layers`` rulesets at several sizes with and without
entrance and corner strips, and ``N`` random stacks of the kind ``tests/layers/test_properties.py`` draws.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import random
import sys
from pathlib import Path

from citygen_layers.parser import load
from citygen_layers.facade import clear_solved, generate
from layers_solve import CASES

from citygen.request import FacadeRequest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # the random stacks come from the layer-stack property tests
from tests.layers.test_properties import FLAGS, X_PATTERNS, Y_PATTERNS  # noqa: E402
from tests.layers.test_properties import random_stack as stack_of  # noqa: E402


def random_stack(rng: random.Random):
    """A random stack of the kind ``tests/layers/test_properties.py`` draws."""
    layers = [(rng.randrange(len(X_PATTERNS)), rng.randrange(len(Y_PATTERNS))) for _ in range(rng.randint(1, 4))]
    return stack_of(layers, {s: rng.choice(FLAGS) for s in "BCD"})


def requests():
    for name, path, request in CASES:
        yield name, load(path), request
    for path in sorted((ROOT / "rulesets").glob("*.layers")) + [ROOT / "benchmarks/data/layers/tonhalle26.layers"]:
        ruleset = load(path)
        for width, height in ((5.0, 3.5), (9.3, 7.0), (14.0, 10.0), (21.7, 16.0), (30.0, 24.0)):
            for entrance in (False, True):
                for corner in (0.0, 0.45):
                    base = FacadeRequest.preview(width, height, 3.0, 4.0, entrance=entrance)
                    request = FacadeRequest(width, height, base.floor_lines, entrance, (corner, corner), base.context)
                    yield f"{path.name} {width}x{height} e={entrance} c={corner}", ruleset, request


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("out")
    parser.add_argument("--random", type=int, default=60)
    args = parser.parse_args()
    out = {}
    for name, ruleset, request in requests():
        clear_solved()
        out[name] = hashlib.sha256(generate(ruleset, request).dumps().encode()).hexdigest()
    rng = random.Random(7)
    for i in range(args.random):
        rs = random_stack(rng)
        request = FacadeRequest(rng.uniform(3.0, 20.0), rng.uniform(3.0, 12.0), (0.0, 0.0))
        request = FacadeRequest(request.width, request.height, (0.0, request.height))
        clear_solved()
        out[f"random {i}"] = hashlib.sha256(generate(rs, request).dumps().encode()).hexdigest()
    Path(args.out).write_text(json.dumps(out, indent=1))
    print(len(out), "layouts")


if __name__ == "__main__":
    main()
