/* Poles: the normal at a point where phi_u x phi_v = 0 seen from each
 * element. On an analytic cone (its apex a pole where the surface has no
 * tangent plane: the normal depends on the direction of approach) elements
 * around the apex measure valid where a direct 3D check finds them valid,
 * at orders 1 to 5, and tangled where they truly fold; q of the linear
 * elements is the closed form of a flat triangle; every pole slot belongs
 * to one element and gives the cone's normal along that element's
 * generator, through elevation, conversion, splitting, copying and a file
 * without parameters. On a sphere (a smooth pole) every element sees the
 * pole's one normal.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "mesh/mesh.h"
#include "quality/quality.h"
#include "test_util.h"

#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

/* The cone of the tests: base radius A, height B, apex at the origin. */
static const double A = 1.0, B = 2.0;
#define K (A / B)

enum { LATTICE = 24 }; /* points of the direct 3D check: the order-24 lattice */

/* Unit normal of the cone in the direction of phi_u x phi_v, along the
 * generator through x (x off the apex): closed form (cos u, sin u, -k). */
static void cone_normal(const double *x, double *n) {
  double u = atan2(x[1], x[0]), s = 1 / sqrt(1 + K * K);
  n[0] = cos(u) * s;
  n[1] = sin(u) * s;
  n[2] = -K * s;
}

/* The lattice's basis values and derivatives for order p (equispaced or
 * another node set): N[n][np], dN[n][np][2], points rs[n][2]. */
typedef struct lattice {
  int n, np;
  double *rs, *N, *dN;
} lattice;

static int lattice_make(int p, hoc_nodeset set, lattice *L) {
  *L = (lattice){0};
  int np = (p + 1) * (p + 2) / 2, n = (LATTICE + 1) * (LATTICE + 2) / 2;
  double *nodes = malloc(2 * (size_t)np * sizeof *nodes);
  L->rs = malloc(2 * (size_t)n * sizeof *L->rs);
  L->N = malloc((size_t)n * (size_t)np * sizeof *L->N);
  L->dN = malloc(2 * (size_t)n * (size_t)np * sizeof *L->dN);
  hoc_lagrange *basis = NULL;
  int ok = nodes && L->rs && L->N && L->dN && hoc_tri_nodes(p, set, nodes) == HOC_OK &&
           hoc_lagrange_create(p, nodes, &basis) == HOC_OK;
  int k = 0;
  for (int j = 0; j <= LATTICE; ++j)
    for (int i = 0; i + j <= LATTICE && ok; ++i, ++k) {
      L->rs[2 * k] = (double)i / LATTICE;
      L->rs[2 * k + 1] = (double)j / LATTICE;
    }
  ok = ok && hoc_lagrange_eval(basis, n, L->rs, L->N, L->dN) == HOC_OK;
  hoc_lagrange_destroy(&basis);
  free(nodes);
  L->n = n;
  L->np = np;
  return ok;
}

static void lattice_free(lattice *L) {
  free(L->rs);
  free(L->N);
  free(L->dN);
}

/* The direct 3D check of element e of a cone mesh: the smallest
 * (x_r x x_s) . n / |x_r x x_s| over the lattice, n the cone's normal
 * along the generator through the point (oriented as the mesh); at the
 * apex, along the generator through a point just inside the element.
 * <= 0: the element folds. */
static double cone_fold_margin(const hoc_mesh *m, const lattice *L, size_t e) {
  int np = m->np;
  const size_t *cn = m->conn + e * (size_t)np;
  double orient = m->face_orient[m->elem_face[e]] < 0 ? -1.0 : 1.0, worst = INFINITY;
  for (int q = 0; q < L->n; ++q) {
    double x[3] = {0, 0, 0}, xr[3] = {0, 0, 0}, xs[3] = {0, 0, 0};
    const double *N = L->N + (size_t)q * np, *dN = L->dN + 2 * (size_t)q * np;
    for (int i = 0; i < np; ++i)
      for (int d = 0; d < 3; ++d) {
        double xi = m->xyz[3 * cn[i] + (size_t)d];
        x[d] += N[i] * xi;
        xr[d] += dN[2 * i] * xi;
        xs[d] += dN[2 * i + 1] * xi;
      }
    if (hypot(x[0], x[1]) < 1e-12 * A) { /* the apex: step towards the centroid */
      double r = L->rs[2 * q] + 1e-6 * (1.0 / 3 - L->rs[2 * q]);
      double s = L->rs[2 * q + 1] + 1e-6 * (1.0 / 3 - L->rs[2 * q + 1]);
      double l[3] = {1 - r - s, r, s}, y[3] = {0, 0, 0};
      for (int c = 0; c < 3; ++c) /* the straight element is enough for the direction */
        for (int d = 0; d < 3; ++d)
          y[d] += l[c] * m->xyz[3 * cn[c] + (size_t)d];
      memcpy(x, y, sizeof x);
    }
    double n[3], c[3];
    cone_normal(x, n);
    c[0] = xr[1] * xs[2] - xr[2] * xs[1];
    c[1] = xr[2] * xs[0] - xr[0] * xs[2];
    c[2] = xr[0] * xs[1] - xr[1] * xs[0];
    double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    double dot = len > 0 ? orient * (c[0] * n[0] + c[1] * n[1] + c[2] * n[2]) / len : 0;
    worst = fmin(worst, dot);
  }
  return worst;
}

/* Whether element e has a corner at a pole slot. */
static int at_pole(const hoc_mesh *m, size_t e) {
  for (int k = 0; k < 3; ++k)
    if (m->slot_pole[m->elem_slot[e * (size_t)m->np + (size_t)k]]) return 1;
  return 0;
}

/* The per-element pole slots: each pole slot of a vertex or curve node is
 * used by exactly one element node, its arbitrary coordinate is that
 * element's (wrapped), and no other two slots are the same (node, face).
 * Returns the number of violations; *n_pole receives the pole slots. */
static size_t pole_slot_errors(const hoc_mesh *m, size_t *n_pole) {
  size_t bad = 0, np = (size_t)m->np;
  size_t *uses = calloc(m->n_slots, sizeof *uses), *plain = calloc(m->n_nodes, sizeof *plain);
  if (!uses || !plain) {
    free(uses);
    free(plain);
    return 1;
  }
  *n_pole = 0;
  const hoc_cad_face *f = &m->model->faces[0];
  for (size_t x = 0; x < m->n_elems * np; ++x) {
    size_t s = m->elem_slot[x];
    uses[s]++;
    bad += m->slot_node[s] != m->conn[x] || m->slot_face[s] != m->elem_face[x / np];
    if (!m->slot_pole[s] || m->dim[m->slot_node[s]] == HOC_ON_FACE) continue;
    double uv[2] = {m->elem_uv[2 * x], m->elem_uv[2 * x + 1]};
    hoc_cad_face_wrap(f, uv);
    for (int d = 0; d < 2; ++d)
      if (m->slot_pole[s] & (1 << d)) bad += m->slot_uv[2 * s + (size_t)d] != uv[d];
  }
  for (size_t s = 0; s < m->n_slots; ++s) {
    int pole = m->slot_pole[s] && m->dim[m->slot_node[s]] != HOC_ON_FACE;
    if (pole) {
      ++*n_pole;
      bad += uses[s] != 1;
    } else {
      bad += uses[s] == 0 || plain[m->slot_node[s]]++ != 0; /* one face: one slot per node */
    }
  }
  free(uses);
  free(plain);
  return bad;
}

/* Every node of an element's edge from the apex on the generator of the
 * edge's far corner (the elements' edges from a pole are meridians, which
 * on a cone are straight lines through the apex). Returns the largest
 * angle between a node's generator and the far corner's. */
static double apex_edge_gap(const hoc_mesh *m) {
  int p = m->order, np = m->np;
  double gap = 0;
  for (size_t e = 0; e < m->n_elems; ++e) {
    const size_t *cn = m->conn + e * (size_t)np;
    for (int k = 0; k < 3; ++k) {
      if (m->dim[cn[k]] != HOC_ON_VERTEX || hypot(m->xyz[3 * cn[k]], m->xyz[3 * cn[k] + 1]) > 0)
        continue;
      for (int side = 0; side < 2; ++side) { /* edge k (k -> k + 1), edge k + 2 (k + 2 -> k) */
        int edge = side ? (k + 2) % 3 : k;
        size_t far = cn[side ? (k + 2) % 3 : (k + 1) % 3];
        double uf = atan2(m->xyz[3 * far + 1], m->xyz[3 * far]);
        for (int j = 0; j < p - 1; ++j) {
          size_t i = cn[3 + edge * (p - 1) + j];
          double d = atan2(m->xyz[3 * i + 1], m->xyz[3 * i]) - uf;
          d -= 2 * PI * floor(d / (2 * PI) + 0.5);
          gap = fmax(gap, fabs(d));
        }
      }
    }
  }
  return gap;
}

/* Measured tangled flags against the direct 3D check, element by element;
 * prints and counts disagreements. *n_tangled, *n_apex_folded: counts. */
static size_t check_against_3d(const hoc_mesh *m, hoc_nodeset set, const char *what,
                               size_t *n_tangled) {
  lattice L;
  unsigned char *tangled = calloc(m->n_elems, 1);
  size_t wrong = 0;
  *n_tangled = 0;
  if (!tangled || !lattice_make(m->order, set, &L)) {
    free(tangled);
    return 1;
  }
  if (hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, tangled, NULL) != HOC_OK) wrong = 1;
  for (size_t e = 0; e < m->n_elems && !wrong; ++e) {
    double margin = cone_fold_margin(m, &L, e);
    *n_tangled += tangled[e];
    /* a fold within 1e-9 of the tangent plane is neither: not asked */
    if (fabs(margin) > 1e-9 && (margin <= 0) != (tangled[e] != 0)) {
      ++wrong;
      fprintf(stderr, "  %s p=%d: element %zu%s measured %s, 3D check margin %.3g\n", what,
              m->order, e + 1, at_pole(m, e) ? " (at the apex)" : "",
              tangled[e] ? "tangled" : "valid", margin);
    }
  }
  lattice_free(&L);
  free(tangled);
  return wrong;
}

/* Flat triangle closed form of the shape measure: q = 4 sqrt(3) area / sum of
 * squared edges. */
static double flat_q(const hoc_mesh *m, size_t e) {
  const size_t *cn = m->conn + e * (size_t)m->np;
  double a[3], b[3], c[3], l2 = 0;
  for (int d = 0; d < 3; ++d) {
    a[d] = m->xyz[3 * cn[1] + (size_t)d] - m->xyz[3 * cn[0] + (size_t)d];
    b[d] = m->xyz[3 * cn[2] + (size_t)d] - m->xyz[3 * cn[0] + (size_t)d];
    l2 += a[d] * a[d] + b[d] * b[d] + (b[d] - a[d]) * (b[d] - a[d]);
  }
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
  return 4 * sqrt(3.0) * 0.5 * sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) / l2;
}

/* Pole slot normals of a cone mesh against the closed form along each
 * slot's generator: the largest |1 - dot|, and the smallest dot between
 * two pole slots (how much the elements' normals at the apex differ). */
static void cone_pole_normals(const hoc_mesh *m, double *err, double *spread) {
  double *nrm = malloc(3 * m->n_slots * sizeof *nrm);
  *err = INFINITY;
  *spread = 1;
  if (!nrm || hoc_mesh_slot_normals(m, nrm) != HOC_OK) {
    free(nrm);
    return;
  }
  *err = 0;
  double orient = m->face_orient[0] < 0 ? -1.0 : 1.0;
  for (size_t s = 0; s < m->n_slots; ++s) {
    if (!m->slot_pole[s]) continue;
    double u = m->slot_uv[2 * s], x[3] = {cos(u), sin(u), 1}, n[3];
    cone_normal(x, n);
    double dot = orient * (n[0] * nrm[3 * s] + n[1] * nrm[3 * s + 1] + n[2] * nrm[3 * s + 2]);
    *err = fmax(*err, fabs(1 - dot));
    for (size_t t = 0; t < s; ++t)
      if (m->slot_pole[t])
        *spread = fmin(*spread, nrm[3 * s] * nrm[3 * t] + nrm[3 * s + 1] * nrm[3 * t + 1] +
                                    nrm[3 * s + 2] * nrm[3 * t + 2]);
  }
  free(nrm);
}

/* A structured cone mesh around the apex raised to orders 1 to 5 (and
 * Fekete nodes from 3): valid where the 3D check says so, which is every
 * element; linear q the flat closed form; the pole slots right. */
static void test_cone_valid(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_CONE, A, B, &model));
  if (!model) return;
  const hoc_cad_face *f = &model->faces[0];
  CHECK(f->pole[2] && !f->pole[0] && !f->pole[1] && !f->pole[3]); /* the apex, v = 0 */
  CHECK(f->period[0] > 0 && f->period[1] == 0);
  CHECK(model->curves[1].degenerate && !model->curves[0].degenerate);
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_grid_linear(model, 12, 4, &lin));
  if (!lin) goto out;
  /* the cone's normals at the apex differ by more than a right angle from
   * one element to another: one normal per node cannot serve them all */
  double err, spread;
  cone_pole_normals(lin, &err, &spread);
  CHECK(err < 1e-12);
  CHECK(spread < -0.5);
  size_t apex = 0;
  for (size_t e = 0; e < lin->n_elems; ++e)
    apex += at_pole(lin, e);
  CHECK(apex == 12);
  for (int p = 1; p <= 5; ++p)
    for (int set = 0; set < 2; ++set) {
      if (set && p < 3) continue;
      hoc_nodeset ns = set ? HOC_NODES_FEKETE : HOC_NODES_EQUISPACED;
      hoc_mesh *m = NULL;
      CHECK_OK(hoc_mesh_elevate(lin, p, ns, &m));
      if (!m) continue;
      size_t n_pole = 0, tangled = 0;
      CHECK(pole_slot_errors(m, &n_pole) == 0);
      CHECK(n_pole == 12);
      cone_pole_normals(m, &err, &spread);
      CHECK(err < 1e-12);
      CHECK(apex_edge_gap(m) < 1e-12);
      CHECK(check_against_3d(m, ns, "cone", &tangled) == 0);
      CHECK(tangled == 0);
      if (p == 1) {
        double *q = malloc(m->n_elems * sizeof *q), dq = 0;
        CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q, NULL, NULL));
        for (size_t e = 0; q && e < m->n_elems; ++e)
          dq = fmax(dq, fabs(q[e] - flat_q(m, e)));
        CHECK(q && dq < 1e-12);
        free(q);
      }
      /* the same measure from one thread and from two */
      double *q1 = malloc(m->n_elems * sizeof *q1), *q2 = malloc(m->n_elems * sizeof *q2);
      int threads = omp_get_max_threads();
      omp_set_num_threads(1);
      CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q1, NULL, NULL));
      omp_set_num_threads(2);
      CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q2, NULL, NULL));
      omp_set_num_threads(threads);
      CHECK(q1 && q2 && !memcmp(q1, q2, m->n_elems * sizeof *q1));
      free(q1);
      free(q2);
      /* a copy keeps the slots (and measures the same) */
      hoc_mesh *c = NULL;
      CHECK_OK(hoc_mesh_copy(m, &c));
      if (c) {
        CHECK(c->n_slots == m->n_slots &&
              !memcmp(c->elem_slot, m->elem_slot,
                      m->n_elems * (size_t)m->np * sizeof *c->elem_slot) &&
              !memcmp(c->slot_uv, m->slot_uv, 2 * m->n_slots * sizeof *c->slot_uv));
        CHECK(pole_slot_errors(c, &n_pole) == 0);
      }
      hoc_mesh_destroy(&c);
      if (p == 3 && !set) {
        /* to Fekete nodes and back: the same slots' directions */
        hoc_mesh *fk = NULL;
        CHECK_OK(hoc_mesh_convert_nodeset(m, HOC_NODES_FEKETE, &fk));
        if (fk) {
          CHECK(pole_slot_errors(fk, &n_pole) == 0 && n_pole == 12);
          CHECK(check_against_3d(fk, HOC_NODES_FEKETE, "cone fekete", &tangled) == 0);
          CHECK(tangled == 0);
        }
        hoc_mesh_destroy(&fk);
      }
      printf("cone p=%d %s: %zu elements, %zu at the apex with a slot each, 0 tangled as the 3D "
             "check says\n",
             p, set ? "fekete" : "equispaced", m->n_elems, n_pole);
      hoc_mesh_destroy(&m);
    }
out:
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* A mesh source from a mesh (its nodes' parameters and connectivity) with
 * the parameters of face node `node` replaced by uv (if node < n_nodes). */
static hoc_status assemble_moved(const hoc_mesh *m, size_t node, const double uv[2],
                                 hoc_mesh **out) {
  double *par = malloc(2 * m->n_nodes * sizeof *par);
  if (!par) return HOC_ERR_MEMORY;
  memcpy(par, m->param, 2 * m->n_nodes * sizeof *par);
  if (node < m->n_nodes) memcpy(par + 2 * node, uv, 2 * sizeof *par);
  hoc_mesh_source src = {0};
  src.order = m->order;
  src.nodeset = m->nodeset;
  src.n_nodes = m->n_nodes;
  src.param = par;
  src.dim = m->dim;
  src.entity = m->entity;
  src.n_elems = m->n_elems;
  src.conn = m->conn;
  src.elem_face = m->elem_face;
  src.n_lines = m->n_lines;
  src.line_conn = m->line_conn;
  src.line_curve = m->line_curve;
  src.face_orient = m->face_orient;
  hoc_status st = hoc_mesh_assemble(m->model, &src, out);
  free(par);
  return st;
}

/* Truly folded elements at the apex are still found: an order-2 apex
 * element whose edge from the apex leaves it on the far side of the other
 * edge (the corner at the apex turned over, the rest of the element
 * valid), raised to orders 3 to 5 with its geometry. */
static void test_cone_folded(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_CONE, A, B, &model));
  if (!model) return;
  hoc_mesh *lin = NULL, *m2 = NULL, *bent = NULL;
  CHECK_OK(hoc_mesh_grid_linear(model, 12, 4, &lin));
  if (lin) CHECK_OK(hoc_mesh_elevate(lin, 2, HOC_NODES_EQUISPACED, &m2));
  if (!m2) goto out;
  /* an apex element away from the seam, opposite the apex's own u = 0 */
  size_t target = SIZE_MAX, moved = SIZE_MAX;
  double uv[2] = {0, 0};
  for (size_t e = 0; e < m2->n_elems && target == SIZE_MAX; ++e) {
    const size_t *cn = m2->conn + e * 6;
    const double *euv = m2->elem_uv + 2 * e * 6;
    for (int k = 0; k < 3 && target == SIZE_MAX; ++k) {
      if (m2->dim[cn[k]] != HOC_ON_VERTEX || m2->dim[cn[(k + 1) % 3]] != HOC_ON_FACE ||
          m2->dim[cn[(k + 2) % 3]] != HOC_ON_FACE || fabs(euv[2 * k] - PI) > 0.3)
        continue;
      /* the node of edge k (from the apex to corner k + 1) moves to the
       * generator one element-width past corner k + 2's */
      int b = (k + 1) % 3, c = (k + 2) % 3;
      target = e;
      moved = cn[3 + k];
      uv[0] = euv[2 * c] + (euv[2 * c] - euv[2 * b]);
      uv[1] = m2->param[2 * moved + 1];
    }
  }
  CHECK(target != SIZE_MAX);
  if (target == SIZE_MAX) goto out;
  CHECK_OK(assemble_moved(m2, moved, uv, &bent));
  for (int p = 2; p <= 5 && bent; ++p) {
    hoc_mesh *m = NULL;
    if (p == 2)
      CHECK_OK(hoc_mesh_copy(bent, &m));
    else
      CHECK_OK(hoc_mesh_elevate(bent, p, HOC_NODES_EQUISPACED, &m));
    if (!m) continue;
    lattice L;
    CHECK(lattice_make(p, HOC_NODES_EQUISPACED, &L));
    double margin = cone_fold_margin(m, &L, target);
    lattice_free(&L);
    CHECK(margin < -0.1); /* folded in 3D */
    unsigned char *tangled = calloc(m->n_elems, 1);
    CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, tangled, NULL));
    CHECK(tangled && tangled[target]);
    free(tangled);
    size_t n_tangled = 0;
    CHECK(check_against_3d(m, HOC_NODES_EQUISPACED, "bent cone", &n_tangled) == 0);
    printf("cone with a folded apex element, p=%d: 3D margin %.3f, %zu tangled as the 3D check "
           "says\n",
           p, margin, n_tangled);
    hoc_mesh_destroy(&m);
  }
out:
  hoc_mesh_destroy(&bent);
  hoc_mesh_destroy(&m2);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* Splitting at the apex: children's edges from the apex stay on their
 * parent's generators, each child has its own pole slot, all valid. */
static void test_cone_split(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_CONE, A, B, &model));
  if (!model) return;
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_grid_linear(model, 12, 4, &lin));
  for (int p = 1; p <= 3 && lin; ++p)
    for (int kind = 0; kind < 2; ++kind) {
      hoc_mesh *m = NULL, *s = NULL;
      CHECK_OK(hoc_mesh_elevate(lin, p, HOC_NODES_EQUISPACED, &m));
      if (!m) continue;
      unsigned char *flag = calloc(m->n_elems, 1);
      size_t flagged = 0;
      for (size_t e = 0; flag && e < m->n_elems; ++e)
        if (at_pole(m, e) && flagged < 3) flag[e] = 1, ++flagged;
      CHECK(flagged == 3);
      CHECK_OK(hoc_mesh_split(m, flag, (hoc_split_kind)kind, &s, NULL));
      if (s) {
        /* the apex keeps its 12 elements, those split replaced by their
         * children at the apex (corners halfway up: z = B / 8) */
        size_t n_pole = 0, tangled = 0, apex = 0, children = 0;
        for (size_t e = 0; e < s->n_elems; ++e) {
          if (!at_pole(s, e)) continue;
          ++apex;
          int low = 0;
          for (int k = 0; k < 3; ++k)
            low |= fabs(s->xyz[3 * s->conn[e * s->np + k] + 2] - B / 8) < 1e-12;
          children += low;
        }
        CHECK(apex == 12);
        CHECK(children >= 3);
        CHECK(pole_slot_errors(s, &n_pole) == 0);
        CHECK(n_pole == apex);
        CHECK(apex_edge_gap(s) < 1e-12);
        CHECK(check_against_3d(s, HOC_NODES_EQUISPACED, "split cone", &tangled) == 0);
        CHECK(tangled == 0);
        printf("cone p=%d split %s: %zu -> %zu elements, %zu at the apex (%zu children), 0 "
               "tangled\n",
               p, kind ? "at longest edges" : "red-green", m->n_elems, s->n_elems, apex, children);
      }
      free(flag);
      hoc_mesh_destroy(&s);
      hoc_mesh_destroy(&m);
    }
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* A cone mesh written without parameters and read back: the nodes located
 * again, each apex element's direction found again from its corners, the
 * same q. */
static void test_cone_file(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_CONE, A, B, &model));
  if (!model) return;
  hoc_mesh *lin = NULL, *m = NULL, *r = NULL;
  CHECK_OK(hoc_mesh_grid_linear(model, 12, 4, &lin));
  if (lin) CHECK_OK(hoc_mesh_elevate(lin, 3, HOC_NODES_EQUISPACED, &m));
  const char *path = "test_mesh_poles_cone.msh";
  if (m) CHECK_OK(hoc_mesh_write_msh(m, path));
  if (m) CHECK_OK(hoc_mesh_read_msh(model, path, &r));
  if (r) {
    size_t n_pole = 0, tangled = 0;
    CHECK(pole_slot_errors(r, &n_pole) == 0 && n_pole == 12);
    CHECK(check_against_3d(r, HOC_NODES_EQUISPACED, "cone read back", &tangled) == 0);
    CHECK(tangled == 0);
    double *qa = malloc(m->n_elems * sizeof *qa), *qb = malloc(r->n_elems * sizeof *qb), dq = 0;
    CHECK(r->n_elems == m->n_elems);
    CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, qa, NULL, NULL));
    CHECK_OK(hoc_mesh_measure(r, HOC_MEASURE_SHAPE, qb, NULL, NULL));
    for (size_t e = 0; qa && qb && e < m->n_elems && r->n_elems == m->n_elems; ++e)
      dq = fmax(dq, fabs(qa[e] - qb[e]));
    CHECK(dq < 1e-9);
    free(qa);
    free(qb);
  }
  remove(path);
  hoc_mesh_destroy(&r);
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* A smooth pole: the sphere's. Every element's slot at a pole gives the
 * pole's one normal (along the axis), and the mesh measures valid. */
static void test_sphere_pole(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_SPHERE, 1, 0, &model));
  if (!model) return;
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_grid_linear(model, 12, 6, &lin));
  for (int p = 1; p <= 5 && lin; ++p) {
    hoc_mesh *m = NULL;
    CHECK_OK(hoc_mesh_elevate(lin, p, HOC_NODES_EQUISPACED, &m));
    if (!m) continue;
    size_t n_pole = 0;
    CHECK(pole_slot_errors(m, &n_pole) == 0);
    CHECK(n_pole == 24); /* 12 elements at each pole */
    double *nrm = malloc(3 * m->n_slots * sizeof *nrm), worst = 1;
    CHECK(nrm && hoc_mesh_slot_normals(m, nrm) == HOC_OK);
    double orient = m->face_orient[0] < 0 ? -1.0 : 1.0;
    for (size_t s = 0; nrm && s < m->n_slots; ++s) {
      if (!m->slot_pole[s]) continue;
      /* phi_u x phi_v points along the axis, outward: +z at the north pole */
      const double *x = m->xyz + 3 * m->slot_node[s];
      double axis = x[2] > 0 ? 1.0 : -1.0;
      worst = fmin(worst, orient * axis * nrm[3 * s + 2]);
    }
    CHECK(worst > 1 - 1e-8);
    free(nrm);
    hoc_quality_stats st;
    CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st));
    CHECK(st.tangled == 0);
    hoc_mesh_destroy(&m);
  }
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* The cone's derivatives against finite differences; its inverse. */
static void test_cone_model(void) {
  hoc_model *m = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_CONE, A, B, &m));
  if (!m) return;
  double uv[2] = {2.1, 0.7}, x[3], du[3], dv[3], xp[3], xm[3], h = 1e-6;
  CHECK_OK(hoc_cad_face_eval(m, 0, 1, uv, x, du, dv));
  CHECK_NEAR(hypot(x[0], x[1]), K * x[2], 1e-15);
  for (int d = 0; d < 2; ++d) {
    double a[2] = {uv[0], uv[1]}, b[2] = {uv[0], uv[1]};
    a[d] += h;
    b[d] -= h;
    CHECK_OK(hoc_cad_face_eval(m, 0, 1, a, xp, NULL, NULL));
    CHECK_OK(hoc_cad_face_eval(m, 0, 1, b, xm, NULL, NULL));
    for (int k = 0; k < 3; ++k)
      CHECK_NEAR((xp[k] - xm[k]) / (2 * h), d ? dv[k] : du[k], 1e-8);
  }
  double back[2] = {0, 0}, dist;
  CHECK_OK(m->ops->face_project(m->ctx, &m->faces[0], 1, x, back));
  CHECK_NEAR(back[0], uv[0], 1e-14);
  CHECK_NEAR(back[1], uv[1], 1e-14);
  double guess[2] = {2.0, 0.6};
  CHECK_OK(hoc_cad_face_invert(m, 0, x, guess, &dist));
  CHECK(dist < 1e-13);
  hoc_model_destroy(&m);
  CHECK_STATUS(hoc_cad_create_analytic(HOC_ANALYTIC_CONE, 1, 0, &m), HOC_ERR_ARGUMENT);
  CHECK(m == NULL);
}

int main(void) {
  test_cone_model();
  test_cone_valid();
  test_cone_folded();
  test_cone_split();
  test_cone_file();
  test_sphere_pole();
  return test_report();
}
