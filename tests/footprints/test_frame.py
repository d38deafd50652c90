"""The local frame: projection round trip, georef inversion."""
from __future__ import annotations

import numpy as np
import pytest
from citygen.footprints import GeoReference
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from pyproj import CRS, Geod
from shapely.geometry import MultiPoint

from citygen_footprints.frame import frame_from_georef, make_frame
from citygen_footprints.geojson import import_geojson
from citygen_footprints.options import ImportOptions

GEOD = Geod(ellps="WGS84")
HELSINKI_LON, HELSINKI_LAT = (24.90, 25.00), (60.14, 60.20)


@st.composite
def polygons_near_helsinki(draw):
    lon0 = draw(st.floats(*HELSINKI_LON))
    lat0 = draw(st.floats(*HELSINKI_LAT))
    offsets = draw(st.lists(st.tuples(st.floats(-300, 300), st.floats(-300, 300)), min_size=3, max_size=12))
    points = np.array([[lon0 + dx / 55500.0, lat0 + dy / 111300.0] for dx, dy in offsets])
    hull = MultiPoint(points).convex_hull
    if hull.geom_type != "Polygon" or hull.area * 55500 * 111300 < 5.0:
        return None
    return [list(map(list, hull.exterior.coords))]


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])
@given(polygons_near_helsinki().filter(lambda p: p is not None))
def test_lonlat_round_trips_through_the_local_frame_within_a_millimetre(rings):
    doc = {"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"@id": "way/1"}, "geometry": {"type": "Polygon", "coordinates": rings}}]}
    from pathlib import Path
    result = import_geojson(doc, Path("prop.geojson"), ImportOptions(min_area=0.0))
    polygon = result.footprints[0].polygon
    back = frame_from_georef(result.georef).to_source(np.asarray(polygon.exterior.coords))
    original = np.asarray(rings[0])
    assert len(back) == len(original)
    for lon, lat in original:  # orientation may have reversed the ring: match each vertex to its nearest
        _, _, dist = GEOD.inv(np.full(len(back), lon), np.full(len(back), lat), back[:, 0], back[:, 1])
        assert dist.min() < 1e-3


@pytest.mark.filterwarnings("error::DeprecationWarning")
def test_tmerc_frame_is_conformal_and_centred():
    """Also a bug fixture: one point (a one-element array) went to pyproj's scalar path, which NumPy >= 1.25 warns
    about and will refuse ("Conversion of an array with ndim > 0 to a scalar")."""
    points = np.array([[24.93, 60.16], [24.96, 60.18]])
    frame = make_frame(CRS("OGC:CRS84"), points, None, "x")
    assert frame.to_local(np.array([[24.945, 60.17]]))[0] == pytest.approx([0, 0], abs=1e-6)
    local = frame.to_local(points)
    geodesic = GEOD.inv(24.93, 60.16, 24.96, 60.18)[2]
    assert np.hypot(*(local[1] - local[0])) == pytest.approx(geodesic, rel=1e-6)


def test_metric_frame_from_georef_is_a_translation():
    frame = frame_from_georef(GeoReference("EPSG:7415", (84941.0, 447540.0)))
    assert frame.to_source(np.array([[1.0, 2.0]]))[0] == pytest.approx([84942.0, 447542.0])
    assert frame.to_local(np.array([[84942.0, 447542.0]]))[0] == pytest.approx([1.0, 2.0])
