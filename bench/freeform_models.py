#!/usr/bin/python3
"""Ten more models no one tuned hocad to, made with gmsh's OpenCASCADE
kernel, for bench/corpus.sh: free-form faces of the kinds IGES and STEP
exports hold (a B-spline sheet whose parametrisation pinches to a point
inside it, rational patches with uneven weights, control nets clustered
at one side, an ellipsoid and a stretched torus that become B-splines,
a cylinder holed across its seam, a sphere with many small holes, a thin
plate, a fragmented assembly with shared faces, a lofted duct whose
sections turn).

usage: /usr/bin/python3 bench/freeform_models.py DIR
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


def pinched_sheet(occ):
    """A bicubic sheet whose middle control row is one point, with a
    triple knot there: the iso-line through it maps to that point."""
    rows = []
    for i in range(7):
        x = 10.0 * (i - 3)
        half = 0.0 if i == 3 else 8.0 + 2.0 * abs(i - 3)
        rows.append([occ.addPoint(x, half * (2 * j / 4.0 - 1.0), 3.0 * math.sin(0.4 * i)
                                  + 0.5 * abs(i - 3) * math.sin(j))
                     for j in range(5)])
    pts = [rows[i][j] for j in range(5) for i in range(7)]
    occ.addBSplineSurface(pts, 7, degreeU=3, degreeV=3,
                          knotsU=[0, 1, 2], multiplicitiesU=[4, 3, 4],
                          knotsV=[0, 1, 2], multiplicitiesV=[4, 1, 4])


def weighted_patch(occ):
    """A rational biquadratic patch whose weights range over 1:20."""
    n = 5
    pts, weights = [], []
    for j in range(n):
        for i in range(n):
            pts.append(occ.addPoint(8.0 * i, 8.0 * j, 5.0 * math.cos(i + 0.7 * j)))
            weights.append(20.0 if (i + j) % 4 == 0 else 1.0)
    occ.addBSplineSurface(pts, n, degreeU=2, degreeV=2, weights=weights)


def clustered_net(occ):
    """A bicubic sheet whose control points crowd at one end: its
    parameters stretch 1:30 across it. Extruded into a slab."""
    n = 6
    xs = [30.0 * (k / (n - 1.0)) ** 3 for k in range(n)]
    pts = [occ.addPoint(xs[i], 6.0 * j, 2.0 * math.sin(0.3 * xs[i]) * math.cos(j))
           for j in range(n) for i in range(n)]
    s = occ.addBSplineSurface(pts, n, degreeU=3, degreeV=3)
    occ.extrude([(2, s)], 0, 0, 2)


def ellipsoid(occ):
    """A sphere scaled 3:1:0.5, which OpenCASCADE turns into a B-spline
    with poles, cut by a box."""
    s = occ.addSphere(0, 0, 0, 5)
    occ.dilate([(3, s)], 0, 0, 0, 3, 1, 0.5)
    b = occ.addBox(5, -10, -10, 20, 20, 20)
    occ.cut([(3, s)], [(3, b)])


def stretched_torus(occ):
    """A torus scaled 1:2:1 into a B-spline, with a hole through its tube."""
    t = occ.addTorus(0, 0, 0, 8, 3)
    occ.dilate([(3, t)], 0, 0, 0, 1, 2, 1)
    c = occ.addCylinder(8, 0, -10, 0, 0, 20, 1.5)
    occ.cut([(3, t)], [(3, c)])


def seam_holes(occ):
    """A pipe whose holes straddle its seam."""
    outer = occ.addCylinder(0, 0, 0, 0, 0, 30, 6)
    inner = occ.addCylinder(0, 0, -1, 0, 0, 32, 5)
    pipe, _ = occ.cut([(3, outer)], [(3, inner)])
    holes = [(3, occ.addCylinder(0, 0, z, 10, 0, 0, 2)) for z in (8, 15, 22)]
    holes.append((3, occ.addCylinder(0, 0, 15, 0, 10, 0, 1.5)))
    occ.cut(pipe, holes)


def holed_sphere(occ):
    """A sphere with twelve small holes, two of them near its poles."""
    s = occ.addSphere(0, 0, 0, 10)
    tools = []
    for k in range(12):
        theta = math.acos(1 - 2 * (k + 0.5) / 12.0)
        phi = k * math.pi * (3 - math.sqrt(5))
        d = (math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi), math.cos(theta))
        tools.append((3, occ.addCylinder(7 * d[0], 7 * d[1], 7 * d[2],
                                         6 * d[0], 6 * d[1], 6 * d[2], 1.2)))
    occ.cut([(3, s)], tools)


def thin_plate(occ):
    """A plate 40 by 30 and 0.05 thick with a round and a slotted hole."""
    p = occ.addBox(0, 0, 0, 40, 30, 0.05)
    h1 = occ.addCylinder(10, 15, -1, 0, 0, 2, 4)
    h2 = occ.addBox(22, 12, -1, 10, 1, 2)
    occ.cut([(3, p)], [(3, h1), (3, h2)])


def fragments(occ):
    """A box, a cylinder and a sphere fragmented: five solids that share
    their faces."""
    a = occ.addBox(0, 0, 0, 10, 10, 10)
    b = occ.addCylinder(5, 5, -3, 0, 0, 16, 3)
    c = occ.addSphere(10, 10, 10, 4)
    occ.fragment([(3, a)], [(3, b), (3, c)])


def turning_duct(occ):
    """A duct lofted through five rounded rectangles that turn and shrink."""
    wires = []
    for k in range(5):
        t = 0.3 * k
        w, h = 10 - 1.2 * k, 5 + 0.5 * k
        r = occ.addRectangle(-w / 2, -h / 2, 0, w, h, roundedRadius=1.0)
        occ.rotate([(2, r)], 0, 0, 0, 0, 0, 1, t)
        occ.translate([(2, r)], 0, 0, 12 * k)
        occ.synchronize()
        loop = [abs(c) for _, c in gmsh.model.getBoundary([(2, r)])]
        wires.append(occ.addWire(loop, checkClosed=True))
        occ.remove([(2, r)])
    occ.addThruSections(wires, makeSolid=True, makeRuled=False)


MODELS = [
    ("pinched_sheet.step", pinched_sheet),
    ("weighted_patch.step", weighted_patch),
    ("clustered_net.brep", clustered_net),
    ("ellipsoid.step", ellipsoid),
    ("stretched_torus.brep", stretched_torus),
    ("seam_holes.step", seam_holes),
    ("holed_sphere.brep", holed_sphere),
    ("thin_plate.step", thin_plate),
    ("fragments.brep", fragments),
    ("turning_duct.step", turning_duct),
]


if __name__ == "__main__":
    main(MODELS, __doc__)
