"""An element's bound from its key (what a tile layer needs of an element in the library) is bit for bit the bound
of its built and welded prototype, for every label, over sizes and depths around every branch of the prototype
builder (mullions, transoms, flat boxes, zero sizes)."""
from __future__ import annotations

import itertools
import random

import numpy as np

from citygen.geometry.prototypes import INSTANCED, ProtoKey
from citygen.usd.definitions import prepare_elements
from citygen.usd.element_bounds import element_bound
from citygen.usd.materials import Material

#: Sizes in units of 0.1 m around the builder's thresholds (frame 0.07, mullion above 1.3 m, transom above 1.9 m,
#: balcony slab and railing heights), and depths in cm of both signs and none.
WIDTHS = (0, 1, 2, 3, 4, 7, 9, 13, 14, 21, 40, 137)
HEIGHTS = (0, 1, 3, 6, 10, 11, 19, 20, 28, 36, 120)
DEPTHS = (-40, -28, -25, -22, -15, -10, -1, 0, 1, 4, 9, 110, 120)


def _keys() -> list[ProtoKey]:
    rng = random.Random(7)
    keys = [ProtoKey(label, "glass" if label == "window" else "wood", w, h, d)
            for label in sorted(INSTANCED) for w, h, d in itertools.product(WIDTHS, HEIGHTS, DEPTHS)
            if rng.random() < 0.35]
    keys += [ProtoKey(rng.choice(sorted(INSTANCED)), rng.choice(["metal", "glass", "frame_dark", "stone"]),
                      rng.randint(0, 300), rng.randint(0, 300), rng.randint(-300, 300)) for _ in range(600)]
    return keys


def test_an_elements_bound_from_its_key_is_its_welded_meshes_bound():
    keys = _keys()
    library: dict[str, Material] = {}
    prepared: dict = {}
    prepare_elements(keys, prepared, library)
    differ = [key for key in keys if element_bound(key).tobytes() != np.asarray(prepared[key].bound).tobytes()]
    assert not differ, f"{len(differ)} of {len(keys)} differ, e.g. {differ[:3]}"
    assert {k.label for k in keys} == set(INSTANCED)
