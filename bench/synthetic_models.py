#!/usr/bin/python3
"""Models no one tuned hocad to, made with gmsh's OpenCASCADE kernel, for
bench/corpus.sh: shapes of the classes real models have (fillets, trimmed
B-spline faces, poles on revolved profiles and cones, lofted blades, swept
pipes, booleans with many small faces, assemblies of overlapping solids, a
wing-body in metres, open surfaces) in STEP and BREP.

usage: /usr/bin/python3 bench/synthetic_models.py DIR
  then: bench/corpus.sh DIR/*.step DIR/*.brep
Needs Debian's python3-gmsh (it belongs to /usr/bin/python3). gmsh cannot
write IGES, so there is no IGES model here. The random bumps are seeded:
the same files every time.
SPDX-License-Identifier: GPL-2.0-or-later
"""
import math
import os
import random
import sys

import gmsh


def curves_of(volume):
    """The curves bounding a volume."""
    faces = gmsh.model.getBoundary([(3, volume)], oriented=False)
    return sorted({abs(t) for f in faces for _, t in gmsh.model.getBoundary([f], oriented=False)})


def make(occ, name, build, out):
    """build() the shapes of one model and write them to out/name."""
    gmsh.clear()
    build(occ)
    occ.synchronize()
    # OpenCASCADE's STEP writer prints its statistics on stdout itself
    sys.stdout.flush()
    saved = os.dup(1)
    null = os.open(os.devnull, os.O_WRONLY)
    os.dup2(null, 1)
    try:
        gmsh.write(os.path.join(out, name))
    finally:
        os.dup2(saved, 1)
        os.close(null)
        os.close(saved)
    print(name)


def fillet_box(occ):
    """A box, every edge filleted, two holes through it."""
    b = occ.addBox(0, 0, 0, 40, 25, 10)
    occ.synchronize()
    f = occ.fillet([b], curves_of(b), [2.0])
    c1 = occ.addCylinder(20, 12.5, -1, 0, 0, 12, 5)
    c2 = occ.addCylinder(8, 6, 5, 0, 10, 0, 3)
    occ.cut(f, [(3, c1), (3, c2)])


def thin_fillets(occ):
    """A box whose fillets are 30 times thinner than its edges."""
    b = occ.addBox(0, 0, 0, 30, 20, 8)
    occ.synchronize()
    occ.fillet([b], curves_of(b), [0.3])


def twisted_loft(occ, sections=5, step=20, turn=0.35):
    """A solid lofted through ellipses that shrink and turn (a blade)."""
    wires = []
    for k in range(sections):
        e = occ.addEllipse(0, 0, step * k, 12 - k, 3 + 0.3 * k)
        occ.rotate([(1, e)], 0, 0, step * k, 0, 0, 1, turn * k)
        wires.append(occ.addCurveLoop([e]))
    occ.addThruSections(wires, makeSolid=True, makeRuled=False)


def blade_loft(occ):
    """A thinner, more twisted loft of six sections."""
    wires = []
    for k in range(6):
        e = occ.addEllipse(0, 0, 15 * k, 14 - 1.5 * k, 2 + 0.2 * k)
        occ.rotate([(1, e)], 0, 0, 15 * k, 0, 0, 1, 0.5 * k)
        wires.append(occ.addCurveLoop([e]))
    occ.addThruSections(wires, makeSolid=True)


def sphere_cuts(occ):
    """A sphere (two poles) cut by a cylinder and a box."""
    s = occ.addSphere(0, 0, 0, 10)
    c = occ.addCylinder(-15, 0, 0, 30, 0, 0, 4)
    b = occ.addBox(0, 0, 5, 20, 20, 20)
    occ.cut([(3, s)], [(3, c), (3, b)])


def cone_apex(occ):
    """A cone (a pole at its apex) on a cylinder."""
    co = occ.addCone(0, 0, 0, 0, 0, 15, 6, 0)
    cy = occ.addCylinder(0, 0, -10, 0, 0, 10, 6)
    occ.fuse([(3, co)], [(3, cy)])


def revolved_vase(occ):
    """A B-spline profile revolved about an axis it touches at both ends."""
    pts = [occ.addPoint(x, 0, z) for x, z in ((0, 0), (6, 2), (3, 8), (7, 14), (0, 18))]
    occ.revolve([(1, occ.addBSpline(pts))], 0, 0, 0, 0, 0, 1, 2 * math.pi)


def wavy_bspline(occ):
    """A bumpy bicubic B-spline sheet with a round hole."""
    rnd = random.Random(7)
    n = 7
    pts = [occ.addPoint(10 * i, 10 * j, 4 * math.sin(i) * math.cos(0.8 * j) + rnd.uniform(-1, 1))
           for j in range(n) for i in range(n)]
    sheet = occ.addBSplineSurface(pts, n, degreeU=3, degreeV=3)
    hole = occ.addCylinder(30, 30, -20, 0, 0, 40, 8)
    occ.cut([(2, sheet)], [(3, hole)])


def torus_box(occ):
    """A torus fused with a box across its tube."""
    t = occ.addTorus(0, 0, 0, 10, 3)
    b = occ.addBox(5, -4, -4, 12, 8, 8)
    occ.fuse([(3, t)], [(3, b)])


def thick_vase(occ):
    """A lofted solid hollowed into a shell of thickness 1, open on top."""
    wires = [occ.addCurveLoop([occ.addCircle(0, 0, 15 * k, r)]) for k, r in enumerate((10, 7, 6))]
    v = occ.addThruSections(wires, makeSolid=True)
    occ.synchronize()
    faces = [t for _, t in gmsh.model.getBoundary(v, combined=False, oriented=False)]
    occ.addThickSolid(v[0][1], [faces[-1]], -1.0)
    occ.remove(v, recursive=True)


def bent_pipe(occ):
    """A disk swept along a bent B-spline path."""
    pts = [occ.addPoint(*p) for p in ((0, 0, 0), (10, 0, 5), (20, 10, 5), (25, 25, 0))]
    wire = occ.addWire([occ.addBSpline(pts)])
    d = occ.addDisk(0, 0, 0, 2, 2)
    occ.rotate([(2, d)], 0, 0, 0, 0, 1, 0, math.pi / 2 - math.atan2(5, 10))
    occ.addPipe([(2, d)], wire)
    occ.remove([(2, d)], recursive=True)


def coil_pipe(occ):
    """A disk swept along a helix-like B-spline (a spring's wire)."""
    pts = [occ.addPoint(8 * math.cos(t), 8 * math.sin(t), 2 * t) for t in (0.4 * i for i in range(20))]
    wire = occ.addWire([occ.addBSpline(pts)])
    d = occ.addDisk(8, 0, 0, 1.5, 1.5)
    occ.rotate([(2, d)], 8, 0, 0, 1, 0, 0, math.pi / 2 - math.atan2(2, 8))
    occ.addPipe([(2, d)], wire, "Frenet")
    occ.remove([(2, d)], recursive=True)


def studs_plate(occ):
    """A plate with 16 studs of different sizes (many small faces)."""
    plate = occ.addBox(0, 0, 0, 50, 50, 3)
    studs = [(3, occ.addCylinder(6 + 12 * i, 6 + 12 * j, 3, 0, 0, 2 + i, 1.5 + 0.5 * j))
             for i in range(4) for j in range(4)]
    occ.fuse([(3, plate)], studs)


def wedge_pocket(occ):
    """A wedge with a spherical pocket cut into its top."""
    w = occ.addWedge(0, 0, 0, 30, 20, 15, ltx=5)
    s = occ.addSphere(15, 10, 15, 6)
    occ.cut([(3, w)], [(3, s)])


def sphere_hole(occ):
    """A sphere with a cylindrical hole through its poles' plane."""
    s = occ.addSphere(0, 0, 0, 10)
    c = occ.addCylinder(-15, 0, 0, 30, 0, 0, 4)
    occ.cut([(3, s)], [(3, c)])


def airfoil(occ, x0, chord, station, thick, vertical, lift=0.0):
    """A closed wire of two splines through a NACA-like 00xx profile of this
    chord, sharp at its trailing edge: in the plane z = station (a fin,
    vertical) or y = station (a wing, raised by lift)."""
    def point(x, y):
        if vertical:
            return occ.addPoint(x0 + x, y, station)
        return occ.addPoint(x0 + x, station, lift + y)

    def half(s):
        return 5 * thick * chord * (0.2969 * s - 0.126 * s * s - 0.3516 * s**4
                                    + 0.2843 * s**6 - 0.1036 * s**8)
    n = 12
    te, le = point(chord, 0.0), point(0.0, 0.0)
    upper = [te] + [point(chord * (1 - i / n)**2, half(1 - i / n)) for i in range(1, n)] + [le]
    lower = [le] + [point(chord * (i / n)**2, -half(i / n)) for i in range(1, n)] + [te]
    return occ.addWire([occ.addSpline(upper), occ.addSpline(lower)])


def lofted_wing(occ, x0, span, chord, sweep, lift=0.0, vertical=False, thick=0.12):
    """A wing (or a fin) lofted through four sections tapering to 40%."""
    wires = []
    for k in range(4):
        f = k / 3
        station = lift + span * f if vertical else span * f
        wires.append(airfoil(occ, x0 + sweep * f, chord * (1 - 0.6 * f), station, thick, vertical,
                             lift + 0.05 * span * f))
    return occ.addThruSections(wires, makeSolid=True)


def round_section(occ, x, ry, rz):
    """An ellipse in the plane x = const."""
    e = occ.addEllipse(x, 0, 0, max(ry, rz), min(ry, rz))
    occ.rotate([(1, e)], x, 0, 0, 0, 1, 0, math.pi / 2)
    return occ.addCurveLoop([e])


def tail_assembly(occ):
    """Five solids, not fused: a tail cone, a fin, two stabilisers and a
    sphere (overlapping solids of an assembly)."""
    occ.addThruSections([round_section(occ, x, r, r)
                         for x, r in ((0, 3.0), (8, 2.4), (16, 1.0), (18, 0.3))], makeSolid=True)
    lofted_wing(occ, 6, 7, 5, 4, lift=1.5, vertical=True)
    lofted_wing(occ, 8, 5, 3.5, 2.5, lift=0.2)
    occ.mirror(lofted_wing(occ, 8, 5, 3.5, 2.5, lift=0.2), 0, 1, 0, 0)
    occ.addSphere(13, 0, 2.0, 0.9)


def wing_body(occ):
    """A fuselage, two wings and a fin fused into one solid."""
    body = occ.addThruSections([round_section(occ, x, 1.1 * r, r) for x, r in (
        (0.5, 0.6), (4, 2.2), (10, 3), (40, 3), (52, 2.0), (60, 0.5))], makeSolid=True)
    right = lofted_wing(occ, 20, 18, 9, 6, lift=-1.5)
    left = lofted_wing(occ, 20, 18, 9, 6, lift=-1.5)
    occ.mirror(left, 0, 1, 0, 0)
    fin = lofted_wing(occ, 48, 8, 6, 5, lift=1.0, vertical=True)
    occ.fuse(body, right + left + fin)


def wing_body_metres(occ):
    """The wing-body scaled to metres; the points its sections were drawn
    through stay where they were (free points far from the faces)."""
    wing_body(occ)
    occ.synchronize()
    occ.dilate(gmsh.model.getEntities(3), 0, 0, 0, 1e-3, 1e-3, 1e-3)


def machined_block(occ):
    """A block with a pocket and 24 drilled holes of two sizes."""
    block = occ.addBox(0, 0, 0, 120, 80, 30)
    tools = [(3, occ.addCylinder(10 + 20 * i, 10 + 20 * j, 20, 0, 0, 11, 2.5 if (i + j) % 2 else 1.6))
             for i in range(6) for j in range(4)]
    tools.append((3, occ.addBox(30, 25, 12, 60, 30, 20)))
    occ.cut([(3, block)], tools)


def crankshaft(occ):
    """Journals, webs and offset pins fused into one solid."""
    parts, x = [], 0
    for k in range(3):
        parts.append((3, occ.addCylinder(x, 0, 0, 10, 0, 0, 4)))
        parts.append((3, occ.addBox(x + 10, -6, -5, 4, 18, 10)))
        parts.append((3, occ.addCylinder(x + 14, 9 if k % 2 else 0, 3 if k % 2 else 0, 8, 0, 0, 3.5)))
        parts.append((3, occ.addBox(x + 22, -6, -5, 4, 18, 10)))
        x += 26
    parts.append((3, occ.addCylinder(x, 0, 0, 12, 0, 0, 4)))
    occ.fuse(parts[:1], parts[1:])


def open_wheel(occ):
    """A hub and nine twisted blades that are open surfaces (no solid)."""
    occ.addCylinder(0, 0, 0, 0, 0, 10, 5)
    for k in range(9):
        a = 2 * math.pi * k / 9
        wires = []
        for j, r in enumerate((4.8, 9, 14)):
            t = a + 0.25 * j
            pts = [occ.addPoint(r * math.cos(t + d), r * math.sin(t + d), z)
                   for d, z in ((-0.15, 1), (0.0, 5), (0.15, 9))]
            wires.append(occ.addWire([occ.addSpline(pts)], checkClosed=False))
        occ.addThruSections(wires, makeSolid=False, makeRuled=False)


MODELS = [
    ("fillet_box.step", fillet_box), ("thin_fillets.brep", thin_fillets),
    ("twisted_loft.brep", twisted_loft), ("blade_loft.brep", blade_loft),
    ("sphere_cuts.step", sphere_cuts), ("sphere_hole.step", sphere_hole),
    ("cone_apex.brep", cone_apex), ("revolved_vase.step", revolved_vase),
    ("wavy_bspline.step", wavy_bspline), ("torus_box.brep", torus_box),
    ("thick_vase.step", thick_vase), ("bent_pipe.brep", bent_pipe),
    ("coil_pipe.brep", coil_pipe), ("studs_plate.step", studs_plate),
    ("wedge_pocket.brep", wedge_pocket), ("tail_assembly.step", tail_assembly),
    ("wing_body.step", wing_body), ("wing_body_metres.step", wing_body_metres),
    ("machined_block.step", machined_block), ("crankshaft.step", crankshaft),
    ("open_wheel.step", open_wheel),
]


def main(models, doc):
    """Write models (name, build) to the directory the command line names;
    doc: the usage printed otherwise."""
    if len(sys.argv) != 2 or sys.argv[1].startswith("-"):
        sys.exit(doc.split("SPDX")[0].rstrip())
    out = sys.argv[1]
    os.makedirs(out, exist_ok=True)
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        for name, build in models:
            make(gmsh.model.occ, name, build, out)
    finally:
        gmsh.finalize()


if __name__ == "__main__":
    main(MODELS, __doc__)
