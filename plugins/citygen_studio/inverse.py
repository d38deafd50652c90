"""The studio's inverse tools: a dropped facade photo (mueller2007) or FacadeLayout JSON as a layout, and a split
grammar extracted from it (wu2014), through the inverse plugin's own functions."""
from __future__ import annotations

import io
import json
import math
import tempfile
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any

from citygen.errors import CitygenError, LayoutError, SourceLocation
from citygen.layout import FacadeLayout, check_partition
from citygen_photo import PARSERS
from citygen_studio.confinement import MAX_UPLOAD, StudioError
from citygen_studio.session import layout_data

#: Extraction methods the studio offers (``exact`` runs an integer program: use the command line).
METHODS = ("greedy", "is", "adp")
MAX_ITERATIONS = 5000


@dataclass(frozen=True)
class ImportOptions:
    """How a dropped file is read, as the command line reads it: a CMP annotation's regularisation tolerances
    (shares of the facade size; ``citygen layout import-cmp --snap --align --equal-sizes``, ``--no-element-caps``
    as ``element_caps=False``, ``--drop-degenerate``) and a photo's crop box (pixels, y down) and facade parser
    (``citygen layout from-photo --crop --parser``)."""

    snap: float = 0.01
    align: float = 0.025
    equal_sizes: float = 0.03
    element_caps: bool = True
    drop_degenerate: bool = False
    crop: tuple[float, float, float, float] | None = None
    parser: str = "learned"

    def __post_init__(self) -> None:
        for name in ("snap", "align", "equal_sizes"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 <= value < 0.5:
                raise StudioError(f"{name} must be a share of the facade size in [0, 0.5), got {value!r}")
        for name in ("element_caps", "drop_degenerate"):
            if not isinstance(getattr(self, name), bool):
                raise StudioError(f"{name} must be true or false, got {getattr(self, name)!r}")
        if self.crop is not None and (len(self.crop) != 4 or not all(
                isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v) for v in self.crop)):
            raise StudioError(f"crop must be four pixel numbers x0, y0, x1, y1 (y down), got {self.crop!r}")
        if self.parser not in PARSERS:
            raise StudioError(f"parser must be one of {', '.join(PARSERS)}, got {self.parser!r}")

    @classmethod
    def from_json(cls, data: Any) -> ImportOptions:
        """Options from the browser's JSON object (absent keys take the command line's defaults)."""
        if data is None:
            return cls()
        if not isinstance(data, dict):
            raise StudioError("options must be a JSON object")
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise StudioError(f"unknown import option(s) {', '.join(unknown)}",
                              hint=f"known: {', '.join(sorted(known))}")
        crop = data.get("crop")
        return cls(**{**data, "crop": tuple(crop) if isinstance(crop, list) else crop})


def import_layout(name: str, data: bytes, width: float | None = None, floor_height: float = 3.0,
                  label_map: bytes | None = None, options: ImportOptions = ImportOptions()) -> dict[str, Any]:
    """A dropped file as a layout: ``*.json`` a FacadeLayout, ``*.xml`` a CMP annotation (with ``label_map``, the
    PNG beside it in the CMP database, for its proportions), anything else a rectified facade photo; ``options``
    as the command line's."""
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
            layout = _cmp(data, label_map, width, floor_height, options)
            summary = (f"{name}: {len(layout.terminals())} terminals, {layout.width:.2f} x {layout.height:.2f} m"
                       + ("" if label_map else " (no label map: proportions assumed square)")
                       + f"; snap {options.snap:g}, align {options.align:g}, equal sizes {options.equal_sizes:g}"
                       + ("" if options.element_caps else ", no element caps"))
        else:
            layout = _photo(data, name, width, floor_height, options)
            summary = (f"{name}: {layout.meta['floors']} floors x {layout.meta['tiles_per_floor']} tiles, "
                       f"{layout.count('window')} windows, {layout.count('door')} doors, "
                       f"{layout.width:.2f} x {layout.height:.2f} m ({options.parser} parser"
                       + (", crop {:g} {:g} {:g} {:g}".format(*options.crop) if options.crop else "") + ")")
    except CitygenError as exc:  # (the file is read from memory or a private folder: name the dropped file)
        where = exc.where
        place = f"{name}:{where.line}:{where.column}" if isinstance(where, SourceLocation) and where.line else name
        raise StudioError(f"{place}: {exc.message}", hint=exc.hint) from None
    return {"layout": layout.to_json(), "drawing": layout_data(layout), "summary": summary}


def _photo(data: bytes, name: str, width: float | None, floor_height: float, options: ImportOptions) -> FacadeLayout:
    """A rectified facade photo through ``citygen layout from-photo``'s analysis (its crop and parser)."""
    from citygen_photo.photo import analyse, load_photo

    rgb = load_photo(io.BytesIO(data), options.crop)
    meta = {"source": name, "image_crop": list(options.crop) if options.crop else None}
    if options.parser == "learned":
        from citygen_photo.learned import analyse_learned
        return analyse_learned(rgb, name, width=width, floor_height=floor_height, meta=meta).layout
    return analyse(rgb, name, width=width, floor_height=floor_height, meta=meta).layout


def _cmp(xml: bytes, label_map: bytes | None, width: float | None, floor_height: float,
         options: ImportOptions) -> FacadeLayout:
    """A CMP annotation through ``citygen layout import-cmp``'s importer, its files in a private folder."""
    from citygen_inverse.cmp import ELEMENT_SHARE, import_cmp
    from citygen_inverse.commands import check_degenerate

    with tempfile.TemporaryDirectory(prefix="citygen-studio-") as folder:
        path = Path(folder) / "annotation.xml"
        path.write_bytes(xml)
        if label_map is not None:
            path.with_suffix(".png").write_bytes(label_map)
        if not options.drop_degenerate:
            check_degenerate(str(path))
        return import_cmp(path, width=width, floor_height=floor_height, snap=options.snap, align=options.align,
                          regularize=options.equal_sizes, element_share=ELEMENT_SHARE if options.element_caps else None)


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
