import numpy as np
import pytest


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(1234)


@pytest.fixture
def nift_cache(tmp_path, monkeypatch):
    """A private, empty cache directory so collision models are really computed."""
    monkeypatch.setenv("NIFT_CACHE", str(tmp_path / "cache"))
    return tmp_path / "cache"
