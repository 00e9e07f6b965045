/* Edge swaps of the linear mesh (mesh/swap.c).
 *
 * Slivers: the unit square (analytic plane) with a thin rhombus L B R T in
 * its middle, split along its long diagonal L-R into two slivers (height
 * 0.02 on 0.8, q = 4 sqrt(3) A / sum of squared edges = 0.0577). The swap
 * to the short diagonal B-T gives two triangles of q 0.1719 (closed form
 * below); without swaps the min q stays 0.0577.
 *
 * Ears: the top face of tests/data/thin_disk.brep (a disk of radius 5) as
 * a fan of six triangles around an inner node X, its rim nodes unevenly
 * spaced. Swapping edge X-P0 raises the smaller q of its pair from 0.594
 * to 0.656, but makes triangle P5 P0 P1, whose three corners lie on the
 * rim circle: raised, its two edges along the circle meet at P0 at 180
 * degrees (the Jacobian is singular there) and the element is tangled at
 * order 2. Every interior edge of a fan is such an edge, so the swaps must
 * leave the fan as it is; the same mesh with that swap made by hand shows
 * the tangle.
 *
 * Inverted ears: the sheet of tests/data/sheet_dots.brep, a square with
 * disks (holes in it, concave from its side). Two triangles of its linear
 * mesh at one of its curves, (A, M, Z) and (M, B, Z) with A-M and M-B on
 * the curve, swapped by hand into (A, M, B) and (A, B, Z): the ear A M B
 * is flat or inverted, outside the sheet (gmsh makes such triangles along
 * sides where a face's parametrisation stalls). The swaps undo it, though
 * no q of the pair rises from a positive one.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"
#include "mesh/mesh.h"
#include "test_util.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DATA HOC_SOURCE_DIR "/tests/data/"

/* Shape q of a straight planar triangle: 4 sqrt(3) area / sum of squared
 * edges. */
static double planar_q(const double a[2], const double b[2], const double c[2]) {
  double area = 0.5 * fabs((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
  double s = 0;
  const double *p[4] = {a, b, c, a};
  for (int i = 0; i < 3; ++i)
    s += (p[i + 1][0] - p[i][0]) * (p[i + 1][0] - p[i][0]) +
         (p[i + 1][1] - p[i][1]) * (p[i + 1][1] - p[i][1]);
  return 4 * sqrt(3.0) * area / s;
}

/* Does the mesh have a triangle with corners {a, b, c} (any order)? Its
 * index, or SIZE_MAX. */
static size_t find_triangle(const hoc_mesh *m, size_t a, size_t b, size_t c) {
  for (size_t e = 0; e < m->n_elems; ++e) {
    const size_t *t = m->conn + 3 * e;
    int n = 0;
    for (int k = 0; k < 3; ++k)
      n += t[k] == a || t[k] == b || t[k] == c;
    if (n == 3) return e;
  }
  return SIZE_MAX;
}

/* Sum of the triangles' areas (flat, in the xy plane). */
static double total_area(const hoc_mesh *m) {
  double s = 0;
  for (size_t e = 0; e < m->n_elems; ++e) {
    const double *x[3];
    for (int k = 0; k < 3; ++k)
      x[k] = m->xyz + 3 * m->conn[3 * e + k];
    s += 0.5 *
         ((x[1][0] - x[0][0]) * (x[2][1] - x[0][1]) - (x[1][1] - x[0][1]) * (x[2][0] - x[0][0]));
  }
  return s;
}

/* A linear source of one face's triangles (par may be NULL: located). */
static hoc_mesh_source linear_source(size_t n_nodes, const double *xyz, const double *par,
                                     const signed char *dim, const int *ent, size_t n_elems,
                                     const size_t *conn, const int *face) {
  hoc_mesh_source src = {0};
  src.order = 1;
  src.nodeset = HOC_NODES_EQUISPACED;
  src.n_nodes = n_nodes;
  src.xyz = xyz;
  src.param = par;
  src.dim = dim;
  src.entity = ent;
  src.n_elems = n_elems;
  src.conn = conn;
  src.elem_face = face;
  return src;
}

static void test_slivers(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_PLANE, 1.0, 0.0, &model));
  if (!model) return;
  /* nodes: the four corners (vertices, located), then L B R T */
  enum { V0, V1, V2, V3, L, B, R, T, N };
  double uv[N][2] = {{0, 0},     {1, 0},      {1, 1},     {0, 1},
                     {0.1, 0.5}, {0.5, 0.48}, {0.9, 0.5}, {0.5, 0.52}};
  double xyz[3 * N], par[2 * N];
  signed char dim[N];
  int ent[N];
  unsigned char has[N];
  for (int i = 0; i < N; ++i) {
    CHECK_OK(hoc_cad_face_eval(model, 0, 1, uv[i], xyz + 3 * i, NULL, NULL));
    par[2 * i] = uv[i][0], par[2 * i + 1] = uv[i][1];
    dim[i] = HOC_ON_FACE, ent[i] = 0, has[i] = 1;
    if (i < L) {
      dim[i] = HOC_ON_VERTEX, has[i] = 0, ent[i] = -1;
      for (int v = 0; v < model->n_vertices; ++v)
        if (fabs(model->vertices[v].xyz[0] - xyz[3 * i]) +
                fabs(model->vertices[v].xyz[1] - xyz[3 * i + 1]) <
            1e-12)
          ent[i] = v;
      CHECK(ent[i] >= 0);
      if (ent[i] < 0) goto done;
    }
  }
  size_t conn[] = {V0, V1, B, V1, R,  B, V1, V2, R, V2, T, R, V2, V3, T,
                   V3, L,  T, V3, V0, L, V0, B,  L, L,  B, R, R,  T,  L};
  int face[10] = {0};
  hoc_mesh_source src = linear_source(N, xyz, par, dim, ent, 10, conn, face);
  src.has_param = has;
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_assemble(model, &src, &lin));
  if (!lin) goto done;
  hoc_quality_stats st0, st1;
  CHECK_OK(hoc_mesh_measure(lin, HOC_MEASURE_SHAPE, NULL, NULL, &st0));
  double q_long = planar_q(uv[L], uv[B], uv[R]), q_short = planar_q(uv[L], uv[B], uv[T]);
  size_t swapped = 0;
  CHECK_OK(hoc_mesh_swap_edges(lin, &swapped, NULL));
  CHECK_OK(hoc_mesh_measure(lin, HOC_MEASURE_SHAPE, NULL, NULL, &st1));
  size_t lbt = find_triangle(lin, L, B, T), brt = find_triangle(lin, B, R, T);
  printf("slivers: %zu swap(s), min q %.4f -> %.4f (closed form %.4f -> %.4f), area %.15f\n",
         swapped, st0.min, st1.min, q_long, q_short, total_area(lin));
  CHECK_NEAR(st0.min, q_long, 1e-12);
  CHECK(swapped >= 1 && lbt != SIZE_MAX && brt != SIZE_MAX);
  CHECK(find_triangle(lin, L, B, R) == SIZE_MAX && find_triangle(lin, R, T, L) == SIZE_MAX);
  CHECK(st1.tangled == 0 && st1.min >= q_short - 1e-12);
  CHECK_NEAR(total_area(lin), 1.0, 1e-12);
  if (lbt != SIZE_MAX && brt != SIZE_MAX) {
    double q[10];
    CHECK_OK(hoc_mesh_measure(lin, HOC_MEASURE_SHAPE, q, NULL, NULL));
    CHECK_NEAR(q[lbt], q_short, 1e-12);
    CHECK_NEAR(q[brt], planar_q(uv[B], uv[R], uv[T]), 1e-12);
  }
  /* the swapped mesh raises and measures like any other */
  hoc_mesh *ho = NULL;
  CHECK_OK(hoc_mesh_elevate(lin, 3, HOC_NODES_EQUISPACED, &ho));
  if (ho) {
    hoc_quality_stats st;
    CHECK_OK(hoc_mesh_measure(ho, HOC_MEASURE_SHAPE, NULL, NULL, &st));
    CHECK(st.tangled == 0 && fabs(st.min - st1.min) < 1e-9);
  }
  hoc_mesh_destroy(&ho);
  hoc_mesh_destroy(&lin);
done:
  hoc_model_destroy(&model);
}

/* The disk's top face: the plane highest in z; its rim curve. */
static int top_face(const hoc_model *model, int *curve) {
  int top = -1;
  for (int f = 0; f < model->n_faces; ++f) {
    const double *b = model->faces[f].bbox;
    if (model->faces[f].plane && (top < 0 || b[2] > model->faces[top].bbox[2])) top = f;
  }
  *curve = -1;
  if (top < 0 || model->faces[top].n_curves != 1) return -1;
  for (int c = 0; c < model->n_curves; ++c)
    if (model->curves[c].tag == abs(model->faces[top].curves[0])) *curve = c;
  return *curve >= 0 ? top : -1;
}

/* Angles of the fan's rim nodes from the rim's vertex (P0), and its inner
 * node X relative to the radius: the pair at P0 is the fan's worst
 * (q 0.594), and the swap into the ear P5 P0 P1 would make it 0.656. */
enum { N_RIM = 6 };

/* P0 at 0, P1 at 1.15 rad, three more evenly spaced, P5 at -1.15 rad. */
static double rim_angle(int i) {
  const double two_pi = 6.28318530717958647692, t = 1.15;
  if (i == 0) return 0;
  if (i == N_RIM - 1) return two_pi - t;
  return t + (two_pi - 2 * t) * (i - 1) / (N_RIM - 2);
}

/* The smaller q of m's elements with a corner at node `at` (all if
 * SIZE_MAX). */
static double min_q_at(const hoc_mesh *m, size_t at) {
  double *q = calloc(m->n_elems, sizeof *q), mn = INFINITY;
  CHECK(q != NULL);
  if (!q) return -1;
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q, NULL, NULL));
  for (size_t e = 0; e < m->n_elems; ++e) {
    const size_t *c = m->conn + e * (size_t)m->np;
    if (at == SIZE_MAX || c[0] == at || c[1] == at || c[2] == at) mn = fmin(mn, q[e]);
  }
  free(q);
  return mn;
}

/* src assembled, its edges swapped if `swap` (*swaps), and the min q of
 * its elements at node `at` (min_q_at), straight (*q1) and raised to
 * order p (*qp). */
static void swap_and_measure(hoc_model *model, const hoc_mesh_source *src, int swap, int p,
                             size_t at, size_t *swaps, double *q1, double *qp) {
  hoc_mesh *lin = NULL, *ho = NULL;
  *q1 = *qp = -1;
  *swaps = SIZE_MAX;
  CHECK_OK(hoc_mesh_assemble(model, src, &lin));
  if (!lin) return;
  *swaps = 0;
  if (swap) CHECK_OK(hoc_mesh_swap_edges(lin, swaps, NULL));
  *q1 = min_q_at(lin, at);
  CHECK_OK(hoc_mesh_elevate(lin, p, HOC_NODES_EQUISPACED, &ho));
  if (ho) *qp = min_q_at(ho, at);
  hoc_mesh_destroy(&ho);
  hoc_mesh_destroy(&lin);
}

/* The fan of six triangles around X on the top face, or with edge X-P0
 * swapped (`ear`); its linear mesh, swapped if `swap` (*swapped), and the
 * min q of its elements at P0, linear (*min_q) and raised to order 3. */
static void disk_fan(hoc_model *model, int ear, int swap, size_t *swapped, double *min_q,
                     double *min_q3) {
  int curve, f = top_face(model, &curve);
  CHECK(f >= 0);
  *min_q = *min_q3 = -1;
  *swapped = SIZE_MAX;
  if (f < 0) return;
  const hoc_cad_curve *cv = &model->curves[curve];
  const double *b = model->faces[f].bbox, *v0 = model->vertices[cv->v0].xyz;
  double cx = 0.5 * (b[0] + b[3]), cy = 0.5 * (b[1] + b[4]), z = v0[2];
  double radius = hypot(v0[0] - cx, v0[1] - cy), angle0 = atan2(v0[1] - cy, v0[0] - cx);
  enum { N = N_RIM + 1 };
  double xyz[3 * N];
  signed char dim[N];
  int ent[N];
  for (int i = 0; i < N_RIM; ++i) {
    double a = angle0 + rim_angle(i);
    xyz[3 * i] = cx + radius * cos(a), xyz[3 * i + 1] = cy + radius * sin(a), xyz[3 * i + 2] = z;
    dim[i] = i ? HOC_ON_CURVE : HOC_ON_VERTEX, ent[i] = i ? curve : cv->v0;
  }
  /* X at (-0.4, -0.85) of the radius in the frame where P0 is at angle 0 */
  double xr = -0.4, yr = -0.85, ca = cos(angle0), sa = sin(angle0);
  xyz[3 * N_RIM] = cx + radius * (ca * xr - sa * yr);
  xyz[3 * N_RIM + 1] = cy + radius * (sa * xr + ca * yr);
  xyz[3 * N_RIM + 2] = z;
  dim[N_RIM] = HOC_ON_FACE, ent[N_RIM] = f;
  size_t conn[3 * N_RIM];
  for (int i = 0; i < N_RIM; ++i)
    conn[3 * i] = (size_t)i, conn[3 * i + 1] = (size_t)(i + 1) % N_RIM, conn[3 * i + 2] = N_RIM;
  if (ear) { /* (0, 1, X) and (5, 0, X) become (5, 0, 1) and (5, 1, X) */
    size_t t[3] = {N_RIM - 1, 0, 1}, u[3] = {N_RIM - 1, 1, N_RIM};
    memcpy(conn, t, sizeof t);
    memcpy(conn + 3 * (N_RIM - 1), u, sizeof u);
  }
  int face[N_RIM];
  for (int i = 0; i < N_RIM; ++i)
    face[i] = f;
  hoc_mesh_source src = linear_source(N, xyz, NULL, dim, ent, N_RIM, conn, face);
  /* the rim's lines given (as gmsh gives them): not inferred from the
   * edges, which would take the ear's chord for one */
  size_t lines[2 * N_RIM];
  int line_curve[N_RIM];
  for (int i = 0; i < N_RIM; ++i)
    lines[2 * i] = (size_t)i, lines[2 * i + 1] = (size_t)(i + 1) % N_RIM, line_curve[i] = curve;
  src.n_lines = N_RIM;
  src.line_conn = lines;
  src.line_curve = line_curve;
  swap_and_measure(model, &src, swap, 3, 0, swapped, min_q, min_q3);
}

static void test_ears(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(DATA "thin_disk.brep", &model));
  if (!model) return;
  size_t swapped, none;
  double q_fan, q_fan3, q_ear, q_ear3, q_fan0, q_fan03;
  disk_fan(model, 0, 0, &none, &q_fan0, &q_fan03);
  disk_fan(model, 0, 1, &swapped, &q_fan, &q_fan3);
  disk_fan(model, 1, 0, &none, &q_ear, &q_ear3);
  printf("ears: at P0 the fan's min q %.4f (%.4f at order 3), %zu swap(s): %.4f (%.4f); with "
         "the ear %.4f (%.4f)\n",
         q_fan0, q_fan03, swapped, q_fan, q_fan3, q_ear, q_ear3);
  /* the swap would raise the linear q at P0, and it tangles when raised */
  CHECK(q_ear > 1.05 * q_fan0 && q_ear3 == 0);
  CHECK(swapped == 0 && q_fan == q_fan0 && q_fan3 > 0.5);
  hoc_model_destroy(&model);
}

/* Shape q of a straight triangle in space. */
static double straight_q(const double *a, const double *b, const double *c) {
  double u[3], v[3], w[3], s = 0;
  for (int d = 0; d < 3; ++d) {
    u[d] = b[d] - a[d], v[d] = c[d] - a[d];
    s += u[d] * u[d] + v[d] * v[d] + (c[d] - b[d]) * (c[d] - b[d]);
  }
  w[0] = u[1] * v[2] - u[2] * v[1], w[1] = u[2] * v[0] - u[0] * v[2],
  w[2] = u[0] * v[1] - u[1] * v[0];
  return 4 * sqrt(3.0) * 0.5 * sqrt(w[0] * w[0] + w[1] * w[1] + w[2] * w[2]) / s;
}

/* Two triangles inside a cylinder of radius 1: a, b at u = pi, v = 1 -+ h
 * and c, d at u = pi -+ D. Straight, the pair on the diagonal c-d looks
 * better (its chord cuts 1 - cos D inside the surface, which widens its
 * triangles); on the surface, developed, it is the worse (height h on
 * base 2 D). The order-2 check must refuse the swap; `swapped` gives the
 * pair on c-d. *q1: min straight q, *q2: min q raised to order 2. */
static void bend_pair(hoc_model *model, int swapped_pair, int swap, size_t *swaps, double *q1,
                      double *q2) {
  const double pi = 3.14159265358979323846, h = 0.05, D = 0.9;
  enum { A, B, C, D_, N };
  double uv[N][2] = {{pi, 1 - h}, {pi, 1 + h}, {pi - D, 1}, {pi + D, 1}};
  double xyz[3 * N], par[2 * N];
  signed char dim[N] = {HOC_ON_FACE, HOC_ON_FACE, HOC_ON_FACE, HOC_ON_FACE};
  int ent[N] = {0, 0, 0, 0};
  for (int i = 0; i < N; ++i) {
    CHECK_OK(hoc_cad_face_eval(model, 0, 1, uv[i], xyz + 3 * i, NULL, NULL));
    par[2 * i] = uv[i][0], par[2 * i + 1] = uv[i][1];
  }
  /* (a, b, c) and (b, a, d), or (a, d, c) and (d, b, c); the face's
   * orientation follows the elements */
  size_t pair[2][6] = {{A, B, C, B, A, D_}, {A, D_, C, D_, B, C}};
  int face[2] = {0, 0};
  hoc_mesh_source src = linear_source(N, xyz, par, dim, ent, 2, pair[swapped_pair], face);
  swap_and_measure(model, &src, swap, 2, SIZE_MAX, swaps, q1, q2);
  if (!swapped_pair && !swap) { /* the straight q in closed form */
    CHECK_NEAR(*q1, straight_q(xyz + 3 * A, xyz + 3 * B, xyz + 3 * C), 1e-9);
  }
}

static void test_bend(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_CYLINDER, 1.0, 2.0, &model));
  if (!model) return;
  size_t swaps, none;
  double q1, q2, s1, s2, k1, k2;
  bend_pair(model, 0, 0, &none, &q1, &q2);
  bend_pair(model, 1, 0, &none, &s1, &s2);
  bend_pair(model, 0, 1, &swaps, &k1, &k2);
  printf("bend: pair on a-b straight q %.4f, order 2 %.4f; on c-d %.4f, %.4f; %zu swap(s): "
         "%.4f, %.4f\n",
         q1, q2, s1, s2, swaps, k1, k2);
  /* straight, the swap looks a gain; raised, it is a loss */
  CHECK(s1 > 2 * q1 && s2 < 0.5 * q2);
  CHECK(swaps == 0 && k1 == q1 && k2 == q2);
  hoc_model_destroy(&model);
}

/* Tangled elements of m. */
static size_t count_tangled(const hoc_mesh *m) {
  unsigned char *t = calloc(m->n_elems + 1, 1);
  size_t n = 0;
  CHECK(t != NULL);
  if (!t) return SIZE_MAX;
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, t, NULL));
  for (size_t e = 0; e < m->n_elems; ++e) n += t[e];
  free(t);
  return n;
}

/* The line of m joining a and b, or SIZE_MAX. */
static size_t line_of(const hoc_mesh *m, size_t a, size_t b) {
  for (size_t l = 0; l < m->n_lines; ++l) {
    const size_t *c = m->line_conn + 2 * l;
    if ((c[0] == a && c[1] == b) || (c[0] == b && c[1] == a)) return l;
  }
  return SIZE_MAX;
}

/* Make the first ear of m on face `face`: elements e = (A, M, Z) and g =
 * (M, B, Z), A-M and M-B lines of one curve, become (A, M, B) and (A, B,
 * Z). 0 if there is no such pair. */
static int make_ear(hoc_mesh *m, int face) {
  for (size_t e = 0; e < m->n_elems; ++e) {
    size_t *ce = m->conn + 3 * e;
    if (m->elem_face[e] != face) continue;
    for (int k = 0; k < 3; ++k) {
      size_t A = ce[k], M = ce[(k + 1) % 3], Z = ce[(k + 2) % 3];
      size_t l1 = line_of(m, A, M);
      if (l1 == SIZE_MAX) continue;
      for (size_t g = 0; g < m->n_elems; ++g) {
        size_t *cg = m->conn + 3 * g;
        if (g == e || m->elem_face[g] != m->elem_face[e]) continue;
        for (int j = 0; j < 3; ++j) {
          if (cg[j] != M || cg[(j + 2) % 3] != Z) continue;
          size_t B = cg[(j + 1) % 3], l2 = line_of(m, M, B);
          if (B == A || l2 == SIZE_MAX || m->line_curve[l2] != m->line_curve[l1]) continue;
          size_t sa = m->elem_slot[3 * e + (size_t)k], sm = m->elem_slot[3 * e + (size_t)(k + 1) % 3];
          size_t sz = m->elem_slot[3 * e + (size_t)(k + 2) % 3];
          size_t sb = m->elem_slot[3 * g + (size_t)(j + 1) % 3];
          double ua[2], um[2], uz[2], ub[2];
          memcpy(ua, m->elem_uv + 6 * e + 2 * k, sizeof ua);
          memcpy(um, m->elem_uv + 6 * e + 2 * ((k + 1) % 3), sizeof um);
          memcpy(uz, m->elem_uv + 6 * e + 2 * ((k + 2) % 3), sizeof uz);
          memcpy(ub, m->elem_uv + 6 * g + 2 * ((j + 1) % 3), sizeof ub);
          size_t t1[3] = {A, M, B}, t2[3] = {A, B, Z}, s1[3] = {sa, sm, sb}, s2[3] = {sa, sb, sz};
          const double *u1[3] = {ua, um, ub}, *u2[3] = {ua, ub, uz};
          for (int i = 0; i < 3; ++i) {
            ce[i] = t1[i], cg[i] = t2[i];
            m->elem_slot[3 * e + (size_t)i] = s1[i], m->elem_slot[3 * g + (size_t)i] = s2[i];
            memcpy(m->elem_uv + 6 * e + 2 * i, u1[i], 2 * sizeof(double));
            memcpy(m->elem_uv + 6 * g + 2 * i, u2[i], 2 * sizeof(double));
          }
          return 1;
        }
      }
    }
  }
  return 0;
}

static void test_inverted_ear(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(DATA "sheet_dots.brep", &model));
  if (!model) return;
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.grading = 0; /* gmsh's mesh, not swapped */
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_generate_linear(model, &lo, &lin));
  if (lin) {
    /* the sheet: the widest face; its curves but the square's are the
     * disks' circles */
    int sheet = 0;
    for (int f = 1; f < model->n_faces; ++f)
      if (model->faces[f].bbox[3] - model->faces[f].bbox[0] >
          model->faces[sheet].bbox[3] - model->faces[sheet].bbox[0])
        sheet = f;
    size_t before = count_tangled(lin), swaps = 0;
    int made = make_ear(lin, sheet);
    size_t with_ear = count_tangled(lin);
    CHECK_OK(hoc_mesh_swap_edges(lin, &swaps, NULL));
    size_t after = count_tangled(lin);
    printf("inverted ear: %zu tangled, %zu with the ear made by hand (%d), %zu swap(s): %zu\n",
           before, with_ear, made, swaps, after);
    CHECK(made && before == 0 && with_ear == 1 && swaps >= 1 && after == 0);
  }
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

int main(void) {
  test_slivers();
  test_ears();
  test_inverted_ear();
  test_bend();
  return test_report();
}
