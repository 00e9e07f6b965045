"""Bad input raises a clean exception carrying hocad's message and status,
and the process carries on: missing, empty, truncated and crashing model
files (gmsh's importer crashes on square_dangling_vector.step, in a child
process), a second model while one is open, a mesh of another model,
bad .msh files, unwritable outputs, closed objects, and options the
library refuses (ArgumentError, a ValueError) or Python does (TypeError).
SPDX-License-Identifier: GPL-2.0-or-later
"""
import os

import numpy as np
import pytest

import hocad

from conftest import DATA, MODELS, SCREW


def open_fails(path, status, words):
    with pytest.raises(hocad.Error) as info:
        hocad.Model(path)
    e = info.value
    assert e.status == status, str(e)
    assert e.status_name == {hocad.ERR_IO: "input/output error",
                             hocad.ERR_FORMAT: "malformed file"}[status]
    for w in words:
        assert w in str(e)
    assert "\n" not in str(e)
    return e


def test_missing_file(tmp_path):
    open_fails(tmp_path / "missing.step", hocad.ERR_IO, ["missing.step", "No such file"])


def test_directory(tmp_path):
    open_fails(tmp_path, hocad.ERR_IO, ["directory"])


def test_not_cad_extension(tmp_path):
    path = tmp_path / "model.txt"
    path.write_text("solid\n")
    open_fails(path, hocad.ERR_FORMAT, ["not a CAD file"])


def test_empty_step(tmp_path):
    path = tmp_path / "empty.step"
    path.write_bytes(b"")
    open_fails(path, hocad.ERR_FORMAT, ["empty"])


def test_truncated_step(tmp_path):
    path = tmp_path / "truncated.step"
    with open(SCREW, "rb") as f:
        path.write_bytes(f.read(20000))
    open_fails(path, hocad.ERR_FORMAT, ["truncated.step", "end of file"])


def test_garbage_step(tmp_path):
    path = tmp_path / "garbage.step"
    path.write_bytes(os.urandom(4096))
    with pytest.raises(hocad.Error) as info:
        hocad.Model(path)
    assert info.value.status in (hocad.ERR_FORMAT, hocad.ERR_CAD)


def test_importer_crash():
    """gmsh 4.8's STEP importer dies of SIGSEGV on this file: in the
    library's child process, so this process only sees the error."""
    open_fails(os.path.join(DATA, "square_dangling_vector.step"), hocad.ERR_FORMAT,
               ["crashed", "SIGSEGV"])


def test_second_model_refused():
    with hocad.Model(SCREW) as first:
        with pytest.raises(hocad.ArgumentError, match="one model at a time"):
            hocad.Model(SCREW)
        assert first.num_faces == 10
    # once closed, another opens
    with hocad.Model(SCREW) as again:
        assert again.num_faces == 10


def test_bad_meshes(tmp_path):
    out = tmp_path / "screw.msh"
    hocad.mesh_file(SCREW, output=out, order=2, optimize=False)
    with hocad.Model(os.path.join(MODELS, "gmsh_t20_component8.step")) as other:
        with pytest.raises(hocad.Error) as info:
            other.read_msh(out)
        assert info.value.status == hocad.ERR_MISMATCH
        with pytest.raises(hocad.Error) as info:
            other.read_msh(tmp_path / "none.msh")
        assert info.value.status == hocad.ERR_IO
        bad = tmp_path / "bad.msh"
        bad.write_bytes(b"$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 2 3\n")
        with pytest.raises(hocad.Error) as info:
            other.read_msh(bad)
        assert info.value.status == hocad.ERR_FORMAT
        truncated = tmp_path / "truncated.msh"
        truncated.write_bytes(out.read_bytes()[:5000])
        with pytest.raises(hocad.Error) as info:
            other.read_msh(truncated)
        assert info.value.status in (hocad.ERR_FORMAT, hocad.ERR_MISMATCH)


def test_bad_options_and_outputs(tmp_path):
    with hocad.Model(SCREW) as model:
        for kwargs, words in [
            (dict(order=0), "order 0"), (dict(order=16), "order 16"),
            (dict(size=-1.0), "sizes"), (dict(curvature=float("nan")), "finite"),
            (dict(max_iterations=-5), "max_iterations"), (dict(refinements=-2), "refinements"),
        ]:
            with pytest.raises(hocad.ArgumentError, match=words) as info:
                model.mesh(**kwargs)
            assert isinstance(info.value, ValueError)
            assert info.value.status == hocad.ERR_ARGUMENT
        for kwargs in [dict(order="3"), dict(order=2.5), dict(order=None), dict(size="big"),
                       dict(optimize=2), dict(bogus=1), dict(keep_nodes=True),
                       dict(nodes=1), dict(progress=42), dict(linear="mesh")]:
            with pytest.raises(TypeError):
                model.mesh(**kwargs)
        for kwargs in [dict(nodes="gauss"), dict(measure="jacobian"), dict(order=2**40)]:
            with pytest.raises(ValueError):
                model.mesh(**kwargs)
        # numpy scalars are numbers
        with model.mesh(order=np.int64(1), size=np.float64(8.0), optimize=np.bool_(False)) as m1:
            assert m1.order == 1
            with pytest.raises(hocad.ArgumentError):
                m1.elevate(0)
            with pytest.raises(hocad.ArgumentError, match="MSH version 30"):
                m1.write(tmp_path / "v30.msh", version=30)
            assert not (tmp_path / "v30.msh").exists()
            with pytest.raises(hocad.Error) as info:
                m1.write(tmp_path / "no" / "dir" / "m.msh")
            assert info.value.status == hocad.ERR_IO
            with m1.elevate(11) as p11:
                with pytest.raises(hocad.Error) as info:
                    p11.write(tmp_path / "p11.msh")
                assert info.value.status == hocad.ERR_UNSUPPORTED
                assert not (tmp_path / "p11.msh").exists()
                p11.write(tmp_path / "p11.vtu")  # VTK has every order
            with pytest.raises(TypeError):
                m1.write(tmp_path / "q.msh", quality=np.ones(m1.num_elements))
            with pytest.raises(TypeError):
                m1.optimize(measure=0)
            with pytest.raises(TypeError, match="unexpected keyword"):
                m1.repair(order=3)  # hoc_mesh_repair keeps its input's order
    # still healthy after all of that
    with hocad.Model(SCREW) as model:
        with model.mesh(order=1) as m:
            assert m.num_elements > 100


def test_closed_objects():
    model = hocad.Model(SCREW)
    mesh = model.mesh(order=1)
    model.close()
    assert model.closed and mesh.closed
    model.close()  # again: nothing
    mesh.close()
    for f in (lambda: model.num_faces, lambda: mesh.nodes, lambda: mesh.measure(),
              lambda: model.mesh()):
        with pytest.raises(ValueError, match="closed"):
            f()
    assert "closed" in repr(model) and "closed" in repr(mesh)
    with pytest.raises(TypeError):
        hocad.Mesh()
