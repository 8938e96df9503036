"""What the Python tests share: the source tree, the command line, and the tolerances, read from
verification/tolerances.hpp (the one place every tolerance the suite asserts is kept)."""
import os
import re

import pytest

SOURCE = os.environ.get("STEPWISE_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
BINARY = os.environ.get("STEPWISE_BIN", os.path.join(SOURCE, "build", "release", "stepwise"))


def tolerance(name):
    """a constexpr double of stepwise::tolerance, by name"""
    text = open(os.path.join(SOURCE, "verification", "tolerances.hpp")).read()
    m = re.search(rf"constexpr double {name} = ([0-9.e+-]+);", text)
    assert m, f"{name} not in verification/tolerances.hpp"
    return float(m.group(1))


def scene(name):
    return os.path.join(SOURCE, "scenes", name + ".toml")


@pytest.fixture(autouse=True)
def private_cache(tmp_path_factory, monkeypatch):
    """the equations' compiled objects in a cache of the session's own"""
    monkeypatch.setenv("STEPWISE_CACHE", str(tmp_path_factory.getbasetemp() / "cache"))
