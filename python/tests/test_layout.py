"""The package matches the library it loads: the ctypes structures have
the compiler's sizes and offsets (python/tests/layout.c), the versions
agree, the shared library is the build tree's, and every public name has
a docstring.
SPDX-License-Identifier: GPL-2.0-or-later
"""
import ctypes
import inspect
import os
import re
import subprocess

import pytest

import hocad
from hocad import _capi

from conftest import SOURCE


def compiler_layout():
    out = subprocess.run([os.environ["HOCAD_LAYOUT"]], capture_output=True, text=True, check=True)
    return [line.split() for line in out.stdout.splitlines()]


def test_every_structure_is_described():
    names = {key.split(".")[0] for key, _ in compiler_layout()}
    assert names == set(_capi.STRUCTURES)


@pytest.mark.parametrize("key,value", compiler_layout(), ids=lambda v: str(v))
def test_structure_layout(key, value):
    if "." in key:
        struct, field = key.split(".")
        assert getattr(_capi.STRUCTURES[struct], field).offset == int(value)
    else:
        assert ctypes.sizeof(_capi.STRUCTURES[key]) == int(value)


def test_fields_in_c_order():
    """A field the C side lists is in the mirror, in the same order."""
    fields = {}
    for key, value in compiler_layout():
        if "." in key:
            struct, field = key.split(".")
            fields.setdefault(struct, []).append((int(value), field))
    for struct, items in fields.items():
        c_order = [f for _, f in sorted(items)]
        assert [name for name, _ in _capi.STRUCTURES[struct]._fields_] == c_order, struct


def test_versions():
    with open(os.path.join(SOURCE, "CMakeLists.txt")) as f:
        project = re.search(r"project\(hocad VERSION ([0-9.]+)", f.read()).group(1)
    assert hocad.__version__ == project
    assert hocad.library_version == project
    assert os.path.samefile(hocad.LIBRARY_PATH, os.environ["HOCAD_LIBRARY"])


def public_objects():
    for name in hocad.__all__:
        obj = getattr(hocad, name)
        if inspect.isclass(obj) or inspect.isfunction(obj):
            yield name, obj
            if inspect.isclass(obj):
                for attr, member in vars(obj).items():
                    if attr.startswith("_"):
                        continue
                    if callable(member) or isinstance(member, property):
                        yield "%s.%s" % (name, attr), member


def test_docstrings():
    assert hocad.__doc__ and "import hocad" in hocad.__doc__
    missing = [name for name, obj in public_objects() if not (obj.__doc__ or "").strip()]
    assert not missing
    assert len(list(public_objects())) > 40
