"""Shared fixtures of the Python package's tests (run by ctest's
python_package with /usr/bin/python3; the environment names the library,
the CLI and the trees: python/CMakeLists.txt).
SPDX-License-Identifier: GPL-2.0-or-later
"""
import gc
import os

import pytest

import hocad

SOURCE = os.environ.get("HOCAD_SOURCE_DIR") or os.path.dirname(
    os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
MODELS = os.path.join(SOURCE, "examples", "models")
DATA = os.path.join(SOURCE, "tests", "data")
SCREW = os.path.join(MODELS, "screw.step")


def close_all_models():
    """Close every Model still open (the CAD kernel holds one at a time; a
    failed test's traceback may keep one alive)."""
    for obj in gc.get_objects():
        if isinstance(obj, hocad.Model) and not obj.closed:
            obj.close()


@pytest.fixture(autouse=True, scope="module")
def _one_model_per_module():
    close_all_models()
    yield
    close_all_models()


@pytest.fixture(scope="module")
def screw():
    """The screw model (10 faces), open for the module."""
    with hocad.Model(SCREW) as model:
        yield model
