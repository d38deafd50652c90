"""The studio's inverse tools: a dropped facade photo (mueller2007) or FacadeLayout JSON as a layout, and a split
grammar extracted from it (wu2014), through the inverse plugin's own functions."""
from __future__ import annotations

import io
import json
import tempfile
from pathlib import Path
from typing import Any

from citygen.errors import CitygenError, LayoutError, SourceLocation
from citygen.layout import FacadeLayout, check_partition
from citygen_studio.confinement import MAX_UPLOAD, StudioError
from citygen_studio.session import layout_data

#: Extraction methods the studio offers (``exact`` runs an integer program: use the command line).
METHODS = ("greedy", "is", "adp")
MAX_ITERATIONS = 5000


def import_layout(name: str, data: bytes, width: float | None = None, floor_height: float = 3.0,
                  label_map: bytes | None = None) -> dict[str, Any]:
    """A dropped file as a layout: ``*.json`` a FacadeLayout, ``*.xml`` a CMP annotation (with ``label_map``, the
    PNG beside it in the CMP database, for its proportions), anything else a rectified facade photo."""
    if len(data) + len(label_map or b"") > MAX_UPLOAD:
        raise StudioError(f"{name} is larger than {MAX_UPLOAD // 2**20} MiB", 413)
    for key, value in (("width", width), ("floor_height", floor_height)):
        if value is not None and (not isinstance(value, (int, float)) or not 0 < value <= 1000):
            raise StudioError(f"{key} must be more than 0 and at most 1000 m, got {value!r}")
    try:
        if name.lower().endswith(".json"):
            layout = FacadeLayout.loads(data.decode("utf-8", errors="replace"), name)
            summary = f"{name}: {len(layout.terminals())} terminals, {layout.width:.2f} x {layout.height:.2f} m"
        elif name.lower().endswith(".xml"):
            layout = _cmp(data, label_map, width, floor_height)
            summary = (f"{name}: {len(layout.terminals())} terminals, {layout.width:.2f} x {layout.height:.2f} m"
                       + ("" if label_map else " (no label map: proportions assumed square)"))
        else:
            from citygen_photo.learned import analyse_learned
            from citygen_photo.photo import load_photo
            layout = analyse_learned(load_photo(io.BytesIO(data)), name, width=width, floor_height=floor_height,
                                     meta={"source": name}).layout
            summary = (f"{name}: {layout.meta['floors']} floors x {layout.meta['tiles_per_floor']} tiles, "
                       f"{layout.count('window')} windows, {layout.count('door')} doors, "
                       f"{layout.width:.2f} x {layout.height:.2f} m")
    except CitygenError as exc:  # (the file is read from memory or a private folder: name the dropped file)
        where = exc.where
        place = f"{name}:{where.line}:{where.column}" if isinstance(where, SourceLocation) and where.line else name
        raise StudioError(f"{place}: {exc.message}", hint=exc.hint) from None
    return {"layout": layout.to_json(), "drawing": layout_data(layout), "summary": summary}


def _cmp(xml: bytes, label_map: bytes | None, width: float | None, floor_height: float) -> FacadeLayout:
    """A CMP annotation through ``citygen layout import-cmp``'s importer, its files in a private folder."""
    from citygen_inverse.cmp import import_cmp

    with tempfile.TemporaryDirectory(prefix="citygen-studio-") as folder:
        path = Path(folder) / "annotation.xml"
        path.write_bytes(xml)
        if label_map is not None:
            path.with_suffix(".png").write_bytes(label_map)
        return import_cmp(path, width=width, floor_height=floor_height)


def extract(layout: Any, method: str, iterations: int, seed: int = 0) -> dict[str, Any]:
    """A split grammar for a layout (its JSON form): the exact one and the size-independent one, cost and rules."""
    from citygen_inverse.extract import extract_grammar

    if method not in METHODS:
        raise StudioError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    if not isinstance(iterations, int) or not 1 <= iterations <= MAX_ITERATIONS:
        raise StudioError(f"iterations must be 1 to {MAX_ITERATIONS}, got {iterations!r}")
    if not isinstance(seed, int) or seed < 0:
        raise StudioError(f"seed must be a whole number, got {seed!r}")
    if not isinstance(layout, dict):
        raise StudioError("layout must be a FacadeLayout JSON object")
    parsed = FacadeLayout.loads(json.dumps(layout), "dropped layout")
    problems = check_partition(parsed)
    if problems:
        raise LayoutError("not a partition: " + "; ".join(problems[:3]),
                          hint="grammar extraction needs terminals that tile the facade exactly")
    result = extract_grammar([parsed], method, iterations, seed)
    return {"text": result.text, "size_independent": result.size_independent, "cost": result.cost,
            "rules": result.rules, "seconds": result.seconds}
