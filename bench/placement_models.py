#!/usr/bin/python3
"""Ten more models no one tuned hocad to, made with gmsh's OpenCASCADE
kernel, for bench/corpus.sh: ordinary parts as assemblies and exports
place them (far from the origin, mirrored, in metres and in kilometres'
worth of millimetres, stretched unevenly, copied round an axis), a model
mixing sizes 1000:1, a box with a plate inside it (a face on three
solids' sides), a sheet swept from a spline, and a profile revolved
three quarters of a turn.

usage: /usr/bin/python3 bench/placement_models.py DIR
  then: bench/corpus.sh DIR/*.step DIR/*.brep
Needs Debian's python3-gmsh, as bench/synthetic_models.py.
SPDX-License-Identifier: GPL-2.0-or-later
"""
import math
import os
import sys

import gmsh

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from synthetic_models import main  # noqa: E402


def bracket(occ):
    """An L bracket with a hole and a rounded inner edge: its volume."""
    a = occ.addBox(0, 0, 0, 40, 20, 5)
    b = occ.addBox(0, 0, 0, 5, 20, 30)
    v = occ.fuse([(3, a)], [(3, b)])[0][0][1]
    h = occ.addCylinder(25, 10, -1, 0, 0, 7, 4)
    v = occ.cut([(3, v)], [(3, h)])[0][0][1]
    return v


def far_offset(occ):
    """The bracket 10^5 from the origin, as an assembly places a part."""
    occ.translate([(3, bracket(occ))], 1.0e5, 2.0e5, -5.0e4)


def mirrored(occ):
    """The bracket mirrored: a left-handed copy (faces reversed)."""
    occ.mirror([(3, bracket(occ))], 1, 0.3, 0, 2)


def in_metres(occ):
    """The bracket in metres: 0.04 across."""
    occ.dilate([(3, bracket(occ))], 0, 0, 0, 1e-3, 1e-3, 1e-3)


def magnified(occ):
    """The bracket a thousand times larger: 40 000 across."""
    occ.dilate([(3, bracket(occ))], 0, 0, 0, 1e3, 1e3, 1e3)


def stretched(occ):
    """The bracket stretched 1:3:0.5 (its cylinder becomes a B-spline)."""
    occ.dilate([(3, bracket(occ))], 0, 0, 0, 1.0, 3.0, 0.5)


def round_copies(occ):
    """Six brackets copied round an axis, each turned 60 degrees."""
    v = bracket(occ)
    for k in range(1, 6):
        (c,) = occ.copy([(3, v)])
        occ.rotate([c], -20, 0, 0, 0, 0, 1, k * math.pi / 3)


def size_mix(occ):
    """A box 1000 across and a sphere of radius 0.5 beside it."""
    occ.addBox(0, 0, 0, 1000, 600, 400)
    occ.addSphere(1010, 300, 200, 0.5)


def plate_in_box(occ):
    """A box with a plate inside it, fragmented: the plate's faces are
    sides of both halves of the box."""
    box = occ.addBox(0, 0, 0, 20, 20, 20)
    plate = occ.addRectangle(-5, -5, 8, 30, 30)
    occ.rotate([(2, plate)], 10, 10, 8, 1, 0.2, 0, 0.3)
    occ.fragment([(3, box)], [(2, plate)])
    occ.synchronize()
    outside = [t for t in gmsh.model.getEntities(2)
               if gmsh.model.getBoundingBox(*t)[0] < -1]
    occ.remove(outside, recursive=True)


def swept_spline(occ):
    """A wavy spline profile swept along a straight line: a surface of
    linear extrusion, open at both ends."""
    pts = [occ.addPoint(4.0 * i, 3.0 * math.sin(0.9 * i), 0) for i in range(9)]
    c = occ.addBSpline(pts)
    occ.extrude([(1, c)], 0, 2.0, 25.0)


def three_quarter_turn(occ):
    """A spline profile revolved through 270 degrees about an axis it
    touches at one end: open revolution ends and a pole."""
    pts = [occ.addPoint(0, 0, 0), occ.addPoint(4, 0, 1), occ.addPoint(6, 0, 5),
           occ.addPoint(3, 0, 9), occ.addPoint(5, 0, 12)]
    occ.revolve([(1, occ.addBSpline(pts))], 0, 0, 0, 0, 0, 1, 1.5 * math.pi)


MODELS = [
    ("far_offset.step", far_offset),
    ("mirrored.brep", mirrored),
    ("in_metres.step", in_metres),
    ("magnified.step", magnified),
    ("stretched.brep", stretched),
    ("round_copies.step", round_copies),
    ("size_mix.brep", size_mix),
    ("plate_in_box.brep", plate_in_box),
    ("swept_spline.step", swept_spline),
    ("three_quarter_turn.brep", three_quarter_turn),
]


if __name__ == "__main__":
    main(MODELS, __doc__)
