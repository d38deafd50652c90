"""Train the U-Net facade parser on CMP photos: ``python -m citygen_photo.train_unet [DATA] [-o MODEL.npz]``.

Needs PyTorch (``pip install -e '.[photo-train]'``, CPU is enough); the shipped model (``model/facade_unet.npz``)
was made by this script with its defaults, reproducible from the seed on the same photos (one thread). Photos
cmp_b0061-0300 train; cmp_b0001-0040 are kept for evaluation and never seen here.

Each photo is cropped to its annotated facade box and reduced to the working size. Every step draws ``--batch``
photos, each with probability proportional to its balcony + blind pixel share plus ``EVEN`` times the mean share
(the held-out kind -- French windows behind railings, closed shutters -- comes up more often without dropping the
photos that have none), ``--dark FACTOR`` times as often where its crop is darker than ``DARK`` on average (the
shaded, shuttered kind of round 10: a label-free property of the photo), jitters its colours (a gain per channel and
a gamma), mirrors it left-right half the time, and cuts a random ``--crop``-pixel window; Adam descends on the
cross-entropy with label weights ``share ** -WEIGHT_POWER`` (:func:`citygen_photo.train_fcn.label_weights`), each
multiplied by its ``--boost`` factor (e.g. ``--boost blind=3``: a rare label weighted above its share), whose
exported ``prior`` turns the outputs back into probabilities. ``--close-shutters SHARE`` closes that share of a
blind photo's windows with its own open shutters (:mod:`citygen_photo.shutters`; the closed kind is rare in CMP).
``--init MODEL.npz`` starts from a trained U-Net of the same widths instead of random weights (fine-tuning, e.g.
with ``--lr 5e-4``).
``--validate`` trains on cmp_b0061-0260 and reports the per-class pixel accuracy
on cmp_b0261-0300; ``--exclude`` leaves photos out (the balcony fold).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from citygen_photo.features import pixel_features
from citygen_photo.labels import CMP_LABELS
from citygen_photo.parser import UNET_PATH, load_parser
from citygen_photo.photo import luminance
from citygen_photo.shutters import ShutterParts, closed_shutters, shutter_parts
from citygen_photo.train import DEFAULT_DATA, add_training_arguments, save, training_photos
from citygen_photo.train_fcn import COLUMN, label_weights
from citygen_photo.unet import BASE_INPUTS, BOTTOM_DILATIONS, FacadeUNet, base_input, layer_shapes

#: Defaults of the shipped model: level widths, steps, photos per step, crop side (working pixels), label weights.
CHANNELS = (16, 32, 48, 64)
STEPS = 2400
LEARNING_RATE = 2e-3
BATCH = 6
CROP = 128
WEIGHT_POWER = 0.5
#: A photo's draw weight is its balcony + blind share plus this many times the photos' mean share.
EVEN = 1.0
#: Colour jitter: gain per channel within 1 +- GAIN, gamma within [1 / GAMMA, GAMMA].
GAIN = 0.1
GAMMA = 1.25
#: A crop darker than this mean luminance is of the held-out kind (round 10: 30 of the 40 held-out crops are).
DARK = 0.45
_HELD_OUT_KIND = (CMP_LABELS.index("balcony") + 1, CMP_LABELS.index("blind") + 1)


def draw_weights(photos: list[tuple[np.ndarray, np.ndarray]], even: float = EVEN,
                 per_kind: bool = False, dark: float = 1.0) -> np.ndarray:
    """Each photo's probability of being drawn: its balcony + blind pixel share plus ``even`` times the mean.
    ``per_kind``: each kind's share counts over its own mean share (blinds, rarer than balconies in CMP, then come
    up as often as balconies), plus ``even`` times the mean of that sum. ``dark``: the factor by which a photo
    darker than ``DARK`` (:func:`dark_photos`) is drawn more often."""
    if per_kind:
        shares = np.array([[np.mean(lab == kind) for kind in _HELD_OUT_KIND] for _, lab in photos])
        share = (shares / np.maximum(shares.mean(axis=0), 1e-9)).sum(axis=1)
    else:
        share = np.array([np.isin(lab, _HELD_OUT_KIND).mean() for _, lab in photos])
    weight = (share + even * share.mean() + 1e-9) * np.where(dark_photos(photos), dark, 1.0)
    return weight / weight.sum()


def dark_photos(photos: list[tuple[np.ndarray, np.ndarray]]) -> np.ndarray:
    """Whether each photo's image (the facade crop at working size) is darker than ``DARK`` on average."""
    return np.array([luminance(work).mean() < DARK for work, _ in photos], dtype=bool)


def boosted(weight: np.ndarray, boost: dict[str, float]) -> np.ndarray:
    """The label weights ``weight`` (one per CMP label) with each label named in ``boost`` multiplied by its
    factor."""
    unknown = sorted(set(boost) - set(CMP_LABELS))
    if unknown:
        raise ValueError(f"--boost names no CMP label: {', '.join(unknown)} (labels: {', '.join(CMP_LABELS)})")
    factor = np.array([boost.get(name, 1.0) for name in CMP_LABELS])
    return weight * factor


def parse_boost(text: str) -> tuple[str, float]:
    """``LABEL=FACTOR`` of ``--boost`` as (label, factor); a clear error otherwise."""
    name, _, value = text.partition("=")
    try:
        factor = float(value)
    except ValueError:
        factor = -1.0
    if name not in CMP_LABELS or factor <= 0:
        raise argparse.ArgumentTypeError(f"--boost {text!r}: want LABEL=FACTOR with a CMP label "
                                         f"({', '.join(CMP_LABELS)}) and a factor > 0, e.g. blind=3")
    return name, factor


def jittered(work: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """``work`` (H, W, 3) in 0..1 with a random gamma and a random gain per channel, clipped to 0..1."""
    gamma = GAMMA ** rng.uniform(-1, 1)
    return np.clip(work ** gamma * rng.uniform(1 - GAIN, 1 + GAIN, 3), 0, 1)


def draw_batch(photos: list[tuple[np.ndarray, np.ndarray]], features: list[np.ndarray] | None,
               weights: np.ndarray, rng: np.random.Generator, batch: int, crop: int,
               column: tuple[float, float] = (0.0, 1.0), shutters: list[ShutterParts] | None = None,
               close: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """One training batch: inputs ``(batch, C, crop, crop)`` float32 and labels ``(batch, crop, crop)`` (ids - 1;
    pixels padded onto a photo smaller than the crop are -100, ignored by the loss). ``features``: the photos'
    standardised pixel features or None; ``column`` the (mean, std) they were standardised with in the column
    position's channel, which a mirrored photo flips. ``shutters``: each photo's blind and window parts, whose
    windows are closed with probability ``close`` (:func:`citygen_photo.shutters.closed_shutters`)."""
    xs, ys = [], []
    for i in rng.choice(len(photos), size=batch, p=weights):
        work, lab = photos[i]
        if shutters is not None:
            work, lab = closed_shutters(work, lab, shutters[i], rng, close)
        x = base_input(jittered(work, rng))
        if features is not None:
            x = np.concatenate([x, features[i]], axis=-1)
        if rng.random() < 0.5:
            x, lab = x[:, ::-1].copy(), lab[:, ::-1]
            if features is not None:
                mean, std = column
                x[..., BASE_INPUTS + COLUMN] = (1 - 2 * mean - x[..., BASE_INPUTS + COLUMN] * std) / std
        h, w = lab.shape
        ch, cw = min(crop, h), min(crop, w)
        y0, x0 = rng.integers(h - ch + 1), rng.integers(w - cw + 1)
        xc = np.zeros((crop, crop, x.shape[-1]), np.float32)
        yc = np.full((crop, crop), -100, np.int64)
        xc[:ch, :cw] = x[y0:y0 + ch, x0:x0 + cw]
        yc[:ch, :cw] = lab[y0:y0 + ch, x0:x0 + cw].astype(np.int64) - 1
        xs.append(xc.transpose(2, 0, 1))
        ys.append(yc)
    return np.stack(xs), np.stack(ys)


def train(photos: list[tuple[np.ndarray, np.ndarray]], *, channels: tuple[int, ...] = CHANNELS,
          features: bool = False, steps: int = STEPS, batch: int = BATCH, crop: int = CROP,
          power: float = WEIGHT_POWER, boost: dict[str, float] | None = None, even: float = EVEN,
          per_kind: bool = False, dark: float = 1.0, close: float = 0.0, lr: float = LEARNING_RATE,
          init: FacadeUNet | None = None, seed: int = 7) -> FacadeUNet:
    """The network fitted on ``photos`` (working image, label map) from ``seed``; ``boost`` multiplies the named labels'
    loss weights, ``dark`` the draw weight of the dark photos (:func:`draw_weights`), ``close`` is the share of a
    blind photo's windows closed with its own shutters; ``init`` a trained network to start from (its widths
    ``channels``, no pixel features), ``lr`` Adam's first step."""
    if init is not None and (init.channels != tuple(channels) or init.feature_mean.size or features):
        raise ValueError(f"--init: the network's widths {init.channels} (pixel features: "
                         f"{bool(init.feature_mean.size)}) differ from the training's {tuple(channels)} "
                         f"({features}); give --channels as the model's, without --features")
    if not 0 <= close <= 1:
        raise ValueError(f"--close-shutters {close}: a share of the windows, from 0 to 1")
    if close and features:
        raise ValueError("--close-shutters changes the photo's pixels after its pixel features are computed: "
                         "use it without --features")
    import torch
    from torch import nn
    torch.set_num_threads(1)
    torch.manual_seed(seed)
    rng = np.random.default_rng(seed)
    feats, mean, std = None, np.zeros(0, np.float32), np.zeros(0, np.float32)
    if features:
        feats = [pixel_features(work) for work, _ in photos]
        flat = np.concatenate([f.reshape(-1, f.shape[-1]) for f in feats])
        mean, std = flat.mean(axis=0).astype(np.float32), (flat.std(axis=0) + 1e-6).astype(np.float32)
        feats = [((f - mean) / std).astype(np.float32) for f in feats]
    net = build_network(BASE_INPUTS + mean.size, channels)
    if init is not None:
        loaded(net, init)
    weight = boosted(label_weights(photos, power), boost or {})
    loss_fn = nn.CrossEntropyLoss(weight=torch.tensor(weight, dtype=torch.float32))
    optimiser = torch.optim.Adam(net.parameters(), lr=lr, weight_decay=1e-5)
    schedule = torch.optim.lr_scheduler.CosineAnnealingLR(optimiser, steps)
    if dark <= 0:
        raise ValueError(f"--dark {dark}: a factor on the dark photos' draw weight, > 0")
    draw = draw_weights(photos, even, per_kind, dark)
    print(f"{int(dark_photos(photos).sum())} of {len(photos)} photos darker than {DARK}, drawn x{dark:g}",
          file=sys.stderr)
    shutters = [shutter_parts(lab) for _, lab in photos] if close else None
    column = (float(mean[COLUMN]), float(std[COLUMN])) if features else (0.0, 1.0)
    t0, running = time.process_time(), 0.0
    for step in range(steps):
        x, y = draw_batch(photos, feats, draw, rng, batch, crop, column, shutters, close)
        loss = loss_fn(net(torch.from_numpy(x)), torch.from_numpy(y))
        optimiser.zero_grad()
        loss.backward()
        optimiser.step()
        schedule.step()
        running = 0.98 * running + 0.02 * loss.item()
        if (step + 1) % 100 == 0:
            print(f"step {step + 1}: loss {running:.3f}, {time.process_time() - t0:.0f} s cpu", file=sys.stderr)
    prior = np.where(weight > 0, 1 / np.maximum(weight, 1e-9), 0.0)
    return exported(net, channels, mean, std, (prior / prior.sum()).astype(np.float32))


def build_network(inputs: int, channels: tuple[int, ...]):
    """The PyTorch module of :class:`citygen_photo.unet.FacadeUNet`'s architecture (same layer order)."""
    import torch
    from torch import nn
    from torch.nn import functional as F
    shapes = layer_shapes(inputs, channels, len(CMP_LABELS))
    levels = len(channels) - 1
    dilations = [1] * (2 * levels) + list(BOTTOM_DILATIONS) + [1] * levels

    class UNet(nn.Module):
        def __init__(self):
            super().__init__()
            self.convs = nn.ModuleList([nn.Conv2d(i, o, 3, padding=d, dilation=d)
                                        for (i, o), d in zip(shapes, dilations)] + [nn.Conv2d(*shapes[-1], 1)])

        def forward(self, x):
            layers, skips = iter(self.convs), []
            for _ in range(levels):
                for _ in range(2):
                    x = torch.relu(next(layers)(x))
                skips.append(x)
                x = F.max_pool2d(x, 2)
            for _ in BOTTOM_DILATIONS:
                x = torch.relu(next(layers)(x))
            for skip in reversed(skips):
                x = torch.relu(next(layers)(torch.cat([F.interpolate(x, scale_factor=2, mode="nearest"), skip], 1)))
            return next(layers)(x)
    return UNet()


def loaded(net, model: FacadeUNet) -> None:
    """Set the PyTorch module ``net``'s weights to those of ``model`` (the inverse of :func:`exported`)."""
    import torch
    with torch.no_grad():
        for conv, (w, b) in zip(net.convs, model.layers):
            kernel = w.transpose(3, 2, 0, 1) if w.ndim == 4 else w.T[:, :, None, None]
            conv.weight.copy_(torch.from_numpy(np.ascontiguousarray(kernel)))
            conv.bias.copy_(torch.from_numpy(b))


def exported(net, channels: tuple[int, ...], mean: np.ndarray, std: np.ndarray, prior: np.ndarray) -> FacadeUNet:
    """The numpy parser of the PyTorch module ``net``, its weights rounded to float16 as stored."""
    import torch
    convs = net.convs
    with torch.no_grad():
        layers = [(c.weight.permute(2, 3, 1, 0).numpy().copy(), c.bias.numpy().copy()) for c in convs[:-1]]
        layers.append((convs[-1].weight[:, :, 0, 0].T.numpy().copy(), convs[-1].bias.numpy().copy()))
    return FacadeUNet(tuple(channels), mean, std, tuple((w.astype(np.float16).astype(np.float32),
                                                         b.astype(np.float16).astype(np.float32)) for w, b in layers),
                      prior)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", nargs="?", type=Path, default=DEFAULT_DATA)
    parser.add_argument("-o", "--output", type=Path, default=UNET_PATH)
    parser.add_argument("--channels", type=int, nargs="+", default=list(CHANNELS),
                        help="widths of the levels, finest first (the last is the bottom's)")
    parser.add_argument("--features", action="store_true", help="add the perceptrons' pixel features as inputs")
    parser.add_argument("--steps", type=int, default=STEPS)
    parser.add_argument("--batch", type=int, default=BATCH)
    parser.add_argument("--crop", type=int, default=CROP, help="crop side, working pixels (a multiple of 8)")
    parser.add_argument("--power", type=float, default=WEIGHT_POWER, help="label weight = share ** -power")
    parser.add_argument("--boost", type=parse_boost, action="append", default=[], metavar="LABEL=FACTOR",
                        help="multiply a label's loss weight (repeatable), e.g. blind=3")
    parser.add_argument("--even", type=float, default=EVEN,
                        help="photo draw weight = balcony + blind share + EVEN x the mean share")
    parser.add_argument("--per-kind", action="store_true",
                        help="draw weight from the balcony and the blind share each over its own mean")
    parser.add_argument("--dark", type=float, default=1.0, metavar="FACTOR",
                        help=f"draw the photos whose crop is darker than {DARK} mean luminance FACTOR times as often")
    parser.add_argument("--close-shutters", type=float, default=0.0, metavar="SHARE",
                        help="close this share of a blind photo's windows with its own shutters (0 to 1)")
    parser.add_argument("--lr", type=float, default=LEARNING_RATE, help="Adam's learning rate (cosine decay)")
    parser.add_argument("--init", type=Path, metavar="MODEL.npz",
                        help="start from this trained U-Net (fine-tuning) instead of random weights")
    add_training_arguments(parser)
    args = parser.parse_args(argv)
    init = None
    if args.init is not None:
        init = load_parser(args.init)
        if not isinstance(init, FacadeUNet):
            print(f"--init {args.init}: not a U-Net's weights (train one with this script)", file=sys.stderr)
            return 2
    photos = training_photos(args)
    if not photos:
        return 2
    model = train(photos, channels=tuple(args.channels), features=args.features, steps=args.steps,
                  batch=args.batch, crop=args.crop, power=args.power, boost=dict(args.boost), even=args.even,
                  per_kind=args.per_kind, dark=args.dark, close=args.close_shutters, lr=args.lr, init=init,
                  seed=args.seed)
    return save(model, model.arrays(), args)


if __name__ == "__main__":
    sys.exit(main())
