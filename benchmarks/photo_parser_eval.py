"""The learned facade parser's pixel accuracy on held-out CMP photos (cmp_b0001-0040, never trained on).

    python benchmarks/photo_parser_eval.py [DATA_DIR] [--model MODEL.npz ...] [--first 1 --last 40 | --photos N ...]

Each photo is cropped to its annotated facade box and parsed; the predicted label (argmax) of every working pixel
is compared with the label map there: per-class recall (pixel accuracy of the class), window pixel precision and
recall, overall accuracy, CPU seconds per photo (process_time). Choices are made on the validation split
(``--first 261 --last 300`` with a model trained by ``--validate``), never on the held-out photos.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from citygen_photo.labels import CMP_LABELS
from citygen_photo.parser import load_labels, load_parser
from citygen_photo.train import _resized_labels

DEFAULT = Path(__file__).resolve().parents[1] / ".." / "shared" / "data" / "cmp_facade" / "base"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", type=Path, default=DEFAULT)
    parser.add_argument("--model", type=Path, nargs="+", default=[],
                        help="the parser's weights, several for their ensemble (default: the shipped parser)")
    parser.add_argument("--first", type=int, default=1)
    parser.add_argument("--last", type=int, default=40)
    parser.add_argument("--photos", type=int, nargs="+", default=[],
                        help="photo numbers instead of --first..--last (e.g. round 2's balcony fold)")
    args = parser.parse_args(argv)
    model = load_parser(*args.model)
    n = len(CMP_LABELS)
    confusion = np.zeros((n, n), dtype=np.int64)
    cpu = []
    for k in args.photos or range(args.first, args.last + 1):
        jpg = args.data / f"cmp_b{k:04d}.jpg"
        if not jpg.exists():
            continue
        rgb, labels = load_labels(jpg)
        t0 = time.process_time()
        prob = model.probabilities(rgb)
        cpu.append(time.process_time() - t0)
        truth = _resized_labels(labels, prob.shape[:2]).ravel() - 1
        confusion += np.bincount(truth * n + prob.argmax(axis=-1).ravel(), minlength=n * n).reshape(n, n)
    if not cpu:
        print(f"no CMP photos of those numbers in {args.data}", file=sys.stderr)
        return 2
    recall = confusion.diagonal() / np.maximum(confusion.sum(axis=1), 1)
    precision = confusion.diagonal() / np.maximum(confusion.sum(axis=0), 1)
    print(f"{len(cpu)} photos, overall pixel accuracy {confusion.trace() / confusion.sum():.3f}, "
          f"CPU per photo median {np.median(cpu):.3f} s, max {max(cpu):.3f} s")
    print(f"{'label':<12}{'pixels':>10}{'recall':>9}{'precision':>11}")
    for i, name in enumerate(CMP_LABELS):
        print(f"{name:<12}{confusion[i].sum():>10}{recall[i]:>9.3f}{precision[i]:>11.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
