"""Shared fixtures: the tests folder is importable (procedural frame drawing)."""

from __future__ import annotations

import functools
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))


@pytest.fixture
def rng() -> np.random.Generator:
    """A fixed-seed generator per test."""
    return np.random.default_rng(12345)


@pytest.fixture
def small_bench_cli(monkeypatch: pytest.MonkeyPatch) -> None:
    """``contactcal bench`` run through the CLI times 128×96 frames on one thread instead of
    2592×1944 ones on one and two: the same code, fast enough for a test."""
    from contactcal.infer.bench import config as bench_config
    from contactcal.infer.bench import run as bench_run
    from contactcal.infer.bench.config import BenchConfig

    small = functools.partial(BenchConfig, full_size=(128, 96), threads=(1,))
    monkeypatch.setattr(bench_config, "BenchConfig", small)
    monkeypatch.setattr(bench_run, "BenchConfig", small)
