"""instances_bounds: the bounds of many PointInstancers in one pass equal each instancer's alone, and each equals
the bound of its instances' prototype boxes transformed as USD composes them."""
from __future__ import annotations

import itertools

import numpy as np
import pytest
from pxr import Gf

from citygen.usd.bounds import instances_bounds


def _instancer(rng: np.random.Generator, n: int, protos: int):
    turn = rng.normal(size=(n, 4))
    turn /= np.linalg.norm(turn, axis=1)[:, None]
    return (rng.integers(0, protos, n), rng.uniform(-50, 50, (n, 3)), turn.astype(np.float16),
            rng.uniform(0.5, 2.0, (n, 3)).astype(np.float32))


def _brute(boxes, indices, positions, orientations, scales):
    """Every corner of every instance's box through Gf: scale, rotate, translate."""
    corners = []
    for p, t, q, s in zip(indices, positions, orientations.astype(float), scales.astype(float)):
        if boxes[p] is None:
            continue
        rot = Gf.Quatd(q[3], Gf.Vec3d(*q[:3])).GetNormalized()
        for corner in itertools.product(*zip(*boxes[p])):
            v = rot.Transform(Gf.Vec3d(*(np.array(corner) * s)))
            corners.append(np.array(v) + t)
    return None if not corners else np.array([np.min(corners, axis=0), np.max(corners, axis=0)])


@pytest.mark.parametrize("seed", range(5))
def test_the_bounds_of_many_instancers_equal_each_alone_and_usds_composition(seed):
    rng = np.random.default_rng(seed)
    boxes = [np.sort(rng.uniform(-2, 2, (2, 3)), axis=0) for _ in range(4)] + [None]  # (the last: unknown)
    sizes = [int(n) for n in rng.choice([0, 1, 3, 7], size=6)] + [0]  # (empty instancers, one at the end)
    parts = [_instancer(rng, n, len(boxes)) for n in sizes]
    grouped = instances_bounds(boxes, *(np.concatenate([p[k] for p in parts]) for k in range(4)), sizes)
    assert len(grouped) == len(sizes)
    for part, size, got in zip(parts, sizes, grouped):
        alone = instances_bounds(boxes, *part, [size])[0]
        expected = _brute(boxes, *part)
        if expected is None:
            assert got is None and alone is None
            continue
        assert np.array_equal(got, alone)
        np.testing.assert_allclose(got, expected, atol=1e-9)


def test_no_instancers_and_only_unknown_prototypes_have_no_bound():
    empty = np.zeros((0, 3))
    assert instances_bounds([None], np.zeros(0, np.int64), empty, np.zeros((0, 4)), empty, []) == []
    one = np.array([0])
    assert instances_bounds([None], one, np.zeros((1, 3)), np.array([[0, 0, 0, 1.0]]), np.ones((1, 3)), [1]) == [None]
