/* The linear mesh graded down to faces narrower than the mesh around
 * them (mesh/grading.c, thin_width; HOC_LINEAR_SHORT_RATIO, _SHORT_SIZE and
 * _GRADE in mesh.h). Its class: a face narrower than the edges (a thin
 * plate's rim, a blunt trailing edge) gets one row of triangles across,
 * each a sliver of q about 2 sqrt(3) w / (1.5 L) along its whole length,
 * and the optimiser, whose objective sums (eta - 1)^2 over the elements,
 * then trades the faces around for a little of the slivers' quality (a
 * washer 0.2 thick, 50 across: mean q 0.836 -> 0.802, the planes' min q
 * 0.89 -> 0.43, the rims' 0.099 -> 0.112).
 *
 * The case: tests/data/thin_disk.brep, a disk of radius 5 and thickness
 * 0.04 (its rim is 0.04 wide; hocad's default edges 0.707). gmsh's mesh:
 * rim triangles of q 0.1; graded: above twice that, in at most twice the
 * triangles (the planes stay at the default size: gmsh's extension of the
 * curves' sizes into the faces is off in the graded meshing, else the
 * fine rim curves refine the whole disk, beyond HOC_LINEAR_GRADED_GROWTH).
 * The size field against its closed form; and at order 2 the optimised
 * mesh keeps mean q within 0.02 of the linear mesh's.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "test_util.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define DATA HOC_SOURCE_DIR "/tests/data/"

/* Counts the notes of a linear mesh graded down to one thin face. */
static int on_event(void *user, const hoc_event *ev) {
  if (ev->kind == HOC_EVENT_NOTE && ev->message &&
      strstr(ev->message, "and 1 face(s) narrower than a tenth of their edges:"))
    ++*(int *)user;
  return 0;
}

int main(void) {
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *first = NULL;
  hoc_linear_grading *g = NULL;
  CHECK_OK(hoc_model_open(DATA "thin_disk.brep", &model));
  if (!model) return test_report();
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.order = 2;
  double hmax, hmin;
  hoc_linear_sizes(model, &lo, &hmax, &hmin);
  CHECK_OK(hoc_mesh_generate_linear_ungraded(model, &lo, &first));
  CHECK_OK(hoc_mesh_generate_linear(model, &lo, &lin));
  if (!first || !lin) goto out;
  hoc_quality_stats s0 = {0}, s1 = {0};
  CHECK_OK(hoc_mesh_measure(first, HOC_MEASURE_SHAPE, NULL, NULL, &s0));
  CHECK_OK(hoc_mesh_measure(lin, HOC_MEASURE_SHAPE, NULL, NULL, &s1));
  size_t n0 = hoc_mesh_num_elements(first), n1 = hoc_mesh_num_elements(lin);
  printf("gmsh's mesh: %zu triangles, min q %.4f; graded: %zu, min q %.4f\n", n0, s0.min, n1,
         s1.min);
  CHECK(s0.min < 0.15);
  CHECK(s1.tangled == 0);
  CHECK(s1.min > 2 * s0.min);
  CHECK(n1 > n0 && n1 < 2 * n0);
  CHECK(lin->graded_faces == 1);

  /* the field: the rim (and its seam, a short curve) are found, the size
   * on the rim is HOC_LINEAR_SHORT_SIZE x its width at most (the width
   * across a rim triangle's longest edge is below the rim's 0.04), and it
   * grows by HOC_LINEAR_GRADE per unit toward the middle, where it is
   * gmsh's (its mesh's mean edge there, at most the default size) */
  CHECK_OK(hoc_linear_grading_make(first, HOC_LINEAR_SHORT_RATIO, hmin, hmax, 8, NULL, &g));
  if (!g) goto out;
  CHECK(hoc_linear_grading_faces(g) == 1);
  CHECK(hoc_linear_grading_curves(g) == 1);
  CHECK(hoc_linear_grading_min_size(g) <= 0.04 + 1e-12);
  const double rim[3] = {0, -5, 0.02}, in[3] = {0, -4.9, 0.04}, mid[3] = {0, 0, 0.04};
  double h_rim = hoc_linear_grading_size(g, rim), h_in = hoc_linear_grading_size(g, in),
         h_mid = hoc_linear_grading_size(g, mid);
  printf("sizes: %.6g on the rim, %.6g at 0.1 from it, %.6g in the middle (default %.6g)\n", h_rim,
         h_in, h_mid, hmax);
  /* (the segments are chords of the rim's circles: edges under 0.8 on a
   * radius of 5 are within 0.016 of the arc) */
  CHECK(h_rim <= HOC_LINEAR_SHORT_SIZE * 0.04 + HOC_LINEAR_GRADE * 0.02 &&
        h_rim > 0.5 * HOC_LINEAR_SHORT_SIZE * 0.04);
  CHECK(h_in > h_rim && h_in <= h_rim + HOC_LINEAR_GRADE * 0.1 + 0.01);
  CHECK(h_mid <= hmax && h_mid > 0.5 * hmax);

  /* hoc_mesh_model notes it, and the optimised mesh meets the bounds
   * (gmsh's mesh optimised at order 2: mean q 0.893 -> 0.878, the rim's
   * min q 0.099 -> 0.115) */
  hoc_mesh_options mo;
  hoc_mesh_options_default(&mo);
  mo.order = 2;
  mo.event = on_event;
  int noted = 0;
  mo.event_user = &noted;
  hoc_mesh *ho = NULL;
  hoc_report *rep = NULL;
  CHECK_OK(hoc_mesh_model(model, &mo, &ho, &rep));
  CHECK(noted == 1);
  if (ho) {
    hoc_quality_stats s2 = {0};
    CHECK_OK(hoc_mesh_measure(ho, HOC_MEASURE_SHAPE, NULL, NULL, &s2));
    printf("order 2 optimised: min q %.4f, mean q %.4f (linear %.4f, %.4f)\n", s2.min, s2.mean,
           s1.min, s1.mean);
    CHECK(s2.tangled == 0);
    CHECK(s2.mean >= s1.mean - 0.02);
    CHECK(s2.min >= 0.9 * s1.min);
  }
  hoc_report_destroy(&rep);
  hoc_mesh_destroy(&ho);
out:
  hoc_linear_grading_free(&g);
  hoc_mesh_destroy(&first);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
  return test_report();
}
