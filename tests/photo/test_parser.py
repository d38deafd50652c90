"""The learned parser's features and auto-context (citygen_photo.features, .parser), its training script
(citygen_photo.train, needs scikit-learn) and the shipped model on shared CMP photos (skipped without the data)."""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from citygen_photo.features import FEATURES, pixel_features, working_image
from citygen_photo.labels import CMP_LABELS
from citygen_photo.parser import CONTEXT_FEATURES, OFFSETS, context_features, load_parser
from tests.photo.synthetic import facade, labelled_photos

CMP = Path(__file__).parents[2] / ".." / "shared" / "data" / "cmp_facade" / "base"


def test_pixel_features_are_finite_and_lighting_invariant_in_luminance():
    rgb, _, _ = facade(floors=3, cols=4)
    work = working_image(rgb)
    a, b = pixel_features(work), pixel_features(0.5 * work)
    assert a.shape == (*work.shape[:2], FEATURES) and np.isfinite(a).all()
    assert np.allclose(a[..., 3], b[..., 3], atol=1e-3)  # normalised luminance: the photo's own statistics


def test_context_sees_the_labels_above_and_below_at_the_offsets():
    """Regression: the shifted context planes must show the probabilities *above* the pixel first, then below,
    left, right (the order the shipped weights were trained with)."""
    n = len(CMP_LABELS)
    prob = np.zeros((100, 100, n))
    prob[..., 1] = 1.0
    prob[20:30, 45:55] = np.eye(n)[2]  # a window block
    ctx = context_features(prob)
    assert ctx.shape == (100, 100, n * CONTEXT_FEATURES)
    d = round(OFFSETS[0] * 100)
    above, below = ctx[..., 4 * n + 2], ctx[..., 5 * n + 2]  # after 2 averages and the row / column profiles
    assert above[25 + d, 50] > 0.5 and above[25 - d, 50] < 0.5  # the block is above pixels d below it
    assert below[25 - d, 50] > 0.5 and below[25 + d, 50] < 0.5


def test_shipped_parser_is_small_and_gives_probabilities():
    """The shipped parser is the ensemble of the perceptrons and the U-Net (round 4), both shipped, together under
    1 MiB; it parses a synthetic facade into probabilities that favour its windows."""
    from citygen_photo.parser import SHIPPED, Ensemble, FacadeParser
    from citygen_photo.unet import FacadeUNet
    model = load_parser()
    assert isinstance(model, Ensemble)
    assert [type(m) for m in model.members] == [FacadeParser, FacadeUNet] and len(model.members[0].stages) >= 2
    rgb, boxes, _ = facade(floors=4, cols=5)
    prob = model.probabilities(rgb)
    assert prob.shape[-1] == len(CMP_LABELS) and np.allclose(prob.sum(axis=-1), 1.0, atol=1e-4)
    f = prob.shape[0] / rgb.shape[0]
    x0, y0, x1, y1 = (round(v * f) for v in boxes[7])
    assert prob[y0 + 1:y1 - 1, x0 + 1:x1 - 1].mean(axis=(0, 1)).argmax() == CMP_LABELS.index("window")
    assert sum(path.stat().st_size for path in SHIPPED) < 1024 * 1024


def test_unreadable_weights_name_the_file(tmp_path):
    from citygen.errors import LayoutError
    bad = tmp_path / "broken.npz"
    bad.write_text("not weights")
    with pytest.raises(LayoutError, match="cannot read the facade parser's weights"):
        load_parser(bad)


def test_training_is_reproducible_and_learns_two_labels():
    """Regression: with two labels scikit-learn's perceptron has one logistic output, which was copied into both
    label columns, so every pixel got the label the prior favours (the synthetic windows were all wall)."""
    pytest.importorskip("sklearn")
    from citygen_photo.train import confusion, train
    photos = labelled_photos(3)
    a = train(photos, 3000, 2, (16,), seed=3)
    b = train(photos, 3000, 2, (16,), seed=3)
    assert len(a.stages) == 2
    assert all(np.array_equal(wa, wb) for sa, sb in zip(a.stages, b.stages)
               for (wa, _), (wb, _) in zip(sa.layers, sb.layers))
    matrix = confusion(a, photos)
    assert matrix[2, 2] / matrix[2].sum() > 0.8  # the synthetic windows are learned


def test_per_photo_draw_shares_set_the_pixels_drawn_from_each_photo():
    pytest.importorskip("sklearn")
    from citygen_photo.train import train
    photos = labelled_photos(3)

    def weights(model):
        return [w for stage in model.stages for w, _ in stage.layers]
    even = train(photos, 600, 1, (8,), seed=3)
    assert all(np.array_equal(a, b) for a, b in zip(weights(even), weights(
        train(photos, 600, 1, (8,), seed=3, draw=np.full(3, 1 / 3)))))  # equal shares: the plain drawing
    skewed = train(photos, 600, 1, (8,), seed=3, draw=np.array([0.8, 0.1, 0.1]))
    assert not all(np.array_equal(a, b) for a, b in zip(weights(even), weights(skewed)))


def test_dark_photos_get_the_dark_factor_times_the_pixels_of_the_others():
    from citygen_photo.train import pixel_shares
    from citygen_photo.train_unet import DARK
    photos = labelled_photos(3)
    photos[0] = (photos[0][0] * (0.8 * DARK / photos[0][0].mean(axis=(0, 1)).max()), photos[0][1])
    assert pixel_shares(photos, None, 1.0) is None  # the plain drawing, as shipped
    shares = pixel_shares(photos, None, 2.0)
    assert shares.sum() == pytest.approx(1) and shares.tolist() == pytest.approx([0.5, 0.25, 0.25])


@pytest.mark.skipif(not (CMP / "cmp_b0031.jpg").is_file(), reason="CMP photos (shared data) not available")
@pytest.mark.parametrize("number, floors", [(28, 4), (31, 4)])
def test_floors_and_window_pixels_of_held_out_photos(number, floors):
    """Two held-out photos (never trained on): the floor count (cmp_b0028: three rows of windows over a
    ground floor of doors and shops) and the layout's window pixels against the label map."""
    from citygen_photo.learned import analyse_learned
    from citygen_photo.parser import load_labels
    rgb, labels = load_labels(CMP / f"cmp_b{number:04d}.jpg")
    result = analyse_learned(rgb, "cmp")
    assert len(result.floor_lines) - 1 == floors
    s = result.layout.meta["metres_per_pixel"]
    mine = np.zeros(labels.shape, dtype=bool)
    for r in result.layout.leaves:
        if r.label == "window":
            y0 = round(labels.shape[0] - (r.y + r.h) / s)
            mine[max(y0, 0):round(labels.shape[0] - r.y / s), round(r.x / s):round((r.x + r.w) / s)] = True
    truth = labels == 3
    assert (mine & truth).sum() >= 0.6 * mine.sum() and (mine & truth).sum() >= 0.6 * truth.sum()


def test_working_image_repeats_its_edge_instead_of_a_black_row():
    """Regression (round 6): zoom's default constant mode left the last row (column) of the working image black
    for some crop sizes, e.g. 445 x 484 -> 177 x 192 (15 of the 64 validation and fold photos)."""
    for shape in ((445, 484, 3), (555, 511, 3), (884, 456, 3)):
        work = working_image(np.full(shape, 0.8))
        assert max(work.shape[:2]) == 192 and np.allclose(work, 0.8)


def test_upsampled_probabilities_keep_their_edges_and_sum_to_one():
    from citygen_photo.parser import upsampled
    prob = np.full((224, 191, len(CMP_LABELS)), 1 / len(CMP_LABELS))
    out = upsampled(prob, (192, 163))
    assert out.shape == (192, 163, len(CMP_LABELS)) and np.allclose(out, 1 / len(CMP_LABELS))


def test_the_ensemble_averages_its_members_over_the_working_sizes():
    """Multi-scale inference (round 6): every member parses the photo at each working size of ``scales``; the
    larger sizes' probabilities are resampled to the first's grid and all are averaged."""
    from citygen_photo.parser import SCALES, Ensemble, upsampled
    from citygen_photo.features import WORK
    shipped = load_parser()
    assert shipped.scales == SCALES and SCALES[0] == WORK and len(SCALES) > 1
    rgb, _, _ = facade(floors=3, cols=4)
    members = shipped.members
    one = Ensemble(members).probabilities(rgb)
    assert np.allclose(one, sum(m.probabilities(rgb) for m in members) / len(members))
    two = Ensemble(members, (WORK, 256)).probabilities(rgb)
    large = sum(m.probabilities(rgb, 256) for m in members) / len(members)
    assert max(large.shape[:2]) == 256 and two.shape == one.shape
    assert np.allclose(two, (one + upsampled(large, one.shape[:2])) / 2)
    assert np.allclose(two.sum(axis=-1), 1.0, atol=1e-5)
