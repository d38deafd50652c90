"""The local metric frame: source CRS -> metres around an origin, with a sanity check of the declared CRS.

Geographic input (lon/lat, any datum) and projected input in non-metre units go through a transverse Mercator
projection centred on the origin (scale error < 1e-8 within a few km), on the source's own datum so no datum
shift is involved. Projected metric input is only translated. Either way local (0, 0) is the origin and the
:class:`~citygen.footprints.GeoReference` records how to go back (:func:`frame_from_georef`).
"""
from __future__ import annotations

import functools
import warnings
from dataclasses import dataclass

import numpy as np
from citygen.errors import FootprintError
from citygen.footprints import GeoReference
from pyproj import CRS, Transformer
from pyproj.crs import ProjectedCRS
from pyproj.crs.coordinate_operation import TransverseMercatorConversion
from pyproj.exceptions import CRSError

#: how far (degrees) data may lie outside a projected CRS's declared area of use before it counts as a mismatch
AREA_MARGIN_DEG = 5.0


@dataclass(frozen=True)
class LocalFrame:
    """Maps source coordinates to the local frame and back; ``(n, 2)`` float arrays in, ``(n, 2)`` out (handed to
    pyproj as lists: it takes a one-element array for a scalar, which NumPy deprecates)."""

    georef: GeoReference
    forward: Transformer | None = None
    offset: tuple[float, float] = (0.0, 0.0)

    def to_local(self, xy: np.ndarray) -> np.ndarray:
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        if self.forward is not None:
            x, y = self.forward.transform(xy[:, 0].tolist(), xy[:, 1].tolist())
            return np.column_stack([x, y])
        return xy - np.asarray(self.offset)

    def to_source(self, xy: np.ndarray) -> np.ndarray:
        xy = np.asarray(xy, dtype=float).reshape(-1, 2)
        if self.forward is not None:
            x, y = self.forward.transform(xy[:, 0].tolist(), xy[:, 1].tolist(), direction="INVERSE")
            return np.column_stack([x, y])
        return xy + np.asarray(self.offset)


@functools.lru_cache(maxsize=64)
def _crs_from_text(text: str) -> CRS:
    return CRS.from_user_input(text)


def parse_crs(text: str, where: str) -> CRS:
    """A pyproj CRS from a user string (``EPSG:3067``, a URN or URL, WKT, PROJ); FootprintError if unknown."""
    try:
        return _crs_from_text(text)
    except CRSError as exc:
        raise FootprintError(f"unknown CRS {text!r}: {exc}", where=where,
                             hint='give crs as e.g. "EPSG:3067" or "OGC:CRS84"') from None


def _horizontal(crs: CRS) -> CRS:
    return crs.sub_crs_list[0] if crs.is_compound else crs


def _is_metric_projected(crs: CRS) -> bool:
    h = _horizontal(crs)
    return not h.is_geographic and all(a.unit_conversion_factor == 1.0 for a in h.axis_info[:2])


def _tmerc_proj(crs: CRS, lon: float, lat: float) -> str:
    conversion = TransverseMercatorConversion(latitude_natural_origin=lat, longitude_natural_origin=lon,
                                              false_easting=0.0, false_northing=0.0,
                                              scale_factor_natural_origin=1.0)
    local = ProjectedCRS(conversion=conversion, geodetic_crs=_horizontal(crs).geodetic_crs)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)  # "you will likely lose information": we keep the datum
        return local.to_proj4()


def is_geographic(crs: CRS) -> bool:
    """The CRS's horizontal part is lon/lat."""
    return _horizontal(crs).is_geographic


def outside_lonlat(points: np.ndarray) -> np.ndarray:
    """Per point ``(n, 2)``: outside the lon/lat range (|lon| > 180 or |lat| > 90)."""
    return (np.abs(points[:, 0]) > 180) | (np.abs(points[:, 1]) > 90)


def _check_geographic(points: np.ndarray, name: str, where: str) -> None:
    bad = outside_lonlat(points)
    if bad.any():
        x, y = points[np.argmax(bad)]
        raise FootprintError(
            f"coordinates such as ({x:.1f}, {y:.1f}) are outside the lon/lat range, but the file is read as "
            f"{name} (lon/lat)", where=where,
            hint="if the file holds projected metres, declare its CRS: set crs = \"EPSG:nnnn\" in the scene's "
                 "[footprints] table (or a crs member in the file)")


def _check_projected(crs: CRS, points: np.ndarray, where: str) -> None:
    area = crs.area_of_use
    if area is None:
        return
    to_geo = Transformer.from_crs(_horizontal(crs), _horizontal(crs).geodetic_crs, always_xy=True)
    centre = (points.min(axis=0) + points.max(axis=0)) / 2
    lon, lat = to_geo.transform(centre[0], centre[1])
    m = AREA_MARGIN_DEG
    inside = (np.isfinite(lon) and np.isfinite(lat) and area.west - m <= lon <= area.east + m
              and area.south - m <= lat <= area.north + m)
    if not inside:
        looks_geographic = bool(np.all(np.abs(points[:, 0]) <= 180) and np.all(np.abs(points[:, 1]) <= 90))
        hint = ("the coordinates look like lon/lat degrees: remove the crs declaration (GeoJSON is lon/lat) "
                "or set crs = \"OGC:CRS84\"" if looks_geographic else
                "set crs in the scene's [footprints] table to the CRS the data is really in")
        raise FootprintError(
            f"the data centre ({centre[0]:.6g}, {centre[1]:.6g}) lies outside the area of use of "
            f"{crs.to_string()} ({crs.name}: lon {area.west:g}..{area.east:g}, lat {area.south:g}..{area.north:g})",
            where=where, hint=hint + " (or crs_check = false to accept it)")


def make_frame(crs: CRS | None, points: np.ndarray, origin: tuple[float, float] | None, where: str,
               check: bool = True) -> LocalFrame:
    """The local frame for data ``points`` (``(n, 2)`` in ``crs``), centred on ``origin`` or the data's bbox.

    ``crs`` None means unknown metric coordinates (only translated, recorded with an empty CRS).
    Raises FootprintError when the coordinates cannot be in ``crs`` (and ``check`` is on).
    """
    points = np.asarray(points, dtype=float).reshape(-1, 2)
    if origin is not None:
        centre = np.asarray(origin, dtype=float)
    elif len(points):  # the bbox centre, rounded to whole units (metres, or 1e-7 degrees below)
        centre = (points.min(axis=0) + points.max(axis=0)) / 2
        centre = centre.round(7) if crs is not None and _horizontal(crs).is_geographic else centre.round()
    else:
        centre = np.zeros(2)
    x0, y0 = float(centre[0]), float(centre[1])
    if crs is None:
        return LocalFrame(GeoReference("", (x0, y0)), None, (x0, y0))
    horizontal = _horizontal(crs)
    if check and len(points):
        if horizontal.is_geographic:
            _check_geographic(points, crs.to_string(), where)
        else:
            _check_projected(crs, points, where)
    if _is_metric_projected(crs):
        return LocalFrame(GeoReference(crs.to_string(), (x0, y0)), None, (x0, y0))
    if horizontal.is_geographic:
        lon, lat = x0, y0
    else:  # projected in feet or other units: a tmerc around the centre's lon/lat
        to_geo = Transformer.from_crs(horizontal, horizontal.geodetic_crs, always_xy=True)
        lon, lat = (round(float(v), 7) for v in to_geo.transform(x0, y0))
    proj = _tmerc_proj(crs, lon, lat)
    forward = Transformer.from_crs(horizontal, CRS.from_proj4(proj), always_xy=True)
    return LocalFrame(GeoReference(crs.to_string(), (x0, y0), proj), forward)


def frame_from_georef(georef: GeoReference) -> LocalFrame:
    """The frame a GeoReference describes, e.g. to map local coordinates back to the source CRS."""
    if not georef.proj:
        return LocalFrame(georef, None, georef.origin)
    source = _horizontal(CRS.from_user_input(georef.crs))
    return LocalFrame(georef, Transformer.from_crs(source, CRS.from_proj4(georef.proj), always_xy=True))
