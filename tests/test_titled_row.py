"""The renders side by side under their titles (``frenbrdf.render.figures.titled_row``): reconstruct's comparison.png
and edit's strip.png."""

from __future__ import annotations

import numpy as np

from frenbrdf.render.figures import titled_row


def _two_colours(size: int) -> tuple[np.ndarray, np.ndarray]:
    left, right = np.zeros((size, size, 3)), np.zeros((size, size, 3))
    left[..., 0], right[..., 2] = 0.8, 0.6  # red beside blue
    return left, right


def test_the_images_keep_their_pixels_under_a_band_with_each_title():
    left, right = _two_colours(256)
    row = titled_row([left, right], ["measured (truth)", "reconstruction: 31.2 dB, ΔE 2.50"])
    band = row.shape[0] - 256
    assert row.shape[1] == 512 and band > 0
    np.testing.assert_array_equal(row[band:], np.concatenate([left, right], axis=1))
    for column in (row[:band, :256], row[:band, 256:]):  # each image has its title in the band above it
        assert (column.min(axis=-1) > 0.5).sum() > 20


def test_an_untitled_column_stays_dark_and_a_row_too_narrow_goes_untitled():
    left, right = _two_colours(64)
    gap = np.ones((64, 4, 3))
    row = titled_row([left, gap, right], ["a", None, "b"])
    band = row.shape[0] - 64
    assert band > 0 and (row[:band, 64:68] == 0).all()
    # One title too long for its column leaves the whole row untitled, not half of it.
    assert titled_row([left, right], ["a", "a title far too long for sixty-four pixels"]).shape == (64, 128, 3)
