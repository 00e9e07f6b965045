/* Nodes at the feet of the source element's points (hoc_cad_face_foot,
 * hoc_mesh_elevate_feet) and the raise that takes them per face where they
 * do better than straight in (u, v) (hoc_pipeline_raise).
 *
 * The class: a face whose parametrisation is only C0 (a B-spline knot
 * where the derivative jumps; fuselage_occ28366 has one at u = 2, where
 * |phi_u| halves). Nodes straight in (u, v) crowd on the slow side of the
 * knot, and an element across it is not affine even on a plane: at order 8
 * it folds or loses quality. The analytic kinked plane shows it in closed
 * form: on a plane the feet of a straight triangle's points are those
 * points, so every raised element is affine and keeps its linear q.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "cad/cad.h"
#include "core/geometry.h"
#include "mesh/mesh.h"
#include "pipeline/pipeline.h"
#include "test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The foot on a sphere and on a circle, against the closed form: the
 * point of radius a along the direction of the given one. */
static void test_foot_closed_form(void) {
  const double a = 2.0;
  hoc_model *m = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_SPHERE, a, 0, &m));
  if (!m) return;
  double worst = 0;
  for (int i = 0; i < 40; ++i) {
    double u = 0.3 + 0.13 * i, v = -1.2 + 0.06 * i, r = a * (1.0 + 0.2 * sin(i));
    double p[3] = {r * cos(v) * cos(u), r * cos(v) * sin(u), r * sin(v)};
    double uv[2] = {u + 0.05, v - 0.04}, x[3]; /* a guess nearby */
    CHECK_OK(hoc_cad_face_foot(m, 0, p, 1e-14, uv));
    CHECK_OK(hoc_cad_face_eval(m, 0, 1, uv, x, NULL, NULL));
    for (int k = 0; k < 3; ++k) worst = fmax(worst, fabs(x[k] - p[k] * a / r));
  }
  /* (the distance to a point 0.4 off varies with the tangential error
   * only at second order: rounding bounds the foot near 1e-11) */
  CHECK(worst < 1e-10 * a);
  hoc_model_destroy(&m);
  /* the cylinder's bottom circle (curve 1): foot at angle atan2(y, x) */
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_CYLINDER, a, 1.0, &m));
  if (!m) return;
  int c = hoc_cad_curve_index(m, 2);
  worst = 0;
  for (int i = 0; i < 20 && c >= 0; ++i) {
    double t = 0.2 + 0.29 * i, p[3] = {1.7 * cos(t), 1.7 * sin(t), 0.3}, tt = t - 0.1;
    CHECK_OK(hoc_cad_curve_foot(m, c, p, 1e-14, &tt));
    worst = fmax(worst, fabs(tt - t));
  }
  CHECK(c >= 0 && worst < 1e-12);
  hoc_model_destroy(&m);
}

/* min q and tangled count of a mesh; q per element in q[] if not NULL */
static hoc_quality_stats measure(const hoc_mesh *m, double *q) {
  hoc_quality_stats st = {0};
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q, NULL, &st));
  return st;
}

static void test_kinked_plane(int p) {
  hoc_model *m = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_KINK, 1.0, 0.5, &m));
  if (!m) return;
  hoc_mesh *lin = NULL, *straight = NULL, *raised = NULL;
  /* columns of width 0.2 in u: the knot at u = 0.5 runs through the middle one */
  CHECK_OK(hoc_mesh_grid_linear(m, 5, 4, &lin));
  if (!lin) goto done;
  hoc_run run = {0};
  hoc_mesh_options_default(&run.o);
  CHECK_OK(hoc_mesh_elevate(lin, p, HOC_NODES_EQUISPACED, &straight));
  size_t ne = hoc_mesh_num_elements(lin);
  double *q1 = calloc(ne, sizeof *q1), *qp = calloc(ne, sizeof *qp), *qr = calloc(ne, sizeof *qr);
  CHECK_OK(hoc_pipeline_raise(&run, lin, p, &raised, qr));
  if (!straight || !raised || !q1 || !qp || !qr) {
    free(q1);
    free(qp);
    free(qr);
    goto done;
  }
  hoc_quality_stats s1 = measure(lin, q1), ss = measure(straight, NULL), sr = measure(raised, qp);
  /* the raise tells the q it measured: those of the mesh it gives */
  CHECK(memcmp(qr, qp, ne * sizeof *qr) == 0);
  /* straight in (u, v), the elements across the knot lose much of their q */
  CHECK(ss.tangled > 0 || ss.min < 0.9 * s1.min);
  /* at the feet every element is affine: its linear q, to rounding */
  double gap = 0;
  for (size_t e = 0; e < ne; ++e) gap = fmax(gap, fabs(qp[e] - q1[e]));
  CHECK(sr.tangled == 0 && gap < 1e-9);
  printf("kinked plane, order %d: linear min q %.4f; straight in (u,v) %.4f (%zu tangled); "
         "feet %.4f, largest change of q %.2g\n",
         p, s1.min, ss.min, ss.tangled, sr.min, gap);
  /* every edge's nodes equally spaced between its corners, on the CAD
   * curves too (v = 0 and v = 1 cross the knot) */
  double wx = 0;
  for (size_t e = 0; e < ne; ++e) {
    const size_t *cn = raised->conn + e * (size_t)raised->np;
    for (int k = 0; k < 3; ++k) { /* edge k: corners k, k+1, nodes 3 + k (p - 1) ... */
      const double *A = raised->xyz + 3 * cn[k], *B = raised->xyz + 3 * cn[(k + 1) % 3];
      for (int j = 0; j < p - 1; ++j) {
        const double *X = raised->xyz + 3 * cn[3 + k * (p - 1) + j];
        double s = (double)(j + 1) / p;
        for (int d = 0; d < 3; ++d) wx = fmax(wx, fabs(X[d] - (A[d] + s * (B[d] - A[d]))));
      }
    }
  }
  CHECK(wx < 1e-12);
  free(q1);
  free(qp);
  free(qr);
done:
  hoc_mesh_destroy(&lin);
  hoc_mesh_destroy(&straight);
  hoc_mesh_destroy(&raised);
  hoc_model_destroy(&m);
}

/* m is r node for node: positions, parameters, slots, elements' parameters
 * (its face_gap at least r's) */
static int same_mesh(const hoc_mesh *m, const hoc_mesh *r) {
  if (!m || !r || m->n_nodes != r->n_nodes || m->n_slots != r->n_slots ||
      m->n_elems != r->n_elems || m->np != r->np)
    return 0;
  size_t nn = r->n_nodes, ns = r->n_slots, ne = r->n_elems, np = (size_t)r->np;
  return memcmp(m->xyz, r->xyz, 3 * nn * sizeof(double)) == 0 &&
         memcmp(m->param, r->param, 2 * nn * sizeof(double)) == 0 &&
         memcmp(m->slot_uv, r->slot_uv, 2 * ns * sizeof(double)) == 0 &&
         memcmp(m->slot_pole, r->slot_pole, ns) == 0 &&
         memcmp(m->elem_uv, r->elem_uv, 2 * ne * np * sizeof(double)) == 0 &&
         m->face_gap >= r->face_gap;
}

/* The raise makes the mesh in which some faces take the feet by copying
 * nodes from the two placements it built (hoc_mesh_take_feet): it must be
 * the mesh a third raise would make, node for node, on a model with curves
 * between faces that take the feet and faces that do not, periodic faces
 * and seams (the screw). */
static void test_take_feet_is_a_raise(void) {
  char path[1024];
  snprintf(path, sizeof path, "%s/screw.step", HOC_MODELS_DIR);
  hoc_model *m = NULL;
  CHECK_OK(hoc_model_open(path, &m));
  if (!m) return;
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  hoc_mesh *lin = NULL, *merged = NULL, *feet = NULL, *third = NULL;
  int nf = hoc_model_num_faces(m);
  unsigned char *all = malloc((size_t)nf), *take = malloc((size_t)nf);
  CHECK_OK(hoc_mesh_generate_linear(m, &lo, &lin));
  if (!lin || !all || !take) goto done;
  for (int f = 0; f < nf; ++f) {
    all[f] = 1;
    take[f] = f % 2;
  }
  CHECK_OK(hoc_mesh_elevate(lin, 4, HOC_NODES_EQUISPACED, &merged));
  CHECK_OK(hoc_mesh_elevate_feet(lin, 4, HOC_NODES_EQUISPACED, all, &feet));
  CHECK_OK(hoc_mesh_elevate_feet(lin, 4, HOC_NODES_EQUISPACED, take, &third));
  if (!merged || !feet || !third) goto done;
  /* the nodes that move: on faces that take the feet and on their curves */
  size_t moved = 0, moved_curve = 0;
  for (size_t i = 0; i < third->n_nodes; ++i)
    if (memcmp(third->xyz + 3 * i, merged->xyz + 3 * i, 3 * sizeof(double))) {
      ++moved;
      moved_curve += third->dim[i] == HOC_ON_CURVE;
    }
  /* the feet from the straight raise: its copy with the feet's nodes moved */
  hoc_mesh *from = NULL;
  CHECK_OK(hoc_mesh_elevate_feet_from(lin, merged, take, &from));
  CHECK(same_mesh(from, third));
  hoc_mesh_destroy(&from);
  CHECK_OK(hoc_mesh_take_feet(merged, feet, take));
  CHECK(same_mesh(merged, third));
  size_t ne = third->n_elems;
  printf("screw at order 4, odd faces at the feet: %zu of %zu nodes moved (%zu on curves), "
         "the copy is the raise\n",
         moved, third->n_nodes, moved_curve);
  CHECK(moved > 0 && moved_curve > 0);
  /* a mesh of another source is refused */
  hoc_mesh *other = NULL;
  CHECK_OK(hoc_mesh_elevate(lin, 3, HOC_NODES_EQUISPACED, &other));
  if (other) CHECK_STATUS(hoc_mesh_take_feet(other, feet, take), HOC_ERR_MISMATCH);
  hoc_mesh_destroy(&other);
  /* the raise's q, known from its placements, are those measured anew */
  hoc_run run = {0};
  hoc_mesh_options_default(&run.o);
  for (int p = 2; p <= 8; p += 3) {
    hoc_mesh *raised = NULL;
    double *q = calloc(ne, sizeof *q), *q2 = calloc(ne, sizeof *q2);
    CHECK_OK(hoc_pipeline_raise(&run, lin, p, &raised, q));
    if (raised && q && q2) {
      CHECK_OK(hoc_mesh_measure(raised, HOC_MEASURE_SHAPE, q2, NULL, NULL));
      CHECK(memcmp(q, q2, ne * sizeof *q) == 0);
    }
    free(q);
    free(q2);
    hoc_mesh_destroy(&raised);
  }
done:
  free(all);
  free(take);
  hoc_mesh_destroy(&lin);
  hoc_mesh_destroy(&merged);
  hoc_mesh_destroy(&feet);
  hoc_mesh_destroy(&third);
  hoc_model_destroy(&m);
}

/* Moving nodes in place (hoc_mesh_move_nodes, the feet's placement as a
 * copy of the straight one) keeps the pole flags: it tells where a moved
 * node lands on a pole side, and hoc_mesh_elevate_feet_from then
 * assembles the mesh afresh. On the sphere (poles at v = +-pi/2). */
static void test_move_onto_pole(void) {
  hoc_model *m = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_SPHERE, 1.0, 0, &m));
  if (!m) return;
  hoc_mesh *lin = NULL, *ho = NULL;
  CHECK_OK(hoc_mesh_grid_linear(m, 6, 4, &lin));
  if (lin) CHECK_OK(hoc_mesh_elevate(lin, 2, HOC_NODES_EQUISPACED, &ho));
  unsigned char *which = ho ? calloc(ho->n_nodes, 1) : NULL;
  size_t i = 0;
  while (ho && i < ho->n_nodes && ho->dim[i] != HOC_ON_FACE) ++i;
  if (!which || i == ho->n_nodes) {
    CHECK(0);
  } else {
    which[i] = 1;
    int at_pole = 1;
    ho->param[2 * i + 1] *= 0.9; /* off any pole */
    CHECK_OK(hoc_mesh_move_nodes(ho, which, &at_pole));
    CHECK(at_pole == 0);
    double x[3];
    CHECK_OK(hoc_cad_face_eval(m, 0, 1, ho->param + 2 * i, x, NULL, NULL));
    CHECK(hoc_dist3(x, ho->xyz + 3 * i) == 0);
    ho->param[2 * i + 1] = acos(-1.0) / 2; /* onto the north pole */
    CHECK_OK(hoc_mesh_move_nodes(ho, which, &at_pole));
    CHECK(at_pole == 1);
  }
  free(which);
  hoc_mesh_destroy(&lin);
  hoc_mesh_destroy(&ho);
  hoc_model_destroy(&m);
}

/* Where the parametrisation is even and the elements coarse against the
 * curvature (a torus, 6 x 4 elements around), straight in (u, v) is the
 * better start; the raise keeps, per face, whichever is better, so it is
 * never worse than straight in (u, v). */
static void test_never_worse(void) {
  hoc_model *m = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_TORUS, 2.0, 0.7, &m));
  if (!m) return;
  hoc_mesh *lin = NULL, *straight = NULL, *feet = NULL, *raised = NULL;
  CHECK_OK(hoc_mesh_grid_linear(m, 6, 4, &lin));
  hoc_run run = {0};
  hoc_mesh_options_default(&run.o);
  unsigned char all = 1;
  CHECK_OK(hoc_mesh_elevate(lin, 8, HOC_NODES_EQUISPACED, &straight));
  CHECK_OK(hoc_mesh_elevate_feet(lin, 8, HOC_NODES_EQUISPACED, &all, &feet));
  CHECK_OK(hoc_pipeline_raise(&run, lin, 8, &raised, NULL));
  if (straight && feet && raised) {
    hoc_quality_stats ss = measure(straight, NULL), sf = measure(feet, NULL),
                      sr = measure(raised, NULL);
    printf("coarse torus, order 8: min q straight %.4f (%zu tangled), feet %.4f (%zu), "
           "raise %.4f (%zu)\n",
           ss.min, ss.tangled, sf.min, sf.tangled, sr.min, sr.tangled);
    CHECK(sr.tangled <= ss.tangled && sr.min >= ss.min);
    CHECK(sr.tangled <= sf.tangled);
  }
  hoc_mesh_destroy(&lin);
  hoc_mesh_destroy(&straight);
  hoc_mesh_destroy(&feet);
  hoc_mesh_destroy(&raised);
  hoc_model_destroy(&m);
}

int main(void) {
  test_foot_closed_form();
  test_kinked_plane(3);
  test_kinked_plane(8);
  test_never_worse();
  test_take_feet_is_a_raise();
  test_move_onto_pole();
  return test_report();
}
