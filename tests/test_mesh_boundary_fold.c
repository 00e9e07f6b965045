/* A face that folds within the model's tolerance of its boundary: a
 * trimmed face's untrimmed parametrisation folds along its boundary curve,
 * and the curve's points on the face land past the fold, on a strip
 * narrower than the model's tolerance (repatch_hpdc.stp: 1.5e-4 against
 * 0.01). The analytic face phi = (u^2 - d^2 (1 - exp(-u / d)), (b + u^2) v,
 * 0) with d = 1e-3 folds at u = 0.3517 d, 0.1728 d^2 = 1.7e-7 from its side
 * u = 0, whose normal points down (the face's is up past the fold). The
 * side is regular: |phi_u| = d is not a stalled derivative.
 * - Tolerance 1e-6 (the strip is within it): the side's slots take the
 *   face's normal past the fold, +z, and neither the linear mesh nor the
 *   same mesh raised to order 3 and optimised has a tangled element.
 * - Tolerance 1e-8 (the strip is 17 times wider): the rule leaves the side's
 *   normals as they are, and the mesh is tangled there, as it is without
 *   the rule at any tolerance.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "cad/cad.h"
#include "mesh/mesh.h"
#include "test_util.h"

#include <math.h>
#include <stdlib.h>

/* Slots on the side u = 0 and those among them whose normal is not +z as
 * oriented; elements tangled. */
static void measure(hoc_mesh *m, size_t *side, size_t *wrong, size_t *tangled) {
  *side = *wrong = *tangled = 0;
  double *normal = malloc(3 * m->n_slots * sizeof *normal);
  double *q = malloc(m->n_elems * sizeof *q);
  if (!normal || !q) {
    CHECK(0);
    goto done;
  }
  CHECK_OK(hoc_mesh_slot_normals_of(m, NULL, normal));
  double up = m->face_orient[0] > 0 ? 1 : -1;
  for (size_t s = 0; s < m->n_slots; ++s) {
    if (m->slot_uv[2 * s] != 0) continue;
    ++*side;
    *wrong += !(fabs(normal[3 * s + 2] - up) < 1e-6);
  }
  hoc_quality_stats st = {0};
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q, NULL, &st));
  *tangled = st.tangled;
done:
  free(normal);
  free(q);
}

int main(void) {
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *p3 = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_EAR, 1.0, 0.1, &model));
  if (!model) goto out;
  /* the fold, closed form: phi_u = 0 at u = 0.3517 d, x = -0.1728 d^2 */
  const hoc_cad_face *f = &model->faces[0];
  double d = 1e-3, du[3], dv[3], x[3], side[2] = {0, 0.5}, fold[2] = {0.35173371 * d, 0.5};
  CHECK_OK(hoc_cad_face_eval(model, 0, 1, side, NULL, du, dv));
  CHECK(!hoc_cad_face_singular(f, du, dv) && du[0] * dv[1] < 0); /* regular, pointing down */
  CHECK_OK(hoc_cad_face_eval(model, 0, 1, fold, x, du, dv));
  printf("fold at u = %.4g: phi_u %.2g, %.4g from the side\n", fold[0], du[0], -x[0]);
  CHECK(fabs(du[0]) < 1e-10 && fabs(-x[0] - 0.17284 * d * d) < 1e-4 * d * d);
  CHECK_OK(hoc_mesh_grid_linear(model, 6, 4, &lin));
  if (lin) CHECK_OK(hoc_mesh_elevate(lin, 3, HOC_NODES_FEKETE, &p3));
  if (!p3) goto out;
  const double tolerance[2] = {1e-6, 1e-8};
  for (int k = 0; k < 2; ++k) {
    model->tolerance = tolerance[k];
    model->tolerance_known = 1;
    size_t s1, w1, t1, s3, w3, t3;
    measure(lin, &s1, &w1, &t1);
    /* at order 3 the side's elements are flat there as raised (x ~ u^2):
     * optimised, the side's nodes follow their normals */
    hoc_mesh *opt = NULL;
    CHECK_OK(hoc_mesh_copy(p3, &opt));
    if (!opt) break;
    CHECK_OK(hoc_mesh_optimize(opt, NULL, NULL));
    measure(opt, &s3, &w3, &t3);
    hoc_mesh_destroy(&opt);
    printf("tolerance %g: linear %zu side slots, %zu not +z, %zu tangled; order 3 optimised "
           "%zu side slots, %zu not +z, %zu tangled\n",
           tolerance[k], s1, w1, t1, s3, w3, t3);
    CHECK(s1 > 0 && s3 > s1);
    if (k == 0) CHECK(w1 == 0 && t1 == 0 && w3 == 0 && t3 == 0);
    else CHECK(w1 == s1 && t1 > 0 && w3 == s3 && t3 > 0);
  }
out:
  hoc_mesh_destroy(&p3);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
  printf("%d passed, %d failed\n", test_passed_, test_failed_);
  return test_failed_ != 0;
}
