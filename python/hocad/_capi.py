"""The C interface of libhocad through ctypes: finding and loading the
library, the structures of include/hocad.h and the functions' prototypes.

Internal to the package: the public classes are in hocad._objects. The
structures here mirror include/hocad.h field by field; the package's tests
compare their sizes and offsets with the compiler's (python/tests/layout.c).
SPDX-License-Identifier: GPL-2.0-or-later
"""
import ctypes
import ctypes.util
import glob
import os

from ctypes import (
    CFUNCTYPE,
    POINTER,
    Structure,
    c_char_p,
    c_double,
    c_int,
    c_size_t,
    c_ubyte,
    c_void_p,
)

#: Version of the C interface this package is written for (MAJOR.MINOR must match).
API_VERSION = "0.1.0"

# hoc_status
OK = 0
ERR_ARGUMENT = 1
ERR_IO = 2
ERR_FORMAT = 3
ERR_CAD = 4
ERR_MESH = 5
ERR_MISMATCH = 6
ERR_MEMORY = 7
ERR_INTERRUPTED = 8
ERR_UNSUPPORTED = 9
ERR_INTERNAL = 10

NODESETS = {"equispaced": 0, "fekete": 1, "warp-blend": 2}
MEASURES = {"shape": 0, "oddy": 1}
EVENT_KINDS = ("progress", "stage", "iteration", "repair", "note", "warning", "check")
SPLIT_KINDS = {"red-green": 0, "longest-edge": 1}


class QualityStats(Structure):
    """hoc_quality_stats"""

    _fields_ = [
        ("elements", c_size_t),
        ("order", c_int),
        ("min", c_double),
        ("max", c_double),
        ("mean", c_double),
        ("std", c_double),
        ("tangled", c_size_t),
        ("seconds", c_double),
    ]


class MshOptions(Structure):
    """hoc_msh_options"""

    _fields_ = [("version", c_int), ("binary", c_int), ("parametric", c_int)]


ProgressFn = CFUNCTYPE(c_int, c_void_p, c_char_p, c_double)


class LinearOptions(Structure):
    """hoc_linear_options"""

    _fields_ = [
        ("size_max", c_double),
        ("size_min", c_double),
        ("curvature", c_double),
        ("order", c_int),
        ("face_size", POINTER(c_double)),
        ("progress", ProgressFn),
        ("progress_user", c_void_p),
        ("mesher_timeout", c_double),
        ("grading", c_int),
        ("keep_pinches", c_int),
    ]


class OptimizeIteration(Structure):
    """hoc_optimize_iteration"""

    _fields_ = [
        ("iteration", c_int),
        ("objective", c_double),
        ("min_q", c_double),
        ("tangled", c_size_t),
        ("moved", c_size_t),
        ("seconds", c_double),
        ("attempt", c_int),
    ]


OptimizeProgressFn = CFUNCTYPE(c_int, c_void_p, POINTER(OptimizeIteration))


class OptimizeOptions(Structure):
    """hoc_optimize_options"""

    _fields_ = [
        ("measure", c_int),
        ("fix_curves", c_int),
        ("max_iterations", c_int),
        ("tolerance", c_double),
        ("progress", OptimizeProgressFn),
        ("progress_user", c_void_p),
        ("free_elements", POINTER(c_ubyte)),
        ("free_rings", c_int),
    ]


class OptimizeDiagnostics(Structure):
    """hoc_optimize_diagnostics"""

    _fields_ = [
        ("second_attempt", c_int),
        ("exact_phase", c_int),
        ("protected_run", c_int),
        ("polished", c_size_t),
        ("fragile", c_size_t),
    ]


class OptimizeResult(Structure):
    """hoc_optimize_result"""

    _fields_ = [
        ("iterations", c_int),
        ("converged", c_int),
        ("objective_initial", c_double),
        ("objective_final", c_double),
        ("tangled_initial", c_size_t),
        ("tangled_final", c_size_t),
        ("best_iteration", c_int),
        ("stopped_at_limit", c_int),
        ("free_nodes", c_size_t),
        ("seconds", c_double),
        ("diagnostics", OptimizeDiagnostics),
    ]


class Stage(Structure):
    """hoc_stage"""

    _fields_ = [
        ("name", c_char_p),
        ("stats", QualityStats),
        ("seconds", c_double),
        ("optimized", c_int),
        ("iterations", c_int),
        ("converged", c_int),
        ("objective_initial", c_double),
        ("objective", c_double),
    ]


class Event(Structure):
    """hoc_event"""

    _fields_ = [
        ("kind", c_int),
        ("message", c_char_p),
        ("stage", POINTER(Stage)),
        ("iteration", POINTER(OptimizeIteration)),
        ("value", c_double),
    ]


EventFn = CFUNCTYPE(c_int, c_void_p, POINTER(Event))


class MeshOptions(Structure):
    """hoc_mesh_options"""

    _fields_ = [
        ("order", c_int),
        ("nodeset", c_int),
        ("measure", c_int),
        ("size", c_double),
        ("size_min", c_double),
        ("curvature", c_double),
        ("linear", c_void_p),
        ("optimize", c_int),
        ("fix_curves", c_int),
        ("max_iterations", c_int),
        ("refinements", c_int),
        ("keep_nodes", c_int),
        ("equispaced", c_int),
        ("keep_stages", c_int),
        ("check_gradient", c_int),
        ("event", EventFn),
        ("event_user", c_void_p),
        ("mesher_timeout", c_double),
        ("grading", c_int),
        ("repair_time", c_double),
    ]


class ReportFiles(Structure):
    """hoc_report_files"""

    _fields_ = [
        ("model", c_char_p),
        ("mesh", c_char_p),
        ("model_seconds", c_double),
        ("write_seconds", c_double),
    ]


class PictureOptions(Structure):
    """hoc_picture_options"""

    _fields_ = [
        ("width", c_int),
        ("height", c_int),
        ("view", c_double * 3),
        ("zoom_worst", c_int),
        ("no_edges", c_int),
        ("transparent", c_int),
    ]


#: The structures above by their C names (for the layout test).
STRUCTURES = {
    "hoc_quality_stats": QualityStats,
    "hoc_msh_options": MshOptions,
    "hoc_linear_options": LinearOptions,
    "hoc_optimize_iteration": OptimizeIteration,
    "hoc_optimize_options": OptimizeOptions,
    "hoc_optimize_diagnostics": OptimizeDiagnostics,
    "hoc_optimize_result": OptimizeResult,
    "hoc_stage": Stage,
    "hoc_event": Event,
    "hoc_mesh_options": MeshOptions,
    "hoc_report_files": ReportFiles,
    "hoc_picture_options": PictureOptions,
}

_P = c_void_p  # an opaque handle (hoc_model *, hoc_mesh *, hoc_report *)
_PP = POINTER(c_void_p)  # its address (hoc_mesh **)
_DP = POINTER(c_double)
_SP = POINTER(c_size_t)
_IP = POINTER(c_int)
_UP = POINTER(c_ubyte)

# name: (restype, argtypes)
_PROTOTYPES = {
    "hoc_last_error": (c_char_p, []),
    "hoc_status_string": (c_char_p, [c_int]),
    "hoc_version": (c_char_p, []),
    "hoc_model_open": (c_int, [c_char_p, _PP]),
    "hoc_model_destroy": (None, [_PP]),
    "hoc_model_num_faces": (c_int, [_P]),
    "hoc_model_num_curves": (c_int, [_P]),
    "hoc_model_num_vertices": (c_int, [_P]),
    "hoc_model_bbox": (None, [_P, _DP]),
    "hoc_model_tolerance": (c_int, [_P, _DP]),
    "hoc_linear_options_default": (None, [POINTER(LinearOptions)]),
    "hoc_mesh_generate_linear": (c_int, [_P, POINTER(LinearOptions), _PP]),
    "hoc_mesh_elevate": (c_int, [_P, c_int, c_int, _PP]),
    "hoc_mesh_convert": (c_int, [_P, c_int, _PP]),
    "hoc_mesh_copy": (c_int, [_P, _PP]),
    "hoc_mesh_read_msh": (c_int, [_P, c_char_p, _PP]),
    "hoc_msh_options_default": (None, [POINTER(MshOptions)]),
    "hoc_mesh_write_msh_with": (c_int, [_P, c_char_p, POINTER(MshOptions)]),
    "hoc_mesh_write_vtu": (c_int, [_P, _DP, c_char_p]),
    "hoc_mesh_destroy": (None, [_PP]),
    "hoc_mesh_num_elements": (c_size_t, [_P]),
    "hoc_mesh_num_nodes": (c_size_t, [_P]),
    "hoc_mesh_order": (c_int, [_P]),
    "hoc_mesh_nodeset": (c_int, [_P]),
    "hoc_mesh_num_failed_faces": (c_int, [_P]),
    "hoc_mesh_failed_face_tag": (c_int, [_P, c_int]),
    "hoc_mesh_max_cad_distance": (c_int, [_P, _DP]),
    "hoc_mesh_face_gap": (c_double, [_P]),
    "hoc_mesh_nodes": (c_int, [_P, _DP]),
    "hoc_mesh_node_entities": (c_int, [_P, _IP, _IP, _DP]),
    "hoc_mesh_elements": (c_int, [_P, _SP]),
    "hoc_mesh_element_faces": (c_int, [_P, _IP]),
    "hoc_mesh_measure": (c_int, [_P, c_int, _DP, _UP, POINTER(QualityStats)]),
    "hoc_mesh_split": (c_int, [_P, _UP, c_int, _PP, _UP]),
    "hoc_optimize_options_default": (None, [POINTER(OptimizeOptions)]),
    "hoc_mesh_optimize": (c_int, [_P, POINTER(OptimizeOptions), POINTER(OptimizeResult)]),
    "hoc_mesh_check_gradient": (c_int, [_P, c_int, c_int, c_int, _DP]),
    "hoc_mesh_options_default": (None, [POINTER(MeshOptions)]),
    "hoc_mesh_model": (c_int, [_P, POINTER(MeshOptions), _PP, _PP]),
    "hoc_mesh_repair": (c_int, [_P, POINTER(MeshOptions), _PP, _PP]),
    "hoc_mesh_quality_report": (c_int, [_P, c_int, _PP]),
    "hoc_report_destroy": (None, [_PP]),
    "hoc_report_num_stages": (c_size_t, [_P]),
    "hoc_report_tangled": (c_size_t, [_P]),
    "hoc_report_refinements": (c_int, [_P]),
    "hoc_report_remeshings": (c_int, [_P]),
    "hoc_report_num_failed_faces": (c_int, [_P]),
    "hoc_report_num_elements": (c_size_t, [_P]),
    "hoc_report_num_nodes": (c_size_t, [_P]),
    "hoc_report_seconds": (c_double, [_P]),
    "hoc_report_quality": (_DP, [_P]),
    "hoc_report_num_findings": (c_size_t, [_P]),
    "hoc_report_finding": (c_char_p, [_P, c_size_t, _IP]),
    "hoc_report_linear": (c_void_p, [_P]),
    "hoc_report_raised": (c_void_p, [_P]),
    # the text is the library's malloc'd memory: kept as an address to free()
    "hoc_report_json": (c_int, [_P, POINTER(ReportFiles), POINTER(c_void_p)]),
    "hoc_picture_options_default": (None, [POINTER(PictureOptions)]),
    "hoc_picture_png": (
        c_int,
        [c_char_p, c_int, POINTER(c_void_p), POINTER(_DP), POINTER(c_char_p), POINTER(PictureOptions)],
    ),
}


def _candidates():
    """Where libhocad is looked for, in order (see hocad's docstring)."""
    here = os.path.dirname(os.path.abspath(__file__))
    env = os.environ.get("HOCAD_LIBRARY")
    if env:
        # the caller's choice only: a wrong path is an error, not a fallback
        return [env]
    found = sorted(glob.glob(os.path.join(here, "libhocad.so*")))
    try:
        from . import _install  # written by cmake --install

        found.append(os.path.normpath(os.path.join(here, _install.LIBRARY)))
    except ImportError:
        pass
    # a checkout: python/hocad -> <repo>/build/libhocad.so
    found.append(os.path.join(os.path.dirname(os.path.dirname(here)), "build", "libhocad.so"))
    system = ctypes.util.find_library("hocad")
    if system:
        found.append(system)
    return found


def _load():
    tried = []
    for path in _candidates():
        if os.sep in path and not os.path.exists(path):
            tried.append(path + " (no such file)")
            continue
        try:
            return ctypes.CDLL(path), path
        except OSError as e:
            tried.append("%s (%s)" % (path, e))
    raise ImportError(
        "hocad: cannot load libhocad.so; tried: %s. Build it (cmake --build build), "
        "install it (cmake --install), or name it in HOCAD_LIBRARY" % "; ".join(tried)
    )


lib, LIBRARY_PATH = _load()
for _name, (_res, _args) in _PROTOTYPES.items():
    _f = getattr(lib, _name)
    _f.restype = _res
    _f.argtypes = _args

_version = lib.hoc_version().decode()
if _version.split(".")[:2] != API_VERSION.split(".")[:2]:
    raise ImportError(
        "hocad: %s is version %s, this package is written for %s"
        % (LIBRARY_PATH, _version, API_VERSION)
    )
VERSION = _version

# free() of the C library libhocad allocates with (its JSON text)
libc = ctypes.CDLL(ctypes.util.find_library("c"))
libc.free.restype = None
libc.free.argtypes = [c_void_p]
