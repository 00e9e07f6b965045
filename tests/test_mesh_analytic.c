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

/* Distance between two parameter pairs, modulo the face's periods. */
static double uv_gap(const hoc_cad_face *f, const double *a, const double *b) {
  double g = 0;
  for (int d = 0; d < 2; ++d) {
    double x = a[d] - b[d];
    if (f->period[d] > 0) x -= f->period[d] * floor(x / f->period[d] + 0.5);
    g = fmax(g, fabs(x));
  }
  return g;
}

/* Signed area of an element's corner triangle in its (u, v). */
static double uv_area(const hoc_mesh *m, size_t e) {
  const double *c = m->elem_uv + 2 * e * (size_t)m->np;
  return 0.5 * ((c[2] - c[0]) * (c[5] - c[1]) - (c[4] - c[0]) * (c[3] - c[1]));
}

/* The longest of element e's corner edges in space (the first on ties). */
static int longest_corner_edge(const hoc_mesh *m, size_t e) {
  const size_t *c = m->conn + e * (size_t)m->np;
  int best = 0;
  double lmax = -1;
  for (int k = 0; k < 3; ++k) {
    double l = 0;
    for (int d = 0; d < 3; ++d) {
      double x = m->xyz[3 * c[k] + (size_t)d] - m->xyz[3 * c[(k + 1) % 3] + (size_t)d];
      l += x * x;
    }
    if (l > lmax) lmax = l, best = k;
  }
  return best;
}

/* Local refinement on the torus (two seams; every edge has two elements):
 * each of two flagged elements split in four and their three neighbours
 * split too (red-green: in two; by longest edge: bisected there first);
 * the mesh conforming (every corner edge in two elements, with the same
 * high-order nodes), the elements not split unchanged and in order, each
 * split one followed by children that tile it in (u, v), with nodes
 * straight between their corners, every node on the surface; without
 * flags, the same mesh. */
static void test_split(hoc_split_kind kind) {
  const double a = 3, b = 1;
  const int bisecting = kind == HOC_SPLIT_LONGEST_EDGE;
  hoc_model *model;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_TORUS, a, b, &model));
  if (!model) return;
  const hoc_cad_face *f = &model->faces[0];
  hoc_mesh *lin = NULL, *m = NULL, *s = NULL;
  CHECK_OK(hoc_mesh_grid_linear(model, 24, 8, &lin));
  CHECK_OK(hoc_mesh_elevate(lin, 3, HOC_NODES_EQUISPACED, &m));
  if (!m) goto out;
  size_t ne = m->n_elems, np = (size_t)m->np;
  unsigned char *flag = calloc(ne, 1);
  CHECK_STATUS(hoc_mesh_split(m, NULL, kind, &s, NULL), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_mesh_split(m, flag, kind, NULL, NULL), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_mesh_split(m, flag, (hoc_split_kind)7, &s, NULL), HOC_ERR_ARGUMENT);
  unsigned char *pieces = malloc(ne);
  CHECK(flag && pieces);
  if (!flag || !pieces) goto done;
  /* nothing flagged: the same mesh */
  CHECK_OK(hoc_mesh_split(m, flag, kind, &s, NULL));
  if (s) {
    int same = s->n_elems == ne && s->n_nodes == m->n_nodes;
    for (size_t i = 0; same && i < ne * np; ++i)
      same = !memcmp(s->xyz + 3 * s->conn[i], m->xyz + 3 * m->conn[i], 3 * sizeof(double));
    CHECK(same);
  }
  hoc_mesh_destroy(&s);
  size_t flagged[2] = {0, ne / 2 + 5};
  flag[flagged[0]] = flag[flagged[1]] = 1;
  memset(pieces, 0, ne);
  CHECK_OK(hoc_mesh_split(m, flag, kind, &s, pieces));
  if (!s) goto done;
  if (!bisecting) CHECK(s->n_elems == ne + 2 * (3 + 3));
  /* (the grid has no curve lines: test_mesh_gmsh splits edges on curves) */
  /* conforming: each corner edge in exactly two elements, the same nodes */
  size_t bad = 0;
  for (size_t e = 0; e < s->n_elems; ++e)
    for (int k = 0; k < 3; ++k) {
      const size_t *c = s->conn + e * np;
      size_t x = c[k], y = c[(k + 1) % 3], found = 0;
      for (size_t e2 = 0; e2 < s->n_elems; ++e2) {
        if (e2 == e) continue;
        const size_t *c2 = s->conn + e2 * np;
        for (int k2 = 0; k2 < 3; ++k2) {
          if (c2[k2] != y || c2[(k2 + 1) % 3] != x) continue; /* the other side runs y -> x */
          ++found;
          for (int j = 0; j < 2; ++j)
            bad += c[3 + k * 2 + j] != c2[3 + k2 * 2 + (1 - j)];
        }
      }
      bad += found != 1;
    }
  CHECK(bad == 0);
  /* parents in order: unsplit ones unchanged; children straight in (u, v),
   * tiling their parent (areas summing to its own), red-green in four or
   * two, bisected ones never keeping the parent's longest edge whole */
  double rs[2 * 10];
  CHECK_OK(hoc_tri_nodes(3, HOC_NODES_EQUISPACED, rs));
  size_t j = 0, kept = 0, wrong_kids = 0, whole_longest = 0;
  double gap = 0;
  for (size_t e = 0; e < ne && j < s->n_elems; ++e) {
    const size_t *c = m->conn + e * np, *c2 = s->conn + j * np;
    int same = 1;
    for (size_t k = 0; k < np; ++k)
      same &= !memcmp(m->xyz + 3 * c[k], s->xyz + 3 * c2[k], 3 * sizeof(double));
    if (same) {
      ++kept;
      ++j;
      wrong_kids += pieces[e] != 1;
      continue;
    }
    const double *P = m->elem_uv + 2 * e * np; /* corners 0..2 */
    double area = uv_area(m, e), sum = 0;
    int lk = longest_corner_edge(m, e);
    const double *la = m->xyz + 3 * c[lk], *lb = m->xyz + 3 * c[(lk + 1) % 3];
    size_t n_kids = 0, first = j;
    for (; j < s->n_elems && sum < area * (1 - 1e-9); ++j, ++n_kids) {
      const double *C = s->elem_uv + 2 * j * np;
      sum += uv_area(s, j);
      /* the child's corners in the parent's (u, v); its nodes affine in them */
      for (size_t k = 0; k < np; ++k) {
        double r = rs[2 * k], t = rs[2 * k + 1], want[2];
        for (int d = 0; d < 2; ++d)
          want[d] = C[d] + r * (C[2 + d] - C[d]) + t * (C[4 + d] - C[d]);
        gap = fmax(gap, uv_gap(f, C + 2 * k, want));
      }
      int has_a = 0, has_b = 0;
      for (int k = 0; k < 3; ++k) {
        const double *x = s->xyz + 3 * s->conn[j * np + (size_t)k];
        has_a |= !memcmp(x, la, 3 * sizeof(double));
        has_b |= !memcmp(x, lb, 3 * sizeof(double));
      }
      whole_longest += has_a && has_b;
    }
    gap = fmax(gap, fabs(sum - area) / area);
    if (bisecting)
      wrong_kids += n_kids < 2 || n_kids > 4 || (flag[e] && n_kids != 4);
    else
      wrong_kids += n_kids != (flag[e] ? 4u : 2u);
    wrong_kids += pieces[e] != n_kids; /* as reported */
    if (flag[e] && !bisecting) { /* the first child: corner 0, then the midpoint of edge 0 */
      const double *C = s->elem_uv + 2 * first * np;
      double mid[2] = {0.5 * (P[0] + P[2]), 0.5 * (P[1] + P[3])};
      gap = fmax(gap, uv_gap(f, C, P));
      gap = fmax(gap, uv_gap(f, C + 2, mid));
    }
  }
  CHECK(j == s->n_elems);
  CHECK(wrong_kids == 0);
  CHECK(bisecting ? kept <= ne - 2 - 2 * 3 : kept == ne - 2 - 2 * 3);
  CHECK(!bisecting || whole_longest == 0);
  CHECK(gap <= 1e-12);
  double worst = 0, dist;
  for (size_t i = 0; i < s->n_nodes; ++i)
    worst = fmax(worst, off_surface(HOC_ANALYTIC_TORUS, a, b, s->xyz + 3 * i));
  CHECK(worst <= 1e-13 * a);
  CHECK_OK(hoc_mesh_max_cad_distance(s, &dist));
  CHECK(dist == 0.0);
  hoc_quality_stats st;
  CHECK_OK(hoc_mesh_measure(s, HOC_MEASURE_SHAPE, NULL, NULL, &st));
  CHECK(st.tangled == 0);
  printf("split %s on the torus: %zu -> %zu elements, %zu kept, %zu unmatched edge nodes, uv gap "
         "%.2g, min q %.3f\n",
         bisecting ? "at longest edges" : "red-green", ne, s->n_elems, kept, bad, gap, st.min);
done:
  free(flag);
  free(pieces);
  hoc_mesh_destroy(&s);
out:
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* Arrays a and b of n items of `size` bytes are the same, bit for bit,
 * and not the same memory (a NULL pair counts as the same). */
static int same_copy(const void *a, const void *b, size_t n, size_t size) {
  if (!a || !b) return a == b;
  return a != b && !memcmp(a, b, n * size);
}

/* hoc_mesh_copy: every array the same bit for bit, in memory of its own. */
static void test_copy(void) {
  hoc_model *model;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_SPHERE, 1, 0, &model));
  if (!model) return;
  hoc_mesh *lin = NULL, *m = NULL, *c = NULL;
  CHECK_OK(hoc_mesh_grid_linear(model, 12, 6, &lin));
  CHECK_OK(hoc_mesh_elevate(lin, 4, HOC_NODES_FEKETE, &m));
  CHECK_STATUS(hoc_mesh_copy(NULL, &c), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_mesh_copy(m, NULL), HOC_ERR_ARGUMENT);
  CHECK_OK(hoc_mesh_copy(m, &c));
  if (m && c) {
    size_t nn = m->n_nodes, ne = m->n_elems, np = (size_t)m->np, ns = m->n_slots;
    CHECK(c->model == m->model && c->order == 4 && c->nodeset == HOC_NODES_FEKETE);
    CHECK(c->n_nodes == nn && c->n_elems == ne && c->n_slots == ns && c->n_lines == m->n_lines);
    CHECK(same_copy(c->xyz, m->xyz, 3 * nn, sizeof *m->xyz));
    CHECK(same_copy(c->param, m->param, 2 * nn, sizeof *m->param));
    CHECK(same_copy(c->dim, m->dim, nn, sizeof *m->dim));
    CHECK(same_copy(c->entity, m->entity, nn, sizeof *m->entity));
    CHECK(same_copy(c->conn, m->conn, ne * np, sizeof *m->conn));
    CHECK(same_copy(c->elem_face, m->elem_face, ne, sizeof *m->elem_face));
    CHECK(same_copy(c->elem_uv, m->elem_uv, 2 * ne * np, sizeof *m->elem_uv));
    CHECK(same_copy(c->elem_slot, m->elem_slot, ne * np, sizeof *m->elem_slot));
    CHECK(same_copy(c->slot_node, m->slot_node, ns, sizeof *m->slot_node));
    CHECK(same_copy(c->slot_uv, m->slot_uv, 2 * ns, sizeof *m->slot_uv));
    CHECK(same_copy(c->slot_pole, m->slot_pole, ns, sizeof *m->slot_pole));
    CHECK(same_copy(c->face_orient, m->face_orient, (size_t)model->n_faces,
                    sizeof *m->face_orient));
    /* the sphere's poles: slots marked, and the copy measures the same */
    size_t poles = 0;
    for (size_t i = 0; i < ns; ++i) poles += c->slot_pole[i] != 0;
    CHECK(poles > 0);
    hoc_quality_stats a, b;
    CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &a));
    CHECK_OK(hoc_mesh_measure(c, HOC_MEASURE_SHAPE, NULL, NULL, &b));
    CHECK(a.min == b.min && a.mean == b.mean && a.tangled == b.tangled);
  }
  hoc_mesh_destroy(&c);
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

int main(void) {
  test_copy();
  test_split(HOC_SPLIT_RED_GREEN);
  test_split(HOC_SPLIT_LONGEST_EDGE);
  test_topology_detection();
  test_derivatives();
  test_invert();
  test_plane_exact();
  check_surface(HOC_ANALYTIC_SPHERE, 1.0, 0, 16, 8, 0.5);
  check_surface(HOC_ANALYTIC_CYLINDER, 1.0, 2.0, 12, 4, 0.5);
  check_surface(HOC_ANALYTIC_TORUS, 3.0, 1.0, 24, 8, 0.5);
  return test_report();
}
