/* Test helper: gmsh's own high-order surface mesh of a CAD model, as
 * `gmsh MODEL -2 -order P -o OUT.msh` makes it (Debian's libgmsh, so that
 * the tests need no gmsh executable).
 * usage: gmsh_ho_mesh MODEL ORDER OUT.msh
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include <gmshc.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv) {
  if (argc != 4) {
    fprintf(stderr, "usage: gmsh_ho_mesh MODEL ORDER OUT.msh\n");
    return 1;
  }
  int ierr = 0;
  gmshInitialize(0, NULL, 0, &ierr);
  gmshOptionSetNumber("General.Terminal", 0, &ierr);
  gmshOpen(argv[1], &ierr);
  if (!ierr) gmshModelMeshGenerate(2, &ierr);
  if (!ierr) gmshModelMeshSetOrder(atoi(argv[2]), &ierr);
  if (!ierr) gmshWrite(argv[3], &ierr);
  int failed = ierr != 0;
  gmshFinalize(&ierr);
  if (failed) fprintf(stderr, "gmsh_ho_mesh: gmsh failed on %s\n", argv[1]);
  return failed;
}
