/* A side of a face where a derivative stalls (hoc_cad_face_singular): the
 * IGES surface models' B-spline patches whose control rows coincide to the
 * file's digits (surf114: |phi_u| 1e-6 of its size along a side 0.65
 * long). There phi_u x phi_v is far from 0 next to |phi_u|^2 + |phi_v|^2,
 * so the old test took it as regular, but its direction is rounding: on
 * the analytic face phi = (u^2 - d^2 (1 - exp(-u / d)), (b + u^2) v, 0) it points down in
 * an ear a few d wide (d = 1e-6) and up everywhere else. The normal at such a side's nodes is
 * the face's just inside it (as at a pole): +z, closed form. Without the
 * rule the side's slots point down and every (straight) element along the
 * side counts as tangled. (Curved elements whose nodes follow such a
 * parametrisation are flat at the side: x ~ u^2 there.)
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "cad/cad.h"
#include "mesh/mesh.h"
#include "test_util.h"

#include <math.h>
#include <stdlib.h>

int main(void) {
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *m = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_STALL, 1.0, 0.1, &model));
  if (!model) goto out;
  const hoc_cad_face *f = &model->faces[0];
  /* the face's scales, and the rule at the side and inside */
  double du[3], dv[3], at[2] = {0, 0.5}, in[2] = {0.5, 0.5};
  CHECK_OK(hoc_cad_face_eval(model, 0, 1, at, NULL, du, dv));
  double n_side = fabs(du[0] * dv[1] - du[1] * dv[0]);
  printf("stalled side: |phi_u| %.3g (face scale %.3g), |phi_u x phi_v| %.3g against "
         "|phi_u|^2 + |phi_v|^2 = %.3g\n",
         fabs(du[0]), f->du_scale, n_side, du[0] * du[0] + dv[1] * dv[1]);
  CHECK(f->du_scale > 1.5 && f->dv_scale > 0.1);
  CHECK(n_side > 1e-10 * (du[0] * du[0] + dv[1] * dv[1])); /* (the old test: regular) */
  CHECK(hoc_cad_face_singular(f, du, dv));
  CHECK_OK(hoc_cad_face_eval(model, 0, 1, in, NULL, du, dv));
  CHECK(!hoc_cad_face_singular(f, du, dv));
  /* a linear mesh along the side: its slots' normals are the face's
   * inside, +z as oriented, and no element is tangled */
  CHECK_OK(hoc_mesh_grid_linear(model, 6, 4, &lin));
  if (lin) CHECK_OK(hoc_mesh_copy(lin, &m));
  if (!m) goto out;
  double *normal = malloc(3 * m->n_slots * sizeof *normal);
  size_t side = 0, wrong = 0;
  if (normal) {
    CHECK_OK(hoc_mesh_slot_normals_of(m, NULL, normal));
    double up = m->face_orient[0] > 0 ? 1 : -1;
    for (size_t s = 0; s < m->n_slots; ++s) {
      if (m->slot_uv[2 * s] != 0) continue;
      ++side;
      wrong += !(fabs(normal[3 * s + 2] - up) < 1e-12);
    }
  }
  free(normal);
  hoc_quality_stats st = {0};
  double *q = malloc(m->n_elems * sizeof *q);
  if (q) CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q, NULL, &st));
  printf("linear mesh, %zu elements: %zu slots on the stalled side, %zu with a normal other than "
         "the face's; %zu elements tangled\n",
         m->n_elems, side, wrong, q ? st.tangled : 0);
  CHECK(side > 0 && wrong == 0);
  CHECK(q && st.tangled == 0);
  free(q);
out:
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
  printf("%d passed, %d failed\n", test_passed_, test_failed_);
  return test_failed_ != 0;
}
