/* A curve or vertex node's place on a face it bounds (its slot's (u, v),
 * from which its normal there comes) follows one rule however the mesh
 * was made: the face's own curve (its pcurve) at the node's parameter,
 * the face's nearest point only where the pcurve gives none or leaves the
 * face's bounds. The model is a trimmed B-spline strip whose curves lie
 * off it within the model's tolerance (tests/data/bspline_strip_gaps.brep):
 * the nearest point of the face to a curve node is not the pcurve's point
 * there. hocad's own linear mesh and the same mesh read back from its
 * file must then give every element corner the same (u, v) and every
 * element the same q; otherwise a mesh hocad reports valid can measure
 * tangled in `hocad quality` (two triangles of the part this strip comes
 * from did at order 1).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "test_util.h"

#define DATA HOC_SOURCE_DIR "/tests/data/"

int main(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(DATA "bspline_strip_gaps.brep", &model));
  if (!model) return test_report();
  double tolerance = 0;
  CHECK_OK(hoc_model_tolerance(model, &tolerance));
  CHECK(tolerance > 1e-4 * model->diagonal); /* the curves lie off the face */
  hoc_mesh *made = NULL, *back = NULL;
  hoc_linear_options o;
  hoc_linear_options_default(&o);
  CHECK_OK(hoc_mesh_generate_linear(model, &o, &made));
  if (made) CHECK_OK(hoc_mesh_write_msh(made, "strip_gaps_p1.msh"));
  if (made) CHECK_OK(hoc_mesh_read_msh(model, "strip_gaps_p1.msh", &back));
  if (made && back) {
    CHECK(made->n_elems == back->n_elems && made->n_elems > 0);
    const hoc_cad_face *f = &model->faces[0];
    double range = fmax(f->hi[0] - f->lo[0], f->hi[1] - f->lo[1]);
    size_t differ = 0, corners = 0;
    for (size_t e = 0; e < made->n_elems && e < back->n_elems; ++e)
      for (int i = 0; i < 3; ++i) {
        size_t a = made->elem_slot[3 * e + i], b = back->elem_slot[3 * e + i];
        if (made->dim[made->conn[3 * e + i]] == HOC_ON_FACE) continue;
        ++corners;
        double d = fabs(made->slot_uv[2 * a] - back->slot_uv[2 * b]) +
                   fabs(made->slot_uv[2 * a + 1] - back->slot_uv[2 * b + 1]);
        differ += !(d <= 1e-9 * range);
      }
    CHECK(corners > 0);
    CHECK(differ == 0);
    if (differ) fprintf(stderr, "%zu of %zu curve corners differ in (u, v)\n", differ, corners);
    double *qa = malloc(made->n_elems * sizeof *qa), *qb = malloc(back->n_elems * sizeof *qb);
    if (qa && qb) {
      CHECK_OK(hoc_mesh_measure(made, HOC_MEASURE_SHAPE, qa, NULL, NULL));
      CHECK_OK(hoc_mesh_measure(back, HOC_MEASURE_SHAPE, qb, NULL, NULL));
      double worst = 0;
      for (size_t e = 0; e < made->n_elems; ++e) worst = fmax(worst, fabs(qa[e] - qb[e]));
      CHECK(worst <= 1e-9);
    }
    free(qa);
    free(qb);
  }
  hoc_mesh_destroy(&back);
  hoc_mesh_destroy(&made);
  hoc_model_destroy(&model);
  remove("strip_gaps_p1.msh");
  return test_report();
}
