"""Mesh a bundled CAD model at order 3, print the paper's Table 2 rows and
what the report found, and write the mesh.

    python3 python/examples/mesh_report.py [MODEL] [OUT.msh]

SPDX-License-Identifier: GPL-2.0-or-later
"""
import os
import sys

import hocad

HERE = os.path.dirname(os.path.abspath(__file__))
model_path = sys.argv[1] if len(sys.argv) > 1 else os.path.join(HERE, "..", "..", "examples",
                                                                 "models", "screw.step")
out = sys.argv[2] if len(sys.argv) > 2 else "screw_p3.msh"


def progress(event):
    """Print the pipeline's steps; return True to cancel."""
    if event.kind in ("progress", "repair", "warning"):
        print("  " + event.message)


with hocad.Model(model_path) as model:
    print(model)
    mesh = model.mesh(order=3, progress=progress)
    print(hocad.format_table(mesh.report))
    for finding in mesh.report["findings"]:
        print("%s: %s" % (finding["kind"], finding["message"]))
    quality = mesh.measure()
    print("%d nodes, %d elements of %d nodes; worst element %d (q = %.4f), %d tangled" % (
        mesh.num_nodes, mesh.num_elements, mesh.nodes_per_element, quality.q.argmin(),
        quality.q.min(), quality.tangled.sum()))
    mesh.write(out)
    print("wrote", out)
