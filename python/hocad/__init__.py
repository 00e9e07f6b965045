"""hocad: valid high-order (curved) triangle surface meshes on CAD models.

Python interface to libhocad (ctypes, numpy arrays in and out). A CAD model
(STEP, IGES, BREP) is meshed with linear triangles, raised to order p in
each face's parametric space, measured with the Jacobian-based distortion
of the paper (Gargallo-Peiro, Roca, Peraire, Sarrate, High-order mesh
generation on CAD geometries), untangled and smoothed over the nodes'
parametric coordinates, so every node stays on the CAD::

    import hocad

    with hocad.Model("examples/models/screw.step") as model:
        mesh = model.mesh(order=3)              # the whole pipeline
        print(hocad.format_table(mesh.report))  # the paper's Table 2 rows
        quality = mesh.measure()                # q and tangled per element
        print(quality.q.min(), quality.tangled.sum())
        xyz, tri = mesh.nodes, mesh.elements    # (n, 3) floats, (m, 10) ints
        mesh.write("screw_p3.msh")              # or .vtu; version=22, binary=True

    # or in one call, as ``hocad mesh`` does (the report as a dict):
    report = hocad.mesh_file("examples/models/screw.step", order=3, output="screw_p3.msh")

Objects:
    Model   a CAD model: mesh(**options), linear_mesh(), read_msh(path)
    Mesh    a mesh: arrays (nodes, elements, element_faces, node_entities()),
            elevate, convert, copy, split, repair, optimize, measure,
            quality_report, write (.msh / .vtu), picture (.png)
    Quality what Mesh.measure returns (q, tangled, stats)
    Event   what a ``progress`` callable receives

Models and meshes own their C handles: close() them, use ``with``, or let
them be garbage-collected. A mesh keeps its model alive; the CAD kernel
holds one model at a time, so close a model before opening the next.

Errors raise hocad.Error (its message is the library's, ``status`` the
hoc_status number); an argument the library refuses raises ArgumentError,
also a ValueError; an unknown keyword or a wrong type raises TypeError. A
``progress`` callable receives an Event for each step; returning True
cancels the run with hocad.Interrupted, and Ctrl-C cancels it with
KeyboardInterrupt: the library cleans up and nothing is written.

The library is found, in order: the file HOCAD_LIBRARY names; a
libhocad.so* inside the package (``pip install``); the library ``cmake
--install`` put beside the package; the build tree of a checkout
(<repo>/build/libhocad.so, for PYTHONPATH=<repo>/python); the system's
(ldconfig). ``hocad.LIBRARY_PATH`` says which was loaded.

SPDX-License-Identifier: GPL-2.0-or-later
"""
from ._capi import (
    API_VERSION as __version__,
    LIBRARY_PATH,
    VERSION as library_version,
    OK,
    ERR_ARGUMENT,
    ERR_IO,
    ERR_FORMAT,
    ERR_CAD,
    ERR_MESH,
    ERR_MISMATCH,
    ERR_MEMORY,
    ERR_INTERRUPTED,
    ERR_UNSUPPORTED,
    ERR_INTERNAL,
)
from ._objects import (
    ArgumentError,
    Error,
    Event,
    Interrupted,
    Mesh,
    Model,
    Quality,
    format_table,
    mesh_file,
)

#: Highest element order the library builds and measures (HOC_MAX_ORDER).
MAX_ORDER = 15

__all__ = [
    "Model", "Mesh", "Quality", "Event", "Error", "ArgumentError", "Interrupted",
    "mesh_file", "format_table", "LIBRARY_PATH", "library_version", "MAX_ORDER",
    "OK", "ERR_ARGUMENT", "ERR_IO", "ERR_FORMAT", "ERR_CAD", "ERR_MESH", "ERR_MISMATCH",
    "ERR_MEMORY", "ERR_INTERRUPTED", "ERR_UNSUPPORTED", "ERR_INTERNAL",
]
