"""The region index's constant-time queries (edge rasters, content hashes) against a brute-force definition."""
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from citygen.errors import LayoutError
from citygen.layout import FacadeLayout, Region
from citygen_inverse.regions import LayoutIndex, _Grid, _upow

from .helpers import random_layout


def _brute_key(index: LayoutIndex, box):
    """wu2014 §3.1 region identity by enumeration: None when ``box`` is not exactly tiled, else its content
    relative to the corner (free width / height: sizes along that axis dropped) and its period if any."""
    x0, y0, x1, y1 = box
    inside = [k for k in range(index.X0.size) if index.X0[k] >= x0 and index.X1[k] <= x1
              and index.Y0[k] >= y0 and index.Y1[k] <= y1]
    area = sum(int((index.X1[k] - index.X0[k]) * (index.Y1[k] - index.Y0[k])) for k in inside)
    if not inside or area != (x1 - x0) * (y1 - y0):
        return None
    fw = all(index.X0[k] == x0 and index.X1[k] == x1 for k in inside)
    fh = all(index.Y0[k] == y0 and index.Y1[k] == y1 for k in inside)
    rows = sorted((int(index.material[k]), int(index.X0[k] - x0), int(index.Y0[k] - y0),
                   0 if fw else int(index.X1[k] - x0), 0 if fh else int(index.Y1[k] - y0)) for k in inside)
    return (fw, fh, tuple(rows))


def _brute_cuts(index: LayoutIndex, box, axis: int) -> list[int]:
    """Interior lines along ``axis`` that start a terminal inside ``box`` and cross none."""
    lo, hi = (index.X0, index.X1) if axis == 0 else (index.Y0, index.Y1)
    inside = [k for k in range(index.X0.size) if index.X0[k] >= box[0] and index.X1[k] <= box[2]
              and index.Y0[k] >= box[1] and index.Y1[k] <= box[3]]
    starts = {int(lo[k]) for k in inside if lo[k] > box[axis]}
    return sorted(c for c in starts if not any(lo[k] < c < hi[k] for k in inside))


@pytest.mark.parametrize("seed", range(4))
def test_grid_signatures_match_brute_force_content(seed):
    rng = np.random.default_rng(seed)
    layout = random_layout(rng, 8.0, 6.0, depth=4)
    index = LayoutIndex([layout], free_extents=True, periodic=False)
    xs, ys = index._grid.xs, index._grid.ys
    boxes = set()
    for _ in range(400):
        (a, b), (c, d) = sorted(rng.choice(xs, 2, replace=False)), sorted(rng.choice(ys, 2, replace=False))
        boxes.add((int(a), int(c), int(b), int(d)))
    by_key: dict = {}
    for box in sorted(boxes):
        key = _brute_key(index, box)
        sid = index.sig(box)
        assert (sid == -1) == (key is None), box
        if key is not None:
            assert by_key.setdefault(key, sid) == sid, box  # same content, same signature
            assert index.sigs[sid].n == len(key[2])
            for axis in (0, 1):
                assert index.cuts(box, axis) == _brute_cuts(index, box, axis)
    assert len(set(by_key.values())) == len(by_key)  # different content, different signatures


@pytest.mark.parametrize("seed", range(3))
def test_slabs_between_valid_cuts_are_tiled(seed):
    """Candidate rules look up the slabs of a region between its cuts with ``tiled`` (no tiling test): every slab
    between any two of a tiled box's sides and cuts is exactly tiled, with the signature a checked lookup finds."""
    layout = random_layout(np.random.default_rng(seed), 10.0, 8.0, depth=5)
    checked, fast = LayoutIndex([layout], periodic=True), LayoutIndex([layout], periodic=True)
    for index in (fast, checked):
        index.terminal_sigs(), index.sig(index.roots[0])
    slabs, k = 0, 1
    while k < len(checked.sigs) and slabs < 5000:  # (every signature, including those the slabs add)
        box, k = checked.sigs[k].box, k + 1
        for axis in (0, 1):
            bl = [box[axis], *checked.cuts(box, axis), box[axis + 2]]
            for a in range(len(bl)):
                for b in range(a + 1, len(bl)):
                    slab = (bl[a], box[1], bl[b], box[3]) if axis == 0 else (box[0], bl[a], box[2], bl[b])
                    assert checked._grid.region(slab) is not None, slab
                    assert fast.sig(slab, True) == checked.sig(slab), slab
                    slabs += 1
    assert slabs > 100


def _tiles(box, axis: int, p: int):
    n = (box[2 + axis] - box[axis]) // p
    return [(box[0] + k * p, box[1], box[0] + (k + 1) * p, box[3]) if axis == 0 else
            (box[0], box[1] + k * p, box[2], box[1] + (k + 1) * p) for k in range(n)]


def _lattice() -> FacadeLayout:
    """Two floors of wall | window | wall bays over a wall band, a window-less bay at the right."""
    ts = [Region(0, 0, 10, 1, "W", "wall")]
    for y in (1, 3):
        ts += [Region(x + dx, y, 1, 2, "T", label) for x in (0, 3, 6)
               for dx, label in enumerate(("wall", "window", "wall"))]
        ts.append(Region(9, y, 1, 2, "W", "wall"))
    return FacadeLayout(10, 5, Region(0, 0, 10, 5, "Facade", children=tuple(ts)))


@pytest.mark.parametrize("layout", ["lattice", 0, 1])
def test_periodic_signatures_are_smallest_identical_tiles(layout):
    layout = _lattice() if layout == "lattice" else random_layout(np.random.default_rng(layout), 12.0, 9.0, depth=5)
    index = LayoutIndex([layout], free_extents=True, periodic=True)
    xs, ys = index._grid.xs, index._grid.ys
    periodic = 0
    for a in range(len(xs)):
        for b in range(a + 1, len(xs)):
            for c, d in ((0, len(ys) - 1), *((j, j + 1) for j in range(len(ys) - 1))):
                box = (xs[a], ys[c], xs[b], ys[d])
                key = _brute_key(index, box)
                if key is None or len(key[2]) < 2 or key[0]:
                    continue
                sid = index.sig(box)
                smallest = next((p for p in (x - box[0] for x in xs[a + 1:b]) if 2 * p <= box[2] - box[0]
                                 and (box[2] - box[0]) % p == 0
                                 and None not in (ts := [_brute_key(index, t) for t in _tiles(box, 0, p)])
                                 and len(set(ts)) == 1), None)
                if smallest is not None:
                    periodic += 1
                    assert index.sigs[sid].period == (0, smallest), box
                elif index.sigs[sid].period is not None:
                    assert index.sigs[sid].period[0] == 1, box
    assert periodic > 0


def test_too_irregular_layout_is_rejected_clearly(monkeypatch):
    monkeypatch.setattr(_Grid, "MAX_CELLS", 10)
    with pytest.raises(LayoutError, match="too irregular"):
        LayoutIndex([random_layout(np.random.default_rng(1), 12.0, 9.0, depth=5)])


@pytest.mark.parametrize("free_extents", [False, True])
def test_terminal_sigs_are_the_lookups_of_every_terminal_in_order(free_extents):
    """With free extents a lone terminal's signature is its material's, so only each material's first terminal is
    looked up: the ids (and the signatures interned) are those of looking up every terminal in order."""
    for seed in range(5):
        layout = random_layout(np.random.default_rng(seed), depth=5)
        fast = LayoutIndex([layout], free_extents, periodic=free_extents)
        slow = LayoutIndex([layout], free_extents, periodic=free_extents)
        boxes = zip(*(v.tolist() for v in (slow.X0, slow.Y0, slow.X1, slow.Y1)))
        assert fast.terminal_sigs() == [slow.sig(box) for box in boxes]
        assert fast.sigs == slow.sigs
        assert fast.terminal_sigs() is fast.terminal_sigs()  # (computed once: later callers read the same ids)


@given(st.lists(st.integers(0, (1 << 64) - 1), min_size=1, max_size=3),
       st.lists(st.integers(0, (1 << 40) - 1), min_size=1, max_size=20))
def test_powers_modulo_2_64_match_python_pow(bases, exps):
    """The hash powers by byte tables equal base ** e mod 2^64 (coordinates reach ~1e8 quanta per facade, more
    side by side in a joint extraction)."""
    got = _upow(bases, exps)
    assert got.tolist() == [[pow(b, e, 1 << 64) for e in exps] for b in bases]
