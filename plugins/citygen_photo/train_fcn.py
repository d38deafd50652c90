"""Train the convolutional facade parser on CMP photos: ``python -m citygen_photo.train_fcn [DATA] [-o MODEL.npz]``.

Needs PyTorch (``pip install -e '.[photo-train]'``, CPU is enough); the shipped model (``model/facade_fcn.npz``) was
made by this script with its defaults, so the result is reproducible from the seed on the same photos (one thread).
Photos cmp_b0061-0300 train; cmp_b0001-0040 are kept for evaluation and never seen here.

Each photo is cropped to its annotated facade box and reduced to the working size; its pixel features
(:mod:`citygen_photo.features`) are computed once. Every step draws ``--batch`` random ``--crop``-pixel windows of
them, half mirrored left-right (the features are mirror-symmetric but for the column position, which is
mirrored with them), and descends (Adam) on the cross-entropy with label weights ``share ** -WEIGHT_POWER``, so
balcony, blind and door pixels count many times a facade pixel. The exported ``prior`` (``1 / weight``) turns the
outputs back into probabilities under the photos' own label frequencies. ``--validate`` trains on
cmp_b0061-0260 and reports the per-class pixel accuracy on cmp_b0261-0300, the split every choice is made on;
``--exclude`` leaves photos out (a second fold).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from citygen_photo.fcn import DILATIONS, FacadeFCN
from citygen_photo.features import FEATURES, pixel_features
from citygen_photo.labels import CMP_LABELS
from citygen_photo.parser import FCN_PATH
from citygen_photo.train import DEFAULT_DATA, add_training_arguments, save, training_photos

#: Defaults of the shipped model: channels, steps, crops per step, crop side (working pixels), label weights.
WIDTH = 24
STEPS = 1500
BATCH = 4
CROP = 96
WEIGHT_POWER = 0.5
#: The feature channel holding the column position (mirrored with a left-right flip).
COLUMN = 54


def label_weights(photos: list[tuple[np.ndarray, np.ndarray]], power: float) -> np.ndarray:
    """Each label's loss weight ``share ** -power`` (labels never seen: 0), scaled to a pixel-weighted mean of 1."""
    counts = sum(np.bincount(lab.ravel() - 1, minlength=len(CMP_LABELS)) for _, lab in photos).astype(float)
    share = counts / counts.sum()
    weight = np.where(share > 0, np.maximum(share, 1e-9) ** -power, 0.0)
    return weight / (weight * share).sum()


def train(photos: list[tuple[np.ndarray, np.ndarray]], *, width: int = WIDTH, steps: int = STEPS,
          batch: int = BATCH, crop: int = CROP, power: float = WEIGHT_POWER, seed: int = 7) -> FacadeFCN:
    """The network fitted on ``photos`` (working image, label map) from ``seed``."""
    import torch
    from torch import nn
    torch.set_num_threads(1)
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    feats = [pixel_features(work) for work, _ in photos]
    flat = np.concatenate([f.reshape(-1, FEATURES) for f in feats])
    mean, std = flat.mean(axis=0), flat.std(axis=0) + 1e-6
    del flat
    data = [torch.from_numpy(((f - mean) / std).transpose(2, 0, 1).astype(np.float32)) for f in feats]
    labels = [torch.from_numpy(lab.astype(np.int64) - 1) for _, lab in photos]
    weight = label_weights(photos, power)

    layers = nn.ModuleList([nn.Conv2d(FEATURES, width, 1)]
                           + [nn.Conv2d(width, width, 3, padding=d, dilation=d) for d in DILATIONS]
                           + [nn.Conv2d(width, len(CMP_LABELS), 1)])

    def forward(x):
        x = torch.relu(layers[0](x))
        for layer in layers[1:-1]:
            x = x + torch.relu(layer(x))
        return layers[-1](x)

    loss_fn = nn.CrossEntropyLoss(weight=torch.tensor(weight, dtype=torch.float32))
    optimiser = torch.optim.Adam(layers.parameters(), lr=2e-3, weight_decay=1e-5)
    schedule = torch.optim.lr_scheduler.CosineAnnealingLR(optimiser, steps)
    t0, running = time.process_time(), 0.0
    for step in range(steps):
        xs, ys = [], []
        for i in rng.integers(len(data), size=batch):
            _, h, w = data[i].shape
            ch, cw = min(crop, h), min(crop, w)
            y0, x0 = rng.integers(h - ch + 1), rng.integers(w - cw + 1)
            x, y = data[i][:, y0:y0 + ch, x0:x0 + cw], labels[i][y0:y0 + ch, x0:x0 + cw]
            if ch < crop or cw < crop:  # a photo smaller than the crop: pad, the padding's pixels ignored
                x = nn.functional.pad(x, (0, crop - cw, 0, crop - ch))
                y = nn.functional.pad(y, (0, crop - cw, 0, crop - ch), value=-100)
            if rng.random() < 0.5:
                x, y = x.flip(-1).clone(), y.flip(-1)
                x[COLUMN] = ((1 - (x[COLUMN] * std[COLUMN] + mean[COLUMN])) - mean[COLUMN]) / std[COLUMN]
            xs.append(x)
            ys.append(y)
        loss = loss_fn(forward(torch.stack(xs)), torch.stack(ys))
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
        schedule.step()
        running = 0.98 * running + 0.02 * loss.item()
        if (step + 1) % 250 == 0:
            print(f"step {step + 1}: loss {running:.3f}, {time.process_time() - t0:.0f} s cpu", file=sys.stderr)
    with torch.no_grad():
        exported = [(layers[0].weight[:, :, 0, 0].T.numpy().copy(), layers[0].bias.numpy().copy())]
        exported += [(layer.weight.permute(2, 3, 1, 0).numpy().copy(), layer.bias.numpy().copy())
                     for layer in layers[1:-1]]
        exported += [(layers[-1].weight[:, :, 0, 0].T.numpy().copy(), layers[-1].bias.numpy().copy())]
    prior = np.where(weight > 0, 1 / np.maximum(weight, 1e-9), 0.0)
    return FacadeFCN(mean.astype(np.float32), std.astype(np.float32),
                     tuple((w.astype(np.float16).astype(np.float32), b.astype(np.float16).astype(np.float32))
                           for w, b in exported),  # as stored
                     (prior / prior.sum()).astype(np.float32))


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", type=Path, default=DEFAULT_DATA)
    parser.add_argument("-o", "--output", type=Path, default=FCN_PATH)
    parser.add_argument("--width", type=int, default=WIDTH, help="channels of the hidden layers")
    parser.add_argument("--steps", type=int, default=STEPS)
    parser.add_argument("--batch", type=int, default=BATCH)
    parser.add_argument("--crop", type=int, default=CROP, help="crop side, working pixels")
    parser.add_argument("--power", type=float, default=WEIGHT_POWER, help="label weight = share ** -power")
    add_training_arguments(parser)
    args = parser.parse_args(argv)
    photos = training_photos(args)
    if not photos:
        return 2
    model = train(photos, width=args.width, steps=args.steps, batch=args.batch, crop=args.crop,
                  power=args.power, seed=args.seed)
    return save(model, model.arrays(), args)


if __name__ == "__main__":
    sys.exit(main())
