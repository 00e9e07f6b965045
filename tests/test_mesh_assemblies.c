/* Models without a solid (a lone B-spline patch, a sphere shell) and
 * assemblies of several solids: meshed, raised, optimised, every node on the
 * CAD, no tangled element. The models are made here with gmsh's
 * OpenCASCADE API and written as BREP and STEP files.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "test_util.h"

#include <gmshc.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

static void make_models(void) {
  int ierr = 0;
  gmshInitialize(0, NULL, 0, &ierr);
  gmshOptionSetNumber("General.Terminal", 0, &ierr);
  /* a surface-only model: a wavy B-spline patch and a spherical shell */
  gmshModelAdd("surfaces", &ierr);
  int pts[16];
  for (int j = 0; j < 4; ++j)
    for (int i = 0; i < 4; ++i)
      pts[4 * j + i] = gmshModelOccAddPoint(i, j, 0.6 * sin(1.3 * i) * cos(1.1 * j), 0, -1, &ierr);
  int wts[1] = {0};
  (void)wts;
  gmshModelOccAddBSplineSurface(pts, 16, 4, -1, 3, 3, NULL, 0, NULL, 0, NULL, 0, NULL, 0, NULL, 0,
                                NULL, 0, 0, &ierr);
  int sph = gmshModelOccAddSphere(8, 1.5, 0, 1.2, -1, -3.14159265358979323846 / 2, 3.14159265358979323846 / 2, 2 * 3.14159265358979323846, &ierr);
  int dt[2] = {3, sph};
  gmshModelOccRemove(dt, 2, 0, &ierr); /* keep the shell, not the solid */
  gmshModelOccSynchronize(&ierr);
  gmshWrite("surfaces_only.brep", &ierr);
  CHECK(ierr == 0);
  /* an assembly: a box, a cylinder and a torus, not fused */
  gmshModelAdd("assembly", &ierr);
  gmshModelOccAddBox(0, 0, 0, 2, 1, 1, -1, &ierr);
  gmshModelOccAddCylinder(4, 0.5, 0, 0, 0, 2, 0.6, -1, 2 * 3.14159265358979323846, &ierr);
  gmshModelOccAddTorus(0, 4, 0.5, 1.2, 0.35, -1, 2 * 3.14159265358979323846, &ierr);
  gmshModelOccSynchronize(&ierr);
  gmshWrite("assembly.step", &ierr);
  CHECK(ierr == 0);
  gmshFinalize(&ierr);
}

static void run(const char *path, int expect_volumes) {
  hoc_model *model;
  CHECK_OK(hoc_model_open(path, &model));
  if (!model) return;
  (void)expect_volumes;
  hoc_mesh *lin;
  hoc_linear_options o;
  hoc_linear_options_default(&o);
  o.order = 3;
  CHECK_OK(hoc_mesh_generate_linear(model, &o, &lin));
  if (!lin) {
    hoc_model_destroy(&model);
    return;
  }
  CHECK(lin->n_failed_faces == 0);
  for (int p = 2; p <= 5; p += 3) {
    hoc_mesh *m;
    CHECK_OK(hoc_mesh_elevate(lin, p, HOC_NODES_EQUISPACED, &m));
    CHECK_OK(hoc_mesh_optimize(m, NULL, NULL));
    hoc_quality_stats st;
    CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st));
    double d;
    CHECK_OK(hoc_mesh_max_cad_distance(m, &d));
    CHECK(d <= 1e-10 * model->diagonal);
    CHECK(st.tangled == 0);
    CHECK(st.min > 0.1);
    printf("%s: %d faces, order %d: %zu elements, q min %.3f mean %.3f, %zu tangled\n", path,
           model->n_faces, p, st.elements, st.min, st.mean, st.tangled);
    hoc_mesh_destroy(&m);
  }
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

int main(void) {
  /* the models are written into a directory of their own (as in
   * test_io_outfile), removed afterwards */
  char own[] = "assemblies-test-XXXXXX", cwd[4096];
  if (!mkdtemp(own) || !getcwd(cwd, sizeof cwd) || chdir(own) != 0) {
    fprintf(stderr, "cannot make a working directory\n");
    return 1;
  }
  make_models();
  run("surfaces_only.brep", 0);
  run("assembly.step", 3);
  remove("surfaces_only.brep");
  remove("assembly.step");
  CHECK(chdir(cwd) == 0 && rmdir(own) == 0);
  return test_report();
}
