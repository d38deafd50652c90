import numpy as np
from hypothesis import given, settings, strategies as st

from citygen.geometry.quads import box_quads, merge_rects, weld


def area(rects):
    return float(np.sum((rects[:, 2] - rects[:, 0]) * (rects[:, 3] - rects[:, 1])))


def test_merge_rects_joins_a_row_and_a_column():
    row = np.array([[0, 0, 1, 1], [1, 0, 2, 1], [2, 0, 3, 1], [0, 1, 3, 2]], float)
    merged = merge_rects(row)
    assert merged.tolist() == [[0, 0, 3, 2]]


@settings(max_examples=50, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 9), st.integers(0, 9)), min_size=1, max_size=60, unique=True))
def test_merge_rects_preserves_the_covered_cells(cells):
    rects = np.array([(x, y, x + 1, y + 1) for x, y in cells], float)
    merged = merge_rects(rects)
    assert area(merged) == area(rects) and len(merged) <= len(rects)
    covered = {(x, y) for x0, y0, x1, y1 in merged for x in range(int(x0), int(x1)) for y in range(int(y0), int(y1))}
    assert covered == set(cells)


def test_box_normals_point_out_of_protrusions_and_into_recesses():
    def normals(q):
        return np.cross(q[:, 1] - q[:, 0], q[:, 3] - q[:, 0])
    out = box_quads(np.array([[0, 0, 1, 1]]), np.array([0.5]))
    centre = np.array([0.5, 0.5, 0.25])
    assert np.all(np.einsum("ij,ij->i", normals(out), out.mean(axis=1) - centre) > 0)
    rec = box_quads(np.array([[0, 0, 1, 1]]), np.array([-0.5]), front=False)
    centre = np.array([0.5, 0.5, -0.25])
    assert np.all(np.einsum("ij,ij->i", normals(rec), rec.mean(axis=1) - centre) < 0)


def test_weld_shares_corners_of_adjacent_quads():
    quads = box_quads(np.array([[0, 0, 1, 1], [1, 0, 2, 1]]), np.zeros(2))
    points, indices = weld(quads)
    assert len(points) == 6 and indices.shape == (8,)
    assert np.allclose(points[indices].reshape(2, 4, 3), quads)
