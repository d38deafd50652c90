"""Evaluate ``citygen layout from-photo`` (mueller2007) on the CMP facade photos against their annotations.

    python benchmarks/photo_eval.py [DATA_DIR] [--first 1 --last 40 | --photos N ...] [--parser learned|contrast]
        [--model M.npz ...] [--darker-than LUM] [--annotated-labels]

DATA_DIR defaults to ../shared/data/cmp_facade/base beside the checkout. Each photo is cropped to its annotated
facade box; detected floors are compared with the annotated rows of windows (their count, which also counts floors
without windows such as a shop ground floor or an attic, and whether every row of windows lies in a floor of its
own; and with the annotated floors: the rows plus a ground floor of doors or shops below them), tiles with the
columns of windows,
detected windows and doors with annotated ones (one-to-one, box IoU >= 0.5); windows both as the reported element
boxes and as the window terminals of the FacadeLayout (what ``citygen layout from-photo`` writes); the layout's
window pixels against the label map's, with the annotated labels under them, and the annotated windows a floor
line crosses. The summary
is given for the development half (cmp_b0001-0020, the only photos to tune on), the held-out half
(cmp_b0021-0040) and all. Timings are CPU seconds (process_time). The learned parser is trained on
cmp_b0061-0300, so for it all of cmp_b0001-0040 is held out: its choices are made on cmp_b0261-0300
(``--first 261 --last 300``) with models trained by ``python -m citygen_photo.train --validate -o M.npz`` and
``python -m citygen_photo.train_fcn --validate -o F.npz`` (``--model M.npz F.npz``: their mean, as shipped).
``--darker-than 0.45`` keeps the photos whose facade crop is darker than that on average: the validation subset
matched to the held-out photos by a label-free property (docs/photo.md, round 10). ``--annotated-labels`` runs
the learned path's structure on each photo's annotated label map instead of the parser's output: the figures a
parser without mistakes would reach, which separates the structure's errors from the parser's (round 14).
Annotated boxes whose centre lies outside the facade crop are not counted (the analysis never sees them).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from citygen.errors import CitygenError
from citygen_inverse.cmp import import_cmp
from citygen_inverse.extract import extract_grammar
from citygen_photo.labels import CMP_LABELS
from citygen_photo.learned import analyse_learned
from citygen_photo.features import working_shape
from citygen_photo.parser import load_parser
from citygen_photo import PARSERS
from citygen_photo.photo import analyse, load_photo, luminance
from citygen_inverse.cmp import count_groups
from citygen_photo.score import cmp_boxes, facade_box, layout_boxes, matches
from citygen_photo.train import _resized_labels

#: Development photos (cmp_b0001-0020): tune only on these; cmp_b0021-0040 are held out.
DEV = range(1, 21)
DEFAULT = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "cmp_facade" / "base"


def facade_crop(jpg: Path) -> tuple[tuple[int, int, int, int], dict]:
    """The photo's crop to its annotated facade box (x0, y0, x1, y1 pixels) and its annotated boxes."""
    from PIL import Image
    with Image.open(jpg) as image:
        size = image.size
    boxes = cmp_boxes(jpg.with_suffix(".xml"), size)
    fx0, fy0, fx1, fy1 = facade_box(boxes)
    return (round(fx0), round(fy0), round(fx1), round(fy1)), boxes


def in_crop(boxes: list[tuple[float, ...]], crop: tuple[int, int, int, int]) -> list[tuple[float, ...]]:
    """The annotated ``boxes`` whose centre lies in the facade ``crop``, in crop pixels: the analysis sees the crop
    alone, and CMP annotates some windows, doors and shops of the neighbours or the street beyond the facade box
    (until round 14 they were counted: a row above the crop or shops below it as floors the layout could not have)."""
    x0, y0, x1, y1 = crop
    return [(a - x0, b - y0, c - x0, d - y0) for a, b, c, d in boxes
            if x0 <= (a + c) / 2 < x1 and y0 <= (b + d) / 2 < y1]


def crop_luminance(jpg: Path) -> float:
    """The mean luminance (0..1) of the photo's facade crop: a label-free property that matches validation photos
    to the held-out kind (30 of the 40 held-out crops are darker than 0.45, 18 of the 56 validation and fold ones;
    docs/photo.md, round 10)."""
    return float(luminance(load_photo(jpg, facade_crop(jpg)[0])).mean())


class AnnotatedLabels:
    """The photo's own label map as the learned parser's probabilities (``--annotated-labels``): the structure's
    ceiling, what the layout would be with a parser that made no mistake. Each pixel gets ``1 - SOFT`` more of its
    annotated label than of the others (a one-hot map leaves the structure's probability thresholds no margin)."""

    SOFT = 0.2

    def __init__(self, jpg: Path, crop: tuple[int, int, int, int]):
        from PIL import Image
        with Image.open(jpg.with_suffix(".png")) as image:
            self.labels = np.asarray(image)[crop[1]:crop[3], crop[0]:crop[2]]

    def probabilities(self, rgb: np.ndarray) -> np.ndarray:
        shape = working_shape(*rgb.shape[:2])
        label = _resized_labels(self.labels, shape).astype(int) - 1
        prob = np.full((*shape, len(CMP_LABELS)), self.SOFT / len(CMP_LABELS))
        np.put_along_axis(prob, label[..., None], 1 - self.SOFT + self.SOFT / len(CMP_LABELS), axis=-1)
        return prob


def evaluate(jpg: Path, parser: str = "learned", model=None, annotated: bool = False) -> dict:
    crop, boxes = facade_crop(jpg)
    if annotated:
        parser, model = "learned", AnnotatedLabels(jpg, crop)
    ref, doors, shops = (in_crop(boxes.get(name, []), crop) for name in ("window", "door", "shop"))
    row = {"photo": jpg.stem, "rows": count_groups([(b[1], b[3]) for b in ref]),
           "cols": count_groups([(b[0], b[2]) for b in ref]), "ref": len(ref), "door_ref": len(doors)}
    row["storeys"] = row["rows"] + ground_without_windows(ref, [*doors, *shops])
    start = time.process_time()
    try:
        image = load_photo(jpg, crop)
        result = analyse_learned(image, str(jpg), meta={"source": jpg.name}, model=model) if parser == "learned" \
            else analyse(image, str(jpg), meta={"source": jpg.name})
    except CitygenError as exc:
        return {**row, "error": exc.message, "cpu": time.process_time() - start}
    pred = result.boxes("window")
    tp = matches(pred, ref)
    terminals = layout_boxes(result.layout)
    door_pred = result.boxes("door")
    return {**row, "floors": len(result.floor_lines) - 1, "rows_ok": rows_in_floors(result.floor_lines, ref),
            "cut": windows_cut(result.floor_lines, ref),
            "tiles": len(result.tile_lines) - 1, "pred": len(pred),
            "tp": tp, "lay_pred": len(terminals), "lay_tp": matches(terminals, ref), "door_pred": len(door_pred),
            "door_tp": matches(door_pred, doors), "cpu": time.process_time() - start,
            "size": (crop[2] - crop[0], crop[3] - crop[1]), **grammar_costs(jpg, result.layout),
            **window_pixels(jpg, crop, result.layout)}


def window_pixels(jpg: Path, crop: tuple[int, int, int, int], layout) -> dict:
    """Pixel counts of the layout's window terminals against the label map's window pixels in the crop, and the
    annotated labels under the layout's window pixels (``px_labels``, by CMP label id; 0: unlabelled)."""
    from PIL import Image
    with Image.open(jpg.with_suffix(".png")) as image:
        labels = np.asarray(image)[crop[1]:crop[3], crop[0]:crop[2]]
    truth = labels == 3  # CMP label 3: window
    mine = np.zeros_like(truth)
    s = layout.meta["metres_per_pixel"]
    H = truth.shape[0]
    for r in layout.leaves:
        if r.label == "window":
            mine[max(round(H - (r.y + r.h) / s), 0):round(H - r.y / s), round(r.x / s):round((r.x + r.w) / s)] = True
    return {"px_tp": int((mine & truth).sum()), "px_pred": int(mine.sum()), "px_ref": int(truth.sum()),
            "px_labels": np.bincount(labels[mine].ravel(), minlength=13)[:13]}


def grammar_costs(jpg: Path, layout) -> dict:
    """wu2014 greedy grammar costs of the photo's layout and of its annotation at the same width."""
    try:
        annotated = import_cmp(jpg.with_suffix(".xml"), width=layout.width)
    except CitygenError:
        return {}
    return {"cost": extract_grammar(layout, method="greedy").cost,
            "cost_ref": extract_grammar(annotated, method="greedy").cost}


def ground_without_windows(windows: list[tuple[float, ...]], ground: list[tuple[float, ...]]) -> int:
    """1 when the annotation has a floor below its rows of windows: a door or shop below the middle of the lowest
    window that no window's height range overlaps (a shop or entrance ground floor is a floor of the layout without
    a row of windows; a door beside ground-floor windows is in their floor)."""
    if not windows:
        return 0
    lowest = max((b[1] + b[3]) / 2 for b in windows)
    return int(any((b[1] + b[3]) / 2 > lowest and all(w[3] <= b[1] or w[1] >= b[3] for w in windows)
                   for b in ground))


def windows_cut(floor_lines: list[float], ref: list[tuple[float, ...]]) -> int:
    """How many annotated windows a floor line crosses (inside the window by more than a tenth of its height)."""
    return sum(any(b[1] + 0.1 * (b[3] - b[1]) < y < b[3] - 0.1 * (b[3] - b[1]) for y in floor_lines) for b in ref)


def rows_in_floors(floor_lines: list[float], ref: list[tuple[float, ...]]) -> int:
    """How many rows of annotated windows (groups of overlapping y intervals) have every window centre in one
    floor band (between consecutive ``floor_lines``) that no other row's windows reach."""
    lines = np.sort(np.asarray(floor_lines, dtype=float))
    rows: list[list[tuple[float, ...]]] = []
    end = -np.inf
    for box in sorted(ref, key=lambda b: b[1]):
        if box[1] >= end:
            rows.append([])
        rows[-1].append(box)
        end = box[3] if box[1] >= end else max(end, box[3])
    bands = [{int(np.searchsorted(lines, (b[1] + b[3]) / 2)) for b in row} for row in rows]
    return sum(len(mine) == 1 and all(not mine & other for other in bands if other is not mine) for mine in bands)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", default=str(DEFAULT))
    parser.add_argument("--first", type=int, default=1)
    parser.add_argument("--last", type=int, default=40)
    parser.add_argument("--photos", type=int, nargs="+", default=[],
                        help="photo numbers instead of --first..--last (e.g. round 2's balcony fold)")
    parser.add_argument("--darker-than", type=float, default=None, metavar="LUM",
                        help="only the photos whose facade crop's mean luminance (0..1) is under LUM: the held-out "
                             "kind (round 10's validation subset: 0.45)")
    parser.add_argument("--parser", choices=PARSERS, default="learned",
                        help="learned (default): the trained parser; contrast: mueller2007's contrast test")
    parser.add_argument("--model", type=Path, nargs="+", default=[],
                        help="the learned parser's weights, several for their ensemble (default: the shipped parser)")
    parser.add_argument("--annotated-labels", action="store_true",
                        help="the learned path's structure on each photo's annotated label map instead of the "
                             "parser's probabilities: the layout a parser without mistakes would give")
    args = parser.parse_args(argv)
    data = Path(args.data)
    model = load_parser(*args.model) if args.model else None
    photos = [data / f"cmp_b{i:04d}.jpg" for i in (args.photos or range(args.first, args.last + 1))]
    photos = [p for p in photos if p.is_file()]
    if args.darker_than is not None:
        photos = [p for p in photos if crop_luminance(p) < args.darker_than]
    if not photos:
        print(f"error: no cmp_b*.jpg photos in {data}", file=sys.stderr)
        return 2
    print(f"{'photo':10} {'crop':>9} {'rows':>4} {'ann':>3} {'floors':>6} {'ok':>3} {'cols':>4} {'tiles':>5} {'ref':>4} "
          f"{'pred':>4} "
          f"{'tp':>4} {'prec':>5} {'rec':>5} {'lay':>4} {'ltp':>4} {'doors':>5} {'pred':>4} {'tp':>3} {'cpu s':>6}")
    rows = []
    for jpg in photos:
        r = evaluate(jpg, args.parser, model, args.annotated_labels)
        rows.append(r)
        if "error" in r:
            print(f"{r['photo']:10} {'':>9} {r['rows']:4d} {r['storeys']:3d} {'-':>6} {r['cols']:4d} {'-':>5} {r['ref']:4d} "
                  f"error: {r['error']}")
            continue
        prec = r["tp"] / r["pred"] if r["pred"] else 0.0
        rec = r["tp"] / r["ref"] if r["ref"] else 0.0
        print(f"{r['photo']:10} {r['size'][0]:4d}x{r['size'][1]:<4d} {r['rows']:4d} {r['storeys']:3d} {r['floors']:6d} {r['rows_ok']:3d} "
              f"{r['cols']:4d} "
              f"{r['tiles']:5d} {r['ref']:4d} {r['pred']:4d} {r['tp']:4d} {prec:5.2f} {rec:5.2f} {r['lay_pred']:4d} "
              f"{r['lay_tp']:4d} {r['door_ref']:5d} "
              f"{r['door_pred']:4d} {r['door_tp']:3d} {r['cpu']:6.2f}")
    for name, part in split(rows):
        summary(name, part)
    return 0


def split(rows: list[dict]) -> list[tuple[str, list[dict]]]:
    """The development photos (``DEV``, the only ones parameters may be tuned on), the held-out rest, and all."""
    dev = [r for r in rows if int(r["photo"][5:]) in DEV]
    held = [r for r in rows if int(r["photo"][5:]) not in DEV]
    parts = [(f"development (cmp_b{DEV.start:04d}-{DEV.stop - 1:04d})", dev), ("held-out", held), ("total", rows)]
    return [(name, part) for name, part in parts if part]


def summary(name: str, rows: list[dict]) -> None:
    ok = [r for r in rows if "error" not in r]
    tp, pred, ref = (sum(r[k] for r in ok) for k in ("tp", "pred", "ref"))
    ref_all = sum(r["ref"] for r in rows)
    cpu = sorted(r["cpu"] for r in rows)
    print(f"\n== {name}: photos {len(rows)}, analysed {len(ok)}, refused (no repetition) {len(rows) - len(ok)}")
    print(f"floors == window rows: {sum(r['floors'] == r['rows'] for r in ok)}/{len(ok)}, within 1: "
          f"{sum(abs(r['floors'] - r['rows']) <= 1 for r in ok)}/{len(ok)}")
    right = [r for r in ok if r["floors"] == r["storeys"] and r["rows_ok"] == r["rows"]]
    print(f"floors == annotated floors (rows of windows + a ground floor of doors / shops below them) with every "
          f"row of windows in a floor of its own: {len(right)}/{len(ok)}; count alone "
          f"{sum(r['floors'] == r['storeys'] for r in ok)}/{len(ok)}")
    print(f"window rows each in a floor of its own: all rows on {sum(r['rows_ok'] == r['rows'] for r in ok)}/"
          f"{len(ok)} photos, {sum(r['rows_ok'] for r in ok)}/{sum(r['rows'] for r in ok)} rows")
    print(f"tiles == window columns: {sum(r['tiles'] == r['cols'] for r in ok)}/{len(ok)}, within 1: "
          f"{sum(abs(r['tiles'] - r['cols']) <= 1 for r in ok)}/{len(ok)}")
    print(f"windows (IoU >= 0.5): precision {tp / max(pred, 1):.3f} ({tp}/{pred}), recall {tp / max(ref, 1):.3f} "
          f"({tp}/{ref}) on analysed photos, {tp / max(ref_all, 1):.3f} over all {ref_all} annotated windows; "
          f"photos without a matched window {sum(r['tp'] == 0 for r in ok)}")
    ltp, lpred = (sum(r[k] for r in ok) for k in ("lay_tp", "lay_pred"))
    print(f"layout window terminals (IoU >= 0.5): precision {ltp / max(lpred, 1):.3f} ({ltp}/{lpred}), recall "
          f"{ltp / max(ref, 1):.3f} ({ltp}/{ref}); photos without a matched terminal "
          f"{sum(r['lay_tp'] == 0 for r in ok)}")
    dtp, dpred, dref = (sum(r[k] for r in ok) for k in ("door_tp", "door_pred", "door_ref"))
    print(f"doors (IoU >= 0.5): precision {dtp / max(dpred, 1):.3f} ({dtp}/{dpred}), recall {dtp / max(dref, 1):.3f} "
          f"({dtp}/{dref}); photos with more detected than annotated doors "
          f"{sum(r['door_pred'] > r['door_ref'] for r in ok)}")
    print(f"cpu per photo: median {cpu[len(cpu) // 2]:.2f} s, max {cpu[-1]:.2f} s")
    ptp, ppred, pref = (sum(r.get(k, 0) for r in ok) for k in ("px_tp", "px_pred", "px_ref"))
    print(f"window pixels of the layout: precision {ptp / max(ppred, 1):.3f}, recall {ptp / max(pref, 1):.3f}")
    spread = sum(r["px_labels"] for r in ok if "px_labels" in r)
    if ppred:
        print("their annotated labels: " + ", ".join(f"{name} {n / ppred:.3f}" for name, n in
                                                      zip(("unlabelled", *CMP_LABELS), spread) if n))
    print(f"annotated windows cut by a floor line: {sum(r['cut'] for r in ok)}/{ref}")
    costed = [r for r in ok if "cost" in r]
    if costed:
        ratio = np.array([r["cost"] / max(r["cost_ref"], 1e-9) for r in costed])
        print(f"greedy grammar cost, photo layout / annotation: median {np.median(ratio):.2f}, mean "
              f"{ratio.mean():.2f}, within 1.3x on {int((ratio <= 1.3).sum())}/{len(costed)} photos")
    return 0


if __name__ == "__main__":
    sys.exit(main())
