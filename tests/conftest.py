"""Shared helpers for the test suite."""
import numpy as np
import pytest

import rodjit


def quiet(**over):
    """A Config with outputs off unless asked (fast runs); dotted-key overrides."""
    base = {"output.snapshot_interval": 0.0, "output.diagnostics_interval": 0.0}
    base.update(over)
    return rodjit.Config().override(base)


@pytest.fixture
def rng():
    return np.random.default_rng(20261122)
