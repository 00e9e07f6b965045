#!/usr/bin/python3
"""Random machined parts no one tuned hocad to, made with gmsh's
OpenCASCADE kernel, for bench/corpus.sh: a box with 2 to 5 random
features (through holes, straight or oblique or sideways, bosses, cones,
slots, spherical pockets), up to six random edges filleted where
OpenCASCADE can, and about one part in three scaled by 1e-3 (an export
in metres; OpenCASCADE's dilation turns its faces into B-splines). Each
part is drawn from its own seed: the same seeds make the same files.

usage: /usr/bin/python3 bench/csg_models.py DIR [COUNT [FIRST_SEED]]
  (default 14 parts from seed 100) then: bench/corpus.sh DIR/*.step
Needs Debian's python3-gmsh, as bench/synthetic_models.py.
SPDX-License-Identifier: GPL-2.0-or-later
"""
import os
import random
import sys

import gmsh


def feature(occ, rnd, size):
    """One random feature of a box of size (L, W, H): (tag, to cut)."""
    length, width, height = size
    kind = rnd.choice(["hole", "boss", "sphere", "slot", "cone"])
    x, y = rnd.uniform(0.15, 0.85) * length, rnd.uniform(0.15, 0.85) * width
    r = rnd.uniform(0.05, 0.2) * min(length, width)
    if kind == "hole":
        ax = rnd.choice([(0, 0, 1), (1, 0, 0), (0.3, 0.2, 1)])
        if ax[0] == 1:
            z = rnd.uniform(0.3, 0.7) * height
            return occ.addCylinder(-1, y, z, length + 2, 0, 0, min(r, 0.3 * height)), True
        h = height + 2
        return occ.addCylinder(x, y, -1, ax[0] * h, ax[1] * h, h, r), True
    if kind == "boss":
        return occ.addCylinder(x, y, height, 0, 0, rnd.uniform(0.2, 1.0) * height + 2, r), False
    if kind == "sphere":
        return occ.addSphere(x, y, height * rnd.uniform(0.6, 1.2), r * 1.3), True
    if kind == "slot":
        y0, z0 = rnd.uniform(-1, 0.2 * width), height * rnd.uniform(0.4, 0.8)
        return occ.addBox(x - r, y0, z0, 2 * r, width + 2, height), True
    tall = rnd.uniform(0.5, 1.5) * height + 1
    return occ.addCone(x, y, height, 0, 0, tall, r, r * rnd.uniform(0, 0.6)), False


def part(seed, path):
    """The part of this seed, written to path; returns its face count."""
    rnd = random.Random(seed)
    gmsh.model.add("csg%d" % seed)
    occ = gmsh.model.occ
    size = (rnd.uniform(20, 60), rnd.uniform(10, 40), rnd.uniform(3, 25))
    cur = [(3, occ.addBox(0, 0, 0, *size))]
    cut, add = [], []
    for _ in range(rnd.randint(2, 5)):
        tag, is_cut = feature(occ, rnd, size)
        (cut if is_cut else add).append((3, tag))
    if add:
        cur = occ.fuse(cur, add)[0]
    if cut:
        cur = occ.cut(cur, cut)[0]
    occ.synchronize()
    vols = [t for d, t in cur if d == 3]
    edges = [t for _, t in gmsh.model.getEntities(1)]
    pick = rnd.sample(edges, min(len(edges), rnd.randint(1, 6)))
    radius = rnd.uniform(0.3, 0.12 * min(size))
    try:
        out = occ.fillet(vols, pick, [radius], removeVolume=False)
        if out:
            occ.remove([(3, v) for v in vols], recursive=True)
    except Exception:  # OpenCASCADE refuses some fillets: the part keeps its edges
        pass
    occ.synchronize()
    if rnd.random() < 0.3:
        occ.dilate(gmsh.model.getEntities(3), 0, 0, 0, 1e-3, 1e-3, 1e-3)
        occ.synchronize()
    gmsh.write(path)
    faces = len(gmsh.model.getEntities(2))
    gmsh.model.remove()
    return faces


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    out = sys.argv[1]
    count = int(sys.argv[2]) if len(sys.argv) > 2 else 14
    first = int(sys.argv[3]) if len(sys.argv) > 3 else 100
    os.makedirs(out, exist_ok=True)
    gmsh.initialize()
    gmsh.option.setNumber("General.Terminal", 0)
    for seed in range(first, first + count):
        path = os.path.join(out, "csg%d.step" % seed)
        print(path, part(seed, path), "faces")
    gmsh.finalize()


if __name__ == "__main__":
    main()
