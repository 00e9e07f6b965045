"""Other programs' readers open what hocad writes.

meshio (Debian 12's python3-meshio), gmsh 4.8's Python API (python3-gmsh)
and VTK 9's XML reader (python3-vtk9) read the .msh files (MSH 4.1 and 2.2,
ASCII and binary) and .vtu files hocad writes of a bundled model at orders
2, 3, 5 and 10, and must find the elements (node order included), the node
coordinates (to 1e-12 of the model's size), the classification and the
per-element q of a reference dump written from the library's own arrays by
tests/io_readers_data.c. gmsh also reads the files with parametric
coordinates (meshio does not: "parametric nodes not implemented"), and
the `hocad mesh` command's default .msh opens in meshio and gmsh.

Run by ctest (tests/CMakeLists.txt) with /usr/bin/python3, the interpreter
Debian's modules belong to; the environment names the helper, the CLI and
the models.
SPDX-License-Identifier: GPL-2.0-or-later
"""
import json
import os
import subprocess

import gmsh
import meshio
import numpy as np
import pytest
import vtk
from vtk.util.numpy_support import vtk_to_numpy

HELPER = os.environ["HOCAD_IO_READERS_DATA"]
CLI = os.environ["HOCAD_CLI"]
MODELS = os.environ["HOCAD_MODELS_DIR"]
MODEL = "screw.step"
ORDERS = (2, 3, 5, 10)
PLAIN = ("41", "41bin", "22", "22bin")  # p{P}_41.msh is the default (hoc_mesh_write_msh)
PARAMETRIC = ("41_param", "22_param")
RTOL = 1e-12


def nodes_per_triangle(p):
    return (p + 1) * (p + 2) // 2


class Reference:
    """A reference dump (format in tests/io_readers_data.c)."""

    def __init__(self, path):
        with open(path) as f:
            lines = f.read().split("\n")
        assert lines[0] == "hocad-reference 1"
        self.order = int(lines[1].split()[1])
        n = int(lines[2].split()[1])
        nodes = np.array([row.split() for row in lines[3 : 3 + n]], dtype=float)
        self.xyz = nodes[:, 0:3]
        self.dim = nodes[:, 3].astype(int)
        self.entity = nodes[:, 4].astype(int)
        self.param = nodes[:, 5:7]
        k = 3 + n
        e = int(lines[k].split()[1])
        rows = [row.split() for row in lines[k + 1 : k + 1 + e]]
        self.face = np.array([int(r[0]) for r in rows])
        self.q = np.array([float(r[1]) for r in rows])
        self.conn = np.array([r[2:] for r in rows], dtype=int)
        k += 1 + e
        nl = int(lines[k].split()[1])
        rows = [row.split() for row in lines[k + 1 : k + 1 + nl]]
        self.line_curve = np.array([int(r[0]) for r in rows])
        self.line_conn = np.array([r[1:] for r in rows], dtype=int).reshape(nl, self.order + 1)
        self.scale = float(np.abs(self.xyz).max())
        self._where = {tuple(x): i for i, x in enumerate(self.xyz.tolist())}
        assert len(self._where) == n, "the reference's nodes must lie apart"
        self._elements = {tuple(c): i for i, c in enumerate(self.conn.tolist())}
        self._lines = {tuple(c): i for i, c in enumerate(self.line_conn.tolist())}

    def node_map(self, xyz):
        """The reference node at each of a reader's points: the one with the
        same coordinates, else the only one within RTOL of the model's size.
        Every reference node must be found exactly once."""
        xyz = np.asarray(xyz, dtype=float)
        found = np.empty(len(xyz), dtype=int)
        for i, x in enumerate(xyz.tolist()):
            j = self._where.get(tuple(x))
            if j is None:
                near = np.flatnonzero(np.abs(self.xyz - x).max(axis=1) <= RTOL * self.scale)
                assert len(near) == 1, f"point {i} {x}: {len(near)} reference nodes within {RTOL}"
                j = int(near[0])
            found[i] = j
        assert len(xyz) == len(self.xyz), f"{len(xyz)} nodes read, {len(self.xyz)} written"
        assert np.array_equal(np.sort(found), np.arange(len(self.xyz))), "nodes read twice"
        assert np.abs(xyz - self.xyz[found]).max() <= RTOL * self.scale
        return found

    def element_map(self, conn, nmap):
        """The reference element of each of a reader's triangles (reader node
        indices): the same nodes in the same (gmsh) order, each once."""
        conn = np.asarray(conn, dtype=int)
        assert conn.shape == self.conn.shape, f"triangles {conn.shape}, written {self.conn.shape}"
        idx = np.array([self._elements.get(tuple(c), -1) for c in nmap[conn].tolist()])
        assert (idx >= 0).all(), f"{int((idx < 0).sum())} triangles are not the written ones"
        assert np.array_equal(np.sort(idx), np.arange(len(self.conn))), "triangles read twice"
        return idx

    def line_map(self, conn, nmap):
        conn = np.asarray(conn, dtype=int)
        assert conn.shape == self.line_conn.shape, f"lines {conn.shape}, written {self.line_conn.shape}"
        idx = np.array([self._lines.get(tuple(c), -1) for c in nmap[conn].tolist()])
        assert (idx >= 0).all() and np.array_equal(np.sort(idx), np.arange(len(self.line_conn)))
        return idx


@pytest.fixture(scope="session")
def data(tmp_path_factory):
    out = tmp_path_factory.mktemp("readers")
    subprocess.run([HELPER, os.path.join(MODELS, MODEL), str(out)] + [str(p) for p in ORDERS],
                   check=True)
    return out


@pytest.fixture(scope="session")
def refs(data):
    return {p: Reference(data / f"p{p}.ref") for p in ORDERS}


@pytest.fixture(scope="session")
def gmsh_api():
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    yield gmsh
    gmsh.finalize()


# meshio -------------------------------------------------------------------------


def meshio_blocks(mesh, cell_type):
    """The blocks of one cell type and their index in mesh.cells."""
    return [(k, b) for k, b in enumerate(mesh.cells) if b.type == cell_type]


@pytest.mark.parametrize("order", ORDERS)
@pytest.mark.parametrize("fmt", PLAIN)
def test_meshio(data, refs, order, fmt):
    ref = refs[order]
    mesh = meshio.read(data / f"p{order}_{fmt}.msh")
    nmap = ref.node_map(mesh.points)
    np_ = nodes_per_triangle(order)
    tris = meshio_blocks(mesh, f"triangle{np_}")
    lines = meshio_blocks(mesh, f"line{order + 1}")
    assert tris and lines, f"types read: {sorted({b.type for b in mesh.cells})}"
    geo = mesh.cell_data["gmsh:geometrical"]
    idx = ref.element_map(np.vstack([b.data for _, b in tris]), nmap)
    assert np.array_equal(np.concatenate([geo[k] for k, _ in tris]), ref.face[idx])
    lidx = ref.line_map(np.vstack([b.data for _, b in lines]), nmap)
    assert np.array_equal(np.concatenate([geo[k] for k, _ in lines]), ref.line_curve[lidx])
    on_vertex = np.flatnonzero(ref.dim == 0)
    if fmt.startswith("41"):
        # 4.1: every node's entity, from its node block
        dim_tags = mesh.point_data["gmsh:dim_tags"]
        assert np.array_equal(dim_tags[:, 0], ref.dim[nmap])
        assert np.array_equal(dim_tags[:, 1], ref.entity[nmap])
        assert "gmsh:physical" not in mesh.cell_data  # no physical groups
    else:
        # 2.2: physical 0 (none), a point element on each node at a CAD vertex
        assert all((p == 0).all() for p in mesh.cell_data["gmsh:physical"])
        verts = meshio_blocks(mesh, "vertex")
        vnodes = nmap[np.concatenate([b.data[:, 0] for _, b in verts])]
        assert np.array_equal(np.sort(vnodes), on_vertex)
        vtags = np.concatenate([geo[k] for k, _ in verts])
        assert np.array_equal(vtags, ref.entity[vnodes])
    kinds = {b.type for b in mesh.cells}
    assert kinds == {f"triangle{np_}", f"line{order + 1}"} | ({"vertex"} if fmt.startswith("22") else set())


@pytest.mark.parametrize("order", ORDERS)
def test_meshio_vtu(data, refs, order):
    """meshio reads the .vtu too (as cells of its type "VTK_LAGRANGE_TRIANGLE",
    not as its "triangle6", "triangle10"...: it keeps them, but writing them
    to another format is up to the user)."""
    ref = refs[order]
    mesh = meshio.read(data / f"p{order}.vtu")
    nmap = ref.node_map(mesh.points)
    (block,) = mesh.cells
    idx = ref.element_map(block.data, nmap)
    (q,) = mesh.cell_data["quality"]
    assert np.array_equal(q, ref.q[idx])


@pytest.mark.parametrize("fmt", PARAMETRIC)
def test_meshio_refuses_parametric_nodes(data, fmt):
    """Why parametric coordinates are opt-in: meshio cannot read them (4.1:
    "parametric nodes not implemented"; 2.2: it skips $ParametricNodes as
    an unknown section, then fails on the elements)."""
    try:
        mesh = meshio.read(data / f"p2_{fmt}.msh")
    except (Exception, SystemExit):  # meshio.read ends in sys.exit(1) when no reader succeeds
        return
    assert len(mesh.points) == 0, "meshio reads parametric files now: the default could change"


# gmsh --------------------------------------------------------------------------


def gmsh_read(api, path, order):
    """Nodes, triangles and lines as gmsh 4.8 reads them, with each node's
    entity and parameters and each element's entity."""
    api.clear()
    api.open(str(path))
    tri_type = api.model.mesh.getElementType("Triangle", order)
    name, dim, el_order, n_nodes, _, _ = api.model.mesh.getElementProperties(tri_type)
    assert (dim, el_order, n_nodes) == (2, order, nodes_per_triangle(order)), name
    line_type = api.model.mesh.getElementType("Line", order)
    tags, coords, _ = api.model.mesh.getNodes()
    row = {int(t): i for i, t in enumerate(tags)}
    out = {"xyz": coords.reshape(-1, 3), "dim": np.full(len(tags), -1),
           "entity": np.zeros(len(tags), dtype=int), "param": np.zeros((len(tags), 2))}
    element_entity = {}
    for d, t in api.model.getEntities():
        ntags, _, par = api.model.mesh.getNodes(d, t, includeBoundary=False,
                                                returnParametricCoord=True)
        for k, nt in enumerate(ntags):
            i = row[int(nt)]
            assert out["dim"][i] == -1, f"node {nt} on two entities"
            out["dim"][i], out["entity"][i] = d, t
            if len(par) == d * len(ntags) and d in (1, 2):
                out["param"][i, :d] = par[d * k : d * k + d]
        etypes, etags, _ = api.model.mesh.getElements(d, t)
        for et in etags:
            element_entity.update((int(e), t) for e in et)
    for key, etype in (("tri", tri_type), ("line", line_type)):
        etags, enodes = api.model.mesh.getElementsByType(etype)
        per = len(enodes) // max(len(etags), 1)
        out[key] = np.array([row[int(n)] for n in enodes], dtype=int).reshape(len(etags), per)
        out[key + "_entity"] = np.array([element_entity[int(e)] for e in etags])
    out["types"] = sorted(int(t) for t in api.model.mesh.getElementTypes())
    return out


@pytest.mark.parametrize("order", ORDERS)
@pytest.mark.parametrize("fmt", PLAIN + PARAMETRIC)
def test_gmsh(data, refs, gmsh_api, order, fmt):
    ref = refs[order]
    g = gmsh_read(gmsh_api, data / f"p{order}_{fmt}.msh", order)
    nmap = ref.node_map(g["xyz"])
    idx = ref.element_map(g["tri"], nmap)
    assert np.array_equal(g["tri_entity"], ref.face[idx])
    lidx = ref.line_map(g["line"], nmap)
    assert np.array_equal(g["line_entity"], ref.line_curve[lidx])
    # 4.1 says each node's entity; gmsh classifies 2.2 nodes by the elements
    assert np.array_equal(g["dim"], ref.dim[nmap])
    assert np.array_equal(g["entity"], ref.entity[nmap])
    expected_types = {gmsh_api.model.mesh.getElementType("Triangle", order),
                      gmsh_api.model.mesh.getElementType("Line", order)}
    if fmt.startswith("22"):
        expected_types.add(15)  # point elements
    assert set(g["types"]) == expected_types
    if fmt in PARAMETRIC:
        for d in (1, 2):
            on = ref.dim[nmap] == d
            assert np.array_equal(g["param"][on, :d], ref.param[nmap][on, :d])


# VTK ---------------------------------------------------------------------------


@pytest.mark.parametrize("order", ORDERS)
def test_vtk(data, refs, order):
    ref = refs[order]
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(data / f"p{order}.vtu"))
    reader.Update()
    grid = reader.GetOutput()
    nmap = ref.node_map(vtk_to_numpy(grid.GetPoints().GetData()))
    cells = grid.GetCells()
    offsets = vtk_to_numpy(cells.GetOffsetsArray())
    conn = vtk_to_numpy(cells.GetConnectivityArray())
    np_ = nodes_per_triangle(order)
    assert np.array_equal(np.diff(offsets), np.full(len(ref.conn), np_))
    types = vtk_to_numpy(grid.GetCellTypesArray())
    assert (types == vtk.VTK_LAGRANGE_TRIANGLE).all()
    idx = ref.element_map(conn.reshape(-1, np_), nmap)
    cell_data = grid.GetCellData()
    q = vtk_to_numpy(cell_data.GetArray("quality"))
    assert np.array_equal(q, ref.q[idx])  # the library's q, bit for bit
    assert np.array_equal(vtk_to_numpy(cell_data.GetArray("face")), ref.face[idx])
    assert np.array_equal(vtk_to_numpy(cell_data.GetArray("tangled")), (ref.q[idx] == 0).astype(np.uint8))
    # VTK's cell interpolates through the nodes as written: at the
    # parametric coordinates of point k it returns node k
    cell = grid.GetCell(0)
    pcoords = cell.GetParametricCoords()
    weights = [0.0] * np_
    for k in range(np_):
        x, sub = [0.0, 0.0, 0.0], vtk.reference(0)
        cell.EvaluateLocation(sub, pcoords[3 * k : 3 * k + 3], x, weights)
        assert np.abs(np.array(x) - ref.xyz[nmap[conn[k]]]).max() <= RTOL * ref.scale


def test_vtk_lagrange_triangle_is_gmsh_ordered(gmsh_api):
    """VTK's Lagrange triangle numbers its points as gmsh's triangle does, at
    every order MSH has (the VTU writer writes gmsh's order unpermuted)."""
    for p in range(1, 11):
        n = nodes_per_triangle(p)
        cell = vtk.vtkLagrangeTriangle() if p > 1 else vtk.vtkTriangle()
        cell.GetPointIds().SetNumberOfIds(n)
        cell.GetPoints().SetNumberOfPoints(n)
        if p > 1:
            cell.Initialize()
        pc = np.array(cell.GetParametricCoords()).reshape(-1, 3)[:, :2]
        etype = gmsh_api.model.mesh.getElementType("Triangle", p)
        local = gmsh_api.model.mesh.getElementProperties(etype)[4].reshape(-1, 2)
        assert pc.shape == local.shape and np.abs(pc - local).max() < 1e-12, f"order {p}"


# the command-line tool ------------------------------------------------------------


def sorted_rows(a):
    """The rows of a 2-D array in lexicographic order."""
    return a[np.lexsort(a.T[::-1])]


def test_cli_default_msh(tmp_path, gmsh_api):
    """`hocad mesh` writes a .msh meshio and gmsh open, with the elements of
    its .vtu."""
    msh, vtu, js = tmp_path / "cli.msh", tmp_path / "cli.vtu", tmp_path / "cli.json"
    subprocess.run([CLI, "mesh", os.path.join(MODELS, MODEL), "--order", "3", "-o", str(msh),
                    "--vtu", str(vtu), "--json", str(js), "-q"], check=True)
    elements = json.loads(js.read_text())["stages"][-1]["elements"]
    reader = vtk.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(vtu))
    reader.Update()
    grid = reader.GetOutput()
    vxyz = vtk_to_numpy(grid.GetPoints().GetData())
    vconn = vtk_to_numpy(grid.GetCells().GetConnectivityArray()).reshape(-1, 10)
    per_element = sorted_rows(vxyz[vconn].reshape(len(vconn), -1))
    mesh = meshio.read(msh)
    tri = np.vstack([b.data for b in mesh.cells if b.type == "triangle10"])
    assert len(tri) == elements == len(vconn)
    assert np.array_equal(sorted_rows(mesh.points[tri].reshape(len(tri), -1)), per_element)
    g = gmsh_read(gmsh_api, msh, 3)
    assert np.array_equal(sorted_rows(g["xyz"][g["tri"]].reshape(len(tri), -1)), per_element)
