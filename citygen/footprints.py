"""Footprints: building outlines in a local metric frame, as importers hand them to the pipeline."""
from __future__ import annotations

from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from typing import Any

from shapely.geometry import MultiPolygon, Polygon


@dataclass(frozen=True)
class GeoReference:
    """How the local frame maps to the source CRS: local (0, 0) is ``origin`` in ``crs``.

    For geographic input (lon/lat) the importer projects to a transverse Mercator frame centred on the data;
    ``proj`` holds that projection's PROJ string so the mapping can be inverted exactly.
    """

    crs: str
    origin: tuple[float, float]
    proj: str = ""

    def to_dict(self) -> dict[str, Any]:
        return {"crs": self.crs, "origin": list(self.origin), "proj": self.proj}


@dataclass(frozen=True)
class Footprint:
    """One building's outline and attributes.

    ``polygon`` is valid, oriented (exterior counter-clockwise, holes clockwise) and in metres in the local frame.
    ``height`` is the height the data give in metres and ``height_source`` says where it came from
    (``"height"``, ``"measuredHeight"``, ``"building:levels"``, ``"default"``, ...): the building's total height,
    roof included, when ``height_is_total`` (OSM ``height``, CityJSON ``measuredHeight``, a scene default), else the
    walls' height (level counts; the roof goes on top). The pipeline splits it into walls and roof
    (:mod:`citygen.roofplan`). ``levels`` is the number of above-ground floors below the roof when known from the
    data, else ``None``; ``base`` is the elevation of the wall's foot:
    the ground, plus ``lift`` for a building (part) that starts above it (OSM ``min_height`` /
    ``building:min_level``: an upper part of a Simple 3D Buildings model, a bridge building), whose foot is not at
    street level.
    """

    id: str
    polygon: Polygon | MultiPolygon
    height: float
    height_source: str
    levels: int | None = None
    base: float = 0.0
    attributes: Mapping[str, Any] = field(default_factory=dict)
    source: str = ""
    lift: float = 0.0
    height_is_total: bool = False


@dataclass(frozen=True)
class Skipped:
    """A feature that could not become a building: its id, where it was, and why (with what to do)."""

    id: str
    reason: str
    where: str = ""


@dataclass(frozen=True)
class ImportResult:
    """What an importer read: the good footprints, the skipped features, warnings, and the frame's reference."""

    footprints: tuple[Footprint, ...]
    skipped: tuple[Skipped, ...] = ()
    warnings: tuple[str, ...] = ()
    georef: GeoReference | None = None


@dataclass(frozen=True)
class FootprintStream:
    """What an importer reads, handed over footprint by footprint: ``footprints`` is iterated once, in the order an
    :class:`ImportResult` would hold them; the features it skips and the warnings it meets are appended to
    ``skipped`` (in file order once it is used up) and ``warnings`` as it goes. ``georef`` is known from the start
    (an importer that streams reads its file twice: first what fixes the frame and the ids, then the footprints)."""

    footprints: Iterator[Footprint]
    skipped: list[Skipped]
    warnings: list[str]
    georef: GeoReference | None = None

    @classmethod
    def of(cls, result: ImportResult) -> FootprintStream:
        """A whole import handed over as a stream (an importer that cannot stream its format)."""
        return cls(iter(result.footprints), list(result.skipped), list(result.warnings), result.georef)

    def collected(self) -> ImportResult:
        """The whole import: every footprint in memory at once."""
        footprints = tuple(self.footprints)
        return ImportResult(footprints, tuple(self.skipped), tuple(self.warnings), self.georef)
