"""Objects own their handles: a mesh keeps its model alive, a model's
close() (or a with block's end) closes its meshes, and garbage collection
destroys what nothing refers to (which frees the kernel's one model slot).
SPDX-License-Identifier: GPL-2.0-or-later
"""
import gc
import weakref

import hocad

from conftest import SCREW


def make_mesh():
    model = hocad.Model(SCREW)
    return model.mesh(order=2, optimize=False)


def test_mesh_keeps_model_alive():
    mesh = make_mesh()
    gc.collect()
    assert not mesh.model.closed
    assert mesh.measure().stats["elements"] == mesh.num_elements
    model = weakref.ref(mesh.model)
    del mesh
    gc.collect()
    assert model() is None
    # the model was destroyed: another may open
    with hocad.Model(SCREW) as again:
        assert again.num_curves == 22


def test_with_blocks():
    with hocad.Model(SCREW) as model:
        with model.mesh(order=1) as mesh:
            pass
        assert mesh.closed and not model.closed
        kept = model.mesh(order=1)
        stages = model.mesh(order=2, keep_stages=True, optimize=False)
    assert model.closed and kept.closed and stages.closed
    assert stages.report["linear_mesh"].closed


def test_report_outlives_mesh():
    with hocad.Model(SCREW) as model:
        mesh = model.mesh(order=2)
        report = mesh.report
        mesh.close()
    assert report["stages"][-1]["name"] == "optimized"
    assert len(report["quality"]) == report["elements"]
