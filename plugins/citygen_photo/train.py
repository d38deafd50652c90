"""Train the learned facade parser on CMP photos: ``python -m citygen_photo.train [DATA] [-o MODEL.npz]``.

Needs scikit-learn (``pip install -e '.[photo-train]'``); the shipped model (``model/facade_parser.npz``) was made
by this script with its defaults, so the result is reproducible from the seed on the same photos. Photos
cmp_b0061-0300 train; cmp_b0001-0040 are kept for evaluation (``benchmarks/photo_eval.py``) and never seen here.

Each photo is cropped to its annotated facade box, reduced to the working size (:mod:`citygen_photo.features`),
and ``--samples`` pixels are drawn per photo (rare labels drawn more often; ``--dark FACTOR``: FACTOR times as
many from a photo whose crop is darker than 0.45 on average, the held-out kind). Stage 1 is a multilayer perceptron on
the pixel features; each further stage (``--stages``, auto-context) another one on the same features plus the
previous stage's label probabilities around the pixel (:func:`citygen_photo.parser.context_features`). All are
exported as plain weight arrays, with the ratio of each label's share of the photos to its share of the drawn
pixels (``prior``), by which inference turns the last stage's output back into probabilities under the photos'
own label frequencies; inference (:mod:`citygen_photo.parser`) needs numpy only. ``--validate`` trains on
cmp_b0061-0260 and reports the per-class pixel accuracy on cmp_b0261-0300, the split every choice is made on.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from citygen_photo.features import pixel_features, working_image
from citygen_photo.labels import CMP_LABELS
from citygen_photo.parser import MODEL_PATH, FacadeParser, Stage, load_labels, predict_stage, stage_input

#: The photos the shipped model is trained on; the last 40 of them are the validation split for choices.
TRAIN = range(61, 301)
VALIDATION = range(261, 301)
#: Defaults of the shipped model: pixels drawn per photo, auto-context stages, hidden layer sizes.
SAMPLES = 1500
STAGES = 2
HIDDEN = (64, 64)
DEFAULT_DATA = Path(__file__).resolve().parents[2] / ".." / "shared" / "data" / "cmp_facade" / "base"


def facade_examples(data: Path, numbers) -> list[tuple[np.ndarray, np.ndarray]]:
    """(features, labels) at working size for every photo of ``numbers`` in ``data`` (missing ones skipped)."""
    out = []
    for n in numbers:
        jpg = data / f"cmp_b{n:04d}.jpg"
        if not jpg.exists():
            continue
        rgb, labels = load_labels(jpg)
        work = working_image(rgb)
        lab = _resized_labels(labels, work.shape[:2])
        out.append((work, lab))
    return out


def _resized_labels(labels: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    rows = np.minimum((np.arange(shape[0]) + 0.5) * labels.shape[0] / shape[0], labels.shape[0] - 1).astype(int)
    cols = np.minimum((np.arange(shape[1]) + 0.5) * labels.shape[1] / shape[1], labels.shape[1] - 1).astype(int)
    return labels[np.ix_(rows, cols)]


def sample(lab: np.ndarray, count: int, rng: np.random.Generator) -> np.ndarray:
    """Flat indices of ``count`` pixels, each label's weight the square root of its share (rare labels more)."""
    flat = lab.ravel()
    share = np.bincount(flat, minlength=len(CMP_LABELS)) / flat.size
    weight = np.where(share > 0, 1 / np.sqrt(np.maximum(share, 1e-9)), 0)[flat]
    return rng.choice(flat.size, size=min(count, flat.size), replace=False, p=weight / weight.sum())


def fit(x: np.ndarray, y: np.ndarray, hidden: tuple[int, ...], seed: int) -> Stage:
    from sklearn.neural_network import MLPClassifier
    mean, std = x.mean(axis=0), x.std(axis=0) + 1e-6
    mlp = MLPClassifier(hidden_layer_sizes=hidden, alpha=1e-4, batch_size=512, learning_rate_init=2e-3,
                        max_iter=40, early_stopping=True, n_iter_no_change=4, random_state=seed)
    mlp.fit((x - mean) / std, y)
    full_w, full_b = mlp.coefs_[-1], mlp.intercepts_[-1]
    last_w = np.zeros((full_w.shape[0], len(CMP_LABELS)), dtype=np.float32)
    last_b = np.full(len(CMP_LABELS), -30.0, dtype=np.float32)  # labels never seen stay improbable
    if len(mlp.classes_) == 2:  # one logistic output: softmax of the logits (0, z) gives the same probabilities
        last_w[:, mlp.classes_[0]], last_b[mlp.classes_[0]] = 0.0, 0.0
        last_w[:, mlp.classes_[1]], last_b[mlp.classes_[1]] = full_w[:, 0], full_b[0]
    else:
        last_w[:, mlp.classes_] = full_w
        last_b[mlp.classes_] = full_b
    layers = [(w.astype(np.float32), b.astype(np.float32)) for w, b in zip(mlp.coefs_[:-1], mlp.intercepts_[:-1])]
    return Stage(mean.astype(np.float32), std.astype(np.float32), (*layers, (last_w, last_b)))


def train(photos: list[tuple[np.ndarray, np.ndarray]], samples: int, stages: int, hidden: tuple[int, ...],
          seed: int, draw: np.ndarray | None = None) -> FacadeParser:
    """The parser's ``stages`` perceptrons fitted in turn on ``samples`` pixels drawn per photo (the same pixels
    for every stage), and the prior that undoes the drawing's label weights; ``draw``: each photo's share of all
    the pixels drawn instead (sums to 1)."""
    rng = np.random.default_rng(seed)
    per_photo = [samples] * len(photos) if draw is None else np.round(draw * samples * len(photos)).astype(int)
    picks = [sample(lab, max(int(n), 1), rng) for (_, lab), n in zip(photos, per_photo)]
    y = np.concatenate([lab.ravel()[p] for (_, lab), p in zip(photos, picks)]) - 1
    fitted: list[Stage] = []
    previous: list[np.ndarray | None] = [None] * len(photos)
    t0 = time.process_time()
    for k in range(stages):
        rows = []
        for i, ((work, _), p) in enumerate(zip(photos, picks)):
            features = stage_input(pixel_features(work), previous[i])
            rows.append(features.reshape(-1, features.shape[-1])[p])
        fitted.append(fit(np.concatenate(rows), y, hidden, seed + k))
        if k + 1 < stages:
            previous = [predict_stage(fitted[-1], stage_input(pixel_features(work), prev))
                        for (work, _), prev in zip(photos, previous)]
        print(f"stage {k + 1}: {len(photos)} photos, {len(y)} pixels, {time.process_time() - t0:.0f} s cpu",
              file=sys.stderr)
    counts = sum(np.bincount(lab.ravel() - 1, minlength=len(CMP_LABELS)) for _, lab in photos)
    drawn = np.bincount(y, minlength=len(CMP_LABELS))
    prior = (counts / counts.sum()) / np.maximum(drawn / drawn.sum(), 1e-9)  # undoes the sampling's label weights
    return FacadeParser(tuple(fitted), prior.astype(np.float32))


def confusion(parser: FacadeParser, photos: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """``(12, 12)`` pixel counts, annotated label by predicted label (argmax), over ``photos`` at working size."""
    n = len(CMP_LABELS)
    out = np.zeros((n, n), dtype=np.int64)
    for work, lab in photos:
        predicted = parser.probabilities(work).argmax(axis=-1).ravel()
        out += np.bincount((lab.ravel() - 1) * n + predicted, minlength=n * n).reshape(n, n)
    return out


def report(matrix: np.ndarray) -> str:
    """Overall pixel accuracy and per-class recall / precision of a confusion matrix."""
    recall = matrix.diagonal() / np.maximum(matrix.sum(axis=1), 1)
    precision = matrix.diagonal() / np.maximum(matrix.sum(axis=0), 1)
    lines = [f"overall pixel accuracy {matrix.trace() / matrix.sum():.3f}",
             f"{'label':<12}{'pixels':>10}{'recall':>9}{'precision':>11}"]
    lines += [f"{name:<12}{matrix[i].sum():>10}{recall[i]:>9.3f}{precision[i]:>11.3f}"
              for i, name in enumerate(CMP_LABELS)]
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", type=Path, default=DEFAULT_DATA)
    parser.add_argument("-o", "--output", type=Path, default=MODEL_PATH)
    parser.add_argument("--samples", type=int, default=SAMPLES, help="pixels drawn per photo")
    parser.add_argument("--stages", type=int, default=STAGES, help="auto-context stages")
    parser.add_argument("--hidden", type=int, nargs="+", default=list(HIDDEN), help="hidden layer sizes")
    parser.add_argument("--per-kind", type=float, metavar="EVEN",
                        help="pixels per photo in proportion to the U-Net's per-kind draw weight with this EVEN "
                             "(citygen_photo.train_unet.draw_weights): balcony and blind photos give more")
    parser.add_argument("--dark", type=float, default=1.0, metavar="FACTOR",
                        help="FACTOR times the pixels per photo where its crop is darker than 0.45 mean luminance "
                             "(citygen_photo.train_unet.DARK, the held-out kind)")
    add_training_arguments(parser)
    args = parser.parse_args(argv)
    photos = training_photos(args)
    if not photos:
        return 2
    if args.dark <= 0:
        parser.error(f"--dark {args.dark}: a factor on the dark photos' pixels, > 0")
    model = train(photos, args.samples, args.stages, tuple(args.hidden), args.seed,
                  pixel_shares(photos, args.per_kind, args.dark))
    arrays = {"prior": model.prior}
    for k, stage in enumerate(model.stages, start=1):
        arrays.update(stage.arrays(f"s{k}"))
    return save(model, arrays, args)


def pixel_shares(photos: list[tuple[np.ndarray, np.ndarray]], per_kind: float | None,
                 dark: float) -> np.ndarray | None:
    """Each photo's share of the drawn pixels (:func:`train`'s ``draw``; None: the same for every photo): with
    ``per_kind`` the U-Net's per-kind draw weight with that EVEN, each photo darker than
    :data:`citygen_photo.train_unet.DARK` ``dark`` times its share."""
    if per_kind is None and dark == 1:
        return None
    from citygen_photo.train_unet import dark_photos, draw_weights
    if per_kind is not None:
        return draw_weights(photos, per_kind, per_kind=True, dark=dark)
    weight = np.where(dark_photos(photos), dark, 1.0)
    return weight / weight.sum()


def add_training_arguments(parser: argparse.ArgumentParser) -> None:
    """The options every training script shares: ``--seed``, ``--exclude`` and ``--validate``."""
    parser.add_argument("--seed", type=int, default=7)
    parser.add_argument("--exclude", type=int, nargs="*", default=[], help="photo numbers left out of training")
    parser.add_argument("--validate", action="store_true",
                        help=f"train on cmp_b{TRAIN.start:04d}-{VALIDATION.start - 1:04d} only and report the pixel "
                             f"accuracy on cmp_b{VALIDATION.start:04d}-{VALIDATION.stop - 1:04d} (for choices)")


def training_photos(args: argparse.Namespace) -> list[tuple[np.ndarray, np.ndarray]]:
    """The photos and label maps ``args`` train on (:func:`add_training_arguments`); none found is said on
    stderr."""
    numbers = [n for n in (range(TRAIN.start, VALIDATION.start) if args.validate else TRAIN)
               if n not in set(args.exclude)]
    photos = facade_examples(args.data, numbers)
    if not photos:
        print(f"no CMP photos among cmp_b{numbers[0]:04d}-{numbers[-1]:04d} in {args.data}", file=sys.stderr)
    return photos


def save(model: FacadeParser, arrays: dict[str, np.ndarray], args: argparse.Namespace) -> int:
    """Write a trained model's ``arrays`` to ``args.output`` and, with ``args.validate``, print its confusion on
    the validation photos; the training scripts' exit status."""
    args.output.parent.mkdir(parents=True, exist_ok=True)
    with open(args.output, "wb") as fh:
        np.savez_compressed(fh, **arrays)
    print(f"wrote {args.output} ({args.output.stat().st_size / 1024:.0f} KiB)", file=sys.stderr)
    if args.validate:
        print(report(confusion(model, facade_examples(args.data, VALIDATION))))
    return 0


if __name__ == "__main__":
    sys.exit(main())
