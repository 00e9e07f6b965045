/* Order elevation: new nodes placed in the face's parameter space from the
 * reference node distribution (straight in (u,v)), nodes on CAD curves
 * placed in the curve's parameter, then mapped onto the CAD; or, on faces
 * asked for, at the feet of the source element's points.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "core/geometry.h"
#include "core/hash.h"
#include "mesh/mesh.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

static double wrap_t(const hoc_cad_curve *c, double t) {
  if (!(c->period > 0)) return t;
  return t - c->period * floor((t - c->lo) / c->period);
}

/* The edges of a triangulation through the lower-numbered vertex of each:
 * a bucket per vertex, scanned linearly (a vertex has a handful of edges).
 * Buckets follow the node numbering, which meshers keep local, so this reads
 * memory nearly in order where a hash table would miss the cache on every
 * edge. Edges are numbered in order of first appearance. */
typedef struct edge_table {
  size_t *start; /* [n_vertices + 1] bucket of each lower vertex */
  size_t *other; /* [3 ne] higher vertex of each entry, in element order */
  size_t *id;    /* [3 ne] edge number at an edge's first entry, else SIZE_MAX */
  size_t n_edges;
} edge_table;

static void edge_table_free(edge_table *t) {
  free(t->start);
  free(t->other);
  free(t->id);
}

/* The entry of edge (a, b) in its bucket, or SIZE_MAX. */
static size_t edge_entry(const edge_table *t, size_t a, size_t b) {
  size_t lo = a < b ? a : b, hi = a < b ? b : a;
  for (size_t x = t->start[lo]; x < t->start[lo + 1]; ++x)
    if (t->other[x] == hi) return x;
  return SIZE_MAX;
}

/* Edge table of the elements' corners (conn with `stride` nodes per element,
 * nn nodes); elem_edge[3 e + k] is the number of element e's edge k (from
 * corner k to k + 1) and first[3 e + k] says whether e is where it appears
 * first. */
static hoc_status edge_table_build(edge_table *t, const size_t *conn, size_t ne, int stride,
                                   size_t nn, size_t *elem_edge, unsigned char *first) {
  *t = (edge_table){0};
  size_t *fill = hoc_calloc(nn + 1, sizeof *fill);
  t->start = hoc_calloc(nn + 1, sizeof *t->start);
  t->other = hoc_realloc(NULL, 3 * ne + 1, sizeof *t->other);
  t->id = hoc_realloc(NULL, 3 * ne + 1, sizeof *t->id);
  if (!fill || !t->start || !t->other || !t->id) {
    free(fill);
    edge_table_free(t);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory for the edges of %zu elements", ne);
  }
  for (size_t e = 0; e < ne; ++e)
    for (int k = 0; k < 3; ++k) {
      size_t a = conn[e * (size_t)stride + k], b = conn[e * (size_t)stride + (k + 1) % 3];
      t->start[(a < b ? a : b) + 1]++;
    }
  for (size_t v = 0; v < nn; ++v)
    t->start[v + 1] += t->start[v];
  memcpy(fill, t->start, (nn + 1) * sizeof *fill);
  for (size_t e = 0; e < ne; ++e)
    for (int k = 0; k < 3; ++k) {
      size_t a = conn[e * (size_t)stride + k], b = conn[e * (size_t)stride + (k + 1) % 3];
      size_t x = fill[a < b ? a : b]++;
      t->other[x] = a < b ? b : a;
      t->id[x] = SIZE_MAX;
    }
  free(fill);
  for (size_t e = 0; e < ne; ++e)
    for (int k = 0; k < 3; ++k) {
      size_t a = conn[e * (size_t)stride + k], b = conn[e * (size_t)stride + (k + 1) % 3];
      size_t x = edge_entry(t, a, b);
      first[3 * e + (size_t)k] = t->id[x] == SIZE_MAX;
      if (first[3 * e + (size_t)k]) t->id[x] = t->n_edges++;
      elem_edge[3 * e + (size_t)k] = t->id[x];
    }
  return HOC_OK;
}

/* An edge on no CAD curve that elements of two faces share (two faces
 * bounded by the same two curves, each meshed there without a vertex
 * inside) gets its own number on each further face, so that each face
 * makes its own nodes on it: a node lies on one face. */
static hoc_status split_face_edges(const hoc_mesh *in, size_t *n_edges, const size_t *edge_line,
                                   size_t *elem_edge, unsigned char *edge_new) {
  size_t n0 = *n_edges;
  int *owner = hoc_realloc(NULL, n0 + 1, sizeof *owner);
  if (!owner) return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  hoc_hash h = {0};
  hoc_status status = HOC_OK;
  for (size_t id = 0; id < n0; ++id)
    owner[id] = -1;
  uint64_t nf = (uint64_t)in->model->n_faces;
  for (size_t x = 0; x < 3 * in->n_elems; ++x) {
    size_t id = elem_edge[x];
    int f = in->elem_face[x / 3];
    if (edge_line[id] != SIZE_MAX) continue;
    if (owner[id] < 0) owner[id] = f; /* the first element using it */
    if (owner[id] == f) continue;
    if (!h.slots) HOC_TRY_GOTO(hoc_hash_init(&h, 16), done);
    int found;
    HOC_TRY_GOTO(
        hoc_hash_insert(&h, (uint64_t)id * nf + (uint64_t)f, *n_edges, &found, &elem_edge[x]),
        done);
    edge_new[x] = !found;
    *n_edges += !found;
  }
done:
  hoc_hash_free(&h);
  free(owner);
  return status;
}

hoc_status hoc_mesh_edges(const hoc_mesh *in, size_t *elem_edge, unsigned char *first,
                          size_t *edge_line, size_t *line_edge, size_t *n_edges) {
  size_t ne = in->n_elems;
  int pin = in->order;
  edge_table edges = {0};
  HOC_TRY(edge_table_build(&edges, in->conn, ne, in->np, in->n_nodes, elem_edge, first));
  for (size_t id = 0; id < 3 * ne + 1; ++id)
    edge_line[id] = SIZE_MAX;
  for (size_t l = 0; l < in->n_lines; ++l) {
    const size_t *ln = in->line_conn + l * (size_t)(pin + 1);
    size_t x = edge_entry(&edges, ln[0], ln[1]);
    line_edge[l] = x == SIZE_MAX ? SIZE_MAX : edges.id[x];
    if (x != SIZE_MAX && edge_line[edges.id[x]] == SIZE_MAX) edge_line[edges.id[x]] = l;
  }
  *n_edges = edges.n_edges;
  edge_table_free(&edges);
  return split_face_edges(in, n_edges, edge_line, elem_edge, first);
}

/* Cusps: at a CAD vertex where an element's two edges follow curves that
 * leave it (nearly) tangentially, a curved element that follows both curves
 * closes there to a zero angle, and the better its edges resolve the curves
 * (the higher the order), the closer its Jacobian comes to 0 over a
 * growing part of it. Edge nodes spaced as s^(1/2) from such a vertex
 * make the interpolated edge leave it at an angle: where the curves part
 * as the square of the distance, the gap between them is then linear in s.
 * grade[edge] is the source node at which an edge is graded, SIZE_MAX if
 * none (also if both its ends would be). A corner counts as a cusp when
 * the curves' angle is under half the straight element's angle there. */
static hoc_status cusp_grading(const hoc_mesh *in, const size_t *elem_edge, const size_t *edge_line,
                               size_t n_edges, size_t *grade) {
  const size_t both = SIZE_MAX - 1;
  for (size_t id = 0; id < n_edges; ++id)
    grade[id] = SIZE_MAX;
  if (in->order != 1) return HOC_OK;
  for (size_t e = 0; e < in->n_elems; ++e) {
    const size_t *cn = in->conn + 3 * e;
    for (int k = 0; k < 3; ++k) {
      size_t v = cn[k];
      if (in->dim[v] != HOC_ON_VERTEX) continue;
      size_t id[2] = {elem_edge[3 * e + (size_t)k], elem_edge[3 * e + (size_t)(k + 2) % 3]};
      size_t other[2] = {cn[(k + 1) % 3], cn[(k + 2) % 3]};
      int c[2];
      double t_far[2], w[2][3], lw[2];
      int j = 0;
      for (; j < 2; ++j) {
        size_t l = edge_line[id[j]];
        if (l == SIZE_MAX) break; /* not on a CAD curve */
        const size_t *ln = in->line_conn + 2 * l;
        c[j] = in->line_curve[l];
        t_far[j] = in->line_t[2 * l + (ln[0] == v ? 1 : 0)];
        for (int q = 0; q < 3; ++q)
          w[j][q] = in->xyz[3 * other[j] + q] - in->xyz[3 * v + q];
        lw[j] = sqrt(w[j][0] * w[j][0] + w[j][1] * w[j][1] + w[j][2] * w[j][2]);
      }
      if (j < 2 || !(lw[0] > 0 && lw[1] > 0)) continue;
      double curves;
      if (hoc_curves_angle_at(in->model, in->entity[v], c, t_far, &curves) != HOC_OK) {
        hoc_error_clear(); /* no tangent there: not a cusp we can tell, evenly spaced */
        continue;
      }
      double c01 = (w[0][0] * w[1][0] + w[0][1] * w[1][1] + w[0][2] * w[1][2]) / (lw[0] * lw[1]);
      double corner = acos(fmax(-1.0, fmin(1.0, c01)));
      if (!(curves < 0.5 * corner)) continue;
      for (j = 0; j < 2; ++j)
        grade[id[j]] = grade[id[j]] == SIZE_MAX || grade[id[j]] == v ? v : both;
    }
  }
  for (size_t id = 0; id < n_edges; ++id)
    if (grade[id] == both) grade[id] = SIZE_MAX;
  return HOC_OK;
}

/* Targets of the new nodes: the source element's point in space. */
typedef struct foot_targets {
  double *xyz;         /* [cap][3] */
  double *tol;         /* [cap] how close: 2e-6 of the source element's longest edge */
  unsigned char *want; /* [cap] 1 where the node may go to the foot of its target */
  size_t cap;
} foot_targets;

static void foot_set(foot_targets *t, size_t node, int n, const double *w, const double *xyz,
                     const size_t *nodes, double tol) {
  if (node >= t->cap) return; /* beyond the reserve: keeps its parameter-space place */
  double *x = t->xyz + 3 * node;
  x[0] = x[1] = x[2] = 0;
  for (int i = 0; i < n; ++i)
    for (int d = 0; d < 3; ++d) x[d] += w[i] * xyz[3 * nodes[i] + (size_t)d];
  t->want[node] = 1;
  t->tol[node] = tol;
}

/* Each flagged node moves to the foot of the perpendicular from its target,
 * starting from its parameter-space place; in parallel, each node alone. */
static hoc_status foot_move(const hoc_model *model, const foot_targets *t, hoc_node_builder *b) {
  size_t n = b->n < t->cap ? b->n : t->cap;
  hoc_par_error err = {0};
#pragma omp parallel for schedule(dynamic, 256) if (n > 256 && model->thread_safe)
  for (size_t i = 0; i < n; ++i) {
    if (!t->want[i]) continue;
    hoc_status st;
    double *par = b->par + 2 * i;
    if (b->dim[i] == HOC_ON_CURVE) {
      st = hoc_cad_curve_foot(model, b->ent[i], t->xyz + 3 * i, t->tol[i], &par[0]);
      par[0] = wrap_t(&model->curves[b->ent[i]], par[0]);
    } else {
      st = hoc_cad_face_foot(model, b->ent[i], t->xyz + 3 * i, t->tol[i], par);
      hoc_cad_face_wrap(&model->faces[b->ent[i]], par);
    }
    if (st != HOC_OK) hoc_par_error_catch(&err, st);
  }
  return hoc_par_error_raise(&err);
}

/* Re-interpolation: the new mesh of order p on node set `set` evaluates
 * each source element's parametric map at the new reference nodes. Nodes
 * on CAD curves are interpolated in the curve's parameter t along the edge;
 * other nodes in the face's (u,v), unwrapped per element. From a linear
 * mesh this is the paper's placement (straight in (u,v)); from a curved mesh
 * it keeps the curved geometry. */
static hoc_status reinterpolate(const hoc_mesh *in, int p, hoc_nodeset set,
                                const unsigned char *face_foot, const hoc_mesh *straight,
                                hoc_mesh **out) {
  const hoc_model *model = in->model;
  int np = hoc_tri_num_nodes(p), npi = in->np, pin = in->order;
  size_t ne = in->n_elems;
  double *rs = NULL, *s = NULL, *rs_in = NULL, *s_in = NULL, *Nsrc = NULL, *L = NULL;
  double *edge_t = NULL, *edge_uv = NULL;
  size_t *vmap = NULL, *conn = NULL, *lconn = NULL, *edge_first = NULL, *edge_a = NULL;
  size_t *elem_edge = NULL, *grade = NULL;
  unsigned char *edge_new = NULL;
  int *lcurve = NULL;
  hoc_lagrange *basis = NULL;
  hoc_node_builder b = {0};
  foot_targets foot = {0};
  unsigned char *curve_foot = NULL;
  size_t *edge_line = NULL, *line_edge = NULL, n_edges = 0;
  hoc_status status = HOC_OK;
  HOC_ALLOC_GOTO(rs, 2 * (size_t)np, done);
  HOC_ALLOC_GOTO(s, (size_t)p + 1, done);
  HOC_ALLOC_GOTO(rs_in, 2 * (size_t)npi, done);
  HOC_ALLOC_GOTO(s_in, (size_t)pin + 1, done);
  HOC_ALLOC_GOTO(Nsrc, (size_t)np * (size_t)npi, done);
  HOC_ALLOC_GOTO(L, (size_t)pin + 1, done);
  HOC_ALLOC_GOTO(edge_t, (size_t)pin + 1, done);
  HOC_ALLOC_GOTO(edge_uv, 2 * ((size_t)pin + 1), done);
  HOC_TRY_GOTO(hoc_tri_nodes(p, set, rs), done);
  HOC_TRY_GOTO(hoc_edge_nodes(p, set, s), done);
  HOC_TRY_GOTO(hoc_tri_nodes(pin, in->nodeset, rs_in), done);
  HOC_TRY_GOTO(hoc_edge_nodes(pin, in->nodeset, s_in), done);
  HOC_TRY_GOTO(hoc_lagrange_create(pin, rs_in, &basis), done);
  HOC_TRY_GOTO(hoc_lagrange_eval(basis, np, rs, Nsrc, NULL), done); /* [np][npi] */
  HOC_ALLOC_GOTO(vmap, in->n_nodes, done);
  HOC_ALLOC_GOTO(conn, ne * (size_t)np, done);
  HOC_ALLOC_GOTO(edge_first, 3 * ne, done);
  HOC_ALLOC_GOTO(edge_a, 3 * ne, done);
  for (size_t i = 0; i < in->n_nodes; ++i)
    vmap[i] = SIZE_MAX;
  HOC_ALLOC_GOTO(elem_edge, 3 * ne, done);
  HOC_ALLOC_GOTO(edge_new, 3 * ne, done);
  /* the source line (CAD curve edge) on each edge, the first if several */
  HOC_ALLOC_GOTO(edge_line, 3 * ne + 1, done);
  HOC_ALLOC_GOTO(line_edge, in->n_lines + 1, done);
  HOC_TRY_GOTO(hoc_mesh_edges(in, elem_edge, edge_new, edge_line, line_edge, &n_edges), done);
  HOC_ALLOC_GOTO(grade, n_edges + 1, done);
  HOC_TRY_GOTO(cusp_grading(in, elem_edge, edge_line, n_edges, grade), done);
  /* corners (at most the source's nodes), edge nodes, interior nodes */
  HOC_TRY_GOTO(hoc_node_builder_reserve(&b, in->n_nodes + n_edges * (size_t)(p - 1) +
                                                ne * (size_t)(np - 3 * p)),
               done);
  if (face_foot) {
    foot.cap = b.cap;
    HOC_ALLOC_GOTO(foot.xyz, 3 * foot.cap, done);
    HOC_ALLOC_GOTO(foot.tol, foot.cap, done);
    foot.want = hoc_calloc(foot.cap + 1, 1);
    curve_foot = hoc_calloc((size_t)model->n_curves + 1, 1);
    if (!foot.want || !curve_foot) {
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      goto done;
    }
    /* a curve's nodes go to the foot where a face along it does */
    for (size_t e = 0; e < ne; ++e)
      for (int k = 0; k < 3 && face_foot[in->elem_face[e]]; ++k) {
        size_t l = edge_line[elem_edge[3 * e + (size_t)k]];
        if (l != SIZE_MAX) curve_foot[in->line_curve[l]] = 1;
      }
  }
  /* vertices keep their classification and parameters */
  for (size_t e = 0; e < ne; ++e)
    for (int k = 0; k < 3; ++k) {
      size_t i = in->conn[e * (size_t)npi + k];
      if (vmap[i] == SIZE_MAX)
        HOC_TRY_GOTO(hoc_node_builder_add(&b, in->dim[i], in->entity[i], in->param[2 * i],
                                          in->param[2 * i + 1], &vmap[i]),
                     done);
      conn[e * (size_t)np + k] = vmap[i];
    }
  for (size_t e = 0; e < ne; ++e) {
    int f = in->elem_face[e];
    const hoc_cad_face *face = &model->faces[f];
    const size_t *cn = in->conn + e * (size_t)npi;
    const size_t *sl = in->elem_slot + e * (size_t)npi;
    const double *euv = in->elem_uv + 2 * e * (size_t)npi;
    size_t *out_cn = conn + e * (size_t)np;
    /* nodes at the feet of the source element's points, except at a pole,
     * whose arbitrary coordinate follows the rules below */
    int to_foot = face_foot && face_foot[f];
    double tol = 0;
    for (int k = 0; k < 3 && face_foot; ++k)
      tol = fmax(tol, 2e-6 * hoc_dist3(in->xyz + 3 * cn[k], in->xyz + 3 * cn[(k + 1) % 3]));
    for (int i = 0; i < npi; ++i) to_foot &= in->slot_pole[sl[i]] == 0;
    size_t lnodes[HOC_MAX_ORDER + 1];
    for (int k = 0; k < 3 && p > 1; ++k) {
      int ka = k, kb = (k + 1) % 3;
      size_t a = cn[ka], id = elem_edge[3 * e + (size_t)k];
      size_t *dst = out_cn + 3 + (size_t)k * (p - 1);
      if (!edge_new[3 * e + (size_t)k]) {
        /* created by a neighbour: same nodes, walked in its direction or back */
        int same = edge_a[id] == a;
        for (int j = 0; j < p - 1; ++j)
          dst[j] = edge_first[id] + (size_t)(same ? j : p - 2 - j);
        continue;
      }
      edge_a[id] = a;
      edge_first[id] = b.n;
      /* the source edge's nodes from a to b: local indices */
      int loc[HOC_MAX_ORDER + 1];
      loc[0] = ka;
      loc[pin] = kb;
      for (int j = 0; j < pin - 1; ++j) loc[1 + j] = 3 + k * (pin - 1) + j;
      for (int j = 0; j <= pin; ++j) lnodes[j] = cn[loc[j]];
      size_t l = edge_line[id];
      if (l != SIZE_MAX) {
        /* on a CAD curve: interpolate t along the edge */
        int c = in->line_curve[l];
        const hoc_cad_curve *cv = &model->curves[c];
        const size_t *ln = in->line_conn + l * (size_t)(pin + 1);
        double ta = in->line_t[2 * l], tb = in->line_t[2 * l + 1];
        if (ln[0] != a) {
          double tmp = ta;
          ta = tb;
          tb = tmp;
        }
        edge_t[0] = ta;
        edge_t[pin] = tb;
        for (int j = 1; j < pin; ++j) {
          double t = in->param[2 * cn[loc[j]]], guess = ta + s_in[j] * (tb - ta);
          if (cv->period > 0) t -= cv->period * floor((t - guess) / cv->period + 0.5);
          edge_t[j] = t;
        }
        for (int j = 0; j < p - 1; ++j) {
          double sj = s[j + 1];
          if (grade[id] == a) sj = sqrt(sj);
          if (grade[id] == cn[kb]) sj = 1 - sqrt(1 - sj);
          hoc_lagrange_1d(pin, s_in, sj, L, NULL);
          double t = 0;
          for (int m = 0; m <= pin; ++m) t += L[m] * edge_t[m];
          HOC_TRY_GOTO(hoc_node_builder_add(&b, HOC_ON_CURVE, c, wrap_t(cv, t), 0, &dst[j]), done);
          if (curve_foot && curve_foot[c] && grade[id] == SIZE_MAX)
            foot_set(&foot, dst[j], pin + 1, L, in->xyz, lnodes, tol);
        }
      } else {
        /* inside the face: interpolate (u,v) along the edge; at a pole the
         * arbitrary coordinate follows the next node (a meridian) */
        for (int j = 0; j <= pin; ++j) memcpy(edge_uv + 2 * j, euv + 2 * loc[j], 2 * sizeof(double));
        for (int end = 0; end < 2; ++end) {
          int j = end ? pin : 0, next = end ? pin - 1 : 1;
          unsigned char pole = in->slot_pole[sl[loc[j]]];
          for (int d = 0; d < 2; ++d)
            if (pole & (1 << d)) edge_uv[2 * j + d] = edge_uv[2 * next + d];
        }
        for (int j = 0; j < p - 1; ++j) {
          hoc_lagrange_1d(pin, s_in, s[j + 1], L, NULL);
          double uv[2] = {0, 0};
          for (int m = 0; m <= pin; ++m) {
            uv[0] += L[m] * edge_uv[2 * m];
            uv[1] += L[m] * edge_uv[2 * m + 1];
          }
          hoc_cad_face_wrap(face, uv);
          HOC_TRY_GOTO(hoc_node_builder_add(&b, HOC_ON_FACE, f, uv[0], uv[1], &dst[j]), done);
          if (to_foot) foot_set(&foot, dst[j], pin + 1, L, in->xyz, lnodes, tol);
        }
      }
    }
    /* interior nodes: the source element's map in (u,v); from a linear
     * element with a pole vertex, the collapsed (Duffy) map instead, whose
     * edges from the pole are the meridians the edge nodes follow */
    int cusp = -1; /* a corner both of whose edges are graded there */
    for (int k = 0; k < 3 && pin == 1 && p > 1; ++k)
      if (grade[elem_edge[3 * e + (size_t)k]] == cn[k] &&
          grade[elem_edge[3 * e + (size_t)(k + 2) % 3]] == cn[k])
        cusp = k;
    for (int k = 3 * p; k < np; ++k) {
      const double *Nk = Nsrc + (size_t)k * npi;
      double uv[2] = {0, 0};
      for (int i = 0; i < npi; ++i) {
        uv[0] += Nk[i] * euv[2 * i];
        uv[1] += Nk[i] * euv[2 * i + 1];
      }
      if (pin == 1) {
        double lam[3] = {1 - rs[2 * k] - rs[2 * k + 1], rs[2 * k], rs[2 * k + 1]};
        if (cusp >= 0) {
          /* graded like the edges: distance from the corner r -> sqrt(r) */
          double r = 1 - lam[cusp], scale = sqrt(r) / r;
          for (int j = 0; j < 3; ++j)
            lam[j] = j == cusp ? 1 - sqrt(r) : lam[j] * scale;
          for (int d = 0; d < 2; ++d)
            uv[d] = lam[0] * euv[d] + lam[1] * euv[2 + d] + lam[2] * euv[4 + d];
        }
        for (int j = 0; j < 3; ++j)
          for (int d = 0; d < 2; ++d) {
            if (!(in->slot_pole[sl[j]] & (1 << d))) continue;
            int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
            double w = lam[j1] + lam[j2];
            if (w > 0) uv[d] = (lam[j1] * euv[2 * j1 + d] + lam[j2] * euv[2 * j2 + d]) / w;
          }
      }
      hoc_cad_face_wrap(face, uv);
      HOC_TRY_GOTO(hoc_node_builder_add(&b, HOC_ON_FACE, f, uv[0], uv[1], &out_cn[k]), done);
      if (to_foot && cusp < 0) foot_set(&foot, out_cn[k], npi, Nk, in->xyz, cn, tol);
    }
  }
  if (straight && (straight->n_nodes != b.n || straight->n_elems != ne ||
                   memcmp(straight->conn, conn, ne * (size_t)np * sizeof *conn) != 0)) {
    status = HOC_ERROR(HOC_ERR_MISMATCH, "the straight raise is not of this source");
    goto done;
  }
  if (face_foot) HOC_TRY_GOTO(foot_move(model, &foot, &b), done);
  if (face_foot && straight && b.n <= foot.cap) {
    /* the straight raise with the nodes at the feet moved; assembled
     * afresh below if one lands on a pole side */
    int at_pole = 0;
    HOC_TRY_GOTO(hoc_mesh_copy(straight, out), done);
    for (size_t i = 0; i < b.n; ++i)
      if (foot.want[i]) memcpy((*out)->param + 2 * i, b.par + 2 * i, 2 * sizeof *b.par);
    status = hoc_mesh_move_nodes(*out, foot.want, &at_pole);
    if (status != HOC_OK || !at_pole) {
      if (status != HOC_OK) hoc_mesh_destroy(out);
      goto done;
    }
    hoc_mesh_destroy(out);
  }
  /* lines of order p along the curve edges that elements use */
  size_t nl = 0;
  HOC_ALLOC_GOTO(lconn, in->n_lines * (size_t)(p + 1) + 1, done);
  HOC_ALLOC_GOTO(lcurve, in->n_lines + 1, done);
  for (size_t l = 0; l < in->n_lines; ++l) {
    const size_t *ln = in->line_conn + l * (size_t)(pin + 1);
    size_t id = line_edge[l];
    if (p > 1 && id == SIZE_MAX) continue; /* a curve no element touches */
    if (vmap[ln[0]] == SIZE_MAX || vmap[ln[1]] == SIZE_MAX) continue;
    size_t *dst = lconn + nl * (size_t)(p + 1);
    dst[0] = vmap[ln[0]];
    dst[1] = vmap[ln[1]];
    int same = p > 1 && edge_a[id] == ln[0];
    for (int j = 0; j < p - 1; ++j) dst[2 + j] = edge_first[id] + (size_t)(same ? j : p - 2 - j);
    lcurve[nl++] = in->line_curve[l];
  }
  hoc_mesh_source src = {0};
  src.order = p;
  src.nodeset = set;
  src.n_nodes = b.n;
  src.param = b.par;
  src.dim = b.dim;
  src.entity = b.ent;
  src.n_elems = ne;
  src.conn = conn;
  src.elem_face = in->elem_face;
  src.n_lines = nl;
  src.line_conn = lconn;
  src.line_curve = lcurve;
  src.face_orient = in->face_orient; /* same faces, same elements: same orientation */
  HOC_TRY_GOTO(hoc_mesh_assemble(in->model, &src, out), done);
  status = hoc_mesh_copy_failed(in, *out);
  if (status != HOC_OK) hoc_mesh_destroy(out);
done:
  hoc_lagrange_destroy(&basis);
  free(rs);
  free(s);
  free(rs_in);
  free(s_in);
  free(Nsrc);
  free(L);
  free(edge_t);
  free(edge_uv);
  free(vmap);
  free(conn);
  free(lconn);
  free(lcurve);
  free(edge_first);
  free(edge_a);
  hoc_node_builder_free(&b);
  free(foot.xyz);
  free(foot.tol);
  free(foot.want);
  free(curve_foot);
  free(elem_edge);
  free(grade);
  free(edge_new);
  free(edge_line);
  free(line_edge);
  return status;
}

static hoc_status check_set(hoc_nodeset set) {
  HOC_CHECK(set == HOC_NODES_EQUISPACED || set == HOC_NODES_FEKETE || set == HOC_NODES_WARP_BLEND,
            HOC_ERR_ARGUMENT, "unknown node set %d", (int)set);
  return HOC_OK;
}

hoc_status hoc_mesh_elevate(const hoc_mesh *in, int order, hoc_nodeset set, hoc_mesh **out) {
  HOC_CHECK(out, HOC_ERR_ARGUMENT, "mesh output is NULL");
  *out = NULL;
  HOC_CHECK(in, HOC_ERR_ARGUMENT, "no mesh given");
  HOC_CHECK(order >= 1 && order <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT,
            "order %d out of range 1..%d", order, HOC_MAX_ORDER);
  HOC_TRY(check_set(set));
  return reinterpolate(in, order, set, NULL, NULL, out);
}

hoc_status hoc_mesh_elevate_feet(const hoc_mesh *in, int order, hoc_nodeset set,
                                 const unsigned char *face_foot, hoc_mesh **out) {
  HOC_CHECK(out, HOC_ERR_ARGUMENT, "mesh output is NULL");
  *out = NULL;
  HOC_CHECK(in && face_foot, HOC_ERR_ARGUMENT, "no mesh or no faces given");
  HOC_CHECK(order >= 1 && order <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT,
            "order %d out of range 1..%d", order, HOC_MAX_ORDER);
  HOC_TRY(check_set(set));
  return reinterpolate(in, order, set, face_foot, NULL, out);
}

void hoc_mesh_feet_curves(const hoc_mesh *m, const unsigned char *faces, unsigned char *curves) {
  size_t np = (size_t)m->np;
  /* those of the curve nodes of the faces' elements: at p >= 2 every edge
   * on a curve has some */
  for (size_t e = 0; e < m->n_elems; ++e) {
    if (!faces[m->elem_face[e]]) continue;
    for (size_t k = 3; k < np; ++k) {
      size_t i = m->conn[e * np + k];
      if (m->dim[i] == HOC_ON_CURVE) curves[m->entity[i]] = 1;
    }
  }
}

hoc_status hoc_mesh_take_feet(hoc_mesh *m, const hoc_mesh *feet, const unsigned char *take) {
  HOC_CHECK(m && feet && take, HOC_ERR_ARGUMENT, "no mesh or no faces given");
  HOC_CHECK(m->model == feet->model && m->order == feet->order && m->n_nodes == feet->n_nodes &&
                m->n_elems == feet->n_elems && m->n_slots == feet->n_slots,
            HOC_ERR_MISMATCH, "the two raises are not of one source");
  unsigned char *curve = hoc_calloc((size_t)m->model->n_curves + 1, 1);
  unsigned char *from = hoc_calloc(m->n_nodes + 1, 1);
  if (!curve || !from) {
    free(curve);
    free(from);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  hoc_mesh_feet_curves(m, take, curve);
  for (size_t i = 0; i < m->n_nodes; ++i) {
    from[i] = m->dim[i] == HOC_ON_FACE    ? take[m->entity[i]]
              : m->dim[i] == HOC_ON_CURVE ? curve[m->entity[i]]
                                          : 0;
    if (!from[i]) continue;
    memcpy(m->xyz + 3 * i, feet->xyz + 3 * i, 3 * sizeof *m->xyz);
    memcpy(m->param + 2 * i, feet->param + 2 * i, 2 * sizeof *m->param);
  }
  for (size_t sl = 0; sl < m->n_slots; ++sl)
    if (from[m->slot_node[sl]])
      memcpy(m->slot_uv + 2 * sl, feet->slot_uv + 2 * sl, 2 * sizeof *m->slot_uv);
  free(from);
  free(curve);
  hoc_mesh_element_params(m);
  hoc_mesh_per_element_pole_params(m);
  if (feet->face_gap > m->face_gap) m->face_gap = feet->face_gap;
  return HOC_OK;
}

hoc_status hoc_mesh_elevate_feet_from(const hoc_mesh *in, const hoc_mesh *straight,
                                      const unsigned char *face_foot, hoc_mesh **out) {
  HOC_CHECK(out, HOC_ERR_ARGUMENT, "mesh output is NULL");
  *out = NULL;
  HOC_CHECK(in && straight && face_foot, HOC_ERR_ARGUMENT, "no mesh or no faces given");
  HOC_CHECK(straight->model == in->model, HOC_ERR_MISMATCH,
            "the straight raise is not of this source");
  return reinterpolate(in, straight->order, straight->nodeset, face_foot, straight, out);
}

/* The displacements in (u, v) of element e's edges on CAD curves, d[k][j]
 * at its p + 1 points (0 at the corners): the edge's nodes of `out`
 * against the points of the source map (src: [np][2], the source
 * element's (u, v) map at out's nodes, in out's unwrapping). *curved: a
 * bit per edge on a curve. */
static void edge_displacements(const hoc_mesh *out, size_t e, const double *src, double *d,
                               int *curved) {
  int p = out->order, np = out->np;
  const double *euv = out->elem_uv + 2 * e * (size_t)np;
  *curved = 0;
  for (int k = 0; k < 3; ++k) {
    double *dk = d + 2 * (size_t)k * (size_t)(p + 1);
    size_t first = out->conn[e * (size_t)np + 3 + (size_t)k * (size_t)(p - 1)];
    memset(dk, 0, 2 * (size_t)(p + 1) * sizeof *dk);
    if (out->dim[first] != HOC_ON_CURVE) continue;
    *curved |= 1 << k;
    for (int j = 1; j < p; ++j) {
      int at = 3 + k * (p - 1) + j - 1;
      for (int c = 0; c < 2; ++c) dk[2 * j + c] = euv[2 * at + c] - src[2 * at + c];
    }
  }
}

hoc_status hoc_mesh_blend_interior(const hoc_mesh *in, hoc_mesh *out, const unsigned char *which) {
  HOC_CHECK(in && out && which, HOC_ERR_ARGUMENT, "no mesh or no elements given");
  HOC_CHECK(in->model == out->model && in->n_elems == out->n_elems, HOC_ERR_MISMATCH,
            "the raise is not of this source");
  int p = out->order, np = out->np, npi = in->np;
  size_t ne = out->n_elems;
  if (p < 3) return HOC_OK; /* no interior node */
  double *rs = NULL, *s = NULL, *rs_in = NULL, *N = NULL, *src = NULL, *d = NULL, *L = NULL;
  double *before = NULL;
  unsigned char *moved = NULL;
  hoc_lagrange *basis = NULL;
  hoc_status status = HOC_OK;
  HOC_ALLOC_GOTO(rs, 2 * (size_t)np, done);
  HOC_ALLOC_GOTO(s, (size_t)p + 1, done);
  HOC_ALLOC_GOTO(rs_in, 2 * (size_t)npi, done);
  HOC_ALLOC_GOTO(N, (size_t)np * (size_t)npi, done);
  HOC_ALLOC_GOTO(src, 2 * (size_t)np, done);
  HOC_ALLOC_GOTO(d, 6 * ((size_t)p + 1), done);
  HOC_ALLOC_GOTO(L, (size_t)p + 1, done);
  HOC_ALLOC_GOTO(moved, out->n_nodes + 1, done);
  HOC_ALLOC_GOTO(before, 2 * out->n_nodes + 1, done);
  memcpy(before, out->param, 2 * out->n_nodes * sizeof *before);
  HOC_TRY_GOTO(hoc_tri_nodes(p, out->nodeset, rs), done);
  HOC_TRY_GOTO(hoc_edge_nodes(p, out->nodeset, s), done);
  HOC_TRY_GOTO(hoc_tri_nodes(in->order, in->nodeset, rs_in), done);
  HOC_TRY_GOTO(hoc_lagrange_create(in->order, rs_in, &basis), done);
  HOC_TRY_GOTO(hoc_lagrange_eval(basis, np, rs, N, NULL), done); /* [np][npi] */
  for (size_t e = 0; e < ne; ++e) {
    if (!which[e]) continue;
    const size_t *sl = out->elem_slot + e * (size_t)np;
    int pole = 0;
    for (int i = 0; i < np; ++i) pole |= out->slot_pole[sl[i]];
    for (int i = 0; i < npi; ++i) pole |= in->slot_pole[in->elem_slot[e * (size_t)npi + (size_t)i]];
    if (pole) continue; /* an arbitrary coordinate: the source map is not the nodes' */
    const double *ein = in->elem_uv + 2 * e * (size_t)npi;
    const double *eout = out->elem_uv + 2 * e * (size_t)np;
    /* the two unwrappings differ by whole periods, as at corner 0 */
    double shift[2] = {eout[0] - ein[0], eout[1] - ein[1]};
    for (int k = 0; k < np; ++k)
      for (int c = 0; c < 2; ++c) {
        double v = shift[c];
        for (int i = 0; i < npi; ++i) v += N[(size_t)k * (size_t)npi + (size_t)i] * ein[2 * i + c];
        src[2 * k + c] = v;
      }
    int curved;
    edge_displacements(out, e, src, d, &curved);
    if (!curved) continue;
    const hoc_cad_face *face = &out->model->faces[out->elem_face[e]];
    for (int k = 3 * p; k < np; ++k) {
      double lam[3] = {1 - rs[2 * k] - rs[2 * k + 1], rs[2 * k], rs[2 * k + 1]}, uv[2];
      for (int c = 0; c < 2; ++c) uv[c] = src[2 * k + c];
      for (int j = 0; j < 3; ++j) {
        double a = lam[j], b = lam[(j + 1) % 3], w = a + b;
        if (!(curved & (1 << j)) || !(w > 0)) continue;
        hoc_lagrange_1d(p, s, b / w, L, NULL);
        const double *dj = d + 2 * (size_t)j * (size_t)(p + 1);
        for (int m = 1; m < p; ++m)
          for (int c = 0; c < 2; ++c) uv[c] += w * L[m] * dj[2 * m + c];
      }
      hoc_cad_face_wrap(face, uv);
      size_t node = out->conn[e * (size_t)np + (size_t)k];
      memcpy(out->param + 2 * node, uv, sizeof uv);
      moved[node] = 1;
    }
  }
  int at_pole = 0;
  HOC_TRY_GOTO(hoc_mesh_move_nodes(out, moved, &at_pole), done);
  if (at_pole) { /* a node on a pole side: the mesh as it was (see hoc_mesh_move_nodes) */
    memcpy(out->param, before, 2 * out->n_nodes * sizeof *before);
    status = hoc_mesh_move_nodes(out, moved, &at_pole);
  }
done:
  free(before);
  hoc_lagrange_destroy(&basis);
  free(rs);
  free(s);
  free(rs_in);
  free(N);
  free(src);
  free(d);
  free(L);
  free(moved);
  return status;
}

hoc_status hoc_mesh_convert(const hoc_mesh *in, hoc_nodeset set, hoc_mesh **out) {
  return hoc_mesh_convert_nodeset(in, set, out);
}

hoc_status hoc_mesh_convert_nodeset(const hoc_mesh *in, hoc_nodeset set, hoc_mesh **out) {
  HOC_CHECK(out, HOC_ERR_ARGUMENT, "mesh output is NULL");
  *out = NULL;
  HOC_CHECK(in, HOC_ERR_ARGUMENT, "no mesh given");
  HOC_TRY(check_set(set));
  return reinterpolate(in, in->order, set, NULL, NULL, out);
}
