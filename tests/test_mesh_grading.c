/* The linear mesh graded down to CAD curves far shorter than the mesh
 * around them (mesh/grading.c; HOC_LINEAR_SHORT_RATIO, _SHORT_SIZE and
 * _GRADE in mesh.h). Its class: a short CAD curve gets one segment, and
 * gmsh's triangles on it are slivers (q about sqrt(3) L / h), which high
 * orders fold and no optimisation opens.
 *
 * The case: tests/data/plate_short_edge.brep, a 10 x 10 plate with a
 * corner cut by a curve 0.00198 long, at hocad's default sizes (edges
 * 0.707, gmsh's minimum 0.0707). Without the grading gmsh's triangle on
 * that curve has q 0.0073 (sides 0.47, 0.47, 0.002; 545 triangles); with
 * it every triangle has q above 0.15 (587 triangles). The size field
 * itself against its closed form: HOC_LINEAR_SHORT_SIZE x the curve's
 * length plus HOC_LINEAR_GRADE x the distance near it, gmsh's size (its
 * mesh's mean edge) away from it. hoc_mesh_model notes it.
 *
 * Faces narrower than the mesh around them (thin_width). Their class: a
 * face narrower than the edges (a thin plate's rim, a blunt trailing
 * edge) gets one row of triangles across,
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
 * mesh meets the bounds.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "test_util.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define DATA HOC_SOURCE_DIR "/tests/data/"

/* Distance from x to the segment a-b in the plane z = 0. */
static double segment_distance(const double *x, const double *a, const double *b) {
  double ab[2] = {b[0] - a[0], b[1] - a[1]}, ax[2] = {x[0] - a[0], x[1] - a[1]};
  double t = (ab[0] * ax[0] + ab[1] * ax[1]) / (ab[0] * ab[0] + ab[1] * ab[1]);
  t = t < 0 ? 0 : t > 1 ? 1 : t;
  return hypot(ax[0] - t * ab[0], ax[1] - t * ab[1]);
}

/* The notes of a graded linear mesh that say `want`. */
typedef struct notes {
  const char *want;
  int n;
} notes;

static int on_event(void *user, const hoc_event *ev) {
  notes *c = user;
  if (ev->kind == HOC_EVENT_NOTE && ev->message && strstr(ev->message, c->want) &&
      strstr(ev->message, "(gmsh's own mesh: "))
    ++c->n;
  return 0;
}

/* hoc_mesh_model on model at order 2: how many notes say `want`; the
 * result's quality in *st. */
static int mesh_notes(hoc_model *model, const char *want, hoc_quality_stats *st) {
  hoc_mesh_options mo;
  hoc_mesh_options_default(&mo);
  mo.order = 2;
  mo.event = on_event;
  notes c = {want, 0};
  mo.event_user = &c;
  hoc_mesh *ho = NULL;
  hoc_report *rep = NULL;
  CHECK_OK(hoc_mesh_model(model, &mo, &ho, &rep));
  if (ho) CHECK_OK(hoc_mesh_measure(ho, HOC_MEASURE_SHAPE, NULL, NULL, st));
  hoc_report_destroy(&rep);
  hoc_mesh_destroy(&ho);
  return c.n;
}

static void test_short_curve(void) {
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *first = NULL;
  hoc_linear_grading *g = NULL;
  CHECK_OK(hoc_model_open(DATA "plate_short_edge.brep", &model));
  if (!model) return;
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.order = 3;
  double hmax, hmin;
  hoc_linear_sizes(model, &lo, &hmax, &hmin);
  CHECK_OK(hoc_mesh_generate_linear(model, &lo, &lin));
  if (!lin) goto out;
  hoc_quality_stats st = {0};
  CHECK_OK(hoc_mesh_measure(lin, HOC_MEASURE_SHAPE, NULL, NULL, &st));
  printf("graded linear mesh: %zu triangles, min q %.4f, mean q %.4f\n", hoc_mesh_num_elements(lin),
         st.min, st.mean);
  CHECK(st.tangled == 0);
  CHECK(st.min > 0.15);
  /* gmsh's own mesh: the sliver, and a few elements fewer */
  CHECK_OK(hoc_mesh_generate_linear_ungraded(model, &lo, &first));
  if (first) {
    hoc_quality_stats s0 = {0};
    CHECK_OK(hoc_mesh_measure(first, HOC_MEASURE_SHAPE, NULL, NULL, &s0));
    printf("gmsh's linear mesh: %zu triangles, min q %.4f\n", hoc_mesh_num_elements(first), s0.min);
    CHECK(s0.min < 0.01);
    CHECK(hoc_mesh_num_elements(lin) < 1.5 * (double)hoc_mesh_num_elements(first));
    /* and nowhere coarser than gmsh's: its mesh near the curve is finer
     * than its curvature sizing (its curves' sizes extend into the face),
     * and the field follows it (without that, 515 triangles, min q 0.18) */
    CHECK(hoc_mesh_num_elements(lin) > hoc_mesh_num_elements(first));
    /* what the graded mesh records of it, for the pipeline's note */
    CHECK(lin->graded_curves == 1);
    CHECK(lin->ungraded_elements == hoc_mesh_num_elements(first));
    CHECK(lin->ungraded_min_q == s0.min);
  }

  /* the field made from gmsh's mesh: its short curve is short at ratio 1
   * (its triangles' edges are longer than it), and nowhere at a ratio
   * above the mesh's longest edge over the curve */
  double L = 0.0014 * sqrt(2.0);
  if (!first) goto out;
  CHECK_OK(hoc_linear_grading_make(first, 1000 * hmax / L, hmin, hmax, 8, NULL, &g));
  CHECK(g == NULL);
  CHECK_OK(hoc_linear_grading_make(first, 1, hmin, hmax, 8, NULL, &g));
  if (!g) goto out;
  CHECK(hoc_linear_grading_segments(g) >= 1);
  CHECK(fabs(hoc_linear_grading_min_size(g) - L) < 1e-9);
  const double far[3] = {5, 5, 0}, corner[3] = {0.0007, 9.9993, 0}, near[3] = {0.0507, 9.9993, 0};
  double h_far = hoc_linear_grading_size(g, far), h_corner = hoc_linear_grading_size(g, corner),
         h_near = hoc_linear_grading_size(g, near);
  printf("sizes: %.6g far (max %.6g), %.6g on the short curve, %.6g at 0.05 from it\n", h_far, hmax,
         h_corner, h_near);
  /* the short curve is the segment a-b; near's foot on it is a */
  const double a[3] = {0.0014, 10, 0};
  double d = sqrt((near[0] - a[0]) * (near[0] - a[0]) + (near[1] - a[1]) * (near[1] - a[1]));
  /* far from it, gmsh's size: its mesh's mean edge at the nodes there */
  CHECK(h_far <= hmax && h_far > 0.5 * hmax);
  CHECK(fabs(h_corner - HOC_LINEAR_SHORT_SIZE * L) < 1e-12);
  CHECK(fabs(h_near - (HOC_LINEAR_SHORT_SIZE * L + HOC_LINEAR_GRADE * d)) < 1e-12);
  /* and out to 0.6 of its reach ((hmax - 5 L) / 2) in three directions,
   * where gmsh's mesh is still coarser: the field's grid of segments (one
   * lookup) misses none of them there */
  const double b_end[3] = {0, 10 - 0.0014, 0}, dirs[3][2] = {{1, 0}, {0, -1}, {0.6, -0.8}};
  for (int k = 0; k < 3; ++k) {
    double r = 0.6 * (hmax - HOC_LINEAR_SHORT_SIZE * L) / HOC_LINEAR_GRADE;
    const double x[3] = {a[0] + r * dirs[k][0], a[1] + r * dirs[k][1], 0};
    double want = HOC_LINEAR_SHORT_SIZE * L + HOC_LINEAR_GRADE * segment_distance(x, a, b_end);
    double got = hoc_linear_grading_size(g, x);
    printf("size at %.4f from the short curve's end: %.6g (closed form %.6g)\n", r, got, want);
    CHECK(fabs(got - want) < 1e-12 && got < hmax);
  }
  /* hoc_mesh_model says so */
  hoc_quality_stats s2 = {0};
  CHECK(mesh_notes(model, "graded down to 1 CAD curve(s)", &s2) == 1);
out:
  hoc_linear_grading_free(&g);
  hoc_mesh_destroy(&first);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* The thin disk (its class and numbers: above). */
static void test_thin_face(void) {
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *first = NULL;
  hoc_linear_grading *g = NULL;
  CHECK_OK(hoc_model_open(DATA "thin_disk.brep", &model));
  if (!model) return;
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
  hoc_quality_stats s2 = {0};
  CHECK(mesh_notes(model, "and 1 face(s) narrower than a tenth of their edges:", &s2) == 1);
  printf("order 2 optimised: min q %.4f, mean q %.4f (linear %.4f, %.4f)\n", s2.min, s2.mean,
         s1.min, s1.mean);
  CHECK(s2.elements > 0 && s2.tangled == 0);
  CHECK(s2.mean >= s1.mean - 0.02);
  CHECK(s2.min >= 0.9 * s1.min);
out:
  hoc_linear_grading_free(&g);
  hoc_mesh_destroy(&first);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* The graded meshing's budget (HOC_LINEAR_GRADED_SECONDS). Its class: a
 * face that pinches to a point asks sizes near nothing at its tip, and
 * gmsh's mesher can then take far longer than the mesh is worth. Past
 * the budget gmsh's first mesh stays, with a note, and the model does not
 * remember the faces as failed (a later meshing at gmsh's sizes tries
 * them). The thin disk's graded meshing does not fit in a millisecond;
 * without a budget it is kept. */
static void test_budget(void) {
  hoc_model *model = NULL;
  hoc_mesh *cut = NULL, *free_run = NULL;
  CHECK_OK(hoc_model_open(DATA "thin_disk.brep", &model));
  if (!model) return;
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.order = 2;
  CHECK_OK(hoc_mesh_generate_linear_ungraded(model, &lo, &cut));
  CHECK_OK(hoc_mesh_generate_linear_ungraded(model, &lo, &free_run));
  if (!cut || !free_run) goto out;
  size_t n0 = hoc_mesh_num_elements(cut);
  CHECK_OK(hoc_mesh_grade(model, &lo, NULL, 1e-3, &cut));
  CHECK_OK(hoc_mesh_grade(model, &lo, NULL, 0, &free_run));
  if (!cut || !free_run) goto out;
  printf("budget 1 ms: %zu triangles (gmsh's %zu), graded faces %d; no budget: %zu, graded "
         "faces %d\n",
         hoc_mesh_num_elements(cut), n0, cut->graded_faces, hoc_mesh_num_elements(free_run),
         free_run->graded_faces);
  CHECK(hoc_mesh_num_elements(cut) == n0 && cut->graded_faces == 0);
  CHECK(cut->graded_budget == 1e-3);
  CHECK(cut->n_failed_faces == 0 && !model->mesher_failed);
  CHECK(free_run->graded_faces == 1 && free_run->graded_budget == 0);
  CHECK(hoc_mesh_num_elements(free_run) > n0);
out:
  hoc_mesh_destroy(&cut);
  hoc_mesh_destroy(&free_run);
  hoc_model_destroy(&model);
}

int main(void) {
  test_short_curve();
  test_thin_face();
  test_budget();
  return test_report();
}
