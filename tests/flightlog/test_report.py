"""Thinning a long series for a figure keeps every bucket's extremes, so spikes are drawn."""

from __future__ import annotations

import numpy as np

from gcs.flightlog._report import envelope


def test_short_series_are_kept_whole() -> None:
    assert list(envelope(np.arange(10.0), buckets=5)) == list(range(10))


def test_every_spike_survives_and_the_order_is_kept() -> None:
    rng = np.random.default_rng(0)
    y = rng.normal(0.0, 0.01, 1_000_003)
    spikes = rng.choice(len(y), 50, replace=False)
    y[spikes] = rng.choice([-1.0, 1.0], 50) * rng.uniform(5, 10, 50)
    keep = envelope(y, buckets=2000)
    assert len(keep) <= 4000
    assert np.all(np.diff(keep) > 0) and keep[-1] < len(y)
    assert set(spikes) <= set(keep.tolist())
    buckets = np.array_split(np.arange(len(y)), 2000)
    assert y[keep].max() == y.max() and y[keep].min() == y.min()
    assert len(buckets) == 2000


def test_nan_stretches_do_not_break_it() -> None:
    y = np.arange(100_000, dtype=float)
    y[10_000:30_000] = np.nan  # a stretch of lost data
    keep = envelope(y, buckets=100)
    assert np.isfinite(y[keep]).sum() >= 150
    assert 0 in keep and 99_999 in keep
