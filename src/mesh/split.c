/* Local refinement: flagged elements split in four at their edges'
 * midpoints, neighbours split so that the mesh stays conforming: red-green
 * (in two for one split edge, else in four) or by their longest edge
 * (bisected there first, then each half at its other split edge). The children's nodes are placed
 * as elevation places them, straight between their corners in the parent's (u, v) (in the curve's t
 * along curve edges; at a pole, on the meridians of the collapsed map); every element not split
 * keeps its nodes. (Children that kept their parent's
 * curved map were measured worse: a map valid at its quadrature points and nodes can fold between
 * them, as an optimised curve edge whose t is not monotone does, and its pieces then measure
 * tangled.) SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "core/hash.h"
#include "mesh/mesh.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* What the split needs of the mesh while building children. */
typedef struct splitter {
  const hoc_mesh *m;
  int p, np;
  const double *rs;        /* [np][2] reference nodes of the node set */
  const double *s1;        /* [p + 1] its edge nodes */
  const size_t *edge_of;   /* [3 ne] edge number of each element edge */
  const size_t *edge_line; /* [edges] line on a CAD curve, or SIZE_MAX */
  hoc_node_builder out;
  hoc_hash new_edges; /* pair of end nodes -> index into new_first and new_start */
  size_t *new_first, *new_start, n_new, cap_new; /* first node, and the end it starts from */
} splitter;

/* Element e's straight map (its corners' unwrapped (u, v)) at parent
 * reference point x (r, s), wrapped into the face's range. At a corner on
 * a pole, the arbitrary coordinate follows the collapsed map instead (as
 * elevation places nodes: mesh/elevate.c), whose lines from the pole are
 * meridians: a child's edge along the parent's edge from the pole stays
 * on the parent's meridian. */
static void face_point(const splitter *S, size_t e, const double x[2], double uv[2]) {
  const hoc_mesh *m = S->m;
  const double *euv = m->elem_uv + 2 * e * (size_t)S->np;
  const size_t *sl = m->elem_slot + e * (size_t)S->np;
  double w[3] = {1 - x[0] - x[1], x[0], x[1]};
  uv[0] = uv[1] = 0;
  for (int i = 0; i < 3; ++i) {
    uv[0] += w[i] * euv[2 * i];
    uv[1] += w[i] * euv[2 * i + 1];
  }
  for (int j = 0; j < 3; ++j)
    for (int d = 0; d < 2; ++d) {
      if (!(m->slot_pole[sl[j]] & (1 << d))) continue;
      int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      double wj = w[j1] + w[j2];
      if (wj > 0) uv[d] = (w[j1] * euv[2 * j1 + d] + w[j2] * euv[2 * j2 + d]) / wj;
    }
  hoc_cad_face_wrap(&m->model->faces[m->elem_face[e]], uv);
}

/* Element e's edge k (corner k to k + 1), 0..1 along it, of reference point x. */
static double along_edge(int k, const double x[2]) {
  return k == 0 ? x[0] : k == 1 ? x[1] : 1 - x[1];
}

/* The parameter t on its curve of element e's edge k at 0..1 along it
 * (from corner k), straight between the curve line's ends. */
static double curve_point(const splitter *S, size_t e, int k, double along) {
  const hoc_mesh *m = S->m;
  size_t l = S->edge_line[S->edge_of[3 * e + (size_t)k]];
  const hoc_cad_curve *cv = &m->model->curves[m->line_curve[l]];
  double ta = m->line_t[2 * l], tb = m->line_t[2 * l + 1];
  if (m->line_conn[l * (size_t)(S->p + 1)] != m->conn[e * (size_t)S->np + (size_t)k])
    along = 1 - along;
  double t = ta + along * (tb - ta);
  if (cv->period > 0) t -= cv->period * floor((t - cv->lo) / cv->period);
  return t;
}

/* Which edge of the parent a child's edge from x to y (parent reference
 * coordinates) lies on, or -1 if inside. */
static int on_parent_edge(const double x[2], const double y[2]) {
  if (x[1] == 0 && y[1] == 0) return 0;
  if (x[0] + x[1] == 1 && y[0] + y[1] == 1) return 1;
  if (x[0] == 0 && y[0] == 0) return 2;
  return -1;
}

/* The p - 1 nodes of a child's edge from end node a (parent coordinates xa)
 * to b (xb), in that direction, into dst: the parent's own edge nodes where
 * the child's edge is a whole edge of the parent, else made once per pair
 * of ends (straight in t along a curve edge, elsewhere in (u, v)) and
 * shared by the other child or neighbour using it. */
static hoc_status child_edge(splitter *S, size_t e, size_t a, size_t b, const double xa[2],
                             const double xb[2], size_t *dst) {
  const hoc_mesh *m = S->m;
  int p = S->p, k = on_parent_edge(xa, xb);
  if (p < 2) return HOC_OK;
  const size_t *cn = m->conn + e * (size_t)S->np;
  if (k >= 0) {
    size_t ca = cn[k], cb = cn[(k + 1) % 3];
    if ((a == ca && b == cb) || (a == cb && b == ca)) { /* the parent's whole edge */
      for (int j = 0; j < p - 1; ++j)
        dst[j] = cn[3 + k * (p - 1) + (a == ca ? j : p - 2 - j)];
      return HOC_OK;
    }
  }
  int found;
  size_t slot;
  HOC_TRY(hoc_hash_insert(&S->new_edges, hoc_pair_key(a, b), S->n_new, &found, &slot));
  if (found) {
    int same = S->new_start[slot] == a;
    for (int j = 0; j < p - 1; ++j)
      dst[j] = S->new_first[slot] + (size_t)(same ? j : p - 2 - j);
    return HOC_OK;
  }
  if (S->n_new == S->cap_new) {
    size_t cap = S->cap_new ? 2 * S->cap_new : 256;
    size_t *f = hoc_realloc(S->new_first, cap, sizeof *f);
    if (f) S->new_first = f;
    size_t *st = hoc_realloc(S->new_start, cap, sizeof *st);
    if (st) S->new_start = st;
    HOC_CHECK(f && st, HOC_ERR_MEMORY, "out of memory");
    S->cap_new = cap;
  }
  S->new_first[S->n_new] = S->out.n;
  S->new_start[S->n_new] = a;
  S->n_new++;
  int curve = k >= 0 && S->edge_line[S->edge_of[3 * e + (size_t)k]] != SIZE_MAX;
  for (int j = 0; j < p - 1; ++j) {
    double w = S->s1[j + 1], x[2] = {xa[0] + w * (xb[0] - xa[0]), xa[1] + w * (xb[1] - xa[1])};
    size_t idx;
    if (curve) {
      size_t l = S->edge_line[S->edge_of[3 * e + (size_t)k]];
      HOC_TRY(hoc_node_builder_add(&S->out, HOC_ON_CURVE, m->line_curve[l],
                                   curve_point(S, e, k, along_edge(k, x)), 0, &idx));
    } else {
      double uv[2];
      face_point(S, e, x, uv);
      HOC_TRY(hoc_node_builder_add(&S->out, HOC_ON_FACE, m->elem_face[e], uv[0], uv[1], &idx));
    }
    dst[j] = idx;
  }
  return HOC_OK;
}

/* One child of element e with corner nodes c[3] at parent coordinates
 * x[3][2]: its np nodes into conn. */
static hoc_status child(splitter *S, size_t e, const size_t c[3], const double x[3][2],
                        size_t *conn) {
  int p = S->p, np = S->np;
  for (int k = 0; k < 3; ++k)
    conn[k] = c[k];
  for (int k = 0; k < 3; ++k)
    HOC_TRY(child_edge(S, e, c[k], c[(k + 1) % 3], x[k], x[(k + 1) % 3], conn + 3 + k * (p - 1)));
  for (int i = 3 * p; i < np; ++i) {
    double r = S->rs[2 * i], s = S->rs[2 * i + 1], y[2], uv[2];
    for (int d = 0; d < 2; ++d)
      y[d] = x[0][d] + r * (x[1][d] - x[0][d]) + s * (x[2][d] - x[0][d]);
    face_point(S, e, y, uv);
    HOC_TRY(hoc_node_builder_add(&S->out, HOC_ON_FACE, S->m->elem_face[e], uv[0], uv[1], &conn[i]));
  }
  return HOC_OK;
}

/* A triangle during splitting: corner nodes and their parent coordinates. */
typedef struct tri {
  size_t c[3];
  double x[3][2];
} tri;

/* t cut in two through the midpoint (node mid, parent coordinates mx) of
 * its edge k and the opposite corner; orientation kept. */
static void bisect(const tri *t, int k, size_t mid, const double mx[2], tri h[2]) {
  int b = (k + 1) % 3, o = (k + 2) % 3;
  tri h0 = {{t->c[k], mid, t->c[o]},
            {{t->x[k][0], t->x[k][1]}, {mx[0], mx[1]}, {t->x[o][0], t->x[o][1]}}};
  tri h1 = {{mid, t->c[b], t->c[o]},
            {{mx[0], mx[1]}, {t->x[b][0], t->x[b][1]}, {t->x[o][0], t->x[o][1]}}};
  h[0] = h0;
  h[1] = h1;
}

/* The longest of element e's edges (corner to corner in space; the first on ties). */
static int longest_edge(const hoc_mesh *m, size_t e) {
  const size_t *cn = m->conn + e * (size_t)m->np;
  int best = 0;
  double lmax = -1;
  for (int k = 0; k < 3; ++k) {
    const double *a = m->xyz + 3 * cn[k], *b = m->xyz + 3 * cn[(k + 1) % 3];
    double l = (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
               (a[2] - b[2]) * (a[2] - b[2]);
    if (l > lmax) lmax = l, best = k;
  }
  return best;
}

hoc_status hoc_mesh_split(const hoc_mesh *mesh, const unsigned char *elements, hoc_split_kind kind,
                          hoc_mesh **out, unsigned char *pieces) {
  HOC_CHECK(out, HOC_ERR_ARGUMENT, "mesh output is NULL");
  *out = NULL;
  HOC_CHECK(mesh && elements, HOC_ERR_ARGUMENT, "no mesh or no element flags");
  HOC_CHECK(kind == HOC_SPLIT_RED_GREEN || kind == HOC_SPLIT_LONGEST_EDGE, HOC_ERR_ARGUMENT,
            "unknown split kind %d", (int)kind);
  const int bisecting = kind == HOC_SPLIT_LONGEST_EDGE;
  const hoc_mesh *m = mesh;
  int p = m->order, np = m->np;
  size_t ne = m->n_elems, nl = m->n_lines;
  hoc_status status = HOC_OK;
  splitter S = {0};
  S.m = m;
  S.p = p;
  S.np = np;
  size_t *edge_of = NULL, *edge_line = NULL, *line_edge = NULL, *mid = NULL, *conn = NULL;
  size_t *lconn = NULL, *remap = NULL;
  unsigned char *first = NULL, *marked = NULL, *used = NULL;
  int *longest = NULL;
  int *eface = NULL, *lcurve = NULL;
  double *rs = NULL, *s1 = NULL;
  HOC_ALLOC_GOTO(rs, 2 * (size_t)np, done);
  HOC_ALLOC_GOTO(s1, (size_t)p + 1, done);
  HOC_TRY_GOTO(hoc_tri_nodes(p, m->nodeset, rs), done);
  HOC_TRY_GOTO(hoc_edge_nodes(p, m->nodeset, s1), done);
  S.rs = rs;
  S.s1 = s1;
  /* edges: shared across a CAD curve, else numbered per face */
  size_t n_edges;
  HOC_ALLOC_GOTO(edge_of, 3 * ne + 1, done);
  HOC_ALLOC_GOTO(first, 3 * ne + 1, done);
  HOC_ALLOC_GOTO(edge_line, 3 * ne + 1, done);
  HOC_ALLOC_GOTO(line_edge, nl + 1, done);
  HOC_TRY_GOTO(hoc_mesh_edges(m, edge_of, first, edge_line, line_edge, &n_edges), done);
  S.edge_of = edge_of;
  S.edge_line = edge_line;
  /* marks: every edge of a flagged element; then, red-green, all edges of
   * an element with two marked edges, or, bisecting, the longest edge of an
   * element with any, until nothing changes */
  HOC_ALLOC_GOTO(marked, n_edges + 1, done);
  HOC_ALLOC_GOTO(longest, ne + 1, done);
  for (size_t e = 0; e < ne; ++e) {
    longest[e] = longest_edge(m, e);
    if (elements[e])
      for (int k = 0; k < 3; ++k)
        marked[edge_of[3 * e + (size_t)k]] = 1;
  }
  for (int changed = 1; bisecting && changed;) {
    changed = 0;
    for (size_t e = 0; e < ne; ++e) {
      const size_t *ed = edge_of + 3 * e;
      if (!(marked[ed[0]] | marked[ed[1]] | marked[ed[2]]) || marked[ed[longest[e]]]) continue;
      marked[ed[longest[e]]] = 1;
      changed = 1;
    }
  }
  for (int changed = !bisecting; changed;) {
    changed = 0;
    for (size_t e = 0; e < ne; ++e) {
      const size_t *ed = edge_of + 3 * e;
      if (marked[ed[0]] + marked[ed[1]] + marked[ed[2]] != 2) continue;
      marked[ed[0]] = marked[ed[1]] = marked[ed[2]] = 1;
      changed = 1;
    }
  }
  /* the mesh's nodes, then midpoints (straight in t on a curve, else in
   * the (u, v) of the first element using the edge) */
  HOC_TRY_GOTO(hoc_node_builder_reserve(&S.out, m->n_nodes + 1024), done);
  memcpy(S.out.par, m->param, 2 * m->n_nodes * sizeof *S.out.par);
  memcpy(S.out.dim, m->dim, m->n_nodes);
  memcpy(S.out.ent, m->entity, m->n_nodes * sizeof *S.out.ent);
  S.out.n = m->n_nodes;
  HOC_TRY_GOTO(hoc_hash_init(&S.new_edges, 64), done);
  HOC_ALLOC_GOTO(mid, n_edges + 1, done);
  for (size_t id = 0; id < n_edges; ++id)
    mid[id] = SIZE_MAX;
  static const double corner_x[3][2] = {{0, 0}, {1, 0}, {0, 1}};
  for (size_t x = 0; x < 3 * ne; ++x) {
    size_t id = edge_of[x];
    if (!marked[id] || mid[id] != SIZE_MAX) continue;
    size_t e = x / 3;
    int k = (int)(x % 3);
    double c[2] = {0.5 * (corner_x[k][0] + corner_x[(k + 1) % 3][0]),
                   0.5 * (corner_x[k][1] + corner_x[(k + 1) % 3][1])};
    if (edge_line[id] != SIZE_MAX) {
      size_t l = edge_line[id];
      HOC_TRY_GOTO(hoc_node_builder_add(&S.out, HOC_ON_CURVE, m->line_curve[l],
                                        curve_point(&S, e, k, 0.5), 0, &mid[id]),
                   done);
    } else {
      double uv[2];
      face_point(&S, e, c, uv);
      HOC_TRY_GOTO(
          hoc_node_builder_add(&S.out, HOC_ON_FACE, m->elem_face[e], uv[0], uv[1], &mid[id]), done);
    }
  }
  /* children: red-green four (red) or two (green: through the split edge's
   * midpoint and the opposite corner); bisecting two to four; corners in
   * the parent's order */
  size_t n_new_elems = 0;
  for (size_t e = 0; e < ne; ++e) {
    int cnt = marked[edge_of[3 * e]] + marked[edge_of[3 * e + 1]] + marked[edge_of[3 * e + 2]];
    int n = cnt == 0 ? 1 : bisecting ? cnt + 1 : cnt == 3 ? 4 : 2;
    if (pieces) pieces[e] = (unsigned char)n;
    n_new_elems += (size_t)n;
  }
  HOC_ALLOC_GOTO(conn, n_new_elems * (size_t)np + 1, done);
  HOC_ALLOC_GOTO(eface, n_new_elems + 1, done);
  size_t ce = 0;
  for (size_t e = 0; e < ne; ++e) {
    const size_t *cn = m->conn + e * (size_t)np;
    size_t md[3];
    int cnt = 0, one = 0;
    for (int k = 0; k < 3; ++k) {
      size_t id = edge_of[3 * e + (size_t)k];
      md[k] = marked[id] ? mid[id] : SIZE_MAX;
      if (marked[id]) cnt++, one = k;
    }
    if (cnt == 0) {
      memcpy(conn + ce * (size_t)np, cn, (size_t)np * sizeof *conn);
      eface[ce++] = m->elem_face[e];
      continue;
    }
    double mx[3][2];
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 2; ++d)
        mx[k][d] = 0.5 * (corner_x[k][d] + corner_x[(k + 1) % 3][d]);
    size_t kc[4][3];
    double kx[4][3][2];
    int nk;
    if (bisecting) { /* at the longest edge, then each half at its marked outer edge */
      tri t = {{cn[0], cn[1], cn[2]}, {{0, 0}, {1, 0}, {0, 1}}}, h[2], out4[4];
      int L = longest[e];
      bisect(&t, L, md[L], mx[L], h);
      nk = 0;
      int side[2] = {(L + 2) % 3, (L + 1) % 3}, sk[2] = {2, 1};
      for (int i = 0; i < 2; ++i) {
        if (md[side[i]] != SIZE_MAX)
          bisect(&h[i], sk[i], md[side[i]], mx[side[i]], out4 + nk), nk += 2;
        else
          out4[nk++] = h[i];
      }
      for (int i = 0; i < nk; ++i) {
        memcpy(kc[i], out4[i].c, sizeof kc[i]);
        memcpy(kx[i], out4[i].x, sizeof kx[i]);
      }
    } else if (cnt == 1) {
      int a = one, b = (one + 1) % 3, o = (one + 2) % 3;
      size_t c0[3] = {cn[a], md[one], cn[o]}, c1[3] = {md[one], cn[b], cn[o]};
      memcpy(kc[0], c0, sizeof c0);
      memcpy(kc[1], c1, sizeof c1);
      double x0[3][2] = {{corner_x[a][0], corner_x[a][1]},
                         {mx[one][0], mx[one][1]},
                         {corner_x[o][0], corner_x[o][1]}};
      double x1[3][2] = {{mx[one][0], mx[one][1]},
                         {corner_x[b][0], corner_x[b][1]},
                         {corner_x[o][0], corner_x[o][1]}};
      memcpy(kx[0], x0, sizeof x0);
      memcpy(kx[1], x1, sizeof x1);
      nk = 2;
    } else {
      size_t c0[3] = {cn[0], md[0], md[2]}, c1[3] = {md[0], cn[1], md[1]};
      size_t c2[3] = {md[2], md[1], cn[2]}, c3[3] = {md[0], md[1], md[2]};
      memcpy(kc[0], c0, sizeof c0);
      memcpy(kc[1], c1, sizeof c1);
      memcpy(kc[2], c2, sizeof c2);
      memcpy(kc[3], c3, sizeof c3);
      double x0[3][2] = {{0, 0}, {mx[0][0], mx[0][1]}, {mx[2][0], mx[2][1]}};
      double x1[3][2] = {{mx[0][0], mx[0][1]}, {1, 0}, {mx[1][0], mx[1][1]}};
      double x2[3][2] = {{mx[2][0], mx[2][1]}, {mx[1][0], mx[1][1]}, {0, 1}};
      double x3[3][2] = {{mx[0][0], mx[0][1]}, {mx[1][0], mx[1][1]}, {mx[2][0], mx[2][1]}};
      memcpy(kx[0], x0, sizeof x0);
      memcpy(kx[1], x1, sizeof x1);
      memcpy(kx[2], x2, sizeof x2);
      memcpy(kx[3], x3, sizeof x3);
      nk = 4;
    }
    for (int j = 0; j < nk; ++j, ++ce) {
      HOC_TRY_GOTO(child(&S, e, kc[j], (const double(*)[2])kx[j], conn + ce * (size_t)np), done);
      eface[ce] = m->elem_face[e];
    }
  }
  /* lines: the split ones in two, with the children's nodes on each half */
  HOC_ALLOC_GOTO(lconn, 2 * nl * (size_t)(p + 1) + 1, done);
  HOC_ALLOC_GOTO(lcurve, 2 * nl + 1, done);
  size_t ml = 0;
  for (size_t l = 0; l < nl; ++l) {
    const size_t *ln = m->line_conn + l * (size_t)(p + 1);
    size_t a = ln[0], b = ln[1];
    size_t id = line_edge[l], cut = id != SIZE_MAX && marked[id] ? mid[id] : SIZE_MAX;
    if (cut == SIZE_MAX) {
      memcpy(lconn + ml * (size_t)(p + 1), ln, (size_t)(p + 1) * sizeof *lconn);
      lcurve[ml++] = m->line_curve[l];
      continue;
    }
    size_t ends[2][2] = {{a, cut}, {cut, b}};
    for (int h = 0; h < 2; ++h, ++ml) {
      size_t *dst = lconn + ml * (size_t)(p + 1);
      dst[0] = ends[h][0];
      dst[1] = ends[h][1];
      lcurve[ml] = m->line_curve[l];
      if (p < 2) continue;
      size_t slot = hoc_hash_get(&S.new_edges, hoc_pair_key(ends[h][0], ends[h][1]));
      if (slot == SIZE_MAX) {
        status = HOC_ERROR(HOC_ERR_INTERNAL, "split: a half of line %zu has no nodes", l);
        goto done;
      }
      int same = S.new_start[slot] == ends[h][0];
      for (int j = 0; j < p - 1; ++j)
        dst[2 + j] = S.new_first[slot] + (size_t)(same ? j : p - 2 - j);
    }
  }
  /* nodes no element uses any more (inside and on the split edges of split
   * elements) are dropped */
  HOC_ALLOC_GOTO(used, S.out.n + 1, done);
  HOC_ALLOC_GOTO(remap, S.out.n + 1, done);
  for (size_t i = 0; i < ce * (size_t)np; ++i)
    used[conn[i]] = 1;
  size_t n_kept = 0;
  for (size_t i = 0; i < S.out.n; ++i) {
    remap[i] = used[i] ? n_kept : SIZE_MAX;
    if (used[i]) {
      S.out.par[2 * n_kept] = S.out.par[2 * i];
      S.out.par[2 * n_kept + 1] = S.out.par[2 * i + 1];
      S.out.dim[n_kept] = S.out.dim[i];
      S.out.ent[n_kept] = S.out.ent[i];
      ++n_kept;
    }
  }
  for (size_t i = 0; i < ce * (size_t)np; ++i)
    conn[i] = remap[conn[i]];
  size_t kl = 0;
  for (size_t l = 0; l < ml; ++l) {
    size_t *src = lconn + l * (size_t)(p + 1), ok = 1;
    for (int j = 0; j <= p; ++j)
      ok &= remap[src[j]] != SIZE_MAX;
    if (!ok) continue; /* a line no element touches any more */
    for (int j = 0; j <= p; ++j)
      lconn[kl * (size_t)(p + 1) + (size_t)j] = remap[src[j]];
    lcurve[kl++] = lcurve[l];
  }
  hoc_mesh_source src = {0};
  src.order = p;
  src.nodeset = m->nodeset;
  src.n_nodes = n_kept;
  src.param = S.out.par;
  src.dim = S.out.dim;
  src.entity = S.out.ent;
  src.n_elems = ce;
  src.conn = conn;
  src.elem_face = eface;
  src.n_lines = kl;
  src.line_conn = lconn;
  src.line_curve = lcurve;
  src.face_orient = m->face_orient;
  status = hoc_mesh_assemble(m->model, &src, out);
  if (status == HOC_OK) status = hoc_mesh_copy_failed(m, *out);
  if (status != HOC_OK) hoc_mesh_destroy(out);
done:
  hoc_hash_free(&S.new_edges);
  hoc_node_builder_free(&S.out);
  free(S.new_first);
  free(S.new_start);
  free(rs);
  free(s1);
  free(line_edge);
  free(first);
  free(edge_of);
  free(edge_line);
  free(marked);
  free(longest);
  free(used);
  free(remap);
  free(mid);
  free(conn);
  free(eface);
  free(lconn);
  free(lcurve);
  return status;
}
