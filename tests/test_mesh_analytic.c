/* Order elevation on exact analytic surfaces (plane, sphere with poles and a
 * seam, cylinder, torus with two seams): node counts, every node exactly on
 * the surface, no NaN, elements valid, parameters unwrapped across seams.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "core/hash.h"
#include "mesh/mesh.h"
#include "quality/quality.h"
#include "test_util.h"

#include <string.h>

static const double PI = 3.14159265358979323846;

/* Distance of x from the analytic surface, computed implicitly. */
static double off_surface(hoc_analytic_kind kind, double a, double b, const double *x) {
  double rho = hypot(x[0], x[1]);
  switch (kind) {
  case HOC_ANALYTIC_PLANE: return fabs(x[2]);
  case HOC_ANALYTIC_SPHERE: return fabs(sqrt(rho * rho + x[2] * x[2]) - a);
  case HOC_ANALYTIC_CYLINDER: return fabs(rho - a);
  case HOC_ANALYTIC_TORUS: default: return fabs(hypot(rho - a, x[2]) - b);
  }
}

static size_t count_edges(const hoc_mesh *m) {
  hoc_hash h;
  if (hoc_hash_init(&h, 3 * m->n_elems) != HOC_OK) return 0;
  for (size_t e = 0; e < m->n_elems; ++e)
    for (int k = 0; k < 3; ++k)
      hoc_hash_insert(&h, hoc_pair_key(m->conn[e * m->np + k], m->conn[e * m->np + (k + 1) % 3]),
                      0, NULL, NULL);
  size_t n = h.count;
  hoc_hash_free(&h);
  return n;
}

static void check_surface(hoc_analytic_kind kind, double a, double b, int nu, int nv,
                          double min_q_expected) {
  hoc_model *model;
  CHECK_OK(hoc_cad_create_analytic(kind, a, b, &model));
  if (!model) return;
  hoc_mesh *lin;
  CHECK_OK(hoc_mesh_grid_linear(model, nu, nv, &lin));
  if (!lin) {
    hoc_model_destroy(&model);
    return;
  }
  size_t V = lin->n_nodes, E = count_edges(lin), F = lin->n_elems;
  int orders[] = {1, 2, 3, 5, 10, 15};
  for (size_t io = 0; io < sizeof orders / sizeof *orders; ++io)
    for (int set = 0; set < 3; ++set) {
      int p = orders[io];
      if (set && p < 3) continue;
      hoc_mesh *m;
      CHECK_OK(hoc_mesh_elevate(lin, p, (hoc_nodeset)set, &m));
      if (!m) continue;
      CHECK(m->n_elems == F);
      CHECK(m->n_nodes == V + E * (size_t)(p - 1) + F * (size_t)((p - 1) * (p - 2) / 2));
      double worst = 0;
      for (size_t i = 0; i < m->n_nodes; ++i) worst = fmax(worst, off_surface(kind, a, b, m->xyz + 3 * i));
      CHECK(worst <= 1e-13 * a);
      double dist;
      CHECK_OK(hoc_mesh_max_cad_distance(m, &dist));
      CHECK(dist == 0.0);
      /* element parameters unwrapped: no element spans half a period */
      const hoc_cad_face *f = &model->faces[0];
      double span = 0;
      for (size_t e = 0; e < m->n_elems; ++e)
        for (int d = 0; d < 2; ++d) {
          double lo = INFINITY, hi = -INFINITY;
          for (int k = 0; k < m->np; ++k) {
            double u = m->elem_uv[2 * (e * m->np + k) + d];
            lo = fmin(lo, u);
            hi = fmax(hi, u);
          }
          if (f->period[d] > 0) span = fmax(span, (hi - lo) / f->period[d]);
        }
      CHECK(span < 0.5);
      hoc_quality_stats st;
      double *q = calloc(m->n_elems, sizeof *q);
      CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q, NULL, &st));
      int finite = 1;
      for (size_t e = 0; e < m->n_elems; ++e) finite &= isfinite(q[e]);
      CHECK(finite);
      CHECK(st.tangled == 0);
      CHECK(st.min >= min_q_expected);
      if (!(st.min >= min_q_expected) || st.tangled)
        fprintf(stderr, "  kind %d p=%d set=%d: min q %.4f mean %.4f tangled %zu\n", (int)kind, p,
                set, st.min, st.mean, st.tangled);
      free(q);
      hoc_mesh_destroy(&m);
    }
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* On a plane the elements stay affine at every order: q equals the linear
 * closed form (right isosceles triangles: sqrt(3)/2). */
static void test_plane_exact(void) {
  hoc_model *model;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_PLANE, 2.0, 0, &model));
  hoc_mesh *lin;
  CHECK_OK(hoc_mesh_grid_linear(model, 4, 4, &lin));
  for (int p = 1; p <= 10; ++p) {
    hoc_mesh *m;
    CHECK_OK(hoc_mesh_elevate(lin, p, HOC_NODES_FEKETE, &m));
    hoc_quality_stats st;
    CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st));
    CHECK_NEAR(st.min, sqrt(3.0) / 2, 1e-12);
    CHECK_NEAR(st.max, sqrt(3.0) / 2, 1e-12);
    CHECK(st.tangled == 0);
    hoc_mesh_destroy(&m);
  }
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* Seams and poles found from the parametrisation alone. */
static void test_topology_detection(void) {
  hoc_model *m;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_SPHERE, 1, 0, &m));
  CHECK_NEAR(m->faces[0].period[0], 2 * PI, 1e-15);
  CHECK(m->faces[0].period[1] == 0);
  CHECK(m->faces[0].pole[2] && m->faces[0].pole[3] && !m->faces[0].pole[0] && !m->faces[0].pole[1]);
  CHECK(m->curves[1].degenerate && m->curves[2].degenerate && !m->curves[0].degenerate);
  hoc_model_destroy(&m);
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_TORUS, 3, 1, &m));
  CHECK(m->faces[0].period[0] > 0 && m->faces[0].period[1] > 0);
  CHECK(m->curves[0].period > 0 && m->curves[1].period > 0);
  hoc_model_destroy(&m);
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_CYLINDER, 1, 2, &m));
  CHECK(m->faces[0].period[0] > 0 && m->faces[0].period[1] == 0);
  CHECK(!m->faces[0].pole[0] && !m->faces[0].pole[2]);
  hoc_model_destroy(&m);
  CHECK_STATUS(hoc_cad_create_analytic(HOC_ANALYTIC_TORUS, 1, 3, &m), HOC_ERR_ARGUMENT);
  CHECK(m == NULL);
}

/* Inverting the parametrisation from a nearby guess. */
static void test_invert(void) {
  hoc_model *m;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_TORUS, 3, 1, &m));
  double target[2] = {0.3, 6.1}, x[3];
  CHECK_OK(hoc_cad_face_eval(m, 0, 1, target, x, NULL, NULL));
  double uv[2] = {0.4, -0.3}, d; /* guess on the other side of the v seam */
  CHECK_OK(hoc_cad_face_invert(m, 0, x, uv, &d));
  CHECK(d < 1e-13);
  CHECK_NEAR(uv[0], 0.3, 1e-12);
  CHECK_NEAR(uv[1], 6.1 - 2 * PI, 1e-12); /* stays on the guess's copy */
  double t = 1.0;
  double y[3];
  double tt = 2.0;
  CHECK_OK(hoc_cad_curve_eval(m, 1, 1, &tt, y, NULL));
  CHECK_OK(hoc_cad_curve_invert(m, 1, y, &t, &d));
  CHECK(d < 1e-13);
  CHECK_NEAR(t, 2.0, 1e-12);
  hoc_model_destroy(&m);
}

/* Derivatives of the analytic surfaces against finite differences. */
static void test_derivatives(void) {
  for (int kind = 0; kind < 4; ++kind) {
    hoc_model *m;
    CHECK_OK(hoc_cad_create_analytic((hoc_analytic_kind)kind, 3, 1, &m));
    double uv[2] = {0.7, 0.4}, du[3], dv[3], xp[3], xm[3], h = 1e-6;
    CHECK_OK(hoc_cad_face_eval(m, 0, 1, uv, NULL, du, dv));
    for (int d = 0; d < 2; ++d) {
      double a[2] = {uv[0], uv[1]}, b[2] = {uv[0], uv[1]};
      a[d] += h;
      b[d] -= h;
      CHECK_OK(hoc_cad_face_eval(m, 0, 1, a, xp, NULL, NULL));
      CHECK_OK(hoc_cad_face_eval(m, 0, 1, b, xm, NULL, NULL));
      for (int k = 0; k < 3; ++k) CHECK_NEAR((xp[k] - xm[k]) / (2 * h), d ? dv[k] : du[k], 1e-8);
    }
    hoc_model_destroy(&m);
  }
}

int main(void) {
  test_topology_detection();
  test_derivatives();
  test_invert();
  test_plane_exact();
  check_surface(HOC_ANALYTIC_SPHERE, 1.0, 0, 16, 8, 0.5);
  check_surface(HOC_ANALYTIC_CYLINDER, 1.0, 2.0, 12, 4, 0.5);
  check_surface(HOC_ANALYTIC_TORUS, 3.0, 1.0, 24, 8, 0.5);
  return test_report();
}
