#!/usr/bin/python3
"""Ten more models no one tuned hocad to, made with gmsh's OpenCASCADE
kernel, for bench/corpus.sh: faces that pinch, touch or nearly touch
(a crescent whose circles are tangent, two crossing pipes of equal
radius, a slot whose ends nearly touch the plate's side, a shaft with a
flat barely cut, a sphere on a cylinder of almost its radius, a horn
torus, a lens, a cone tangent to a sphere, three fillets of two radii at
a corner, a twisted open ribbon).

usage: /usr/bin/python3 bench/pinch_models.py DIR
  then: bench/corpus.sh DIR/*.step DIR/*.brep
Needs Debian's python3-gmsh, as bench/synthetic_models.py.
SPDX-License-Identifier: GPL-2.0-or-later
"""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from synthetic_models import curves_of, main  # noqa: E402


def crescent_plate(occ):
    """A disk minus a disk inside it, tangent at one point: its faces
    pinch to nothing there."""
    a = occ.addDisk(0, 0, 0, 10, 10)
    b = occ.addDisk(2, 0, 0, 8, 8)
    s, _ = occ.cut([(2, a)], [(2, b)])
    occ.extrude(s, 0, 0, 3)


def equal_tee(occ):
    """Two pipes of equal radius crossing: their intersection curves touch."""
    a = occ.addCylinder(-20, 0, 0, 40, 0, 0, 5)
    b = occ.addCylinder(0, 0, 0, 0, 0, 20, 5)
    occ.fuse([(3, a)], [(3, b)])


def d_shaft(occ):
    """A shaft with a flat barely cut: a face 2 wide, 20 long."""
    a = occ.addCylinder(0, 0, 0, 0, 0, 40, 5)
    b = occ.addBox(-10, 4.98, 10, 20, 10, 20)
    occ.cut([(3, a)], [(3, b)])


def horn_torus(occ):
    """A torus whose hole is almost closed."""
    occ.addTorus(0, 0, 0, 5, 4.9)


def lens(occ):
    """Two spheres' common part: a lens with a sharp rim."""
    a = occ.addSphere(0, 0, -40, 42)
    b = occ.addSphere(0, 0, 40, 42)
    occ.intersect([(3, a)], [(3, b)])


def slot_plate(occ):
    """A plate with a slot whose walls come within 0.05 of its side."""
    p = occ.addBox(0, 0, 0, 60, 30, 4)
    s = occ.addBox(15, 20, -1, 30, 9.95, 6)
    c1 = occ.addCylinder(15, 24.975, -1, 0, 0, 6, 4.975)
    c2 = occ.addCylinder(45, 24.975, -1, 0, 0, 6, 4.975)
    occ.cut([(3, p)], [(3, s), (3, c1), (3, c2)])


def ball_joint(occ):
    """A sphere on a cylinder of almost its radius."""
    a = occ.addSphere(0, 0, 10, 6)
    b = occ.addCylinder(0, 0, -10, 0, 0, 20, 5.9)
    occ.fuse([(3, a)], [(3, b)])


def fillet_corner(occ):
    """Three fillets meeting at a box's corner, one far smaller."""
    b = occ.addBox(0, 0, 0, 20, 20, 20)
    occ.synchronize()
    occ.fillet([b], curves_of(b)[:3], [3.0, 3.0, 0.4])


def twisted_ribbon(occ):
    """An open sheet lofted through segments turning by 0.5 rad."""
    wires = []
    for k in range(6):
        a = 0.5 * k
        p1 = occ.addPoint(-10 * math.cos(a), -10 * math.sin(a), 8.0 * k)
        p2 = occ.addPoint(10 * math.cos(a), 10 * math.sin(a), 8.0 * k)
        wires.append(occ.addWire([occ.addLine(p1, p2)]))
    occ.addThruSections(wires, makeSolid=False)


def cone_sphere(occ):
    """A cone and a sphere of its base's radius centred there."""
    occ.addSphere(0, 0, 20, 5)
    occ.addCone(0, 0, 0, 0, 0, 20, 0, 5)
    occ.fuse([(3, 1)], [(3, 2)])


MODELS = [
    ("crescent_plate.step", crescent_plate),
    ("equal_tee.step", equal_tee),
    ("d_shaft.brep", d_shaft),
    ("horn_torus.brep", horn_torus),
    ("lens.step", lens),
    ("slot_plate.step", slot_plate),
    ("ball_joint.brep", ball_joint),
    ("fillet_corner.step", fillet_corner),
    ("twisted_ribbon.step", twisted_ribbon),
    ("cone_sphere.brep", cone_sphere),
]


if __name__ == "__main__":
    main(MODELS, __doc__)
