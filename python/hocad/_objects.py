"""Models, meshes, reports, events and errors over libhocad (see the package
docstring). SPDX-License-Identifier: GPL-2.0-or-later
"""
import ctypes
import json
import numbers
import os
import weakref

import numpy as np

from . import _capi as C
from ._capi import lib


# ---------------------------------------------------------------------------
# Errors


class Error(Exception):
    """A libhocad call failed.

    ``str(error)`` is the library's one-line message (``hoc_last_error``);
    ``status`` is the ``hoc_status`` number (``hocad.ERR_IO``, ...) and
    ``status_name`` its short name ("invalid argument", ...).
    """

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status
        self.status_name = lib.hoc_status_string(status).decode()


class ArgumentError(Error, ValueError):
    """An argument the library refuses (HOC_ERR_ARGUMENT): also a ValueError."""


class Interrupted(Error):
    """The operation was cancelled (HOC_ERR_INTERRUPTED): a progress callback
    returned True, or the kernel's child process was interrupted. Nothing
    was returned or written."""


def _raise(status, what=""):
    message = lib.hoc_last_error().decode(errors="replace")
    if not message:
        message = lib.hoc_status_string(status).decode()
        if what:
            message = "%s: %s" % (what, message)
    cls = {C.ERR_ARGUMENT: ArgumentError, C.ERR_INTERRUPTED: Interrupted}.get(status, Error)
    raise cls(status, message)


def _check(status, what=""):
    if status != C.OK:
        _raise(status, what)


def _path(path):
    """A file name as the library takes it (bytes, in the file system's encoding)."""
    return os.fsencode(os.fspath(path))


# ---------------------------------------------------------------------------
# Events and cancellation


class Event:
    """An event of a running operation, passed to the ``progress`` callable.

    Attributes:
        kind: "progress" (a step starts), "stage" (a stage was measured),
            "iteration" (an optimiser sweep ended), "repair", "note",
            "warning" or "check" (the gradient check), as hoc_event_kind.
        message: one line of text.
        stage: for "stage", a dict of the stage (as in the report), else None.
        iteration: for "iteration", a dict with iteration, objective, min_q,
            tangled, moved, seconds and attempt, else None.
        value: for "check", the largest relative gradient difference.
    """

    __slots__ = ("kind", "message", "stage", "iteration", "value")

    def __init__(self, kind, message, stage=None, iteration=None, value=0.0):
        self.kind = kind
        self.message = message
        self.stage = stage
        self.iteration = iteration
        self.value = value

    def __repr__(self):
        return "Event(%r, %r)" % (self.kind, self.message)


def _struct_dict(s):
    out = {}
    for name, _ in s._fields_:
        v = getattr(s, name)
        if isinstance(v, ctypes.Structure):
            v = _struct_dict(v)
        elif isinstance(v, bytes):
            v = v.decode()
        out[name] = v
    return out


def _stats_dict(stats):
    return {
        "elements": stats.elements,
        "order": stats.order,
        "min": stats.min,
        "max": stats.max,
        "mean": stats.mean,
        "std": stats.std,
        "tangled": stats.tangled,
        "seconds": stats.seconds,
    }


def _stage_dict(stage):
    d = {"name": stage.name.decode()}
    d.update(_stats_dict(stage.stats))
    d["measure_seconds"] = d.pop("seconds")
    d["seconds"] = stage.seconds
    if stage.optimized:
        d.update(
            iterations=stage.iterations,
            converged=bool(stage.converged),
            objective_initial=stage.objective_initial,
            objective=stage.objective,
        )
    return d


class _Callback:
    """A Python callable behind a C callback: the exception it raises, or a
    KeyboardInterrupt (Ctrl-C) that arrives while the library runs Python
    code, cancels the operation and is raised again once the library has
    cleaned up; a true return value cancels with hocad.Interrupted."""

    def __init__(self, fn, convert):
        if fn is not None and not callable(fn):
            raise TypeError("progress must be callable, not %s" % type(fn).__name__)
        self.fn = fn
        self.convert = convert
        self.exception = None
        self.cancelled = False

    def __call__(self, *args):
        if self.exception is not None or self.cancelled:
            return 1
        try:
            if self.fn is not None and self.fn(self.convert(*args)):
                self.cancelled = True
                return 1
        except BaseException as e:  # KeyboardInterrupt too: cancel, raise it afterwards
            self.exception = e
            return 1
        return 0

    def finish(self, status, what=""):
        """Raise what the call's status and the callback say."""
        if self.exception is not None:
            e, self.exception = self.exception, None
            raise e
        _check(status, what)


def _event(_user, ev):
    e = ev.contents
    kind = C.EVENT_KINDS[e.kind] if 0 <= e.kind < len(C.EVENT_KINDS) else str(e.kind)
    return Event(
        kind,
        e.message.decode(errors="replace") if e.message else "",
        _stage_dict(e.stage.contents) if e.stage else None,
        _struct_dict(e.iteration.contents) if e.iteration else None,
        e.value,
    )


def _iteration_event(_user, it):
    d = _struct_dict(it.contents)
    return Event(
        "iteration",
        "sweep %d: objective %.6g, min q %.4f, %d tangled"
        % (d["iteration"], d["objective"], d["min_q"], d["tangled"]),
        iteration=d,
    )


def _linear_event(_user, stage, fraction):
    return Event("progress", "%s %.0f%%" % (stage.decode(errors="replace"), 100 * fraction),
                 value=fraction)


# ---------------------------------------------------------------------------
# Options


def _choice(name, value, table):
    if isinstance(value, str):
        if value not in table:
            raise ValueError("%s must be one of %s, not %r" % (name, ", ".join(table), value))
        return table[value]
    raise TypeError("%s must be a string (%s), not %s" % (name, ", ".join(table), type(value).__name__))


def _int(name, value):
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError("%s must be an integer, not %s" % (name, type(value).__name__))
    value = int(value)
    if not -(2**31) <= value < 2**31:
        raise ValueError("%s = %d is out of range" % (name, value))
    return value


def _flag(name, value):
    if not isinstance(value, (bool, np.bool_, numbers.Integral)) or value not in (0, 1):
        raise TypeError("%s must be True or False, not %r" % (name, value))
    return int(bool(value))


def _real(name, value):
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError("%s must be a number, not %s" % (name, type(value).__name__))
    return float(value)


# keyword -> (hoc_mesh_options field, converter)
_MESH_OPTIONS = {
    "order": ("order", _int),
    "nodes": ("nodeset", lambda n, v: _choice(n, v, C.NODESETS)),
    "measure": ("measure", lambda n, v: _choice(n, v, C.MEASURES)),
    "size": ("size", _real),
    "size_min": ("size_min", _real),
    "curvature": ("curvature", _real),
    "mesher_timeout": ("mesher_timeout", _real),
    "grading": ("grading", _flag),
    "optimize": ("optimize", _flag),
    "fix_curves": ("fix_curves", _flag),
    "max_iterations": ("max_iterations", _int),
    "refinements": ("refinements", _int),
    "keep_nodes": ("keep_nodes", _flag),
    "equispaced": ("equispaced", _flag),
    "keep_stages": ("keep_stages", _flag),
    "check_gradient": ("check_gradient", _flag),
    "repair_time": ("repair_time", _real),
}
# what hoc_mesh_model and hoc_mesh_repair use (each ignores the others)
_MODEL_OPTIONS = tuple(k for k in _MESH_OPTIONS if k != "keep_nodes")
_REPAIR_OPTIONS = ("measure", "optimize", "fix_curves", "max_iterations", "refinements",
                   "keep_nodes", "check_gradient", "repair_time")


def _mesh_options(options, allowed, callback):
    o = C.MeshOptions()
    lib.hoc_mesh_options_default(ctypes.byref(o))
    for key, value in options.items():
        if key not in allowed:
            raise TypeError("unexpected keyword argument %r (expected: %s)"
                            % (key, ", ".join(sorted(allowed))))
        field, convert = _MESH_OPTIONS[key]
        setattr(o, field, convert(key, value))
    o.event = C.EventFn(callback)
    return o


# ---------------------------------------------------------------------------
# Handles


class _Handle:
    """An object owning a libhocad handle: close() (or the end of a with
    block, or garbage collection) destroys it; using it afterwards raises
    ValueError."""

    _destroy = None

    def __init__(self):
        self._h = ctypes.c_void_p()

    @property
    def closed(self):
        """True once close() has been called."""
        return not self._h

    def _handle(self):
        if not self._h:
            raise ValueError("operation on a closed %s" % type(self).__name__)
        return self._h

    def close(self):
        """Destroy the handle (again: nothing)."""
        if self._h:
            type(self)._destroy(ctypes.byref(self._h))

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __del__(self):
        try:
            self.close()
        except Exception:
            pass


def _to_report_dict(report, files=None):
    """The report as a dict: the library's JSON, with "tangled",
    "failed_faces", "elements", "findings" and "quality" added."""
    text = ctypes.c_void_p()
    _check(lib.hoc_report_json(report, ctypes.byref(files) if files else None, ctypes.byref(text)))
    try:
        d = json.loads(ctypes.string_at(text.value).decode())
    finally:
        C.libc.free(text)
    d["tangled"] = lib.hoc_report_tangled(report)
    d["failed_faces"] = lib.hoc_report_num_failed_faces(report)
    d["elements"] = n = lib.hoc_report_num_elements(report)
    findings = []
    kind = ctypes.c_int()
    for i in range(lib.hoc_report_num_findings(report)):
        text = lib.hoc_report_finding(report, i, ctypes.byref(kind))
        findings.append({"kind": C.EVENT_KINDS[kind.value], "message": text.decode(errors="replace")})
    d["findings"] = findings
    q = lib.hoc_report_quality(report)
    d["quality"] = np.ctypeslib.as_array(q, shape=(n,)).copy() if q and n else np.zeros(0)
    return d


class Model(_Handle):
    """A CAD model (STEP .step/.stp, IGES .igs/.iges, OpenCASCADE .brep).

    ``Model(path)`` opens it (the kernel's import runs in a child process
    first, so a file that crashes it raises hocad.Error). The CAD kernel
    holds one model at a time: close a model (``close()``, or a ``with``
    block) before opening another. Closing a model closes its meshes.
    """

    _destroy = lib.hoc_model_destroy

    def __init__(self, path):
        super().__init__()
        self._meshes = weakref.WeakSet()
        self.path = os.fspath(path)
        _check(lib.hoc_model_open(_path(path), ctypes.byref(self._h)))

    def close(self):
        """Close the model and every mesh still open on it."""
        for m in list(getattr(self, "_meshes", ())):
            m.close()
        super().close()

    def __repr__(self):
        if self.closed:
            return "<hocad.Model %r (closed)>" % self.path
        return "<hocad.Model %r: %d faces, %d curves, %d vertices>" % (
            self.path, self.num_faces, self.num_curves, self.num_vertices)

    @property
    def num_faces(self):
        """Number of CAD faces."""
        return lib.hoc_model_num_faces(self._handle())

    @property
    def num_curves(self):
        """Number of CAD curves."""
        return lib.hoc_model_num_curves(self._handle())

    @property
    def num_vertices(self):
        """Number of CAD vertices."""
        return lib.hoc_model_num_vertices(self._handle())

    @property
    def bbox(self):
        """Bounding box, a (6,) array [xmin, ymin, zmin, xmax, ymax, zmax]."""
        b = np.zeros(6)
        lib.hoc_model_bbox(self._handle(), b.ctypes.data_as(C._DP))
        return b

    @property
    def tolerance(self):
        """The model's own tolerance (hoc_model_tolerance), a length."""
        t = ctypes.c_double()
        _check(lib.hoc_model_tolerance(self._handle(), ctypes.byref(t)))
        return t.value

    def _mesh(self, handle, report=None, path=None):
        m = Mesh._wrap(self, handle, report, path)
        self._meshes.add(m)
        return m

    def mesh(self, progress=None, linear=None, **options):
        """Mesh the model with hocad's pipeline (``hocad mesh``, hoc_mesh_model):
        a linear mesh, raised to the order, untangled and smoothed, with its
        repairs where elements stay tangled.

        Keyword arguments (hoc_mesh_options; unset ones keep its defaults):
            order (int, 1..15, default 3), nodes ("equispaced", "fekete",
            "warp-blend"), measure ("shape", "oddy"), size, size_min,
            curvature (floats, 0: chosen), mesher_timeout (seconds gmsh's
            mesher may take, 0: 300, < 0: no limit), grading (bool, default
            True: gmsh's mesh graded down to short curves and thin faces,
            and its edges swapped where that raises the smaller q),
            optimize (bool, default True),
            fix_curves (bool), max_iterations (int, 0: default),
            refinements (int, -1: default), equispaced (bool: convert the
            result to equispaced nodes), keep_stages (bool: the report's
            "linear_mesh" and "raised_mesh"), check_gradient (bool),
            repair_time (seconds the repairs after the first optimisation
            may take, 0: 4 x the time to it + 60 s, < 0: no bound),
            linear (a Mesh of this model whose corners are the linear mesh).
            progress: a callable taking an Event; returning True cancels.

        Returns the resulting Mesh; its ``report`` is the pipeline's report
        (a dict, see Mesh.report). Raises ArgumentError (a ValueError) for
        an option out of range, TypeError for an unknown keyword or a wrong
        type, Interrupted when cancelled, KeyboardInterrupt on Ctrl-C.
        """
        cb = _Callback(progress, _event)
        o = _mesh_options(options, _MODEL_OPTIONS, cb)
        if linear is not None:
            if not isinstance(linear, Mesh):
                raise TypeError("linear must be a hocad.Mesh")
            o.linear = linear._handle()
        mesh, report = ctypes.c_void_p(), ctypes.c_void_p()
        try:
            st = lib.hoc_mesh_model(self._handle(), ctypes.byref(o), ctypes.byref(mesh),
                                    ctypes.byref(report))
            cb.finish(st)
            files = C.ReportFiles(model=_path(self.path))
            return self._mesh(mesh, _report(self, report, files))
        except BaseException:
            lib.hoc_mesh_destroy(ctypes.byref(mesh))
            raise
        finally:
            lib.hoc_report_destroy(ctypes.byref(report))

    def linear_mesh(self, size=0.0, size_min=0.0, curvature=0.0, order=1, progress=None,
                    grading=True):
        """A linear (order-1) mesh of every face (hoc_mesh_generate_linear).

        size, size_min: maximum and minimum edge lengths (0: chosen);
        curvature: elements per 2 pi of curvature radius (0: chosen for
        ``order``, the order the mesh will be raised to). progress: a
        callable taking an Event ("progress", value the fraction done);
        returning True cancels. grading: False keeps gmsh's mesh as it is
        (not graded down to short curves and thin faces, no edge swapped).
        """
        cb = _Callback(progress, _linear_event)
        o = C.LinearOptions()
        lib.hoc_linear_options_default(ctypes.byref(o))
        o.size_max = _real("size", size)
        o.size_min = _real("size_min", size_min)
        o.curvature = _real("curvature", curvature)
        o.order = _int("order", order)
        o.grading = _flag("grading", grading)
        o.progress = C.ProgressFn(cb)
        mesh = ctypes.c_void_p()
        st = lib.hoc_mesh_generate_linear(self._handle(), ctypes.byref(o), ctypes.byref(mesh))
        cb.finish(st)
        return self._mesh(mesh)

    def read_msh(self, path):
        """Read a gmsh .msh mesh of this model (MSH 4.1 or 2.2, ASCII or
        binary, hoc_mesh_read_msh). Raises hocad.Error with status
        ERR_MISMATCH if it does not lie on the model."""
        mesh = ctypes.c_void_p()
        _check(lib.hoc_mesh_read_msh(self._handle(), _path(path), ctypes.byref(mesh)))
        return self._mesh(mesh, path=os.fspath(path))


def _report(model, report, files):
    d = _to_report_dict(report, files)
    for key, getter in (("linear_mesh", lib.hoc_report_linear), ("raised_mesh", lib.hoc_report_raised)):
        stage = getter(report)
        if stage:
            copy = ctypes.c_void_p()
            _check(lib.hoc_mesh_copy(stage, ctypes.byref(copy)))
            d[key] = model._mesh(copy)
    return d


class Quality:
    """The measure of every element of a mesh (Mesh.measure).

    Attributes:
        q: (elements,) float array, q = 1/eta of each element (0: tangled).
        tangled: (elements,) bool array.
        stats: dict of elements, order, min, max, mean, std, tangled and
            seconds (the paper's Table 2 row).
    """

    __slots__ = ("q", "tangled", "stats")

    def __init__(self, q, tangled, stats):
        self.q = q
        self.tangled = tangled
        self.stats = stats

    def __repr__(self):
        s = self.stats
        return "<hocad.Quality: %d elements, min q %.4f, mean q %.4f, %d tangled>" % (
            s["elements"], s["min"], s["mean"], s["tangled"])


class Mesh(_Handle):
    """A high-order triangle mesh on a Model (made by Model.mesh,
    Model.linear_mesh, Model.read_msh or a Mesh's methods).

    A mesh keeps its model alive. Arrays (``nodes``, ``elements``, ...) are
    new numpy arrays on each access. ``report`` is the report of the
    pipeline that made the mesh, or None.
    """

    _destroy = lib.hoc_mesh_destroy

    @classmethod
    def _wrap(cls, model, handle, report=None, path=None):
        m = cls.__new__(cls)
        _Handle.__init__(m)
        m._h = handle
        m.model = model
        m.report = report
        m.path = path
        return m

    def __init__(self, *args, **kwargs):
        raise TypeError("meshes come from Model.mesh, Model.linear_mesh, Model.read_msh "
                        "and Mesh methods")

    def __repr__(self):
        if self.closed:
            return "<hocad.Mesh (closed)>"
        return "<hocad.Mesh: order %d, %d elements, %d nodes>" % (
            self.order, self.num_elements, self.num_nodes)

    # properties -------------------------------------------------------------

    @property
    def order(self):
        """Element order p."""
        return lib.hoc_mesh_order(self._handle())

    @property
    def nodeset(self):
        """Reference node distribution: "equispaced", "fekete" or "warp-blend"."""
        k = lib.hoc_mesh_nodeset(self._handle())
        return {v: n for n, v in C.NODESETS.items()}[k]

    @property
    def num_nodes(self):
        """Number of nodes."""
        return lib.hoc_mesh_num_nodes(self._handle())

    @property
    def num_elements(self):
        """Number of triangles."""
        return lib.hoc_mesh_num_elements(self._handle())

    @property
    def nodes_per_element(self):
        """(p + 1)(p + 2) / 2."""
        p = self.order
        return (p + 1) * (p + 2) // 2

    @property
    def nodes(self):
        """Node positions, a (num_nodes, 3) float array."""
        x = np.empty((self.num_nodes, 3))
        _check(lib.hoc_mesh_nodes(self._handle(), x.ctypes.data_as(C._DP)))
        return x

    @property
    def elements(self):
        """Each element's nodes, a (num_elements, nodes_per_element) int
        array of 0-based node numbers in gmsh's ordering: the 3 corners, the
        p-1 nodes of each edge (0-1, 1-2, 2-0), then the interior nodes
        recursively (hoc_mesh_elements)."""
        e = np.empty((self.num_elements, self.nodes_per_element), dtype=np.uintp)
        _check(lib.hoc_mesh_elements(self._handle(), e.ctypes.data_as(C._SP)))
        return e.view(np.intp)

    @property
    def element_faces(self):
        """The CAD face tag of each element, a (num_elements,) int array."""
        f = np.empty(self.num_elements, dtype=np.intc)
        _check(lib.hoc_mesh_element_faces(self._handle(), f.ctypes.data_as(C._IP)))
        return f

    def node_entities(self):
        """Where each node lies on the CAD: (dim, tag, param), arrays of
        shapes (num_nodes,), (num_nodes,) and (num_nodes, 2): dim 0 on a CAD
        vertex, 1 on a curve, 2 inside a face; tag the kernel's tag of that
        entity; param (u, v) on the face, (t, 0) on the curve, (0, 0) at a
        vertex (hoc_mesh_node_entities)."""
        n = self.num_nodes
        dim = np.empty(n, dtype=np.intc)
        tag = np.empty(n, dtype=np.intc)
        par = np.empty((n, 2))
        _check(lib.hoc_mesh_node_entities(self._handle(), dim.ctypes.data_as(C._IP),
                                          tag.ctypes.data_as(C._IP), par.ctypes.data_as(C._DP)))
        return dim, tag, par

    @property
    def failed_faces(self):
        """Tags of the CAD faces the linear mesher could not mesh (a list)."""
        h = self._handle()
        return [lib.hoc_mesh_failed_face_tag(h, i) for i in range(lib.hoc_mesh_num_failed_faces(h))]

    @property
    def max_cad_distance(self):
        """Largest distance from a node to its CAD entity (hoc_mesh_max_cad_distance)."""
        d = ctypes.c_double()
        _check(lib.hoc_mesh_max_cad_distance(self._handle(), ctypes.byref(d)))
        return d.value

    @property
    def face_gap(self):
        """Largest distance between a curve or vertex node and a face around it
        (hoc_mesh_face_gap)."""
        return lib.hoc_mesh_face_gap(self._handle())

    # new meshes -------------------------------------------------------------

    def _new(self, fn, *args, report=None):
        out = ctypes.c_void_p()
        _check(fn(self._handle(), *args, ctypes.byref(out)))
        return self.model._mesh(out, report)

    def elevate(self, order, nodes="equispaced"):
        """A new mesh of order ``order`` (1..15) with the nodes of ``nodes``
        ("equispaced", "fekete", "warp-blend") placed in each face's
        parameters (hoc_mesh_elevate: the paper's step 2 from a linear mesh)."""
        return self._new(lib.hoc_mesh_elevate, _int("order", order),
                         _choice("nodes", nodes, C.NODESETS))

    raise_order = elevate

    def convert(self, nodes):
        """The same elements with another node distribution (hoc_mesh_convert)."""
        return self._new(lib.hoc_mesh_convert, _choice("nodes", nodes, C.NODESETS))

    def copy(self):
        """An exact copy on the same model (hoc_mesh_copy)."""
        return self._new(lib.hoc_mesh_copy)

    def split(self, elements, kind="red-green"):
        """Split the flagged elements in four and their neighbours so that the
        mesh stays conforming (hoc_mesh_split). elements: a (num_elements,)
        bool array; kind: "red-green" or "longest-edge". Returns (mesh,
        pieces), pieces a (num_elements,) array of how many elements each
        became."""
        flags = self._flags(elements, "elements")
        pieces = np.zeros(self.num_elements, dtype=np.uint8)
        out = ctypes.c_void_p()
        _check(lib.hoc_mesh_split(self._handle(), flags.ctypes.data_as(C._UP),
                                  _choice("kind", kind, C.SPLIT_KINDS), ctypes.byref(out),
                                  pieces.ctypes.data_as(C._UP)))
        return self.model._mesh(out), pieces

    def _flags(self, a, name):
        a = np.asarray(a)
        if a.shape != (self.num_elements,):
            raise ValueError("%s must have shape (%d,), not %s" % (name, self.num_elements, a.shape))
        return np.ascontiguousarray(a != 0, dtype=np.uint8)

    def repair(self, progress=None, **options):
        """Untangle and smooth this mesh with hocad's repairs (``hocad
        optimize``, hoc_mesh_repair): a new mesh, with its report. This
        mesh is not changed.

        Keyword arguments: measure, optimize, fix_curves, max_iterations,
        refinements, keep_nodes, check_gradient, repair_time (as Model.mesh),
        progress.
        """
        cb = _Callback(progress, _event)
        o = _mesh_options(options, _REPAIR_OPTIONS, cb)
        mesh, report = ctypes.c_void_p(), ctypes.c_void_p()
        try:
            st = lib.hoc_mesh_repair(self._handle(), ctypes.byref(o), ctypes.byref(mesh),
                                     ctypes.byref(report))
            cb.finish(st)
            files = C.ReportFiles(model=_path(self.model.path),
                                  mesh=_path(self.path) if self.path else None)
            return self.model._mesh(mesh, _report(self.model, report, files))
        except BaseException:
            lib.hoc_mesh_destroy(ctypes.byref(mesh))
            raise
        finally:
            lib.hoc_report_destroy(ctypes.byref(report))

    # in place ---------------------------------------------------------------

    def optimize(self, measure="shape", fix_curves=False, max_iterations=0, tolerance=0.0,
                 free_elements=None, free_rings=0, progress=None):
        """Untangle and smooth this mesh in place, the optimiser alone
        (hoc_mesh_optimize; Mesh.repair adds the pipeline's repairs).

        measure: "shape" or "oddy"; fix_curves: nodes on CAD curves stay;
        max_iterations: sweeps (0: 100); tolerance (0: 0.1); free_elements:
        None, or a (num_elements,) bool array of the elements whose nodes
        (and those within free_rings rings) may move; progress: a callable
        taking an Event per sweep, returning True cancels (the mesh is then
        left as the last sweep made it).

        Returns a dict of hoc_optimize_result (iterations, converged,
        objective_initial, objective_final, tangled_initial, tangled_final,
        ..., diagnostics).
        """
        cb = _Callback(progress, _iteration_event)
        o = C.OptimizeOptions()
        lib.hoc_optimize_options_default(ctypes.byref(o))
        o.measure = _choice("measure", measure, C.MEASURES)
        o.fix_curves = _flag("fix_curves", fix_curves)
        o.max_iterations = _int("max_iterations", max_iterations)
        o.tolerance = _real("tolerance", tolerance)
        o.free_rings = _int("free_rings", free_rings)
        if free_elements is not None:
            flags = self._flags(free_elements, "free_elements")
            o.free_elements = flags.ctypes.data_as(C._UP)
        o.progress = C.OptimizeProgressFn(cb)
        result = C.OptimizeResult()
        st = lib.hoc_mesh_optimize(self._handle(), ctypes.byref(o), ctypes.byref(result))
        cb.finish(st)
        d = _struct_dict(result)
        d["converged"] = bool(d["converged"])
        d["stopped_at_limit"] = bool(d["stopped_at_limit"])
        return d

    # measuring --------------------------------------------------------------

    def measure(self, measure="shape"):
        """Measure every element (hoc_mesh_measure, Definition 2 of the
        paper): a Quality with q and tangled arrays and the statistics."""
        n = self.num_elements
        q = np.empty(n)
        t = np.empty(n, dtype=np.uint8)
        stats = C.QualityStats()
        _check(lib.hoc_mesh_measure(self._handle(), _choice("measure", measure, C.MEASURES),
                                    q.ctypes.data_as(C._DP), t.ctypes.data_as(C._UP),
                                    ctypes.byref(stats)))
        return Quality(q, t.astype(bool), _stats_dict(stats))

    def quality_report(self, measure="shape"):
        """``hocad quality``: a report (dict) of one stage, "input", measuring
        this mesh (hoc_mesh_quality_report)."""
        report = ctypes.c_void_p()
        _check(lib.hoc_mesh_quality_report(self._handle(), _choice("measure", measure, C.MEASURES),
                                           ctypes.byref(report)))
        try:
            files = C.ReportFiles(model=_path(self.model.path),
                                  mesh=_path(self.path) if self.path else None)
            return _to_report_dict(report, files)
        finally:
            lib.hoc_report_destroy(ctypes.byref(report))

    def check_gradient(self, measure="shape", fix_curves=False, samples=20):
        """Largest relative difference between the optimiser's analytic
        gradient and central finite differences at up to ``samples`` nodes
        (hoc_mesh_check_gradient)."""
        err = ctypes.c_double()
        _check(lib.hoc_mesh_check_gradient(self._handle(), _choice("measure", measure, C.MEASURES),
                                           _flag("fix_curves", fix_curves), _int("samples", samples),
                                           ctypes.byref(err)))
        return err.value

    # files ------------------------------------------------------------------

    def write(self, path, version=41, binary=False, parametric=False, quality=None):
        """Write the mesh: a .vtu file (VTK Lagrange triangles with cell data
        quality, tangled and face; ``quality`` a (num_elements,) array of q,
        or None to measure it) when the name ends in .vtu, else a gmsh .msh
        file (``version`` 41 or 22, ``binary``, ``parametric``: with each
        node's parametric coordinates; hoc_mesh_write_msh_with). The file is
        written to a temporary name and renamed: nothing is left half
        written."""
        if os.fspath(path).lower().endswith(".vtu"):
            if (version, binary, parametric) != (41, False, False):
                raise TypeError("version, binary and parametric are .msh options")
            return self.write_vtu(path, quality)
        if quality is not None:
            raise TypeError("quality is a .vtu option")
        return self.write_msh(path, version, binary, parametric)

    def write_msh(self, path, version=41, binary=False, parametric=False):
        """Write a gmsh .msh file (see write)."""
        o = C.MshOptions()
        lib.hoc_msh_options_default(ctypes.byref(o))
        o.version = _int("version", version)
        o.binary = _flag("binary", binary)
        o.parametric = _flag("parametric", parametric)
        _check(lib.hoc_mesh_write_msh_with(self._handle(), _path(path), ctypes.byref(o)))

    def write_vtu(self, path, quality=None):
        """Write a VTK .vtu file (see write)."""
        q = None
        if quality is not None:
            q = np.ascontiguousarray(quality, dtype=float)
            if q.shape != (self.num_elements,):
                raise ValueError("quality must have shape (%d,), not %s" % (self.num_elements, q.shape))
        _check(lib.hoc_mesh_write_vtu(self._handle(), q.ctypes.data_as(C._DP) if q is not None else None,
                                      _path(path)))

    def picture(self, path, quality=None, width=0, height=0, view=None, zoom_worst=False,
                edges=True, transparent=False, title=None):
        """Draw the mesh coloured by q into a PNG file (hoc_picture_png):
        ``quality`` as in write_vtu (None: measured), width and height in
        pixels (0: 1600 x 1200), view a direction from the model to the eye
        (None: isometric)."""
        q = self.measure().q if quality is None else np.ascontiguousarray(quality, dtype=float)
        if q.shape != (self.num_elements,):
            raise ValueError("quality must have shape (%d,), not %s" % (self.num_elements, q.shape))
        o = C.PictureOptions()
        lib.hoc_picture_options_default(ctypes.byref(o))
        o.width, o.height = _int("width", width), _int("height", height)
        if view is not None:
            v = [_real("view", x) for x in view]
            if len(v) != 3:
                raise ValueError("view must have 3 components")
            o.view[:] = v
        o.zoom_worst = _flag("zoom_worst", zoom_worst)
        o.no_edges = 1 - _flag("edges", edges)
        o.transparent = _flag("transparent", transparent)
        meshes = (ctypes.c_void_p * 1)(self._handle())
        qs = (C._DP * 1)(q.ctypes.data_as(C._DP))
        titles = (ctypes.c_char_p * 1)(title.encode() if title else None)
        _check(lib.hoc_picture_png(_path(path), 1, meshes, qs, titles if title else None,
                                   ctypes.byref(o)))

    def close(self):
        """Destroy the mesh (its model stays open)."""
        super().close()
        model = getattr(self, "model", None)
        if model is not None:
            model._meshes.discard(self)


# ---------------------------------------------------------------------------
# Conveniences


def mesh_file(model, output=None, progress=None, **options):
    """Open a CAD file, mesh it (Model.mesh with these keyword arguments),
    write the result if ``output`` is given (.msh or .vtu by its name),
    close everything and return the report (a dict): what ``hocad mesh
    MODEL -o OUTPUT`` does. When cancelled nothing is written."""
    with Model(model) as m:
        with m.mesh(progress=progress, **options) as mesh:
            if output is not None:
                mesh.write(output)
            report = mesh.report
            for key in ("linear_mesh", "raised_mesh"):
                if key in report:
                    report.pop(key).close()
            return report


def format_table(report):
    """The report's stages as the rows of the paper's Table 2, as ``hocad
    mesh`` prints them (a string of lines)."""
    lines = ["%-11s %5s %9s %7s %7s %7s %7s %8s %8s" % (
        "stage", "order", "elements", "min q", "max q", "mean q", "std q", "tangled", "seconds")]
    for s in report["stages"]:
        lines.append("%-11s %5d %9d %7.4f %7.4f %7.4f %7.4f %8d %8.3f" % (
            s["name"], s["order"], s["elements"], s["min"], s["max"], s["mean"], s["std"],
            s["tangled"], s["seconds"]))
    for s in report["stages"]:
        if "iterations" in s:
            lines.append("%s: %d iterations, objective %.6g -> %.6g, %s" % (
                s["name"], s["iterations"], s["objective_initial"], s["objective"],
                "converged" if s["converged"] else "not converged"))
    return "\n".join(lines)
