/* Simultaneous untangling and smoothing in parametric coordinates (the
 * seed's Section 4).
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * Objective: f(z) = sum_e sum_q r_eq^2, r_eq = sqrt(w_q) (eta(x~_q) - 1), the
 * quadrature of sum_e int_{t_I} (eta - 1)^2 (weights normalised per element),
 * with sigma replaced by sigma_delta = (sigma + sqrt(sigma^2 + 4 delta_e^2))/2
 * on elements that are tangled at the start of a sweep (Escobar et al.).
 * Unknowns z: (u, v) of face-interior nodes, t of nodes on CAD curves.
 * Positions x(z) = phi(u, v) or c(t) are always CAD evaluations.
 *
 * Solver: nonlinear block Gauss-Seidel. The free nodes are coloured so that
 * no two nodes of a colour share an element; each colour takes one damped
 * Gauss-Newton step per node on its local objective (the elements around
 * it), with a backtracking line search that rejects any step that tangles a
 * valid element, folds an element in the parameter plane (so a node never
 * leaves its face's domain), or reorders nodes along a curve. Nodes of a
 * colour are independent: they are updated in parallel and the result does
 * not depend on the thread count. CAD evaluations are batched per colour.
 */
#include "mesh/mesh.h"
#include "quality/quality.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void hoc_optimize_options_default(hoc_optimize_options *o) {
  if (!o) return;
  memset(o, 0, sizeof *o);
  o->measure = HOC_MEASURE_SHAPE;
  o->max_iterations = 100;
  o->tolerance = 0.1;
}

typedef struct opt {
  hoc_mesh *m;
  const hoc_model *model;
  const hoc_quality_tables *t;
  hoc_measure measure;
  int np, nq;
  unsigned char *ndof;  /* [n_nodes] unknowns of the node: 0, 1 (t) or 2 (u, v) */
  size_t *ne_start;     /* [n_nodes+1] node -> elements */
  size_t *ne_elem;      /* element */
  int *ne_local;        /* local index of the node in it */
  size_t *ns_start;     /* [n_nodes+1] node -> slots */
  size_t *ns_slot;
  size_t *nl_start;     /* [n_nodes+1] node -> lines */
  size_t *nl_line;
  int n_colors;
  size_t *color_start;  /* [n_colors+1] */
  size_t *color_node;
  double *dz;           /* [n_nodes][6] dx/dz: (phi_u, phi_v) or (c', 0) */
  double *normal;       /* [n_slots][3] unit CAD normal at each slot, oriented */
  double *delta;        /* [n_elems] regularisation of the sweep */
  unsigned char *valid; /* [n_elems] not tangled (Definition 2) */
  unsigned char *pvalid;/* [n_elems] not folded in the (u,v) plane */
  unsigned char *region;/* [n_elems] tangled or next to a tangled element: regularised, and
                           free to pass through sigma = 0 during the sweep */
  double *hsize;        /* [n_nodes] local length: bound on one step's displacement */
  unsigned char *active;/* [n_nodes] */
  double min_gain;      /* a move that lowers f by less does not wake the neighbours */
  unsigned char *moving;/* [n_nodes] use the trial state of this node */
  size_t *carry_start;  /* [n_nodes+1] face-interior vertex -> the high-order nodes of its */
  size_t *carry_node;   /*   star, moved with it in (u,v) ... */
  double *carry_w;      /*   ... by their barycentric weight of the vertex */
  double *fnew;         /* [n_nodes] local objective after an accepted move */
  /* per-node trial state of the colour being processed */
  double *step;         /* [n_nodes][2] Gauss-Newton direction */
  double *alpha;        /* [n_nodes] step length */
  double *f0;           /* [n_nodes] local objective before */
  double *slope;        /* [n_nodes] g . step (< 0) */
  double *tpar;         /* [n_nodes][2] trial parameters */
  double *txyz;         /* [n_nodes][3] */
  double *tdz;          /* [n_nodes][6] */
  double *tslot_uv;     /* [n_slots][2] */
  double *tnormal;      /* [n_slots][3] */
  unsigned char *state; /* [n_nodes] 0 idle, 1 trying, 2 accepted */
  size_t *list;         /* [n_nodes] scratch */
  size_t max_star;      /* largest number of elements around a node */
} opt;

typedef struct scratch {
  double *x, *n, *r, *J, *uv;
} scratch;

static void opt_free(opt *o) {
  free(o->ndof);
  free(o->ne_start);
  free(o->ne_elem);
  free(o->ne_local);
  free(o->ns_start);
  free(o->ns_slot);
  free(o->nl_start);
  free(o->nl_line);
  free(o->color_start);
  free(o->color_node);
  free(o->dz);
  free(o->normal);
  free(o->delta);
  free(o->valid);
  free(o->pvalid);
  free(o->region);
  free(o->hsize);
  free(o->active);
  free(o->fnew);
  free(o->moving);
  free(o->carry_start);
  free(o->carry_node);
  free(o->carry_w);
  free(o->step);
  free(o->alpha);
  free(o->f0);
  free(o->slope);
  free(o->tpar);
  free(o->txyz);
  free(o->tdz);
  free(o->tslot_uv);
  free(o->tnormal);
  free(o->state);
  free(o->list);
}

/* CSR from (key, value) pairs produced by a callback-free double pass. */
static hoc_status csr_alloc(size_t n, size_t total, size_t **start, size_t **items) {
  *start = hoc_calloc(n + 1, sizeof **start);
  *items = hoc_calloc(total + 1, sizeof **items);
  HOC_CHECK(*start && *items, HOC_ERR_MEMORY, "out of memory for the optimiser's adjacency");
  return HOC_OK;
}

static void csr_finish_counts(size_t n, size_t *start) {
  for (size_t i = 0; i < n; ++i) start[i + 1] += start[i];
}

static void csr_restore(size_t n, size_t *start) {
  for (size_t i = n; i > 0; --i) start[i] = start[i - 1];
  start[0] = 0;
}

static double dist3(const double *a, const double *b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
              (a[2] - b[2]) * (a[2] - b[2]));
}

static void cross(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

/* Unit normal of face f at uv from its derivatives, oriented like the mesh;
 * where the parametrisation is singular, from just inside the face. */
static hoc_status face_normal(const opt *o, int f, const double *uv, const double *du,
                              const double *dv, double *n) {
  double c[3], a[3], b[3];
  cross(du, dv, c);
  double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  double scale = du[0] * du[0] + du[1] * du[1] + du[2] * du[2] + dv[0] * dv[0] +
                 dv[1] * dv[1] + dv[2] * dv[2];
  if (!(len > 1e-10 * scale)) {
    const hoc_cad_face *face = &o->model->faces[f];
    double p[2];
    for (int d = 0; d < 2; ++d) {
      double mid = 0.5 * (face->lo[d] + face->hi[d]);
      p[d] = uv[d] + 1e-5 * (face->hi[d] - face->lo[d]) * (mid > uv[d] ? 1.0 : -1.0);
    }
    HOC_TRY(hoc_cad_face_eval(o->model, f, 1, p, NULL, a, b));
    cross(a, b, c);
    len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  }
  double s = (o->m->face_orient[f] < 0 ? -1.0 : 1.0) / (len > 0 ? len : 1.0);
  for (int k = 0; k < 3; ++k) n[k] = s * c[k];
  return HOC_OK;
}

/* Setup ------------------------------------------------------------------- */

static hoc_status build_carry(opt *o);

static hoc_status setup(opt *o, hoc_mesh *m, hoc_measure measure, int fix_curves) {
  memset(o, 0, sizeof *o);
  o->m = m;
  o->model = m->model;
  o->measure = measure;
  HOC_TRY(hoc_quality_tables_get(m->order, m->nodeset, &o->t));
  o->np = o->t->np;
  o->nq = o->t->nq;
  size_t nn = m->n_nodes, ne = m->n_elems, np = (size_t)o->np;
  HOC_ALLOC(o->ndof, nn);
  HOC_ALLOC(o->ne_local, ne * np + 1);
  HOC_TRY(csr_alloc(nn, ne * np, &o->ne_start, &o->ne_elem));
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < np; ++k) o->ne_start[m->conn[e * np + k] + 1]++;
  csr_finish_counts(nn, o->ne_start);
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < np; ++k) {
      size_t i = m->conn[e * np + k], pos = o->ne_start[i]++;
      o->ne_elem[pos] = e;
      o->ne_local[pos] = (int)k;
    }
  csr_restore(nn, o->ne_start);
  HOC_TRY(csr_alloc(nn, m->n_slots, &o->ns_start, &o->ns_slot));
  for (size_t s = 0; s < m->n_slots; ++s) o->ns_start[m->slot_node[s] + 1]++;
  csr_finish_counts(nn, o->ns_start);
  for (size_t s = 0; s < m->n_slots; ++s) o->ns_slot[o->ns_start[m->slot_node[s]]++] = s;
  csr_restore(nn, o->ns_start);
  size_t lp = (size_t)m->order + 1;
  HOC_TRY(csr_alloc(nn, m->n_lines * lp, &o->nl_start, &o->nl_line));
  for (size_t l = 0; l < m->n_lines; ++l)
    for (size_t k = 0; k < lp; ++k) o->nl_start[m->line_conn[l * lp + k] + 1]++;
  csr_finish_counts(nn, o->nl_start);
  for (size_t l = 0; l < m->n_lines; ++l)
    for (size_t k = 0; k < lp; ++k) o->nl_line[o->nl_start[m->line_conn[l * lp + k]]++] = l;
  csr_restore(nn, o->nl_start);
  for (size_t i = 0; i < nn; ++i) {
    if (o->ne_start[i + 1] == o->ne_start[i]) continue; /* used by no element */
    if (m->dim[i] == HOC_ON_FACE) o->ndof[i] = 2;
    else if (m->dim[i] == HOC_ON_CURVE && !fix_curves && !m->model->curves[m->entity[i]].degenerate)
      o->ndof[i] = 1;
    size_t star = o->ne_start[i + 1] - o->ne_start[i];
    if (star > o->max_star) o->max_star = star;
  }
  HOC_ALLOC(o->dz, 6 * nn);
  HOC_ALLOC(o->normal, 3 * m->n_slots + 3);
  HOC_ALLOC(o->delta, ne);
  HOC_ALLOC(o->valid, ne);
  HOC_ALLOC(o->pvalid, ne);
  HOC_ALLOC(o->region, ne);
  HOC_ALLOC(o->hsize, nn);
  HOC_ALLOC(o->active, nn);
  HOC_ALLOC(o->fnew, nn);
  HOC_ALLOC(o->moving, nn);
  HOC_ALLOC(o->step, 2 * nn);
  HOC_ALLOC(o->alpha, nn);
  HOC_ALLOC(o->f0, nn);
  HOC_ALLOC(o->slope, nn);
  HOC_ALLOC(o->tpar, 2 * nn);
  HOC_ALLOC(o->txyz, 3 * nn);
  HOC_ALLOC(o->tdz, 6 * nn);
  HOC_ALLOC(o->tslot_uv, 2 * m->n_slots + 2);
  HOC_ALLOC(o->tnormal, 3 * m->n_slots + 3);
  HOC_ALLOC(o->state, nn);
  HOC_ALLOC(o->list, nn);
  /* local length: the longest edge of the linear sub-triangles around */
  for (size_t i = 0; i < nn; ++i) o->hsize[i] = 0;
  for (size_t e = 0; e < ne; ++e) {
    const size_t *cn = m->conn + e * np;
    double h = 0;
    for (int k = 0; k < 3; ++k) h = fmax(h, dist3(m->xyz + 3 * cn[k], m->xyz + 3 * cn[(k + 1) % 3]));
    for (size_t k = 0; k < np; ++k) o->hsize[cn[k]] = fmax(o->hsize[cn[k]], h);
  }
  /* greedy colouring of the free nodes: neighbours share an element */
  int *color = hoc_calloc(nn, sizeof *color);
  size_t *stamp = NULL, *count = NULL;
  int max_colors = 0;
  hoc_status status = HOC_OK;
  if (!color) return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  size_t cap = 64;
  stamp = hoc_calloc(cap, sizeof *stamp);
  if (!stamp) {
    free(color);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  for (size_t i = 0; i < nn; ++i) color[i] = -1;
  for (size_t i = 0; i < nn; ++i) {
    if (!o->ndof[i]) continue;
    for (size_t a = o->ne_start[i]; a < o->ne_start[i + 1]; ++a) {
      const size_t *cn = m->conn + o->ne_elem[a] * np;
      for (size_t k = 0; k < np; ++k) {
        int c = color[cn[k]];
        if (c >= 0) stamp[c] = i + 1;
      }
    }
    int c = 0;
    while ((size_t)c < cap && stamp[c] == i + 1) ++c;
    if ((size_t)c >= cap) {
      size_t *s2 = hoc_realloc(stamp, 2 * cap, sizeof *s2);
      if (!s2) {
        status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
        goto done;
      }
      stamp = s2;
      memset(stamp + cap, 0, cap * sizeof *stamp);
      cap *= 2;
    }
    color[i] = c;
    if (c + 1 > max_colors) max_colors = c + 1;
  }
  o->n_colors = max_colors;
  count = hoc_calloc((size_t)max_colors + 1, sizeof *count);
  if (!count) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  HOC_TRY_GOTO(csr_alloc((size_t)max_colors, nn, &o->color_start, &o->color_node), done);
  for (size_t i = 0; i < nn; ++i)
    if (color[i] >= 0) o->color_start[color[i] + 1]++;
  csr_finish_counts((size_t)max_colors, o->color_start);
  for (size_t i = 0; i < nn; ++i)
    if (color[i] >= 0) o->color_node[o->color_start[color[i]]++] = i;
  csr_restore((size_t)max_colors, o->color_start);
  HOC_TRY_GOTO(build_carry(o), done);
done:
  free(color);
  free(stamp);
  free(count);
  return status;
}

/* Carried moves: a free face-interior vertex of the linear mesh (a node at
 * a corner of every element around it) moves with the free high-order
 * nodes of its star, each displaced in (u,v) by the vertex's barycentric
 * weight at its reference position. Those nodes lie only in the star, so
 * vertices of one colour carry disjoint sets. */
static hoc_status build_carry(opt *o) {
  hoc_mesh *m = o->m;
  size_t nn = m->n_nodes, np = (size_t)o->np;
  HOC_ALLOC(o->carry_start, nn + 1);
  if (m->order < 2) return HOC_OK;
  size_t total = 0;
  for (size_t k = 0; k < nn; ++k) {
    if (o->ndof[k] != 2) continue;
    int corner = 1;
    for (size_t a = o->ne_start[k]; a < o->ne_start[k + 1]; ++a) corner &= o->ne_local[a] < 3;
    if (!corner) continue;
    /* an upper bound: every high-order node of every element of the star */
    total += (o->ne_start[k + 1] - o->ne_start[k]) * (np - 3);
  }
  HOC_ALLOC(o->carry_node, total + 1);
  HOC_ALLOC(o->carry_w, total + 1);
  size_t n = 0;
  for (size_t k = 0; k < nn; ++k) {
    o->carry_start[k] = n;
    if (o->ndof[k] != 2) continue;
    int corner = 1;
    for (size_t a = o->ne_start[k]; a < o->ne_start[k + 1]; ++a) corner &= o->ne_local[a] < 3;
    if (!corner) continue;
    size_t first = n;
    for (size_t a = o->ne_start[k]; a < o->ne_start[k + 1]; ++a) {
      size_t e = o->ne_elem[a];
      int kk = o->ne_local[a];
      for (size_t i = 3; i < np; ++i) {
        size_t node = m->conn[e * np + i];
        if (o->ndof[node] != 2 || m->entity[node] != m->entity[k]) continue;
        double r = o->t->rs[2 * i], t = o->t->rs[2 * i + 1];
        double lam = kk == 0 ? 1 - r - t : kk == 1 ? r : t;
        if (!(lam > 1e-12)) continue;
        int seen = 0;
        for (size_t j = first; j < n && !seen; ++j) seen = o->carry_node[j] == node;
        if (seen) continue;
        o->carry_node[n] = node;
        o->carry_w[n] = lam;
        ++n;
      }
    }
  }
  o->carry_start[nn] = n;
  return HOC_OK;
}

/* Derivatives dx/dz of every free node and the normals of every slot. */
static hoc_status eval_all(opt *o) {
  hoc_mesh *m = o->m;
  HOC_TRY(hoc_mesh_slot_normals(m, o->normal));
  /* face nodes grouped per face, curve nodes per curve */
  size_t nn = m->n_nodes;
  int nf = o->model->n_faces, nc = o->model->n_curves;
  size_t *start = hoc_calloc((size_t)(nf + nc) + 1, sizeof *start);
  size_t *order = hoc_calloc(nn + 1, sizeof *order);
  double *par = hoc_calloc(2 * nn + 2, sizeof *par), *a = hoc_calloc(3 * nn + 3, sizeof *a),
         *b = hoc_calloc(3 * nn + 3, sizeof *b);
  hoc_status status = HOC_OK;
  if (!start || !order || !par || !a || !b) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (size_t i = 0; i < nn; ++i) {
    if (!o->ndof[i]) continue;
    int g = m->dim[i] == HOC_ON_FACE ? m->entity[i] : nf + m->entity[i];
    start[g + 1]++;
  }
  csr_finish_counts((size_t)(nf + nc), start);
  for (size_t i = 0; i < nn; ++i) {
    if (!o->ndof[i]) continue;
    int g = m->dim[i] == HOC_ON_FACE ? m->entity[i] : nf + m->entity[i];
    order[start[g]++] = i;
  }
  csr_restore((size_t)(nf + nc), start);
  for (int g = 0; g < nf + nc; ++g) {
    size_t n = start[g + 1] - start[g];
    if (!n) continue;
    const size_t *nodes = order + start[g];
    if (g < nf) {
      for (size_t k = 0; k < n; ++k) memcpy(par + 2 * k, m->param + 2 * nodes[k], 2 * sizeof *par);
      HOC_TRY_GOTO(hoc_cad_face_eval(o->model, g, n, par, NULL, a, b), done);
    } else {
      for (size_t k = 0; k < n; ++k) par[k] = m->param[2 * nodes[k]];
      HOC_TRY_GOTO(hoc_cad_curve_eval(o->model, g - nf, n, par, NULL, a), done);
      memset(b, 0, 3 * n * sizeof *b);
    }
    for (size_t k = 0; k < n; ++k) {
      memcpy(o->dz + 6 * nodes[k], a + 3 * k, 3 * sizeof *a);
      memcpy(o->dz + 6 * nodes[k] + 3, b + 3 * k, 3 * sizeof *b);
    }
  }
done:
  free(start);
  free(order);
  free(par);
  free(a);
  free(b);
  return status;
}

/* Element data ------------------------------------------------------------ */

/* Positions and normals of element e's nodes: the trial state of nodes
 * flagged `moving`, else the current one. */
static void gather(const opt *o, size_t e, double *x, double *n) {
  const hoc_mesh *m = o->m;
  size_t np = (size_t)o->np;
  const size_t *cn = m->conn + e * np, *sl = m->elem_slot + e * np;
  for (size_t i = 0; i < np; ++i) {
    int mv = o->moving[cn[i]];
    memcpy(x + 3 * i, (mv ? o->txyz : m->xyz) + 3 * cn[i], 3 * sizeof *x);
    memcpy(n + 3 * i, (mv ? o->tnormal : o->normal) + 3 * sl[i], 3 * sizeof *n);
  }
}

static void trial_elem_uv(const opt *o, size_t k, size_t e, int kk, double *uv);

/* Element not folded in the (u,v) plane: orient * det(D u(xi)) > 0 at its
 * nodes (trial state of `moving` nodes). uv: [np][2] scratch. */
static int param_valid(const opt *o, size_t e, double *uv) {
  const hoc_mesh *m = o->m;
  int np = o->np;
  const size_t *cn = m->conn + e * (size_t)np;
  memcpy(uv, m->elem_uv + 2 * e * (size_t)np, 2 * (size_t)np * sizeof *uv);
  for (int i = 0; i < np; ++i)
    if (o->moving[cn[i]]) trial_elem_uv(o, cn[i], e, i, uv + 2 * i);
  double sign = m->face_orient[m->elem_face[e]] < 0 ? -1.0 : 1.0;
  for (int j = 0; j < np; ++j) {
    const double *g = o->t->Gn + 2 * (size_t)j * np;
    double a = 0, b = 0, c = 0, d = 0;
    for (int i = 0; i < np; ++i) {
      a += uv[2 * i] * g[2 * i];
      b += uv[2 * i] * g[2 * i + 1];
      c += uv[2 * i + 1] * g[2 * i];
      d += uv[2 * i + 1] * g[2 * i + 1];
    }
    if (!(sign * (a * d - b * c) > 0)) return 0;
  }
  return 1;
}

/* Smallest sigma and the size scale mean(|D phi|^2 / 2) of an element. */
static void sigma_stats(const opt *o, const double *x, const double *n, double *smin,
                        double *scale) {
  const hoc_quality_tables *t = o->t;
  int np = t->np;
  double mn = INFINITY, sum = 0;
  for (int q = 0; q < t->nq + np; ++q) {
    const double *G = q < t->nq ? t->G + 2 * (size_t)q * np : t->Gn + 2 * (size_t)(q - t->nq) * np;
    double a1[3] = {0, 0, 0}, a2[3] = {0, 0, 0}, nq[3] = {0, 0, 0}, c[3];
    for (int i = 0; i < np; ++i)
      for (int k = 0; k < 3; ++k) {
        a1[k] += G[2 * i] * x[3 * i + k];
        a2[k] += G[2 * i + 1] * x[3 * i + k];
      }
    if (q < t->nq) {
      for (int i = 0; i < np; ++i)
        for (int k = 0; k < 3; ++k) nq[k] += t->N[(size_t)q * np + i] * n[3 * i + k];
    } else {
      memcpy(nq, n + 3 * (q - t->nq), sizeof nq);
    }
    cross(a1, a2, c);
    double cl = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    double sig = c[0] * nq[0] + c[1] * nq[1] + c[2] * nq[2] > 0 ? cl : -cl;
    mn = fmin(mn, sig);
    if (q < t->nq)
      sum += t->w[q] * 0.5 * (a1[0] * a1[0] + a1[1] * a1[1] + a1[2] * a1[2] + a2[0] * a2[0] +
                              a2[1] * a2[1] + a2[2] * a2[2]);
  }
  *smin = mn;
  *scale = sum;
}

/* Per-element state at the start of a sweep: validity, parametric
 * validity, regularisation; also f, q and the tangled count. */
static hoc_status sweep_start(opt *o, double *objective, double *min_q, size_t *tangled) {
  hoc_mesh *m = o->m;
  size_t ne = m->n_elems;
  int np = o->np, nq = o->nq;
  double *fe = hoc_calloc(ne, sizeof *fe), *qe = hoc_calloc(ne, sizeof *qe);
  if (!fe || !qe) {
    free(fe);
    free(qe);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  int failed = 0;
#pragma omp parallel
  {
    double *x = malloc((6 * (size_t)np + (size_t)nq + 2 * (size_t)np) * sizeof *x);
    if (!x) {
#pragma omp atomic write
      failed = 1;
    }
    double *n = x ? x + 3 * np : NULL, *r = x ? x + 6 * np : NULL, *uv = x ? r + nq : NULL;
#pragma omp for schedule(static)
    for (size_t e = 0; e < ne; ++e) {
      if (!x) continue;
      gather(o, e, x, n);
      double eta;
      qe[e] = hoc_element_quality(o->t, o->measure, x, n, &eta, NULL);
      o->valid[e] = qe[e] > 0;
      o->pvalid[e] = (unsigned char)param_valid(o, e, uv);
      o->delta[e] = 0;
      if (!o->valid[e]) {
        double smin, scale;
        sigma_stats(o, x, n, &smin, &scale);
        double eps = (getenv("HOC_EPS") ? atof(getenv("HOC_EPS")) : 1e-3) * scale;
        o->delta[e] = smin < eps ? sqrt(eps * (eps - smin)) : 0;
        if (!(o->delta[e] > 0)) o->delta[e] = eps;
      }
      hoc_element_residuals(o->t, o->measure, x, n, o->delta[e], r, NULL);
      double f = 0;
      for (int q = 0; q < nq; ++q) f += r[q] * r[q];
      fe[e] = f;
    }
    free(x);
  }
  /* the tangled region: tangled elements and those sharing a node with one
   * take the largest regularisation around them (Escobar et al. regularise
   * the whole mesh with one delta; this keeps the rest of it exact) */
  memset(o->region, 0, ne);
  for (size_t e = 0; e < ne && !failed; ++e) {
    if (o->valid[e]) continue;
    for (int i = 0; i < np; ++i) {
      size_t node = m->conn[e * (size_t)np + (size_t)i];
      for (size_t a = o->ne_start[node]; a < o->ne_start[node + 1]; ++a) {
        size_t e2 = o->ne_elem[a];
        o->region[e2] = 1;
        if (o->delta[e2] < o->delta[e]) o->delta[e2] = o->delta[e];
      }
    }
  }
#pragma omp parallel
  {
    double *x = malloc((6 * (size_t)np + (size_t)nq) * sizeof *x);
    if (!x) {
#pragma omp atomic write
      failed = 1;
    }
    double *n = x ? x + 3 * np : NULL, *r = x ? x + 6 * np : NULL;
#pragma omp for schedule(static)
    for (size_t e = 0; e < ne; ++e) {
      if (!x || !o->region[e] || !o->valid[e]) continue;
      gather(o, e, x, n);
      hoc_element_residuals(o->t, o->measure, x, n, o->delta[e], r, NULL);
      double f = 0;
      for (int q = 0; q < nq; ++q) f += r[q] * r[q];
      fe[e] = f;
    }
    free(x);
  }
  if (failed) {
    free(fe);
    free(qe);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  double f = 0, qmin = INFINITY;
  size_t nt = 0;
  for (size_t e = 0; e < ne; ++e) {
    f += fe[e];
    qmin = fmin(qmin, qe[e]);
    nt += qe[e] == 0.0;
  }
  free(fe);
  free(qe);
  *objective = f;
  *min_q = ne ? qmin : 0;
  *tangled = nt;
  return HOC_OK;
}

/* Local objective of node k at the current state: f, gradient g and
 * Gauss-Newton matrix H (packed h00 h01 h11) in its parameters. */
static double carry_weight(const opt *o, size_t k, size_t node) {
  for (size_t j = o->carry_start[k]; j < o->carry_start[k + 1]; ++j)
    if (o->carry_node[j] == node) return o->carry_w[j];
  return 0;
}

/* Residual derivatives of element e with respect to node k's parameters
 * when k moves with its carried nodes: Jz[q][2]. */
static void carried_jacobian(const opt *o, size_t k, size_t e, scratch *s, double *Jz) {
  const hoc_mesh *m = o->m;
  int np = o->np, nq = o->nq;
  const size_t *cn = m->conn + e * (size_t)np;
  hoc_element_residuals(o->t, o->measure, s->x, s->n, o->delta[e], s->r, s->J);
  for (int q = 0; q < nq; ++q) Jz[2 * q] = Jz[2 * q + 1] = 0;
  for (int i = 0; i < np; ++i) {
    double w = cn[i] == k ? 1.0 : carry_weight(o, k, cn[i]);
    if (w == 0) continue;
    const double *dz = o->dz + 6 * cn[i];
    for (int q = 0; q < nq; ++q) {
      const double *j = s->J + 3 * ((size_t)q * np + (size_t)i);
      Jz[2 * q] += w * (j[0] * dz[0] + j[1] * dz[1] + j[2] * dz[2]);
      Jz[2 * q + 1] += w * (j[0] * dz[3] + j[1] * dz[4] + j[2] * dz[5]);
    }
  }
}

static void local_model(const opt *o, size_t k, scratch *s, double *f, double g[2], double H[3]) {
  int nd = o->ndof[k], nq = o->nq;
  const double *dz = o->dz + 6 * k;
  int carried = o->carry_start[k + 1] > o->carry_start[k];
  *f = 0;
  g[0] = g[1] = H[0] = H[1] = H[2] = 0;
  for (size_t a = o->ne_start[k]; a < o->ne_start[k + 1]; ++a) {
    size_t e = o->ne_elem[a];
    int kk = o->ne_local[a];
    gather(o, e, s->x, s->n);
    if (carried) {
      double *Jz = s->J + 3 * (size_t)nq * (size_t)o->np; /* after the full Jacobian */
      carried_jacobian(o, k, e, s, Jz);
      for (int q = 0; q < nq; ++q) {
        double r = s->r[q], z0 = Jz[2 * q], z1 = Jz[2 * q + 1];
        *f += r * r;
        g[0] += 2 * r * z0;
        g[1] += 2 * r * z1;
        H[0] += 2 * z0 * z0;
        H[1] += 2 * z0 * z1;
        H[2] += 2 * z1 * z1;
      }
      continue;
    }
    hoc_element_residuals_node(o->t, o->measure, s->x, s->n, o->delta[e], kk, s->r, s->J);
    for (int q = 0; q < nq; ++q) {
      const double *j = s->J + 3 * q;
      double r = s->r[q];
      double z0 = j[0] * dz[0] + j[1] * dz[1] + j[2] * dz[2];
      double z1 = nd > 1 ? j[0] * dz[3] + j[1] * dz[4] + j[2] * dz[5] : 0;
      *f += r * r;
      g[0] += 2 * r * z0;
      g[1] += 2 * r * z1;
      H[0] += 2 * z0 * z0;
      H[1] += 2 * z0 * z1;
      H[2] += 2 * z1 * z1;
    }
  }
}

/* Parameters of node k's slot s for the trial: (u,v) of the slot, unwrapped
 * near the element's current value. */
static void trial_elem_uv(const opt *o, size_t k, size_t e, int kk, double *uv) {
  const hoc_mesh *m = o->m;
  const double *cur = m->elem_uv + 2 * (e * (size_t)o->np + (size_t)kk);
  if (m->dim[k] == HOC_ON_FACE) {
    /* the same displacement as the node's parameters */
    uv[0] = cur[0] + (o->tpar[2 * k] - m->param[2 * k]);
    uv[1] = cur[1] + (o->tpar[2 * k + 1] - m->param[2 * k + 1]);
    return;
  }
  size_t s = m->elem_slot[e * (size_t)o->np + (size_t)kk];
  uv[0] = o->tslot_uv[2 * s];
  uv[1] = o->tslot_uv[2 * s + 1];
  hoc_cad_face_unwrap_near(&o->model->faces[m->elem_face[e]], cur, uv);
}

/* Curve parameters of line l's nodes in order along the line, unwrapped
 * from its first end; node k at tk. Returns 1 if strictly monotone in the
 * line's direction. */
static int line_monotone(const opt *o, size_t l, size_t k, double tk) {
  const hoc_mesh *m = o->m;
  int p = m->order;
  const size_t *ln = m->line_conn + l * (size_t)(p + 1);
  const hoc_cad_curve *c = &o->model->curves[m->line_curve[l]];
  double ta = m->line_t[2 * l], tb = m->line_t[2 * l + 1], dir = tb > ta ? 1.0 : -1.0;
  double prev = NAN;
  for (int j = 0; j <= p; ++j) {
    int idx = j == 0 ? 0 : j == p ? 1 : j + 1;
    size_t i = ln[idx];
    double t;
    if (i == k) t = tk;
    else if (m->dim[i] == HOC_ON_CURVE) t = m->param[2 * i];
    else t = j == 0 ? ta : tb;
    if (i != k && m->dim[i] != HOC_ON_CURVE) {
      /* a vertex end: its parameter is the line's */
    } else if (c->period > 0) {
      double guess = ta + (tb - ta) * j / p;
      t -= c->period * floor((t - guess) / c->period + 0.5);
    }
    if (j > 0 && !(dir * (t - prev) > 0)) return 0;
    prev = t;
  }
  return 1;
}

/* Local objective at the trial; 0 if the trial breaks a rule. */
static void set_moving(opt *o, size_t k, unsigned char v) {
  o->moving[k] = v;
  for (size_t j = o->carry_start[k]; j < o->carry_start[k + 1]; ++j) o->moving[o->carry_node[j]] = v;
}

/* Local objective at the trial of node k (and the nodes it carries); 0 if
 * the trial breaks a rule. */
static int local_trial_flagged(const opt *o, size_t k, scratch *s, double *f) {
  const hoc_mesh *m = o->m;
  int nq = o->nq;
  *f = 0;
  if (m->dim[k] == HOC_ON_CURVE)
    for (size_t a = o->nl_start[k]; a < o->nl_start[k + 1]; ++a)
      if (!line_monotone(o, o->nl_line[a], k, o->tpar[2 * k])) return 0;
  for (size_t a = o->ne_start[k]; a < o->ne_start[k + 1]; ++a) {
    size_t e = o->ne_elem[a];
    gather(o, e, s->x, s->n);
    if (o->pvalid[e] && !param_valid(o, e, s->uv)) return 0;
    double smin = hoc_element_residuals(o->t, o->measure, s->x, s->n, o->delta[e], s->r, NULL);
    if (o->valid[e] && !o->region[e] &&
        (!(smin > 0) || hoc_element_nodes_tangled(o->t, s->x, s->n)))
      return 0;
    for (int q = 0; q < nq; ++q) *f += s->r[q] * s->r[q];
  }
  return isfinite(*f);
}

static int local_trial(opt *o, size_t k, scratch *s, double *f) {
  set_moving(o, k, 1);
  int ok = local_trial_flagged(o, k, s, f);
  set_moving(o, k, 0);
  return ok;
}

/* CAD evaluation of the trial parameters of the nodes in list[0..n). */
static hoc_status eval_trials(opt *o, const size_t *list, size_t n) {
  hoc_mesh *m = o->m;
  const hoc_model *model = o->model;
  for (size_t a = 0; a < n;) {
    /* runs of nodes on one entity (the list is sorted by entity) */
    size_t k = list[a], b = a;
    while (b < n && m->dim[list[b]] == m->dim[k] && m->entity[list[b]] == m->entity[k]) ++b;
    int ent = m->entity[k];
    for (size_t c = a; c < b; ++c) {
      size_t i = list[c];
      if (m->dim[i] == HOC_ON_FACE) {
        HOC_TRY(hoc_cad_face_eval(model, ent, 1, o->tpar + 2 * i, o->txyz + 3 * i, o->tdz + 6 * i,
                                  o->tdz + 6 * i + 3));
        size_t s = o->ns_slot[o->ns_start[i]];
        o->tslot_uv[2 * s] = o->tpar[2 * i];
        o->tslot_uv[2 * s + 1] = o->tpar[2 * i + 1];
        HOC_TRY(face_normal(o, ent, o->tpar + 2 * i, o->tdz + 6 * i, o->tdz + 6 * i + 3,
                            o->tnormal + 3 * s));
      } else {
        HOC_TRY(hoc_cad_curve_eval(model, ent, 1, o->tpar + 2 * i, o->txyz + 3 * i, o->tdz + 6 * i));
        o->tdz[6 * i + 3] = o->tdz[6 * i + 4] = o->tdz[6 * i + 5] = 0;
        for (size_t j = o->ns_start[i]; j < o->ns_start[i + 1]; ++j) {
          size_t s = o->ns_slot[j];
          int f = m->slot_face[s];
          double uv[2], du[3], dv[3];
          HOC_TRY(hoc_cad_curve_to_face(model, ent, f, 1, o->tpar + 2 * i, uv));
          hoc_cad_face_unwrap_near(&model->faces[f], m->slot_uv + 2 * s, uv);
          HOC_TRY(hoc_cad_face_eval(model, f, 1, uv, NULL, du, dv));
          o->tslot_uv[2 * s] = uv[0];
          o->tslot_uv[2 * s + 1] = uv[1];
          HOC_TRY(face_normal(o, f, uv, du, dv, o->tnormal + 3 * s));
        }
      }
    }
    a = b;
  }
  return HOC_OK;
}

/* Accept node k's trial. */
static void commit(opt *o, size_t k) {
  hoc_mesh *m = o->m;
  int np = o->np;
  for (size_t a = o->ne_start[k]; a < o->ne_start[k + 1]; ++a) {
    size_t e = o->ne_elem[a];
    int kk = o->ne_local[a];
    double uv[2];
    trial_elem_uv(o, k, e, kk, uv);
    memcpy(m->elem_uv + 2 * (e * (size_t)np + (size_t)kk), uv, sizeof uv);
  }
  if (m->dim[k] == HOC_ON_CURVE) {
    const hoc_cad_curve *c = &o->model->curves[m->entity[k]];
    for (size_t a = o->nl_start[k]; a < o->nl_start[k + 1]; ++a) {
      size_t l = o->nl_line[a];
      const size_t *ln = m->line_conn + l * (size_t)(m->order + 1);
      for (int end = 0; end < 2; ++end) {
        if (ln[end] != k) continue;
        double t = o->tpar[2 * k], old = m->line_t[2 * l + end];
        if (c->period > 0) t -= c->period * floor((t - old) / c->period + 0.5);
        m->line_t[2 * l + end] = t;
      }
    }
  }
  for (size_t j = o->ns_start[k]; j < o->ns_start[k + 1]; ++j) {
    size_t s = o->ns_slot[j];
    memcpy(m->slot_uv + 2 * s, o->tslot_uv + 2 * s, 2 * sizeof(double));
    memcpy(o->normal + 3 * s, o->tnormal + 3 * s, 3 * sizeof(double));
  }
  double p[2] = {o->tpar[2 * k], o->tpar[2 * k + 1]};
  if (m->dim[k] == HOC_ON_FACE) {
    hoc_cad_face_wrap(&o->model->faces[m->entity[k]], p);
    /* the slot keeps the wrapped value too (elements hold unwrapped copies) */
    size_t s = o->ns_slot[o->ns_start[k]];
    memcpy(m->slot_uv + 2 * s, p, sizeof p);
  } else {
    const hoc_cad_curve *c = &o->model->curves[m->entity[k]];
    if (c->period > 0) p[0] -= c->period * floor((p[0] - c->lo) / c->period);
  }
  m->param[2 * k] = p[0];
  m->param[2 * k + 1] = p[1];
  memcpy(m->xyz + 3 * k, o->txyz + 3 * k, 3 * sizeof(double));
  memcpy(o->dz + 6 * k, o->tdz + 6 * k, 6 * sizeof(double));
}

/* Sorting the trial list by (dim, entity) with a global context: qsort has
 * none in C11, so a small insertion-friendly merge sort instead. */
static void sort_by_entity(const hoc_mesh *m, size_t *list, size_t n, size_t *tmp) {
  for (size_t w = 1; w < n; w *= 2) {
    for (size_t lo = 0; lo < n; lo += 2 * w) {
      size_t mid = lo + w < n ? lo + w : n, hi = lo + 2 * w < n ? lo + 2 * w : n;
      size_t a = lo, b = mid, out = lo;
      while (a < mid || b < hi) {
        int take_a = b >= hi;
        if (!take_a && a < mid) {
          long ka = (long)m->dim[list[a]] * 1000000000L + m->entity[list[a]];
          long kb = (long)m->dim[list[b]] * 1000000000L + m->entity[list[b]];
          take_a = ka <= kb;
        }
        tmp[out++] = take_a ? list[a++] : list[b++];
      }
    }
    memcpy(list, tmp, n * sizeof *list);
  }
}

/* Node k touches an element that is (or was at the sweep's start) tangled. */
static int near_tangled(const opt *o, size_t k) {
  for (size_t a = o->ne_start[k]; a < o->ne_start[k + 1]; ++a)
    if (o->region[o->ne_elem[a]] || !o->valid[o->ne_elem[a]]) return 1;
  return 0;
}

/* One colour: a Gauss-Newton step per active node, then a common
 * backtracking line search. Returns the number of nodes moved. */
static hoc_status do_color(opt *o, int color, scratch *scr, int nthreads, size_t *moved) {
  hoc_mesh *m = o->m;
  size_t first = o->color_start[color], last = o->color_start[color + 1];
  size_t n = 0;
  for (size_t a = first; a < last; ++a) {
    size_t k = o->color_node[a];
    if (o->active[k]) o->list[n++] = k;
  }
  *moved = 0;
  if (!n) return HOC_OK;
  size_t *list = o->list;
#pragma omp parallel for schedule(dynamic, 16) num_threads(nthreads)
  for (size_t a = 0; a < n; ++a) {
    size_t k = list[a];
    scratch *s = &scr[omp_get_thread_num()];
    o->active[k] = 0;
    double f, g[2], H[3];
    local_model(o, k, s, &f, g, H);
    o->f0[k] = f;
    o->state[k] = 0;
    double step[2] = {0, 0};
    if (o->ndof[k] == 2) {
      double tr = H[0] + H[2], mu = 1e-10 * tr + 1e-300;
      double a00 = H[0] + mu, a11 = H[2] + mu, det = a00 * a11 - H[1] * H[1];
      if (det > 0) {
        step[0] = -(a11 * g[0] - H[1] * g[1]) / det;
        step[1] = -(a00 * g[1] - H[1] * g[0]) / det;
      }
    } else if (H[0] > 0) {
      step[0] = -g[0] / (H[0] * (1 + 1e-10));
    }
    double slope = g[0] * step[0] + g[1] * step[1];
    /* limit the displacement to a fraction of the local element size */
    const double *dz = o->dz + 6 * k;
    double dx[3];
    for (int c = 0; c < 3; ++c) dx[c] = dz[c] * step[0] + dz[3 + c] * step[1];
    double len = sqrt(dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2]);
    double alpha = 1;
    if (len > 0.25 * o->hsize[k]) alpha = 0.25 * o->hsize[k] / len;
    if (!(slope < 0) || !(len * alpha > 1e-12 * o->hsize[k]) || !isfinite(slope)) continue;
    o->step[2 * k] = step[0];
    o->step[2 * k + 1] = step[1];
    o->slope[k] = slope;
    o->alpha[k] = alpha;
    o->state[k] = 1;
  }
  /* compact to the nodes trying a step; keep them sorted by entity for the
   * batched CAD calls */
  size_t nt = 0;
  for (size_t a = 0; a < n; ++a)
    if (o->state[list[a]] == 1) list[nt++] = list[a];
  size_t n_eval = 0;
  for (size_t a = 0; a < nt; ++a) n_eval += 1 + o->carry_start[list[a] + 1] - o->carry_start[list[a]];
  size_t *tmp = hoc_calloc(nt + 1, sizeof *tmp), *elist = hoc_calloc(n_eval + 1, sizeof *elist);
  if (!tmp || !elist) {
    free(tmp);
    free(elist);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  sort_by_entity(m, list, nt, tmp);
  hoc_status status = HOC_OK;
  for (int attempt = 0; attempt < 10 && nt; ++attempt) {
    /* trial parameters; out of a non-closed range: shorten the step first */
    for (size_t a = 0; a < nt; ++a) {
      size_t k = list[a];
      for (int tries = 0; tries < 40; ++tries) {
        double u = m->param[2 * k] + o->alpha[k] * o->step[2 * k];
        double v = m->param[2 * k + 1] + o->alpha[k] * o->step[2 * k + 1];
        int inside = 1;
        if (m->dim[k] == HOC_ON_FACE) {
          const hoc_cad_face *f = &o->model->faces[m->entity[k]];
          if (!(f->period[0] > 0) && (u < f->lo[0] || u > f->hi[0])) inside = 0;
          if (!(f->period[1] > 0) && (v < f->lo[1] || v > f->hi[1])) inside = 0;
        } else {
          const hoc_cad_curve *c = &o->model->curves[m->entity[k]];
          if (!(c->period > 0) && (u < c->lo || u > c->hi)) inside = 0;
          v = 0;
        }
        o->tpar[2 * k] = u;
        o->tpar[2 * k + 1] = v;
        const hoc_cad_face *f = m->dim[k] == HOC_ON_FACE ? &o->model->faces[m->entity[k]] : NULL;
        for (size_t j = o->carry_start[k]; j < o->carry_start[k + 1] && inside; ++j) {
          size_t c = o->carry_node[j];
          double w = o->alpha[k] * o->carry_w[j];
          o->tpar[2 * c] = m->param[2 * c] + w * o->step[2 * k];
          o->tpar[2 * c + 1] = m->param[2 * c + 1] + w * o->step[2 * k + 1];
          for (int d = 0; d < 2; ++d)
            if (!(f->period[d] > 0) && (o->tpar[2 * c + d] < f->lo[d] || o->tpar[2 * c + d] > f->hi[d]))
              inside = 0;
        }
        if (inside) break;
        o->alpha[k] *= 0.5;
      }
    }
    /* the nodes to evaluate: the trying ones and those they carry */
    size_t ne_list = 0;
    for (size_t a = 0; a < nt; ++a) {
      size_t k = list[a];
      elist[ne_list++] = k;
      for (size_t j = o->carry_start[k]; j < o->carry_start[k + 1]; ++j) elist[ne_list++] = o->carry_node[j];
    }
    HOC_TRY_GOTO(eval_trials(o, elist, ne_list), done);
#pragma omp parallel for schedule(dynamic, 16) num_threads(nthreads)
    for (size_t a = 0; a < nt; ++a) {
      size_t k = list[a];
      scratch *s = &scr[omp_get_thread_num()];
      double f;
      int ok = local_trial(o, k, s, &f);
      if (ok && f <= o->f0[k] + 1e-4 * o->alpha[k] * o->slope[k]) {
        commit(o, k);
        for (size_t j = o->carry_start[k]; j < o->carry_start[k + 1]; ++j) commit(o, o->carry_node[j]);
        o->fnew[k] = f;
        o->state[k] = 2;
      } else {
        o->alpha[k] *= 0.5;
      }
    }
    size_t keep = 0;
    for (size_t a = 0; a < nt; ++a) {
      size_t k = list[a];
      if (o->state[k] == 2) {
        ++*moved;
        o->state[k] = 0;
        if (o->f0[k] - o->fnew[k] < o->min_gain && !near_tangled(o, k)) continue;
        /* wake the neighbours (and the node itself) for the next sweep */
        for (size_t b = o->ne_start[k]; b < o->ne_start[k + 1]; ++b) {
          const size_t *cn = m->conn + o->ne_elem[b] * (size_t)o->np;
          for (int i = 0; i < o->np; ++i) o->active[cn[i]] = 1;
        }
      } else {
        list[keep++] = k; /* order by entity is kept */
      }
    }
    nt = keep;
  }
  for (size_t a = 0; a < nt; ++a) o->state[list[a]] = 0; /* gave up: stays inactive */
  /* validity may have been gained */
#pragma omp parallel for schedule(dynamic, 16) num_threads(nthreads)
  for (size_t a = first; a < last; ++a) {
    size_t k = o->color_node[a];
    scratch *s = &scr[omp_get_thread_num()];
    for (size_t b = o->ne_start[k]; b < o->ne_start[k + 1]; ++b) {
      size_t e = o->ne_elem[b];
      if (!o->valid[e]) {
        gather(o, e, s->x, s->n);
        o->valid[e] = (unsigned char)!hoc_element_tangled(o->t, s->x, s->n);
      }
      if (!o->pvalid[e]) o->pvalid[e] = (unsigned char)param_valid(o, e, s->uv);
    }
  }
done:
  free(tmp);
  free(elist);
  return status;
}

static hoc_status scratch_alloc(const opt *o, int nthreads, scratch **out) {
  scratch *s = hoc_calloc((size_t)nthreads, sizeof *s);
  HOC_CHECK(s, HOC_ERR_MEMORY, "out of memory");
  size_t np = (size_t)o->np, nq = (size_t)o->nq;
  for (int i = 0; i < nthreads; ++i) {
    s[i].x = hoc_calloc(3 * np, sizeof(double));
    s[i].n = hoc_calloc(3 * np, sizeof(double));
    s[i].r = hoc_calloc(nq, sizeof(double));
    s[i].J = hoc_calloc(3 * nq * np + 2 * nq, sizeof(double));
    s[i].uv = hoc_calloc(2 * np, sizeof(double));
    if (!s[i].x || !s[i].n || !s[i].r || !s[i].J || !s[i].uv) {
      for (int j = 0; j <= i; ++j) {
        free(s[j].x);
        free(s[j].n);
        free(s[j].r);
        free(s[j].J);
        free(s[j].uv);
      }
      free(s);
      return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    }
  }
  *out = s;
  return HOC_OK;
}

static void scratch_free(scratch *s, int nthreads) {
  if (!s) return;
  for (int i = 0; i < nthreads; ++i) {
    free(s[i].x);
    free(s[i].n);
    free(s[i].r);
    free(s[i].J);
    free(s[i].uv);
  }
  free(s);
}

hoc_status hoc_mesh_optimize(hoc_mesh *mesh, const hoc_optimize_options *options,
                             hoc_optimize_result *result) {
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "no mesh given");
  hoc_optimize_options o;
  hoc_optimize_options_default(&o);
  if (options) o = *options;
  if (o.max_iterations <= 0) o.max_iterations = 100;
  if (!(o.tolerance > 0)) o.tolerance = 0.1;
  HOC_CHECK(o.measure == HOC_MEASURE_SHAPE || o.measure == HOC_MEASURE_ODDY, HOC_ERR_ARGUMENT,
            "unknown distortion measure %d", (int)o.measure);
  HOC_CHECK(o.max_iterations <= 1000000, HOC_ERR_ARGUMENT, "too many iterations requested");
  double t0 = now();
  opt ctx;
  scratch *scr = NULL;
  int nthreads = omp_get_max_threads();
  hoc_status status = setup(&ctx, mesh, o.measure, o.fix_curves);
  if (status == HOC_OK) status = eval_all(&ctx);
  if (status == HOC_OK) status = scratch_alloc(&ctx, nthreads, &scr);
  if (status != HOC_OK) {
    opt_free(&ctx);
    return status;
  }
  hoc_optimize_result res = {0};
  for (size_t i = 0; i < mesh->n_nodes; ++i) {
    ctx.active[i] = ctx.ndof[i] > 0;
    res.free_nodes += ctx.ndof[i] > 0;
  }
  double f, qmin;
  size_t tangled;
  HOC_TRY_GOTO(sweep_start(&ctx, &f, &qmin, &tangled), done);
  res.objective_initial = f;
  res.tangled_initial = tangled;
  for (int it = 1; it <= o.max_iterations; ++it) {
    size_t moved = 0;
    /* nodes of tangled elements never sleep */
    for (size_t e = 0; e < mesh->n_elems; ++e)
      if (ctx.delta[e] > 0)
        for (int i = 0; i < ctx.np; ++i) {
          size_t node = mesh->conn[e * (size_t)ctx.np + (size_t)i];
          if (ctx.ndof[node]) ctx.active[node] = 1;
        }
    /* moves worth a small fraction of the average node's share of f keep
     * their neighbourhood active; the rest of the mesh settles */
    ctx.min_gain = o.tolerance * f / (double)(res.free_nodes ? res.free_nodes : 1);
    for (int c = 0; c < ctx.n_colors; ++c) {
      size_t mc;
      HOC_TRY_GOTO(do_color(&ctx, c, scr, nthreads, &mc), done);
      moved += mc;
    }
    HOC_TRY_GOTO(sweep_start(&ctx, &f, &qmin, &tangled), done);
    res.iterations = it;
    if (o.progress) {
      hoc_optimize_iteration info = {it, f, qmin, tangled, moved, now() - t0};
      if (o.progress(o.progress_user, &info)) {
        status = HOC_ERROR(HOC_ERR_INTERRUPTED, "optimisation interrupted");
        goto done;
      }
    }
    /* converged: no node can lower f by a worthwhile amount any more */
    size_t active = 0;
    for (size_t i = 0; i < mesh->n_nodes; ++i) active += ctx.active[i];
    if (!active || !moved) {
      res.converged = tangled == 0;
      break;
    }
  }
done:
  res.objective_final = f;
  res.tangled_final = tangled;
  res.seconds = now() - t0;
  if (result) *result = res;
  scratch_free(scr, nthreads);
  opt_free(&ctx);
  return status;
}

/* Gradient check -------------------------------------------------------- */



/* Local objective of node k with its position at parameters z (positions
 * evaluated on the CAD; normals kept). */
static hoc_status local_f_at(opt *o, size_t k, const double *z, scratch *s, double *f) {
  hoc_mesh *m = o->m;
  size_t list[1 + 4 * (HOC_MAX_ORDER + 1) * (HOC_MAX_ORDER + 2)], n = 0;
  list[n++] = k;
  o->tpar[2 * k] = z[0];
  o->tpar[2 * k + 1] = m->dim[k] == HOC_ON_FACE ? z[1] : 0;
  for (size_t j = o->carry_start[k]; j < o->carry_start[k + 1]; ++j) {
    size_t c = o->carry_node[j];
    for (int d = 0; d < 2; ++d)
      o->tpar[2 * c + d] = m->param[2 * c + d] + o->carry_w[j] * (z[d] - m->param[2 * k + d]);
    if (n < sizeof list / sizeof *list) list[n++] = c;
  }
  HOC_TRY(eval_trials(o, list, n));
  set_moving(o, k, 1);
  *f = 0;
  for (size_t a = o->ne_start[k]; a < o->ne_start[k + 1]; ++a) {
    size_t e = o->ne_elem[a];
    gather(o, e, s->x, s->n);
    hoc_element_residuals(o->t, o->measure, s->x, s->n, o->delta[e], s->r, NULL);
    for (int q = 0; q < o->nq; ++q) *f += s->r[q] * s->r[q];
  }
  set_moving(o, k, 0);
  return HOC_OK;
}

hoc_status hoc_mesh_check_gradient(hoc_mesh *mesh, hoc_measure measure, int fix_curves,
                                   int samples, double *max_rel_error) {
  HOC_CHECK(mesh && max_rel_error, HOC_ERR_ARGUMENT, "NULL argument");
  HOC_CHECK(samples > 0, HOC_ERR_ARGUMENT, "need at least one sample");
  opt ctx;
  scratch *scr = NULL;
  hoc_status status = setup(&ctx, mesh, measure, fix_curves);
  if (status == HOC_OK) status = eval_all(&ctx);
  if (status == HOC_OK) status = scratch_alloc(&ctx, 1, &scr);
  if (status != HOC_OK) {
    opt_free(&ctx);
    return status;
  }
  double f, qmin;
  size_t tangled;
  HOC_TRY_GOTO(sweep_start(&ctx, &f, &qmin, &tangled), done);
  size_t n_free = 0;
  for (size_t i = 0; i < mesh->n_nodes; ++i) n_free += ctx.ndof[i] > 0;
  size_t stride = n_free > (size_t)samples ? n_free / (size_t)samples : 1;
  double worst = 0, gmax = 0;
  size_t seen = 0;
  for (size_t k = 0; k < mesh->n_nodes; ++k) {
    if (!ctx.ndof[k]) continue;
    if (seen++ % stride) continue;
    double fl, g[2], H[3];
    local_model(&ctx, k, scr, &fl, g, H);
    for (int d = 0; d < ctx.ndof[k]; ++d) {
      /* step: a small fraction of the local size in parameter units */
      const double *dz = ctx.dz + 6 * k + 3 * d;
      double speed = sqrt(dz[0] * dz[0] + dz[1] * dz[1] + dz[2] * dz[2]);
      if (!(speed > 0)) continue;
      double h = 1e-5 * ctx.hsize[k] / speed;
      double zp[2] = {mesh->param[2 * k], mesh->param[2 * k + 1]}, zm[2];
      memcpy(zm, zp, sizeof zm);
      zp[d] += h;
      zm[d] -= h;
      double fp, fm;
      HOC_TRY_GOTO(local_f_at(&ctx, k, zp, scr, &fp), done);
      HOC_TRY_GOTO(local_f_at(&ctx, k, zm, scr, &fm), done);
      double fd = (fp - fm) / (2 * h);
      if (!isfinite(fd)) continue;
      /* in parameter units: scaled by the node's speed to compare nodes */
      worst = fmax(worst, fabs(fd - g[d]) / speed);
      gmax = fmax(gmax, fabs(g[d]) / speed);
    }
  }
  /* a norm-wise relative error, as PETSc's -snes_test_jacobian reports */
  worst = gmax > 0 ? worst / gmax : worst;
  *max_rel_error = worst;
done:
  scratch_free(scr, 1);
  opt_free(&ctx);
  return status;
}
