"""Meshing a bundled model through the package: the pipeline's result at
orders 2 and 3 agrees with its report, with its own measure and with
`hocad quality` of the written file; the arrays have the documented shapes
and ordering; each MSH flavour reads back to the same mesh; the other
operations (linear mesh, elevate, convert, copy, split, optimize, repair,
write_vtu, picture) do what the C interface says.
SPDX-License-Identifier: GPL-2.0-or-later
"""
import json
import os
import subprocess

import numpy as np
import pytest

import hocad

from conftest import SCREW

CLI = os.environ["HOCAD_CLI"]
STAT_KEYS = ("elements", "order", "min", "max", "mean", "std", "tangled")


@pytest.fixture(scope="module", params=[2, 3])
def meshed(request, screw):
    """(order, mesh) of the screw, made by the whole pipeline."""
    mesh = screw.mesh(order=request.param)
    yield request.param, mesh
    mesh.close()


def cli_quality(path, tmp_path):
    out = tmp_path / "quality.json"
    subprocess.run([CLI, "quality", SCREW, str(path), "--json", str(out), "-q"], check=True)
    with open(out) as f:
        return json.load(f)["stages"][0]


def test_report_matches_mesh(meshed):
    order, mesh = meshed
    r = mesh.report
    assert r["command"] == "mesh"
    assert r["model"] == SCREW
    assert [s["name"] for s in r["stages"]] == ["linear", "high-order", "optimized"]
    last = r["stages"][-1]
    assert last["order"] == mesh.order == order
    assert last["elements"] == r["elements"] == mesh.num_elements > 100
    assert r["nodes"] == mesh.num_nodes == len(mesh.nodes)
    assert r["tangled"] == last["tangled"] == 0
    assert r["failed_faces"] == 0 and mesh.failed_faces == []
    assert r["findings"] == []
    quality = mesh.measure()
    # the report's per-element q is hoc_mesh_measure's, bit for bit
    assert np.array_equal(r["quality"], quality.q)
    for key in STAT_KEYS:
        assert quality.stats[key] == last[key], key
    assert quality.q.min() == last["min"]
    assert not quality.tangled.any()
    assert quality.q.dtype == float and quality.tangled.dtype == bool
    assert quality.q.shape == quality.tangled.shape == (mesh.num_elements,)
    # the optimiser raised the minimum over the raised mesh's
    assert last["min"] > r["stages"][1]["min"]
    assert "converged" in last and last["iterations"] >= 1


def test_cli_quality_of_written_file(meshed, tmp_path):
    order, mesh = meshed
    path = tmp_path / ("screw_p%d.msh" % order)
    mesh.write(path)
    stage = cli_quality(path, tmp_path)
    last = mesh.report["stages"][-1]
    assert stage["elements"] == last["elements"] and stage["order"] == order
    assert stage["tangled"] == last["tangled"]
    for key in ("min", "max", "mean", "std"):
        assert stage[key] == pytest.approx(last[key], rel=1e-9, abs=1e-12), key


def test_array_shapes_and_ordering(meshed, screw):
    order, mesh = meshed
    n, m, k = mesh.num_nodes, mesh.num_elements, (order + 1) * (order + 2) // 2
    assert mesh.nodes_per_element == k
    xyz, elements, faces = mesh.nodes, mesh.elements, mesh.element_faces
    assert xyz.shape == (n, 3) and xyz.dtype == float
    assert elements.shape == (m, k) and elements.dtype == np.intp
    assert faces.shape == (m,)
    assert elements.min() == 0 and elements.max() == n - 1
    assert len(np.unique(elements)) == n  # every node belongs to an element
    # the nodes lie within the model's box
    box = screw.bbox
    tol = 1e-9 * np.linalg.norm(box[3:] - box[:3])
    assert (xyz >= box[:3] - tol).all() and (xyz <= box[3:] + tol).all()
    dim, tag, param = mesh.node_entities()
    assert dim.shape == tag.shape == (n,) and param.shape == (n, 2)
    assert set(np.unique(dim)) == {0, 1, 2}
    assert (dim == 0).sum() == screw.num_vertices
    assert set(np.unique(faces)) <= set(tag[dim == 2])
    assert len(np.unique(faces)) == screw.num_faces
    # gmsh ordering: the corners first, then edge j's nodes (corner j to
    # j + 1), together nearest to the straight segment between those
    # corners (one node alone may bulge nearer another edge's segment
    # close to their shared corner, in a thin element)
    corners = xyz[elements[:, :3]]

    def to_segment(x, a, b):
        t = np.clip(np.einsum("ij,ij->i", x - a, b - a) / np.einsum("ij,ij->i", b - a, b - a), 0, 1)
        return np.linalg.norm(x - (a + t[:, None] * (b - a)), axis=1)

    for j in range(3):
        d = np.zeros((3, m))
        for i in range(order - 1):
            x = xyz[elements[:, 3 + (order - 1) * j + i]]
            for k in range(3):
                d[k] += to_segment(x, corners[:, k], corners[:, (k + 1) % 3])
        assert (d[j] < np.minimum(d[(j + 1) % 3], d[(j + 2) % 3])).all(), j
    # each edge of the closed surface is shared by two elements, listed
    # in opposite directions with its nodes reversed
    edges = {}
    for e in range(m):
        for j, (a, b) in enumerate(((0, 1), (1, 2), (2, 0))):
            inner = tuple(elements[e, 3 + (order - 1) * j: 3 + (order - 1) * (j + 1)])
            edges[(elements[e, a], elements[e, b])] = inner
    assert len(edges) == 3 * m
    for (a, b), inner in edges.items():
        assert edges[(b, a)] == inner[::-1]
    # face-interior nodes belong to the element's face
    if order >= 3:
        interior = elements[:, 3 * order:]
        assert (dim[interior] == 2).all()
        assert (tag[interior] == faces[:, None]).all()


def test_arrays_are_copies(meshed):
    _, mesh = meshed
    xyz = mesh.nodes
    xyz[:] = 0
    assert np.abs(mesh.nodes).max() > 0


FLAVOURS = [
    dict(version=41), dict(version=41, binary=True), dict(version=22),
    dict(version=22, binary=True), dict(version=41, parametric=True),
    dict(version=22, parametric=True), dict(version=22, binary=True, parametric=True),
]


@pytest.mark.parametrize("flavour", FLAVOURS, ids=lambda f: "-".join("%s%s" % kv for kv in f.items()))
def test_read_back(meshed, screw, flavour, tmp_path):
    order, mesh = meshed
    path = tmp_path / "back.msh"
    mesh.write(path, **flavour)
    with open(path, "rb") as f:
        head = f.read(64)
    assert head.startswith(b"$MeshFormat\n%s %d" % (b"4.1" if flavour["version"] == 41 else b"2.2",
                                                     1 if flavour.get("binary") else 0))
    back = screw.read_msh(path)
    try:
        assert back.path == os.fspath(path)
        assert (back.order, back.num_nodes, back.num_elements) == (order, mesh.num_nodes,
                                                                    mesh.num_elements)
        # elements in the same order, each with the same node positions (17 digits)
        assert np.array_equal(back.nodes[back.elements], mesh.nodes[mesh.elements])
        assert np.array_equal(back.element_faces, mesh.element_faces)
        dim0, tag0, _ = mesh.node_entities()
        dim1, tag1, _ = back.node_entities()
        assert np.array_equal(dim1[back.elements], dim0[mesh.elements])
        assert np.array_equal(tag1[back.elements], tag0[mesh.elements])
        q0, q1 = mesh.measure(), back.measure()
        assert np.allclose(q1.q, q0.q, rtol=1e-9, atol=1e-12)
        assert back.max_cad_distance < 1e-9
        report = back.quality_report()
        assert report["command"] == "quality" and report["mesh"] == os.fspath(path)
        assert [s["name"] for s in report["stages"]] == ["input"]
    finally:
        back.close()


def test_linear_elevate_convert_copy(screw):
    with screw.linear_mesh() as linear:
        assert linear.order == 1 and linear.num_nodes == len(np.unique(linear.elements))
        with linear.elevate(4, nodes="fekete") as p4:
            assert (p4.order, p4.nodeset, p4.num_elements) == (4, "fekete", linear.num_elements)
            # raising keeps the corners
            assert np.array_equal(p4.nodes[p4.elements[:, :3]], linear.nodes[linear.elements])
            with p4.convert("equispaced") as eq, p4.copy() as twin:
                assert eq.nodeset == "equispaced" and twin.nodeset == "fekete"
                assert np.array_equal(twin.nodes, p4.nodes)
                assert np.array_equal(eq.nodes[eq.elements[:, :3]], p4.nodes[p4.elements[:, :3]])
                assert not np.array_equal(eq.nodes, p4.nodes)
        # the pipeline from this linear mesh: the same corners
        with screw.mesh(order=2, linear=linear, optimize=False) as m2:
            assert np.array_equal(m2.nodes[m2.elements[:, :3]], linear.nodes[linear.elements])
            assert [s["name"] for s in m2.report["stages"]] == ["linear", "high-order"]


def test_optimize_in_place_and_repair(screw):
    with screw.mesh(order=3, optimize=False) as raised:
        before = raised.measure()
        events = []
        result = raised.optimize(progress=events.append)
        after = raised.measure()
        assert result["iterations"] == len(events) >= 1
        assert [e.kind for e in events] == ["iteration"] * len(events)
        assert events[-1].iteration["iteration"] == result["iterations"]
        assert result["tangled_final"] == after.stats["tangled"] == 0
        assert after.stats["min"] > before.stats["min"]
        assert result["objective_final"] < result["objective_initial"]
        assert isinstance(result["diagnostics"], dict)
        with raised.repair() as repaired:
            r = repaired.report
            assert r["command"] == "optimize"
            assert r["stages"][0]["name"] == "input"
            assert r["stages"][0]["min"] == pytest.approx(after.stats["min"], rel=1e-12)
            last = r["stages"][-1]
            assert last["name"] == "optimized" and last["tangled"] == r["tangled"] == 0
            assert last["objective"] <= last["objective_initial"]
            assert repaired.measure().stats["min"] == last["min"]
        # only the worst element and two rings around it may move
        worst = np.zeros(raised.num_elements, dtype=bool)
        worst[np.argmin(after.q)] = True
        nodes = raised.nodes
        raised.optimize(free_elements=worst, free_rings=2)
        moved = np.any(raised.nodes != nodes, axis=1)
        assert moved.sum() < raised.num_nodes / 2


def test_split(screw):
    with screw.mesh(order=2, optimize=False) as mesh:
        flags = np.zeros(mesh.num_elements, dtype=bool)
        flags[:3] = True
        child, pieces = mesh.split(flags)
        with child:
            assert (pieces[:3] == 4).all() and (pieces >= 1).all()
            assert child.num_elements == pieces.sum()
        with pytest.raises(ValueError):
            mesh.split(flags[:-1])


def test_vtu_and_picture(meshed, tmp_path):
    _, mesh = meshed
    q = mesh.measure().q
    mesh.write(tmp_path / "m.vtu")
    mesh.write_vtu(tmp_path / "q.vtu", quality=q)
    for name in ("m.vtu", "q.vtu"):
        data = (tmp_path / name).read_bytes()
        assert data.startswith(b"<?xml") and b'Name="quality"' in data
        assert b'NumberOfCells="%d"' % mesh.num_elements in data
    with pytest.raises(TypeError):
        mesh.write(tmp_path / "m.vtu", binary=True)
    with pytest.raises(ValueError):
        mesh.write_vtu(tmp_path / "bad.vtu", quality=q[:-1])
    assert not (tmp_path / "bad.vtu").exists()
    mesh.picture(tmp_path / "m.png", width=320, height=240, title="screw")
    with open(tmp_path / "m.png", "rb") as f:
        assert f.read(8) == b"\x89PNG\r\n\x1a\n"


def test_keep_stages_and_gradient(screw):
    with screw.mesh(order=2, keep_stages=True, check_gradient=True,
                    progress=lambda e: None) as mesh:
        r = mesh.report
        lin, raised = r["linear_mesh"], r["raised_mesh"]
        assert lin.order == 1 and raised.order == 2
        assert lin.num_elements == raised.num_elements == mesh.num_elements
        assert lin.measure().stats["min"] == r["stages"][0]["min"]
        assert raised.measure().stats["min"] == r["stages"][1]["min"]
        assert mesh.check_gradient(samples=10) < 1e-4
