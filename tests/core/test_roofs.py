import numpy as np
from shapely.geometry import MultiPolygon, Polygon

from citygen_roofs.plugin import FlatRoof


def test_flat_roof_faces_up_and_covers_the_outline_minus_courtyards():
    outline = MultiPolygon([Polygon([(0, 0), (30, 0), (30, 20), (0, 20)], [[(5, 5), (5, 15), (15, 15), (15, 5)]]),
                            Polygon([(40, 0), (50, 0), (45, 8)])])
    mesh = FlatRoof().build(outline, 12.0)
    tris = mesh.indices.reshape(-1, 3)
    p = mesh.points.astype(float)
    normal = np.cross(p[tris[:, 1]] - p[tris[:, 0]], p[tris[:, 2]] - p[tris[:, 0]])
    assert np.all(normal[:, 2] > 0) and np.allclose(p[:, 2], 12.0)
    assert np.isclose(normal[:, 2].sum() / 2, outline.area)
