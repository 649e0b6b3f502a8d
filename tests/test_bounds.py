"""No silent garbage: every path from input values to output values is bounded by the readers' own limit."""

from __future__ import annotations

import numpy as np
import torch

from frenbrdf.io.reflectance import MAX_REFLECTANCE
from frenbrdf.models.mapping import LogRelativeMapping
from frenbrdf.models.nbrdf import NBRDF

from .conftest import random_nbrdf_params


def test_an_nbrdf_that_overflows_gives_back_at_most_what_a_reader_accepts(tmp_path):
    """An NBRDF refined on values at the readers' limit extrapolates beyond it; its table must not (a table of
    2.4e263 came out of samples of 1e8 before the mapping was bounded)."""
    params = random_nbrdf_params()
    params[-1] = torch.full_like(params[-1], 200.0)  # exp(200) overflows float32 to inf
    nbrdf = NBRDF(params, LogRelativeMapping(np.full(3, 0.1)))
    table = nbrdf.merl_table()
    present = table[table >= 0]
    assert np.isfinite(table).all() and present.max() <= MAX_REFLECTANCE
    wi, wo = np.array([[0.0, 0.6, 0.8]]), np.array([[0.0, -0.6, 0.8]])
    assert np.all(nbrdf(wi, wo) <= MAX_REFLECTANCE)


def test_the_torch_and_numpy_inverses_agree_on_the_bound():
    mapping = LogRelativeMapping(np.full(3, 0.1))
    mapped = np.array([-5.0, 0.0, 30.0, 200.0])
    reference = np.full(4, 0.1)
    bounded = mapping.inverse(mapped, reference)
    assert bounded.max() == MAX_REFLECTANCE and bounded.min() >= 0
    np.testing.assert_allclose(mapping.inverse(torch.tensor(mapped), torch.tensor(reference)).numpy(), bounded)
