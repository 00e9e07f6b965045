"""The linear mesh graded down to thin faces, and grading=False: gmsh's
mesh as it makes it (tests/data/thin_disk.brep: a rim 0.04 wide among
edges of 0.707; gmsh's mesh has 872 triangles).
SPDX-License-Identifier: GPL-2.0-or-later
"""
import os

import hocad

from conftest import DATA

DISK = os.path.join(DATA, "thin_disk.brep")


def test_grading_keyword():
    with hocad.Model(DISK) as model:
        with model.linear_mesh(grading=False) as plain, model.linear_mesh() as graded:
            assert plain.num_elements == 872
            assert graded.num_elements > plain.num_elements
            assert graded.measure().stats["min"] > 2 * plain.measure().stats["min"]
        with model.mesh(order=1, optimize=False, grading=False) as m:
            assert m.report["stages"][0]["elements"] == 872
