/* Simultaneous untangling and smoothing in parametric coordinates (the
 * seed's Section 4).
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * Objective: f(z) = sum_e sum_q r_eq^2, r_eq = sqrt(w_q) (eta(x~_q) - 1), the
 * quadrature of sum_e int_{t_I} (eta - 1)^2 (weights normalised per element),
 * with sigma replaced by sigma_delta = (sigma + sqrt(sigma^2 + 4 delta_e^2))/2
 * on tangled elements and their neighbours (Escobar et al.), where the
 * nodes also count as sample points (Definition 2 asks det > 0 there).
 * Unknowns z: (u, v) of face-interior nodes, t of nodes on CAD curves.
 * Positions x(z) = phi(u, v) or c(t) are always CAD evaluations.
 *
 * Solver: nonlinear block Gauss-Seidel. Each sweep visits the natural
 * blocks of the high-order mesh: each vertex of the linear mesh (a
 * face-interior vertex carries the high-order nodes of its star along,
 * displaced in (u,v) by their barycentric weight, so the star moves as a
 * whole), the nodes inside each element edge, and the nodes inside each
 * element; then every free node on its own (the two families reach
 * different places: blocks untangle high orders, single nodes let curve
 * vertices slide where a block's compromise stalls). A block takes a damped
 * Gauss-Newton step on the elements it touches (a small dense system),
 * followed by a backtracking line search that rejects any step that tangles
 * a valid element, folds an element in the parameter plane (so no node
 * leaves its face's domain) or reorders nodes along a curve. Blocks are
 * coloured so that blocks of a colour touch no common element: they are
 * updated in parallel and the result does not depend on the thread count.
 * A block whose step lowers f by less than a small share of f goes to
 * sleep; the iteration ends when every block sleeps.
 *
 * Two phases: the tangle test first looks at samples (quadrature points,
 * nodes, the order-2p lattice); once they say untangled, the exact fold
 * tests of measuring (Bernstein coefficients, quality.h) may still find
 * folds between them, and the sweeps go on with the exact test in every
 * verdict, residuals at dense edge points, and in each element that only
 * the exact tests find folded a residual at the point where they found
 * sigma < 0 (see the end of hoc_mesh_optimize).
 */
#include "optimize/optimize_impl.h"
#include "optimize/tunables.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

double hoc_opt_now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

void hoc_optimize_options_default(hoc_optimize_options *o) {
  if (!o) return;
  memset(o, 0, sizeof *o);
  o->measure = HOC_MEASURE_SHAPE;
  o->max_iterations = HOC_OPT_DEFAULT_MAX_ITERATIONS;
  o->tolerance = HOC_OPT_DEFAULT_TOLERANCE;
}

void hoc_opt_free(hoc_opt *o) {
  for (int f = 0; f < 2; ++f) {
    hoc_opt_blockset *b = &o->fam[f];
    void *q[] = {b->bn_start,    b->bn_node,     b->be_start,    b->be_elem,    b->bd_start,
                 b->node_block,  b->node_off,    b->carry_start, b->carry_node, b->carry_w,
                 b->color_start, b->color_block, b->block_color, b->queue_head, b->queue_next,
                 b->queued,      b->scan_all};
    for (size_t i = 0; i < sizeof q / sizeof *q; ++i) free(q[i]);
  }
  void *p[] = {o->ndof,      o->ne_start,    o->ne_elem, o->ne_local,   o->ns_start, o->ns_slot,
               o->nl_start,  o->nl_line,     o->dz,      o->normal,     o->delta,    o->valid,
               o->pvalid,    o->on_boundary, o->region,  o->was_region, o->dirty,    o->delta_own,
               o->fe,        o->qe,          o->hsize,   o->active,     o->moving,   o->step,
               o->alpha,     o->f0,          o->fnew,    o->slope,      o->state,    o->list,
               o->committed, o->tpar,        o->txyz,    o->tdz,        o->tslot_uv, o->tnormal,
               o->xvalid,    o->near,        o->near_e,  o->touched,    o->has_fold, o->fold_rs,
               o->fragile};
  for (size_t i = 0; i < sizeof p / sizeof *p; ++i) free(p[i]);
}

/* CSR from (key, value) pairs produced by a callback-free double pass. */
hoc_status hoc_opt_csr_alloc(size_t n, size_t total, size_t **start, size_t **items) {
  *start = hoc_calloc(n + 1, sizeof **start);
  *items = hoc_calloc(total + 1, sizeof **items);
  HOC_CHECK(*start && *items, HOC_ERR_MEMORY, "out of memory for the optimiser's adjacency");
  return HOC_OK;
}

void hoc_opt_csr_finish_counts(size_t n, size_t *start) {
  for (size_t i = 0; i < n; ++i) start[i + 1] += start[i];
}

void hoc_opt_csr_restore(size_t n, size_t *start) {
  for (size_t i = n; i > 0; --i) start[i] = start[i - 1];
  start[0] = 0;
}

static double dist3(const double *a, const double *b) {
  return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
              (a[2] - b[2]) * (a[2] - b[2]));
}

/* Unit normal of face f at uv from its derivatives, oriented like the mesh;
 * where the parametrisation is singular, from just inside the face. */
static hoc_status face_normal(const hoc_opt *o, int f, const double *uv, const double *du,
                              const double *dv, double *n) {
  double c[3], a[3], b[3];
  hoc_opt_cross(du, dv, c);
  double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  double scale = du[0] * du[0] + du[1] * du[1] + du[2] * du[2] + dv[0] * dv[0] +
                 dv[1] * dv[1] + dv[2] * dv[2];
  if (!(len > HOC_OPT_SINGULAR_NORMAL * scale)) {
    const hoc_cad_face *face = &o->model->faces[f];
    double p[2];
    for (int d = 0; d < 2; ++d) {
      double mid = 0.5 * (face->lo[d] + face->hi[d]);
      p[d] = uv[d] + HOC_OPT_NORMAL_OFFSET * (face->hi[d] - face->lo[d]) * (mid > uv[d] ? 1.0 : -1.0);
    }
    HOC_TRY(hoc_cad_face_eval(o->model, f, 1, p, NULL, a, b));
    hoc_opt_cross(a, b, c);
    len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  }
  double s = (o->m->face_orient[f] < 0 ? -1.0 : 1.0) / (len > 0 ? len : 1.0);
  for (int k = 0; k < 3; ++k) n[k] = s * c[k];
  return HOC_OK;
}

/* Setup ------------------------------------------------------------------- */

hoc_status hoc_grow_push(hoc_growlist *g, size_t x) {
  if (g->n == g->cap) {
    size_t cap = g->cap ? 2 * g->cap : 256;
    size_t *v = hoc_realloc(g->v, cap, sizeof *v);
    HOC_CHECK(v, HOC_ERR_MEMORY, "out of memory for the optimiser's blocks");
    g->v = v;
    g->cap = cap;
  }
  g->v[g->n++] = x;
  return HOC_OK;
}

/* Blocks of family 0: vertices, edges, element interiors; of family 1:
 * single nodes. Their nodes, footprints, unknowns and carried nodes. */
hoc_status hoc_opt_build_blocks(hoc_opt *o, int family) {
  hoc_opt_blockset *B = &o->fam[family];
  hoc_mesh *m = o->m;
  size_t nn = m->n_nodes, ne = m->n_elems, np = (size_t)o->np;
  int p = m->order;
  HOC_ALLOC(B->node_block, nn);
  HOC_ALLOC(B->node_off, nn);
  for (size_t i = 0; i < nn; ++i) B->node_block[i] = SIZE_MAX;
  hoc_growlist start = {0}, nodes = {0};
  hoc_status status = HOC_OK;
  /* vertex blocks first, then edge blocks, then interior blocks */
  for (int kind = 0; kind < 3; ++kind)
    for (size_t e = 0; e < ne; ++e) {
      if (family == 1) { /* every free node alone, in element order */
        if (kind) break;
        const size_t *cn = m->conn + e * np;
        for (size_t k = 0; k < np; ++k) {
          size_t i = cn[k];
          if (!o->ndof[i] || B->node_block[i] != SIZE_MAX) continue;
          B->node_block[i] = start.n;
          HOC_TRY_GOTO(hoc_grow_push(&start, nodes.n), done);
          HOC_TRY_GOTO(hoc_grow_push(&nodes, i), done);
        }
        continue;
      }
      const size_t *cn = m->conn + e * np;
      if (kind == 0) {
        for (int k = 0; k < 3; ++k) {
          size_t i = cn[k];
          if (!o->ndof[i] || B->node_block[i] != SIZE_MAX) continue;
          B->node_block[i] = start.n;
          HOC_TRY_GOTO(hoc_grow_push(&start, nodes.n), done);
          HOC_TRY_GOTO(hoc_grow_push(&nodes, i), done);
        }
      } else if (kind == 1) {
        /* an edge seen from its second element has its nodes in a block already */
        for (int k = 0; k < 3 && p > 1; ++k) {
          size_t first = nodes.n;
          for (int j = 0; j < p - 1; ++j) {
            size_t i = cn[3 + k * (p - 1) + j];
            if (!o->ndof[i] || B->node_block[i] != SIZE_MAX) continue;
            if (nodes.n == first) HOC_TRY_GOTO(hoc_grow_push(&start, nodes.n), done);
            B->node_block[i] = start.n - 1;
            HOC_TRY_GOTO(hoc_grow_push(&nodes, i), done);
          }
        }
      } else {
        size_t first = nodes.n;
        for (size_t k = 3 * (size_t)p; k < np; ++k) {
          size_t i = cn[k];
          if (!o->ndof[i] || B->node_block[i] != SIZE_MAX) continue;
          if (nodes.n == first) HOC_TRY_GOTO(hoc_grow_push(&start, nodes.n), done);
          B->node_block[i] = start.n - 1;
          HOC_TRY_GOTO(hoc_grow_push(&nodes, i), done);
        }
      }
    }
  size_t nb = start.n;
  B->n_blocks = nb;
  HOC_TRY_GOTO(hoc_grow_push(&start, nodes.n), done);
  B->bn_start = start.v;
  B->bn_node = nodes.v;
  start.v = nodes.v = NULL;
  /* unknowns */
  B->bd_start = hoc_calloc(nb + 1, sizeof *B->bd_start);
  if (!B->bd_start) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (size_t b = 0; b < nb; ++b) {
    int off = 0;
    for (size_t a = B->bn_start[b]; a < B->bn_start[b + 1]; ++a) {
      B->node_off[B->bn_node[a]] = off;
      off += o->ndof[B->bn_node[a]];
    }
    B->bd_start[b + 1] = B->bd_start[b] + (size_t)off;
    if (off > B->max_nd) B->max_nd = off;
  }
  /* footprints: the elements of the block's nodes */
  {
    hoc_growlist fs = {0}, fe = {0};
    for (size_t b = 0; b < nb && status == HOC_OK; ++b) {
      status = hoc_grow_push(&fs, fe.n);
      for (size_t a = B->bn_start[b]; a < B->bn_start[b + 1] && status == HOC_OK; ++a) {
        size_t i = B->bn_node[a];
        for (size_t c = o->ne_start[i]; c < o->ne_start[i + 1] && status == HOC_OK; ++c) {
          size_t e = o->ne_elem[c];
          int seen = 0;
          for (size_t d = fs.v[b]; d < fe.n && !seen; ++d) seen = fe.v[d] == e;
          if (!seen) status = hoc_grow_push(&fe, e);
        }
      }
    }
    if (status == HOC_OK) status = hoc_grow_push(&fs, fe.n);
    B->be_start = fs.v;
    B->be_elem = fe.v;
    if (status != HOC_OK) goto done;
  }
  /* carried nodes of face-interior vertex blocks */
  {
    hoc_growlist cs = {0}, cn = {0};
    double *w = NULL;
    size_t wcap = 0;
    size_t *last = hoc_realloc(NULL, nn + 1, sizeof *last); /* block that last took the node */
    if (!last) status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    for (size_t i = 0; last && i <= nn; ++i)
      last[i] = SIZE_MAX;
    for (size_t b = 0; b < nb && status == HOC_OK; ++b) {
      status = hoc_grow_push(&cs, cn.n);
      size_t k = B->bn_node[B->bn_start[b]];
      int vertex = family == 0 && B->bn_start[b + 1] - B->bn_start[b] == 1 && p >= 2 &&
                   o->ndof[k] == 2;
      for (size_t a = o->ne_start[k]; a < o->ne_start[k + 1] && vertex; ++a) vertex = o->ne_local[a] < 3;
      if (!vertex) continue;
      for (size_t a = o->ne_start[k]; a < o->ne_start[k + 1] && status == HOC_OK; ++a) {
        size_t e = o->ne_elem[a];
        int kk = o->ne_local[a];
        for (size_t i = 3; i < np && status == HOC_OK; ++i) {
          size_t node = m->conn[e * np + i];
          if (o->ndof[node] != 2 || m->entity[node] != m->entity[k] || last[node] == b) continue;
          double r = o->t->rs[2 * i], s = o->t->rs[2 * i + 1];
          double lam = kk == 0 ? 1 - r - s : kk == 1 ? r : s;
          if (!(lam > HOC_OPT_CARRY_MIN_WEIGHT)) continue;
          last[node] = b;
          status = hoc_grow_push(&cn, node);
          if (status != HOC_OK) break;
          if (cn.n > wcap) {
            wcap = cn.cap;
            double *w2 = hoc_realloc(w, wcap, sizeof *w2);
            if (!w2) {
              status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
              break;
            }
            w = w2;
          }
          w[cn.n - 1] = lam;
        }
      }
    }
    free(last);
    if (status == HOC_OK) status = hoc_grow_push(&cs, cn.n);
    B->carry_start = cs.v;
    B->carry_node = cn.v;
    B->carry_w = w;
    if (status != HOC_OK) goto done;
  }
  /* colours: blocks touching a common element differ; every element's
   * blocks are the blocks of its nodes */
  {
    int *color = hoc_calloc(nb + 1, sizeof *color);
    size_t cap = 64, *stamp = hoc_calloc(cap, sizeof *stamp);
    int max_colors = 0;
    if (!color || !stamp) {
      free(color);
      free(stamp);
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      goto done;
    }
    for (size_t b = 0; b < nb; ++b) color[b] = -1;
    for (size_t b = 0; b < nb && status == HOC_OK; ++b) {
      for (size_t a = B->be_start[b]; a < B->be_start[b + 1]; ++a) {
        const size_t *cn = m->conn + B->be_elem[a] * np;
        for (size_t k = 0; k < np; ++k) {
          size_t b2 = B->node_block[cn[k]];
          if (b2 != SIZE_MAX && color[b2] >= 0) stamp[color[b2]] = b + 1;
        }
      }
      int c = 0;
      while ((size_t)c < cap && stamp[c] == b + 1) ++c;
      if ((size_t)c >= cap) {
        size_t *s2 = hoc_realloc(stamp, 2 * cap, sizeof *s2);
        if (!s2) {
          status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
          break;
        }
        stamp = s2;
        memset(stamp + cap, 0, cap * sizeof *stamp);
        cap *= 2;
      }
      color[b] = c;
      if (c + 1 > max_colors) max_colors = c + 1;
    }
    B->n_colors = max_colors;
    if (status == HOC_OK) status = hoc_opt_csr_alloc((size_t)max_colors, nb, &B->color_start, &B->color_block);
    if (status == HOC_OK) {
      for (size_t b = 0; b < nb; ++b) B->color_start[color[b] + 1]++;
      hoc_opt_csr_finish_counts((size_t)max_colors, B->color_start);
      for (size_t b = 0; b < nb; ++b) B->color_block[B->color_start[color[b]]++] = b;
      hoc_opt_csr_restore((size_t)max_colors, B->color_start);
    }
    if (status == HOC_OK) {
      B->block_color = color;
      color = NULL;
      B->queue_head = hoc_calloc((size_t)max_colors + 1, sizeof *B->queue_head);
      B->queue_next = hoc_calloc(nb + 1, sizeof *B->queue_next);
      B->queued = hoc_calloc(nb + 1, 1);
      B->scan_all = hoc_calloc((size_t)max_colors + 1, 1);
      if (!B->queue_head || !B->queue_next || !B->queued || !B->scan_all)
        status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      for (int c = 0; c < max_colors && status == HOC_OK; ++c) {
        B->queue_head[c] = SIZE_MAX;
        B->scan_all[c] = 1;
      }
    }
    free(color);
    free(stamp);
  }
done:
  free(start.v);
  free(nodes.v);
  return status;
}

/* elem[ne] grown by `rings` rings of elements (sharing a node); node[nn]
 * becomes the nodes of the grown set. */
void hoc_opt_grow_rings(const hoc_mesh *m, unsigned char *elem, unsigned char *node, int rings) {
  size_t ne = m->n_elems, np = (size_t)m->np;
  memset(node, 0, m->n_nodes);
  for (int r = 0;; ++r) {
    for (size_t e = 0; e < ne; ++e)
      if (elem[e])
        for (size_t k = 0; k < np; ++k) node[m->conn[e * np + k]] = 1;
    if (r >= rings) break;
    for (size_t e = 0; e < ne; ++e)
      for (size_t k = 0; k < np && !elem[e]; ++k) elem[e] = node[m->conn[e * np + k]];
  }
}

/* Only the nodes of flagged elements and of those within `rings` rings of
 * them (sharing a node) keep their unknowns. */
static hoc_status restrict_free(hoc_opt *o, const unsigned char *flagged, int rings) {
  const hoc_mesh *m = o->m;
  size_t ne = m->n_elems, nn = m->n_nodes, np = (size_t)o->np;
  unsigned char *elem = hoc_calloc(ne + 1, 1), *node = hoc_calloc(nn + 1, 1);
  if (!elem || !node) {
    free(elem);
    free(node);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  memcpy(elem, flagged, ne);
  hoc_opt_grow_rings(m, elem, node, rings);
  for (size_t i = 0; i < nn; ++i)
    if (!node[i]) o->ndof[i] = 0;
  memset(elem, 0, ne);
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < np && !elem[e]; ++k) elem[e] = o->ndof[m->conn[e * np + k]] > 0;
  o->touched = elem;
  free(node);
  return HOC_OK;
}

/* The part of f the free nodes can change (all of it without
 * free_elements): the stopping rules' measure of progress. */
static double free_objective(const hoc_opt *o, double f) {
  if (!o->touched) return f;
  double fl = 0;
  for (size_t e = 0; e < o->m->n_elems; ++e)
    if (o->touched[e]) fl += o->fe[e];
  return fl;
}

hoc_status hoc_opt_setup(hoc_opt *o, hoc_mesh *m, hoc_measure measure, int fix_curves,
                        const unsigned char *free_elements, int free_rings) {
  memset(o, 0, sizeof *o);
  o->m = m;
  o->model = m->model;
  o->measure = measure;
  o->eps = HOC_OPT_EPS;
  HOC_TRY(hoc_quality_tables_get(m->order, m->nodeset, &o->t));
  o->np = o->t->np;
  o->nq = o->t->nq;
  size_t nn = m->n_nodes, ne = m->n_elems, np = (size_t)o->np;
  HOC_ALLOC(o->ndof, nn);
  HOC_ALLOC(o->ne_local, ne * np + 1);
  HOC_TRY(hoc_opt_csr_alloc(nn, ne * np, &o->ne_start, &o->ne_elem));
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < np; ++k) o->ne_start[m->conn[e * np + k] + 1]++;
  hoc_opt_csr_finish_counts(nn, o->ne_start);
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < np; ++k) {
      size_t i = m->conn[e * np + k], pos = o->ne_start[i]++;
      o->ne_elem[pos] = e;
      o->ne_local[pos] = (int)k;
    }
  hoc_opt_csr_restore(nn, o->ne_start);
  HOC_TRY(hoc_opt_csr_alloc(nn, m->n_slots, &o->ns_start, &o->ns_slot));
  for (size_t s = 0; s < m->n_slots; ++s) o->ns_start[m->slot_node[s] + 1]++;
  hoc_opt_csr_finish_counts(nn, o->ns_start);
  for (size_t s = 0; s < m->n_slots; ++s) o->ns_slot[o->ns_start[m->slot_node[s]]++] = s;
  hoc_opt_csr_restore(nn, o->ns_start);
  size_t lp = (size_t)m->order + 1;
  HOC_TRY(hoc_opt_csr_alloc(nn, m->n_lines * lp, &o->nl_start, &o->nl_line));
  for (size_t l = 0; l < m->n_lines; ++l)
    for (size_t k = 0; k < lp; ++k) o->nl_start[m->line_conn[l * lp + k] + 1]++;
  hoc_opt_csr_finish_counts(nn, o->nl_start);
  for (size_t l = 0; l < m->n_lines; ++l)
    for (size_t k = 0; k < lp; ++k) o->nl_line[o->nl_start[m->line_conn[l * lp + k]]++] = l;
  hoc_opt_csr_restore(nn, o->nl_start);
  for (size_t i = 0; i < nn; ++i) {
    if (o->ne_start[i + 1] == o->ne_start[i]) continue; /* used by no element */
    if (m->dim[i] == HOC_ON_FACE) o->ndof[i] = 2;
    else if (m->dim[i] == HOC_ON_CURVE && !fix_curves && !m->model->curves[m->entity[i]].degenerate)
      o->ndof[i] = 1;
  }
  if (free_elements) HOC_TRY(restrict_free(o, free_elements, free_rings));
  /* the two families at once (each fills only its own blockset) */
  hoc_par_error err = {0};
#pragma omp parallel for schedule(static, 1) num_threads(2) if (omp_get_max_threads() > 1)
  for (int family = 0; family < 2; ++family) hoc_par_error_catch(&err, hoc_opt_build_blocks(o, family));
  HOC_TRY(hoc_par_error_raise(&err));
  o->B = &o->fam[0]; /* family 0 is current by default */
  o->max_nd = o->fam[0].max_nd > o->fam[1].max_nd ? o->fam[0].max_nd : o->fam[1].max_nd;
  size_t nb = o->fam[0].n_blocks > o->fam[1].n_blocks ? o->fam[0].n_blocks : o->fam[1].n_blocks;
  size_t nd_total = o->fam[0].bd_start[o->fam[0].n_blocks] > o->fam[1].bd_start[o->fam[1].n_blocks]
                        ? o->fam[0].bd_start[o->fam[0].n_blocks]
                        : o->fam[1].bd_start[o->fam[1].n_blocks];
  HOC_ALLOC(o->dz, 6 * nn);
  HOC_ALLOC(o->normal, 3 * m->n_slots + 3);
  HOC_ALLOC(o->delta, ne);
  HOC_ALLOC(o->valid, ne);
  HOC_ALLOC(o->xvalid, ne);
  HOC_ALLOC(o->fragile, ne);
  memset(o->fragile, 0, ne);
  HOC_ALLOC(o->pvalid, ne);
  HOC_ALLOC(o->on_boundary, ne);
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < np; ++k) o->on_boundary[e] |= m->dim[m->conn[e * np + k]] != HOC_ON_FACE;
  HOC_ALLOC(o->region, ne);
  HOC_ALLOC(o->was_region, ne);
  HOC_ALLOC(o->dirty, ne);
  HOC_ALLOC(o->delta_own, ne);
  HOC_ALLOC(o->has_fold, ne);
  HOC_ALLOC(o->fold_rs, 2 * ne);
  HOC_ALLOC(o->fe, ne);
  HOC_ALLOC(o->qe, ne);
  memset(o->dirty, 1, ne);
  HOC_ALLOC(o->hsize, nn);
  HOC_ALLOC(o->active, nn);
  HOC_ALLOC(o->near, nn);
  HOC_ALLOC(o->near_e, ne);
  HOC_ALLOC(o->moving, nn);
  HOC_ALLOC(o->step, nd_total + 1);
  HOC_ALLOC(o->alpha, nb + 1);
  HOC_ALLOC(o->f0, nb + 1);
  HOC_ALLOC(o->fnew, nb + 1);
  HOC_ALLOC(o->slope, nb + 1);
  HOC_ALLOC(o->state, nb + 1);
  HOC_ALLOC(o->list, nb + 1);
  HOC_ALLOC(o->committed, nb + 1);
  HOC_ALLOC(o->tpar, 2 * nn);
  HOC_ALLOC(o->txyz, 3 * nn);
  HOC_ALLOC(o->tdz, 6 * nn);
  HOC_ALLOC(o->tslot_uv, 2 * m->n_slots + 2);
  HOC_ALLOC(o->tnormal, 3 * m->n_slots + 3);
  /* local length: the longest edge of the linear sub-triangles around */
  for (size_t e = 0; e < ne; ++e) {
    const size_t *cn = m->conn + e * np;
    double h = 0;
    for (int k = 0; k < 3; ++k) h = fmax(h, dist3(m->xyz + 3 * cn[k], m->xyz + 3 * cn[(k + 1) % 3]));
    for (size_t k = 0; k < np; ++k) o->hsize[cn[k]] = fmax(o->hsize[cn[k]], h);
  }
  return HOC_OK;
}

/* Derivatives dx/dz of every free node and the normals of every slot. */
hoc_status hoc_opt_eval_all(hoc_opt *o) {
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
  hoc_opt_csr_finish_counts((size_t)(nf + nc), start);
  for (size_t i = 0; i < nn; ++i) {
    if (!o->ndof[i]) continue;
    int g = m->dim[i] == HOC_ON_FACE ? m->entity[i] : nf + m->entity[i];
    order[start[g]++] = i;
  }
  hoc_opt_csr_restore((size_t)(nf + nc), start);
  size_t *piece = NULL, n_pieces = 0;
  HOC_TRY_GOTO(hoc_split_groups(start, nf + nc, 1024, &piece, &n_pieces), done);
  hoc_par_error err = {0};
#pragma omp parallel for schedule(dynamic, 1) if (o->model->thread_safe)
  for (size_t c = 0; c < n_pieces; ++c) {
    int g = (int)piece[2 * c];
    size_t first = piece[2 * c + 1], n = start[g + 1] - first < 1024 ? start[g + 1] - first : 1024;
    const size_t *nodes = order + first;
    /* this piece's part of the work arrays */
    double *pp = par + 2 * first, *pa = a + 3 * first, *pb = b + 3 * first;
    hoc_status st;
    if (g < nf) {
      for (size_t k = 0; k < n; ++k)
        memcpy(pp + 2 * k, m->param + 2 * nodes[k], 2 * sizeof *pp);
      st = hoc_cad_face_eval(o->model, g, n, pp, NULL, pa, pb);
    } else {
      for (size_t k = 0; k < n; ++k)
        pp[k] = m->param[2 * nodes[k]];
      st = hoc_cad_curve_eval(o->model, g - nf, n, pp, NULL, pa);
      memset(pb, 0, 3 * n * sizeof *pb);
    }
    hoc_par_error_catch(&err, st);
    for (size_t k = 0; k < n && st == HOC_OK; ++k) {
      memcpy(o->dz + 6 * nodes[k], pa + 3 * k, 3 * sizeof *pa);
      memcpy(o->dz + 6 * nodes[k] + 3, pb + 3 * k, 3 * sizeof *pb);
    }
  }
  free(piece);
  status = hoc_par_error_raise(&err);
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
void hoc_opt_gather(const hoc_opt *o, size_t e, double *x, double *n) {
  const hoc_mesh *m = o->m;
  size_t np = (size_t)o->np;
  const size_t *cn = m->conn + e * np, *sl = m->elem_slot + e * np;
  for (size_t i = 0; i < np; ++i) {
    int mv = o->moving[cn[i]];
    memcpy(x + 3 * i, (mv ? o->txyz : m->xyz) + 3 * cn[i], 3 * sizeof *x);
    memcpy(n + 3 * i, (mv ? o->tnormal : o->normal) + 3 * sl[i], 3 * sizeof *n);
  }
}

/* Element not folded in the (u,v) plane: orient * det(D u(xi)) > 0 at its
 * nodes (trial state of `moving` nodes). uv: [np][2] scratch. */
int hoc_opt_param_valid(const hoc_opt *o, size_t e, double *uv) {
  const hoc_mesh *m = o->m;
  int np = o->np;
  const size_t *cn = m->conn + e * (size_t)np;
  memcpy(uv, m->elem_uv + 2 * e * (size_t)np, 2 * (size_t)np * sizeof *uv);
  for (int i = 0; i < np; ++i)
    if (o->moving[cn[i]]) hoc_opt_trial_elem_uv(o, cn[i], e, i, uv + 2 * i);
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
static void sigma_stats(const hoc_opt *o, const double *x, const double *n, double *smin,
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
    hoc_opt_cross(a1, a2, c);
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

/* Residuals of element e's objective: the quadrature points, and in the
 * tangled region also the nodes and validation points (the tangle test
 * asks det > 0 there too) and, where only the exact tests find the element
 * folded, the point where they found it. r: [nq + np + nv + 1],
 * J: [nq + np + nv + 1][np][3] or NULL. Returns the count and sets
 * *smin to the smallest sigma / |D phi|^2 over the quadrature points. */
int hoc_opt_elem_residuals(const hoc_opt *o, size_t e, const double *x, const double *n,
                          const unsigned char *need, double *r, double *J, double *smin) {
  int nq = o->nq, np = o->np;
  double s = hoc_element_residuals(o->t, o->measure, x, n, o->delta[e], need, r, J);
  if (smin) *smin = s;
  if (!o->region[e]) return nq;
  hoc_element_node_residuals(o->t, o->measure, x, n, o->delta[e], o->exact, need, r + nq,
                             J ? J + 3 * (size_t)nq * (size_t)np : NULL);
  int count = nq + hoc_element_node_points(o->t, o->exact);
  if (!o->has_fold[e]) return count;
  /* weighted as one of the node residuals */
  hoc_element_point_residual(o->t, o->measure, x, n, o->delta[e], o->fold_rs + 2 * e,
                             1.0 / hoc_element_node_points(o->t, o->exact), need, r + count,
                             J ? J + 3 * (size_t)count * (size_t)np : NULL);
  return count + 1;
}

/* Per-element state at the start of a sweep: validity, parametric
 * validity, regularisation; also f, q and the tangled count. */
hoc_status hoc_opt_sweep_start(hoc_opt *o, double *objective, double *min_q, size_t *tangled) {
  hoc_mesh *m = o->m;
  size_t ne = m->n_elems;
  int np = o->np, nq = o->nq;
  double *fe = o->fe, *qe = o->qe;
  int failed = 0;
  /* elements whose nodes moved: q, validity, their own regularisation */
#pragma omp parallel
  {
    double *x = malloc((6 * (size_t)np + (size_t)nq + 2 * (size_t)np) * sizeof *x);
    if (!x) {
#pragma omp atomic write
      failed = 1;
    }
    double *n = x ? x + 3 * np : NULL, *uv = x ? x + 6 * np + nq : NULL;
#pragma omp for schedule(static)
    for (size_t e = 0; e < ne; ++e) {
      if (!x || !o->dirty[e]) continue;
      hoc_opt_gather(o, e, x, n);
      double eta;
      qe[e] = hoc_element_quality_test(o->t, o->measure, x, n, o->exact, &eta, NULL);
      o->valid[e] = qe[e] > 0;
      o->xvalid[e] = o->valid[e] && (o->exact || !hoc_opt_guarded(o, e) || !hoc_element_folded(o->t, x, n));
      o->pvalid[e] = (unsigned char)hoc_opt_param_valid(o, e, uv);
      o->delta_own[e] = 0;
      /* a fold the samples miss: a residual where the exact tests found it
       * (the samples' residuals cannot see it, and no step would open it) */
      o->has_fold[e] = o->exact && !o->valid[e] && !hoc_element_tangled(o->t, x, n, 0) &&
                       hoc_element_fold_point(o->t, x, n, o->fold_rs + 2 * e);
      if (!o->valid[e]) {
        double smin, scale;
        sigma_stats(o, x, n, &smin, &scale);
        double eps = o->eps * scale;
        o->delta_own[e] = smin < eps ? sqrt(eps * (eps - smin)) : 0;
        if (!(o->delta_own[e] > 0)) o->delta_own[e] = eps;
      }
    }
    free(x);
  }
  /* the tangled region: tangled elements and those sharing a node with one
   * take the largest regularisation around them (Escobar et al. regularise
   * the whole mesh with one delta; this keeps the rest of it exact) */
  memcpy(o->was_region, o->region, ne);
  memset(o->region, 0, ne);
  for (size_t e = 0; e < ne; ++e) o->delta[e] = o->delta_own[e];
  for (size_t e = 0; e < ne && !failed; ++e) {
    if (o->valid[e]) continue;
    for (int i = 0; i < np; ++i) {
      size_t node = m->conn[e * (size_t)np + (size_t)i];
      for (size_t a = o->ne_start[node]; a < o->ne_start[node + 1]; ++a) {
        size_t e2 = o->ne_elem[a];
        o->region[e2] = 1;
        if (o->delta[e2] < o->delta_own[e]) o->delta[e2] = o->delta_own[e];
      }
    }
  }
  /* objective parts that changed: moved, or in or out of the region */
#pragma omp parallel
  {
    double *x =
        malloc((6 * (size_t)np + (size_t)nq + (size_t)np + (size_t)o->t->nv + 1) * sizeof *x);
    if (!x) {
#pragma omp atomic write
      failed = 1;
    }
    double *n = x ? x + 3 * np : NULL, *r = x ? x + 6 * np : NULL;
#pragma omp for schedule(static)
    for (size_t e = 0; e < ne; ++e) {
      if (!x || !(o->dirty[e] || o->region[e] || o->was_region[e])) continue;
      hoc_opt_gather(o, e, x, n);
      double f = 0;
      int nr = hoc_opt_elem_residuals(o, e, x, n, NULL, r, NULL, NULL);
      for (int q = 0; q < nr; ++q) f += r[q] * r[q];
      fe[e] = f;
    }
    free(x);
  }
  if (failed) return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  memset(o->dirty, 0, ne);
  double f = 0, qmin = INFINITY;
  size_t nt = 0;
  for (size_t e = 0; e < ne; ++e) {
    f += fe[e];
    qmin = fmin(qmin, qe[e]);
    nt += qe[e] == 0.0;
  }
  *objective = f;
  *min_q = ne ? qmin : 0;
  *tangled = nt;
  return HOC_OK;
}

/* Parameters of node k's slot s for the trial: (u,v) of the slot, unwrapped
 * near the element's current value. */
void hoc_opt_trial_elem_uv(const hoc_opt *o, size_t k, size_t e, int kk, double *uv) {
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

/* CAD evaluation of node i's trial parameters: position, derivatives, and
 * the parameters and normals of its slots. */
hoc_status hoc_opt_eval_trial(hoc_opt *o, size_t i) {
  hoc_mesh *m = o->m;
  const hoc_model *model = o->model;
  int ent = m->entity[i];
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
      /* a small move cannot turn the surface over: where the CAD normal
       * flips (a folded parametrisation at the boundary, see
       * hoc_mesh_slot_normals) the slot keeps its orientation */
      const double *old = o->normal + 3 * s;
      double *nw = o->tnormal + 3 * s;
      if (nw[0] * old[0] + nw[1] * old[1] + nw[2] * old[2] < 0)
        for (int d = 0; d < 3; ++d)
          nw[d] = -nw[d];
    }
  }
  return HOC_OK;
}

/* CAD evaluation of the trial parameters of the nodes in list[0..n) (no
 * node twice), on nthreads threads. */
hoc_status hoc_opt_eval_trials(hoc_opt *o, const size_t *list, size_t n, int nthreads) {
  hoc_par_error err = {0};
#pragma omp parallel for schedule(dynamic, 4) num_threads(nthreads) if (n > 8 && o->model->thread_safe)
  for (size_t c = 0; c < n; ++c)
    hoc_par_error_catch(&err, hoc_opt_eval_trial(o, list[c]));
  return hoc_par_error_raise(&err);
}

/* Accept node k's trial. */
void hoc_opt_commit(hoc_opt *o, size_t k) {
  hoc_mesh *m = o->m;
  int np = o->np;
  for (size_t a = o->ne_start[k]; a < o->ne_start[k + 1]; ++a) o->dirty[o->ne_elem[a]] = 1;
  for (size_t a = o->ne_start[k]; a < o->ne_start[k + 1]; ++a) {
    size_t e = o->ne_elem[a];
    int kk = o->ne_local[a];
    double uv[2];
    hoc_opt_trial_elem_uv(o, k, e, kk, uv);
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

/* Blocks ------------------------------------------------------------------- */

double hoc_opt_carry_weight(const hoc_opt *o, size_t b, size_t node) {
  for (size_t j = o->B->carry_start[b]; j < o->B->carry_start[b + 1]; ++j)
    if (o->B->carry_node[j] == node) return o->B->carry_w[j];
  return 0;
}

void hoc_opt_set_moving(hoc_opt *o, size_t b, unsigned char v) {
  for (size_t a = o->B->bn_start[b]; a < o->B->bn_start[b + 1]; ++a) o->moving[o->B->bn_node[a]] = v;
  for (size_t j = o->B->carry_start[b]; j < o->B->carry_start[b + 1]; ++j) o->moving[o->B->carry_node[j]] = v;
}

/* Screening: every node's single-node Gauss-Newton decrease estimate
 * 0.5 g^T H^-1 g from one evaluation per element (instead of one per block
 * through each element); nodes whose estimate is below the gain threshold
 * (and not near a tangle) start asleep. Element contributions are stored
 * and summed per node in element order, so the result does not depend on
 * the thread count. */
hoc_status hoc_opt_screen(hoc_opt *o) {
  hoc_mesh *m = o->m;
  size_t ne = m->n_elems, np = (size_t)o->np;
  /* [ne][np][g0 g1 h00 h01 h11], every entry written below (not zeroed) */
  double *contrib = hoc_realloc(NULL, 5 * ne * np + 1, sizeof *contrib);
  HOC_CHECK(contrib, HOC_ERR_MEMORY, "out of memory");
  int nr_max = o->nq + o->np + o->t->nv + 1, failed = 0; /* + 1: a fold point */
#pragma omp parallel
  {
    double *x = malloc((6 * np + (size_t)nr_max + 3 * (size_t)nr_max * np) * sizeof *x);
    if (!x) {
#pragma omp atomic write
      failed = 1;
    }
    double *n = x ? x + 3 * np : NULL, *r = x ? x + 6 * np : NULL, *J = r ? r + nr_max : NULL;
    unsigned char *need = x ? malloc(np) : NULL; /* the free nodes' columns of J */
    if (x && !need) {
#pragma omp atomic write
      failed = 1;
    }
#pragma omp for schedule(static)
    for (size_t e = 0; e < ne; ++e) {
      if (!need || (o->touched && !o->touched[e])) continue; /* (no free node reads it) */
      const size_t *cn = m->conn + e * np;
      for (size_t i = 0; i < np; ++i) need[i] = o->ndof[cn[i]] > 0;
      hoc_opt_gather(o, e, x, n);
      int nr = hoc_opt_elem_residuals(o, e, x, n, need, r, J, NULL);
      for (size_t i = 0; i < np; ++i) {
        const double *dz = o->dz + 6 * cn[i];
        double c[5] = {0, 0, 0, 0, 0};
        for (int q = 0; q < nr && need[i]; ++q) {
          const double *j = J + 3 * ((size_t)q * np + i);
          double z0 = j[0] * dz[0] + j[1] * dz[1] + j[2] * dz[2];
          double z1 = j[0] * dz[3] + j[1] * dz[4] + j[2] * dz[5];
          c[0] += 2 * r[q] * z0;
          c[1] += 2 * r[q] * z1;
          c[2] += 2 * z0 * z0;
          c[3] += 2 * z0 * z1;
          c[4] += 2 * z1 * z1;
        }
        /* written once, never read first: a fresh page read before it is
         * written is copied from the zero page, and with two threads every
         * such copy flushes the other core's TLB */
        memcpy(contrib + 5 * (e * np + i), c, sizeof c);
      }
    }
    free(need);
    free(x);
  }
  if (failed) {
    free(contrib);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < m->n_nodes; ++k) {
    if (!o->ndof[k]) continue;
    double c[5] = {0, 0, 0, 0, 0};
    int near = 0;
    for (size_t a = o->ne_start[k]; a < o->ne_start[k + 1]; ++a) {
      size_t e = o->ne_elem[a];
      const double *ce = contrib + 5 * (e * np + (size_t)o->ne_local[a]);
      for (int d = 0; d < 5; ++d) c[d] += ce[d];
      near |= o->region[e] || !o->valid[e];
    }
    double gain;
    if (o->ndof[k] == 2) {
      double det = c[2] * c[4] - c[3] * c[3];
      gain = det > 0 ? 0.5 * (c[4] * c[0] * c[0] - 2 * c[3] * c[0] * c[1] + c[2] * c[1] * c[1]) / det
                     : INFINITY;
    } else {
      gain = c[2] > 0 ? 0.5 * c[0] * c[0] / c[2] : INFINITY;
    }
    o->active[k] = near || !(gain < o->min_gain);
  }
  free(contrib);
  return HOC_OK;
}

/* Local objective of block b at the current state: f, gradient g[nd] and
 * Gauss-Newton matrix H[nd][nd] in its unknowns. */
void hoc_opt_block_model(const hoc_opt *o, size_t b, hoc_opt_scratch *s, double *f, double *g, double *H) {
  const hoc_mesh *m = o->m;
  int np = o->np, nd = (int)(o->B->bd_start[b + 1] - o->B->bd_start[b]);
  int carries = o->B->carry_start[b + 1] > o->B->carry_start[b];
  *f = 0;
  memset(g, 0, (size_t)nd * sizeof *g);
  memset(H, 0, (size_t)nd * (size_t)nd * sizeof *H);
  for (size_t a = o->B->be_start[b]; a < o->B->be_start[b + 1]; ++a) {
    size_t e = o->B->be_elem[a];
    const size_t *cn = m->conn + e * (size_t)np;
    /* the block's nodes and those it carries: the columns of J it needs */
    for (int i = 0; i < np; ++i) {
      size_t node = cn[i];
      s->w[i] = 1;
      if (o->B->node_block[node] == b) {
        s->off[i] = o->B->node_off[node];
        s->nd[i] = o->ndof[node];
      } else if (carries && (s->w[i] = hoc_opt_carry_weight(o, b, node)) > 0) {
        s->off[i] = 0;
        s->nd[i] = 2;
      } else {
        s->nd[i] = 0;
      }
    }
    hoc_opt_gather(o, e, s->x, s->n);
    int nr = hoc_opt_elem_residuals(o, e, s->x, s->n, s->nd, s->r, s->J, NULL);
    double *Jz = s->Jz; /* [nr][nd] */
    memset(Jz, 0, (size_t)nr * (size_t)nd * sizeof *Jz);
    for (int i = 0; i < np; ++i) {
      size_t node = cn[i];
      int off = s->off[i], nd_i = s->nd[i];
      double w = s->w[i];
      if (!nd_i) continue;
      const double *dz = o->dz + 6 * node;
      for (int q = 0; q < nr; ++q) {
        const double *j = s->J + 3 * ((size_t)q * np + (size_t)i);
        Jz[q * nd + off] += w * (j[0] * dz[0] + j[1] * dz[1] + j[2] * dz[2]);
        if (nd_i == 2) Jz[q * nd + off + 1] += w * (j[0] * dz[3] + j[1] * dz[4] + j[2] * dz[5]);
      }
    }
    for (int q = 0; q < nr; ++q) {
      double r = s->r[q];
      const double *jz = Jz + q * nd;
      *f += r * r;
      for (int c = 0; c < nd; ++c) {
        g[c] += 2 * r * jz[c];
        for (int d = 0; d <= c; ++d) H[c * nd + d] += 2 * jz[c] * jz[d];
      }
    }
  }
  for (int c = 0; c < nd; ++c)
    for (int d = c + 1; d < nd; ++d) H[c * nd + d] = H[d * nd + c];
}

/* Solve (H + mu diag(H)) x = -g by Cholesky, raising mu until it works.
 * L: [nd][nd] scratch. Returns 0 if no step could be found. */
static int damped_solve(int nd, const double *H, const double *g, double *L, double *x) {
  double dmax = 0;
  for (int c = 0; c < nd; ++c) dmax = fmax(dmax, H[c * nd + c]);
  if (!(dmax > 0)) return 0;
  for (double mu = HOC_OPT_MU_FIRST; mu < HOC_OPT_MU_LAST; mu *= HOC_OPT_MU_GROWTH) {
    int ok = 1;
    for (int c = 0; c < nd && ok; ++c)
      for (int d = 0; d <= c; ++d) {
        double v = H[c * nd + d];
        if (c == d) v += mu * fmax(H[c * nd + c], HOC_OPT_DIAG_FLOOR * dmax);
        for (int k = 0; k < d; ++k) v -= L[c * nd + k] * L[d * nd + k];
        if (c == d) {
          if (!(v > 0)) {
            ok = 0;
            break;
          }
          L[c * nd + c] = sqrt(v);
        } else {
          L[c * nd + d] = v / L[d * nd + d];
        }
      }
    if (!ok) continue;
    for (int c = 0; c < nd; ++c) { /* L y = -g */
      double v = -g[c];
      for (int k = 0; k < c; ++k) v -= L[c * nd + k] * x[k];
      x[c] = v / L[c * nd + c];
    }
    for (int c = nd - 1; c >= 0; --c) { /* L^T x = y */
      double v = x[c];
      for (int k = c + 1; k < nd; ++k) v -= L[k * nd + c] * x[k];
      x[c] = v / L[c * nd + c];
    }
    return 1;
  }
  return 0;
}

/* Curve parameters of line l's nodes in order along the line (trial values
 * for moving nodes), unwrapped from its first end: 1 if strictly monotone in
 * the line's direction. */
int hoc_opt_line_monotone(const hoc_opt *o, size_t l) {
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
    if (m->dim[i] != HOC_ON_CURVE) {
      t = j == 0 ? ta : tb; /* a vertex end: the line's own parameter */
    } else {
      t = o->moving[i] ? o->tpar[2 * i] : m->param[2 * i];
      if (c->period > 0) {
        double guess = ta + (tb - ta) * j / p;
        t -= c->period * floor((t - guess) / c->period + 0.5);
      }
    }
    if (j > 0 && !(dir * (t - prev) > 0)) return 0;
    prev = t;
  }
  return 1;
}

/* While untangling stalls (a raised regularisation), the valid neighbours
 * of tangled elements may pass through sigma = 0 for a while: some folds
 * only open by moving their neighbourhood through an invalid state.
 * Fragile elements never (mark_fragile). Above HOC_OPT_PROTECT_MAX_ORDER
 * only in the exact phase: in the sampled phase of a high order, the
 * relaxed region folds between the samples more than it opens, and the
 * exact phase cannot open those folds again. In the exact phase the last
 * folds may need it (a single fold left on a periodic face at order 10
 * opens only so). */
static int relaxed(const hoc_opt *o, size_t e) {
  return o->region[e] && o->eps > HOC_OPT_EPS_RAISED && !o->fragile[e] &&
         (o->m->order <= HOC_OPT_PROTECT_MAX_ORDER || o->exact);
}

/* In the second attempt (relax_uv), relaxed elements on a face's boundary
 * may also fold in (u, v): on a regular parametrisation that is the same
 * fold as in 3D, and the (u, v) rule would otherwise hold them where the 3D
 * rule lets go. Not on faces with a pole, where (u, v) folds without the
 * surface folding. Only in a second attempt: from the start, on thin parts
 * at high orders, it trades one fold for several. */
static int relaxed_uv(const hoc_opt *o, size_t e) {
  if (!o->relax_uv || !relaxed(o, e)) return 0;
  const hoc_cad_face *f = &o->model->faces[o->m->elem_face[e]];
  return !(f->pole[0] || f->pole[1] || f->pole[2] || f->pole[3]);
}

/* Local objective of block b at its trial (nodes flagged moving); 0 if the
 * trial breaks a rule. */
static int block_trial_flagged(const hoc_opt *o, size_t b, hoc_opt_scratch *s, double fmax, double *f) {
  const hoc_mesh *m = o->m;
  *f = 0;
  for (size_t a = o->B->bn_start[b]; a < o->B->bn_start[b + 1]; ++a) {
    size_t k = o->B->bn_node[a];
    if (m->dim[k] != HOC_ON_CURVE) continue;
    for (size_t c = o->nl_start[k]; c < o->nl_start[k + 1]; ++c)
      if (!hoc_opt_line_monotone(o, o->nl_line[c])) return 0;
  }
  for (size_t a = o->B->be_start[b]; a < o->B->be_start[b + 1]; ++a) {
    size_t e = o->B->be_elem[a];
    hoc_opt_gather(o, e, s->x, s->n);
    if (o->pvalid[e] && o->on_boundary[e] && !relaxed_uv(o, e) && !hoc_opt_param_valid(o, e, s->uv))
      return 0;
    double smin;
    int nr = hoc_opt_elem_residuals(o, e, s->x, s->n, NULL, s->r, NULL, &smin);
    if (o->valid[e] && !relaxed(o, e) && !(smin > 0)) return 0;
    for (int q = 0; q < nr; ++q) *f += s->r[q] * s->r[q];
  }
  if (!isfinite(*f) || !(*f <= fmax)) return 0;
  /* a candidate: the dense part of the tangle test (nodes, validation
   * lattice) for the elements that must stay valid */
  for (size_t a = o->B->be_start[b]; a < o->B->be_start[b + 1]; ++a) {
    size_t e = o->B->be_elem[a];
    if (!o->valid[e] || relaxed(o, e)) continue;
    hoc_opt_gather(o, e, s->x, s->n);
    if (hoc_element_nodes_tangled(o->t, s->x, s->n, o->exact || (hoc_opt_guarded(o, e) && o->xvalid[e])))
      return 0;
  }
  return 1;
}

static int block_trial(hoc_opt *o, size_t b, hoc_opt_scratch *s, double fmax, double *f) {
  hoc_opt_set_moving(o, b, 1);
  int ok = block_trial_flagged(o, b, s, fmax, f);
  hoc_opt_set_moving(o, b, 0);
  return ok;
}

/* A trial parameter is acceptable inside [lo, hi], or outside but closer to
 * it than the current value (a node outside its face's range, e.g. read from
 * a file, may come back). */
static int param_ok(double cur, double v, double lo, double hi) {
  if (v >= lo && v <= hi) return 1;
  double dv = v < lo ? lo - v : v - hi, dc = cur < lo ? lo - cur : cur > hi ? cur - hi : 0;
  return dv < dc;
}

/* Trial parameters of block b at step length alpha[b]: the block's nodes
 * and the nodes it carries. Returns 0 if one leaves a non-closed range. */
int hoc_opt_set_trial_params(hoc_opt *o, size_t b) {
  const hoc_mesh *m = o->m;
  const double *st = o->step + o->B->bd_start[b];
  double al = o->alpha[b];
  int inside = 1;
  for (size_t a = o->B->bn_start[b]; a < o->B->bn_start[b + 1]; ++a) {
    size_t k = o->B->bn_node[a];
    int off = o->B->node_off[k];
    if (m->dim[k] == HOC_ON_FACE) {
      const hoc_cad_face *f = &o->model->faces[m->entity[k]];
      for (int d = 0; d < 2; ++d) {
        double v = m->param[2 * k + d] + al * st[off + d];
        o->tpar[2 * k + d] = v;
        if (!(f->period[d] > 0) && !param_ok(m->param[2 * k + d], v, f->lo[d], f->hi[d])) inside = 0;
      }
    } else {
      const hoc_cad_curve *c = &o->model->curves[m->entity[k]];
      double v = m->param[2 * k] + al * st[off];
      o->tpar[2 * k] = v;
      o->tpar[2 * k + 1] = 0;
      if (!(c->period > 0) && !param_ok(m->param[2 * k], v, c->lo, c->hi)) inside = 0;
    }
  }
  for (size_t j = o->B->carry_start[b]; j < o->B->carry_start[b + 1]; ++j) {
    size_t c = o->B->carry_node[j];
    const hoc_cad_face *f = &o->model->faces[m->entity[c]];
    for (int d = 0; d < 2; ++d) {
      double v = m->param[2 * c + d] + al * o->B->carry_w[j] * st[d];
      o->tpar[2 * c + d] = v;
      if (!(f->period[d] > 0) && !param_ok(m->param[2 * c + d], v, f->lo[d], f->hi[d])) inside = 0;
    }
  }
  return inside;
}

/* Block b touches a tangled element or one next to it. */
static int near_tangled(const hoc_opt *o, size_t b) {
  for (size_t a = o->B->be_start[b]; a < o->B->be_start[b + 1]; ++a)
    if (o->region[o->B->be_elem[a]] || !o->valid[o->B->be_elem[a]]) return 1;
  return 0;
}

static int block_active(const hoc_opt *o, size_t b) {
  int act = 0, near = !o->local;
  for (size_t a = o->B->bn_start[b]; a < o->B->bn_start[b + 1]; ++a) {
    act |= o->active[o->B->bn_node[a]];
    near |= o->near[o->B->bn_node[a]];
  }
  return act && near;
}

/* Node k is active again: its blocks of both families go on their colours'
 * queues. */
void hoc_opt_wake_node(hoc_opt *o, size_t k) {
  o->active[k] = 1;
  for (int f = 0; f < 2; ++f) {
    hoc_opt_blockset *B = &o->fam[f];
    size_t b = B->node_block[k];
    if (b == SIZE_MAX || B->queued[b]) continue;
    B->queued[b] = 1;
    int c = B->block_color[b];
    B->queue_next[b] = B->queue_head[c];
    B->queue_head[c] = b;
  }
}

/* Flags the nodes within HOC_OPT_NEAR_RINGS rings of a tangled element. */
void hoc_opt_mark_near(hoc_opt *o) {
  for (size_t e = 0; e < o->m->n_elems; ++e) o->near_e[e] = !o->valid[e];
  hoc_opt_grow_rings(o->m, o->near_e, o->near, HOC_OPT_NEAR_RINGS);
}

/* Every block may be active (after a change of every node's flag). */
void hoc_opt_wake_all(hoc_opt *o) {
  for (int f = 0; f < 2; ++f)
    memset(o->fam[f].scan_all, 1, (size_t)o->fam[f].n_colors);
}

/* The blocks of a colour with an active node into o->list (in an order that
 * does not matter: blocks of one colour share no element); returns their
 * number. Empties the colour's queue. */
size_t hoc_opt_select_active(hoc_opt *o, int color) {
  hoc_opt_blockset *B = o->B;
  size_t n = 0;
  for (size_t b = B->queue_head[color], next; b != SIZE_MAX; b = next) {
    next = B->queue_next[b];
    B->queued[b] = 0;
    if (!B->scan_all[color] && block_active(o, b)) o->list[n++] = b;
  }
  B->queue_head[color] = SIZE_MAX;
  if (B->scan_all[color]) {
    B->scan_all[color] = 0;
    for (size_t a = B->color_start[color]; a < B->color_start[color + 1]; ++a)
      if (block_active(o, B->color_block[a])) o->list[n++] = B->color_block[a];
  }
  return n;
}

/* One colour: a Gauss-Newton step per active block, then a common
 * backtracking line search. *moved counts the nodes moved. */
hoc_status hoc_opt_do_color(hoc_opt *o, int color, hoc_opt_scratch *scr, int nthreads, size_t *moved) {
  hoc_mesh *m = o->m;
  size_t n = hoc_opt_select_active(o, color);
  *moved = 0;
  if (!n) return HOC_OK;
  size_t *list = o->list;
#pragma omp parallel for schedule(dynamic, 8) num_threads(nthreads)
  for (size_t a = 0; a < n; ++a) {
    size_t b = list[a];
    hoc_opt_scratch *s = &scr[omp_get_thread_num()];
    for (size_t c = o->B->bn_start[b]; c < o->B->bn_start[b + 1]; ++c) o->active[o->B->bn_node[c]] = 0;
    int nd = (int)(o->B->bd_start[b + 1] - o->B->bd_start[b]);
    double f;
    hoc_opt_block_model(o, b, s, &f, s->g, s->H);
    o->f0[b] = f;
    o->state[b] = 0;
    double *st = o->step + o->B->bd_start[b];
    if (!damped_solve(nd, s->H, s->g, s->L, st)) continue;
    double slope = 0;
    for (int c = 0; c < nd; ++c) slope += s->g[c] * st[c];
    /* limit every node's displacement to a quarter of its local size */
    double alpha = 1, len_max = 0;
    for (size_t c = o->B->bn_start[b]; c < o->B->bn_start[b + 1]; ++c) {
      size_t k = o->B->bn_node[c];
      const double *dz = o->dz + 6 * k, *sk = st + o->B->node_off[k];
      double dx[3];
      for (int d = 0; d < 3; ++d) dx[d] = dz[d] * sk[0] + (o->ndof[k] == 2 ? dz[3 + d] * sk[1] : 0);
      double len = sqrt(dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2]);
      len_max = fmax(len_max, len / o->hsize[k]);
    }
    if (len_max > HOC_OPT_STEP_CAP) alpha = HOC_OPT_STEP_CAP / len_max;
    if (!(slope < 0) || !isfinite(slope) || !(len_max * alpha > HOC_OPT_STEP_MIN)) continue;
    o->slope[b] = slope;
    o->alpha[b] = alpha;
    o->state[b] = 1;
  }
  size_t nt = 0;
  for (size_t a = 0; a < n; ++a)
    if (o->state[list[a]] == 1) list[nt++] = list[a];
  size_t n_eval = 0;
  for (size_t a = 0; a < nt; ++a) {
    size_t b = list[a];
    n_eval += o->B->bn_start[b + 1] - o->B->bn_start[b] + o->B->carry_start[b + 1] - o->B->carry_start[b];
  }
  size_t *elist = hoc_calloc(n_eval + 1, sizeof *elist), n_committed = 0;
  HOC_CHECK(elist, HOC_ERR_MEMORY, "out of memory");
  hoc_status status = HOC_OK;
  for (int attempt = 0; attempt < HOC_OPT_LINE_SEARCH_TRIES && nt; ++attempt) {
    size_t ne_list = 0;
    for (size_t a = 0; a < nt; ++a) {
      size_t b = list[a];
      for (int tries = 0; tries < HOC_OPT_RANGE_HALVINGS && !hoc_opt_set_trial_params(o, b); ++tries)
        o->alpha[b] *= HOC_OPT_BACKTRACK;
      for (size_t c = o->B->bn_start[b]; c < o->B->bn_start[b + 1]; ++c) elist[ne_list++] = o->B->bn_node[c];
      for (size_t j = o->B->carry_start[b]; j < o->B->carry_start[b + 1]; ++j) elist[ne_list++] = o->B->carry_node[j];
    }
    HOC_TRY_GOTO(hoc_opt_eval_trials(o, elist, ne_list, nthreads), done);
#pragma omp parallel for schedule(dynamic, 8) num_threads(nthreads)
    for (size_t a = 0; a < nt; ++a) {
      size_t b = list[a];
      hoc_opt_scratch *s = &scr[omp_get_thread_num()];
      double f;
      int ok = block_trial(o, b, s, o->f0[b] + HOC_OPT_ARMIJO * o->alpha[b] * o->slope[b], &f);
      if (ok) {
        for (size_t c = o->B->bn_start[b]; c < o->B->bn_start[b + 1]; ++c) hoc_opt_commit(o, o->B->bn_node[c]);
        for (size_t j = o->B->carry_start[b]; j < o->B->carry_start[b + 1]; ++j) hoc_opt_commit(o, o->B->carry_node[j]);
        o->fnew[b] = f;
        o->state[b] = 2;
      } else {
        o->alpha[b] *= HOC_OPT_BACKTRACK;
      }
    }
    size_t keep = 0;
    for (size_t a = 0; a < nt; ++a) {
      size_t b = list[a];
      if (o->state[b] != 2) {
        list[keep++] = b;
        continue;
      }
      o->state[b] = 0;
      o->committed[n_committed++] = b;
      size_t nodes = o->B->bn_start[b + 1] - o->B->bn_start[b];
      *moved += nodes;
      /* only a significant move wakes the neighbourhood (small ones would
       * spread waves of smaller ones through the whole mesh) */
      if (o->f0[b] - o->fnew[b] < o->wake_factor * o->min_gain * (double)nodes && !near_tangled(o, b))
        continue;
      /* wake every node of the elements it touches (itself included) */
      for (size_t c = o->B->be_start[b]; c < o->B->be_start[b + 1]; ++c) {
        const size_t *cn = m->conn + o->B->be_elem[c] * (size_t)o->np;
        for (int i = 0; i < o->np; ++i)
          hoc_opt_wake_node(o, cn[i]);
      }
    }
    nt = keep;
  }
  for (size_t a = 0; a < nt; ++a) o->state[list[a]] = 0; /* gave up: asleep */
    /* validity may have been gained where blocks moved */
#pragma omp parallel for schedule(dynamic, 8) num_threads(nthreads)
  for (size_t a = 0; a < n_committed; ++a) {
    size_t b = o->committed[a];
    hoc_opt_scratch *s = &scr[omp_get_thread_num()];
    for (size_t c = o->B->be_start[b]; c < o->B->be_start[b + 1]; ++c) {
      size_t e = o->B->be_elem[c];
      if (!o->valid[e] || !o->xvalid[e]) {
        hoc_opt_gather(o, e, s->x, s->n);
        if (!o->valid[e]) o->valid[e] = (unsigned char)!hoc_element_tangled(o->t, s->x, s->n, o->exact);
        o->xvalid[e] =
            o->valid[e] && (o->exact || !hoc_opt_guarded(o, e) || !hoc_element_folded(o->t, s->x, s->n));
      }
      if (!o->pvalid[e]) o->pvalid[e] = (unsigned char)hoc_opt_param_valid(o, e, s->uv);
    }
  }
done:
  free(elist);
  return status;
}

hoc_status hoc_opt_scratch_alloc(const hoc_opt *o, int nthreads, hoc_opt_scratch **out) {
  hoc_opt_scratch *s = hoc_calloc((size_t)nthreads, sizeof *s);
  HOC_CHECK(s, HOC_ERR_MEMORY, "out of memory");
  size_t np = (size_t)o->np, nq = (size_t)o->nq, nd = (size_t)(o->max_nd ? o->max_nd : 1);
  int failed = 0;
  for (int i = 0; i < nthreads; ++i) {
    s[i].x = hoc_calloc(3 * np, sizeof(double));
    s[i].n = hoc_calloc(3 * np, sizeof(double));
    size_t nr = nq + np + (size_t)o->t->nv + 1; /* + 1: a fold point */
    s[i].r = hoc_calloc(nr, sizeof(double));
    s[i].J = hoc_calloc(3 * nr * np, sizeof(double));
    s[i].uv = hoc_calloc(2 * np, sizeof(double));
    s[i].Jz = hoc_calloc(nr * nd, sizeof(double));
    s[i].H = hoc_calloc(nd * nd, sizeof(double));
    s[i].g = hoc_calloc(nd, sizeof(double));
    s[i].L = hoc_calloc(nd * nd, sizeof(double));
    s[i].w = hoc_calloc(np, sizeof(double));
    s[i].off = hoc_calloc(np, sizeof(int));
    s[i].nd = hoc_calloc(np, 1);
    if (!s[i].x || !s[i].n || !s[i].r || !s[i].J || !s[i].uv || !s[i].Jz || !s[i].H || !s[i].g ||
        !s[i].L || !s[i].w || !s[i].off || !s[i].nd)
      failed = 1;
  }
  *out = s;
  if (failed) return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  return HOC_OK;
}

void hoc_opt_scratch_free(hoc_opt_scratch *s, int nthreads) {
  if (!s) return;
  for (int i = 0; i < nthreads; ++i) {
    free(s[i].x);
    free(s[i].n);
    free(s[i].r);
    free(s[i].J);
    free(s[i].uv);
    free(s[i].Jz);
    free(s[i].H);
    free(s[i].g);
    free(s[i].L);
    free(s[i].w);
    free(s[i].off);
    free(s[i].nd);
  }
  free(s);
}

void hoc_opt_snapshot_free(hoc_opt_snapshot *s) {
  free(s->param);
  free(s->xyz);
  free(s->slot_uv);
  free(s->elem_uv);
  free(s->line_t);
}

/* Copy src of n doubles into *dst (allocated on first use). */
static hoc_status keep(double **dst, const double *src, size_t n) {
  if (!*dst) *dst = hoc_realloc(NULL, n + 1, sizeof **dst);
  HOC_CHECK(*dst, HOC_ERR_MEMORY, "out of memory for the best mesh reached");
  memcpy(*dst, src, n * sizeof **dst);
  return HOC_OK;
}

hoc_status hoc_opt_snapshot_take(hoc_opt_snapshot *s, const hoc_mesh *m, size_t tangled, double f) {
  HOC_TRY(keep(&s->param, m->param, 2 * m->n_nodes));
  HOC_TRY(keep(&s->xyz, m->xyz, 3 * m->n_nodes));
  HOC_TRY(keep(&s->slot_uv, m->slot_uv, 2 * m->n_slots));
  HOC_TRY(keep(&s->elem_uv, m->elem_uv, 2 * m->n_elems * (size_t)m->np));
  HOC_TRY(keep(&s->line_t, m->line_t, 2 * m->n_lines));
  s->tangled = tangled;
  s->objective = f;
  return HOC_OK;
}

void hoc_opt_snapshot_restore(const hoc_opt_snapshot *s, hoc_mesh *m) {
  memcpy(m->param, s->param, 2 * m->n_nodes * sizeof *s->param);
  memcpy(m->xyz, s->xyz, 3 * m->n_nodes * sizeof *s->xyz);
  memcpy(m->slot_uv, s->slot_uv, 2 * m->n_slots * sizeof *s->slot_uv);
  memcpy(m->elem_uv, s->elem_uv, 2 * m->n_elems * (size_t)m->np * sizeof *s->elem_uv);
  memcpy(m->line_t, s->line_t, 2 * m->n_lines * sizeof *s->line_t);
}

/* Polish ------------------------------------------------------------------ */

/* The final polish of the elements the sweeps leave tangled: a
 * derivative-free pattern search around each, one node at a time, on the
 * exact verdict itself. Gauss-Newton on the regularised objective trades a
 * fold against the shape of the whole neighbourhood and can settle with a
 * fold of a few thousandths where the surface's parametrisation is very
 * uneven (a face whose speed across its ends is a small fraction of that in
 * its middle); the
 * search looks at nothing but the patch's folds. A move is kept only if no
 * element of the patch that was valid turns tangled or folds in (u, v), the
 * nodes stay in order along their curves, and the patch has fewer tangled
 * elements or the same with less negative sigma. */

/* Element e's margin in the trial state of `moving` nodes: positive if the
 * exact test finds it valid; else its smallest sigma over its corners'
 * area if that is negative, or HOC_OPT_POLISH_HIDDEN_FOLD for a fold
 * between the samples. (Not sigma / |D phi|^2, which a node moved far away
 * shrinks towards 0: the search would improve the margin by moving a node
 * out of its element.) */
static double polish_margin(const hoc_opt *o, size_t e, double *x, double *n) {
  hoc_opt_gather(o, e, x, n);
  double eta, ms = 0;
  double q = hoc_element_quality_test(o->t, o->measure, x, n, 1, &eta, &ms);
  if (q > 0) return ms > 0 ? ms : DBL_MIN;
  double s = hoc_element_min_sigma_area(o->t, x, n);
  return s < 0 ? s : HOC_OPT_POLISH_HIDDEN_FOLD;
}

/* Tangled count and the sum of negative margins of elements el[0..n). */
static void polish_score(const hoc_opt *o, const size_t *el, size_t n, double *margin, double *x,
                         double *nrm, size_t *count, double *neg) {
  *count = 0;
  *neg = 0;
  for (size_t a = 0; a < n; ++a) {
    margin[a] = polish_margin(o, el[a], x, nrm);
    if (margin[a] < 0) {
      ++*count;
      *neg += margin[a];
    }
  }
}

/* One patch: the free nodes of the elements sharing a corner with e0. */
static hoc_status polish_patch(hoc_opt *o, size_t e0, unsigned char *mark) {
  hoc_mesh *m = o->m;
  int np = o->np;
  hoc_status status = HOC_OK;
  hoc_growlist gn = {0}, ge = {0};
  double *margin = NULL, *trial = NULL, *x = NULL, *nrm = NULL, *uv = NULL;
  unsigned char *pv = NULL;
  /* the patch's nodes, then every element using one of them (in order) */
  for (int c = 0; c < 3 && status == HOC_OK; ++c) {
    size_t corner = m->conn[e0 * (size_t)np + (size_t)c];
    for (size_t a = o->ne_start[corner]; a < o->ne_start[corner + 1]; ++a) {
      size_t e = o->ne_elem[a];
      for (int i = 0; i < np && status == HOC_OK; ++i) {
        size_t k = m->conn[e * (size_t)np + (size_t)i];
        if (!o->ndof[k] || o->moving[k]) continue;
        o->moving[k] = 1; /* (as a mark while collecting) */
        status = hoc_grow_push(&gn, k);
      }
    }
  }
  for (size_t a = 0; a < gn.n && status == HOC_OK; ++a)
    for (size_t b = o->ne_start[gn.v[a]]; b < o->ne_start[gn.v[a] + 1] && status == HOC_OK; ++b) {
      size_t e = o->ne_elem[b];
      if (mark[e]) continue;
      mark[e] = 1;
      status = hoc_grow_push(&ge, e);
    }
  for (size_t a = 0; a < gn.n; ++a)
    o->moving[gn.v[a]] = 0;
  for (size_t a = 0; a < ge.n; ++a)
    mark[ge.v[a]] = 0;
  if (status != HOC_OK || !gn.n) goto done; /* (every node fixed: nothing to move) */
  const size_t *nodes = gn.v, *el = ge.v, nn = gn.n, nel = ge.n;
  margin = malloc(2 * nel * sizeof *margin);
  pv = malloc(nel);
  x = malloc(3 * (size_t)np * sizeof *x);
  nrm = malloc(3 * (size_t)np * sizeof *nrm);
  uv = malloc(2 * (size_t)np * sizeof *uv);
  if (!(margin && pv && x && nrm && uv)) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  trial = margin + nel;
  size_t count;
  double neg;
  polish_score(o, el, nel, margin, x, nrm, &count, &neg);
  for (size_t a = 0; a < nel; ++a)
    pv[a] = (unsigned char)hoc_opt_param_valid(o, el[a], uv);
  size_t measures = nel;
  /* steps: a share of the node's local length, halved when no move helps */
  for (double share = HOC_OPT_POLISH_SHARE;
       share > HOC_OPT_POLISH_MIN_SHARE && count && measures < HOC_OPT_POLISH_MAX_MEASURES;) {
    int improved = 0;
    for (size_t a = 0; a < nn && count && measures < HOC_OPT_POLISH_MAX_MEASURES; ++a) {
      size_t k = nodes[a];
      int nd = o->ndof[k];
      for (int dir = 0; dir < 2 * nd && count; ++dir) {
        int d = dir / 2;
        const double *dz = o->dz + 6 * k + 3 * d;
        double speed = sqrt(dz[0] * dz[0] + dz[1] * dz[1] + dz[2] * dz[2]);
        if (!(speed > 0)) continue;
        double h = (dir % 2 ? -1 : 1) * share * o->hsize[k] / speed;
        o->tpar[2 * k] = m->param[2 * k];
        o->tpar[2 * k + 1] = m->param[2 * k + 1];
        o->tpar[2 * k + d] += h;
        if (m->dim[k] == HOC_ON_CURVE) {
          const hoc_cad_curve *c = &o->model->curves[m->entity[k]];
          if (!(c->period > 0) && (o->tpar[2 * k] < c->lo || o->tpar[2 * k] > c->hi)) continue;
        }
        status = hoc_opt_eval_trial(o, k);
        if (status != HOC_OK) goto done;
        o->moving[k] = 1;
        int ok = 1;
        for (size_t b = o->nl_start[k]; b < o->nl_start[k + 1] && ok; ++b)
          ok = hoc_opt_line_monotone(o, o->nl_line[b]);
        size_t tc = 0;
        double tneg = 0;
        for (size_t b = 0; b < nel && ok; ++b) {
          const size_t *cn = m->conn + el[b] * (size_t)np;
          int touches = 0;
          for (int i = 0; i < np && !touches; ++i)
            touches = cn[i] == k;
          trial[b] = touches ? polish_margin(o, el[b], x, nrm) : margin[b];
          measures += (size_t)touches;
          if (trial[b] < 0) {
            ok = margin[b] < 0; /* a valid element stays valid */
            tc++;
            tneg += trial[b];
          }
          if (ok && touches && pv[b]) ok = hoc_opt_param_valid(o, el[b], uv);
        }
        ok = ok && (tc < count || (tc == count && tneg > neg + HOC_OPT_POLISH_GAIN * fabs(neg)));
        if (ok) {
          hoc_opt_commit(o, k);
          memcpy(margin, trial, nel * sizeof *margin);
          count = tc;
          neg = tneg;
          improved = 1;
        }
        o->moving[k] = 0;
      }
    }
    if (!improved) share *= 0.5;
  }
done:
  free(gn.v);
  free(ge.v);
  free(margin);
  free(pv);
  free(x);
  free(nrm);
  free(uv);
  return status;
}

/* The polish of every element still tangled by the exact test (at most
 * HOC_OPT_POLISH_MAX_TANGLED of them), in element order; the caller counts what it
 * untangled at its next hoc_opt_sweep_start. */
hoc_status hoc_opt_polish(hoc_opt *o) {
  hoc_mesh *m = o->m;
  size_t tangled = 0;
  for (size_t e = 0; e < m->n_elems; ++e)
    tangled += o->qe[e] == 0.0;
  if (!tangled || tangled > HOC_OPT_POLISH_MAX_TANGLED) return HOC_OK;
  double *x = malloc(6 * (size_t)o->np * sizeof *x);
  unsigned char *mark = calloc(m->n_elems, 1);
  if (!x || !mark) {
    free(x);
    free(mark);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  hoc_status status = HOC_OK;
  for (size_t e = 0; e < m->n_elems && status == HOC_OK; ++e) {
    if (o->qe[e] != 0.0 || polish_margin(o, e, x, x + 3 * o->np) > 0) continue;
    status = polish_patch(o, e, mark);
  }
  free(x);
  free(mark);
  /* every element again at the next hoc_opt_sweep_start */
  memset(o->dirty, 1, m->n_elems);
  return status;
}

hoc_status hoc_mesh_polish(hoc_mesh *mesh, hoc_measure measure, int fix_curves, size_t *untangled) {
  HOC_CHECK(mesh && untangled, HOC_ERR_ARGUMENT, "NULL argument");
  *untangled = 0;
  hoc_opt ctx = {0};
  double f, qmin;
  size_t before = 0, after = 0;
  hoc_status status = hoc_mesh_update_xyz(mesh);
  if (status == HOC_OK) status = hoc_opt_setup(&ctx, mesh, measure, fix_curves, NULL, 0);
  if (status == HOC_OK) status = hoc_opt_eval_all(&ctx);
  ctx.exact = 1;
  if (status == HOC_OK) status = hoc_opt_sweep_start(&ctx, &f, &qmin, &before);
  if (status == HOC_OK) status = hoc_opt_polish(&ctx);
  if (status == HOC_OK) status = hoc_opt_sweep_start(&ctx, &f, &qmin, &after);
  if (status == HOC_OK) *untangled = before > after ? before - after : 0;
  hoc_opt_free(&ctx);
  return status;
}

/* Above HOC_OPT_PROTECT_MAX_ORDER, in a whole-mesh run, the elements that
 * start valid (exact test) with q < HOC_OPT_FRAGILE_Q are fragile: no step
 * may fold them between the samples (hoc_opt_guarded), and they are never
 * relaxed (relaxed). Sets o->fragile from qe; returns how many. */
static size_t mark_fragile(hoc_opt *o) {
  const hoc_mesh *m = o->m;
  size_t n = 0;
  if (m->order <= HOC_OPT_PROTECT_MAX_ORDER || o->touched) return 0;
  for (size_t e = 0; e < m->n_elems; ++e) {
    o->fragile[e] = o->qe[e] > 0 && o->qe[e] < HOC_OPT_FRAGILE_Q;
    n += o->fragile[e];
  }
  return n;
}

/* One run of the optimiser from the mesh as it is (see hoc_mesh_optimize);
 * its sweeps are numbered from it0 + 1, its seconds from t0; *limited:
 * its first phase used all its sweeps with elements still tangled. */
hoc_status hoc_opt_run(hoc_mesh *mesh, const hoc_optimize_options *options, int protect,
                               int it0, double t0, hoc_optimize_result *result, int *limited) {
  *limited = 0;
  hoc_optimize_options o;
  hoc_optimize_options_default(&o);
  if (options) o = *options;
  if (o.max_iterations <= 0) o.max_iterations = HOC_OPT_DEFAULT_MAX_ITERATIONS;
  if (!(o.tolerance > 0)) o.tolerance = HOC_OPT_DEFAULT_TOLERANCE;
  HOC_CHECK(o.measure == HOC_MEASURE_SHAPE || o.measure == HOC_MEASURE_ODDY, HOC_ERR_ARGUMENT,
            "unknown distortion measure %d", (int)o.measure);
  HOC_CHECK(o.max_iterations <= HOC_OPT_MAX_ITERATIONS_LIMIT, HOC_ERR_ARGUMENT, "too many iterations requested");
  HOC_CHECK(isfinite(o.tolerance), HOC_ERR_ARGUMENT, "tolerance must be a finite number");
  HOC_CHECK(o.free_rings >= 0, HOC_ERR_ARGUMENT, "free_rings must not be negative");
  hoc_opt ctx = {0};
  hoc_opt_scratch *scr = NULL;
  int nthreads = omp_get_max_threads();
  /* every node on the CAD from the start (a mesh read as written may have
   * nodes off the surface) */
  hoc_status status = hoc_mesh_update_xyz(mesh);
  if (status == HOC_OK) mesh->off_cad = 0;
  if (status == HOC_OK)
    status = hoc_opt_setup(&ctx, mesh, o.measure, o.fix_curves, o.free_elements, o.free_rings);
  ctx.protect = protect; /* (setup clears ctx) */
  if (status == HOC_OK) status = hoc_opt_eval_all(&ctx);
  if (status == HOC_OK) status = hoc_opt_scratch_alloc(&ctx, nthreads, &scr);
  if (status != HOC_OK) {
    hoc_opt_scratch_free(scr, nthreads);
    hoc_opt_free(&ctx);
    return status;
  }
  hoc_optimize_result res = {0};
  hoc_opt_snapshot best = {0}, pre = {0}; /* pre: the state before the polish */
  best.tangled = SIZE_MAX;
  for (size_t i = 0; i < mesh->n_nodes; ++i) {
    ctx.active[i] = ctx.ndof[i] > 0;
    res.free_nodes += ctx.ndof[i] > 0;
  }
  hoc_opt_wake_all(&ctx);
  double f, qmin;
  size_t tangled;
  /* the initial tangled count by the exact test (as measuring counts),
   * then the first phase's sampled state */
  ctx.exact = 1;
  HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
  res.tangled_initial = tangled;
  res.fragile = mark_fragile(&ctx);
  /* the first phase counts at the samples; a local repair (free_elements)
   * has no first phase: its few folds are counted by the exact test from
   * the start (the aircraft at order 10, a red-green split of its 11 folds:
   * 32 -> 1 so, where 32 -> 2 at the samples became 26 by the exact test
   * and went no lower than 11 in the exact phase) */
  ctx.exact = ctx.touched != NULL;
  memset(ctx.dirty, 1, mesh->n_elems);
  HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
  res.objective_initial = f;
  size_t fewest = tangled; /* and res.best_iteration = 0: when it was reached */
  if (tangled) HOC_TRY_GOTO(hoc_opt_snapshot_take(&best, mesh, tangled, f), done);
  /* last: the last sweep of this attempt; since: the sweep before the
   * mesh's run of untangled sweeps (or the second attempt) began */
  int stalled = 0, last = it0 + o.max_iterations, since = it0;
  int fell = it0; /* the last sweep of this attempt with a new fewest tangled */
  int smoothing = 0; /* sweeps after a polish that left none tangled */
  int cut = 0;  /* this attempt was ended before its sweeps ran out */
  double hist_f[HOC_OPT_STAGNATION_SWEEPS + 1], hist_q[HOC_OPT_STAGNATION_SWEEPS + 1];
  int it = it0;
  res.best_iteration = it0;
sweeps:
  for (;;) {
    ++it;
    if (it > last) {
      /* still tangled when the sweeps run out (or nothing moves): a second
       * attempt of half as many sweeps from the best state reached, with
       * the (u, v) rule relaxed too (relaxed_uv). Not in a local repair:
       * its regularisation is never raised, so nothing is relaxed and the
       * second attempt would only go over the first one's ground again
       * (the aircraft at order 10: sweeps 39-53 of a red-green split's
       * repair, no fewer tangled) */
      if (!tangled || ctx.relax_uv || best.tangled == SIZE_MAX || ctx.touched) {
        res.stopped_at_limit = tangled && !cut;
        break;
      }
      hoc_opt_snapshot_restore(&best, mesh);
      HOC_TRY_GOTO(hoc_opt_eval_all(&ctx), done);
      ctx.relax_uv = 1;
      ctx.eps = HOC_OPT_EPS;
      stalled = 0;
      since = fell = it - 1;
      cut = 0;
      last = it - 1 + HOC_OPT_LATER_SWEEPS(o.max_iterations);
      memset(ctx.dirty, 1, mesh->n_elems);
      hoc_opt_wake_all(&ctx);
      HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
      res.second_attempt = it;
    }
    size_t moved = 0;
    int local = ctx.exact && tangled;
    if (local) hoc_opt_mark_near(&ctx);
    else if (ctx.local) hoc_opt_wake_all(&ctx); /* the nodes left awake elsewhere */
    ctx.local = local;
    /* nodes near tangled elements and nodes of poor elements (q below half
     * the mean: those that set the mesh's worst quality) never sleep */
    double qmean = 0;
    for (size_t e = 0; e < mesh->n_elems; ++e) qmean += ctx.qe[e];
    qmean /= (double)(mesh->n_elems ? mesh->n_elems : 1);
    for (size_t e = 0; e < mesh->n_elems; ++e)
      if (ctx.region[e] || ctx.qe[e] < HOC_OPT_POOR_Q_SHARE * qmean)
        for (int i = 0; i < ctx.np; ++i) {
          size_t node = mesh->conn[e * (size_t)ctx.np + (size_t)i];
          if (ctx.ndof[node]) hoc_opt_wake_node(&ctx, node);
        }
    /* a step worth less than a small share of the average node's part of f
     * puts its block to sleep */
    ctx.min_gain =
        o.tolerance * free_objective(&ctx, f) / (double)(res.free_nodes ? res.free_nodes : 1);
    /* while untangling, every move wakes its neighbourhood (room is made by
     * moving nodes further out); then only significant ones do */
    ctx.wake_factor = tangled ? HOC_OPT_WAKE_UNTANGLING : HOC_OPT_WAKE_SMOOTHING;
    if (it == it0 + 1) {
      HOC_TRY_GOTO(hoc_opt_screen(&ctx), done);
      hoc_opt_wake_all(&ctx);
      for (size_t e = 0; e < mesh->n_elems; ++e)
        if (ctx.qe[e] < HOC_OPT_POOR_Q_SHARE * qmean)
          for (int i = 0; i < ctx.np; ++i) {
            size_t node = mesh->conn[e * (size_t)ctx.np + (size_t)i];
            if (ctx.ndof[node]) hoc_opt_wake_node(&ctx, node);
          }
    }
    /* the natural blocks, then every node on its own */
    for (int fam = 0; fam < 2; ++fam) {
      ctx.B = &ctx.fam[fam];
      for (int c = 0; c < ctx.B->n_colors; ++c) {
        size_t mc;
        HOC_TRY_GOTO(hoc_opt_do_color(&ctx, c, scr, nthreads, &mc), done);
        moved += mc;
      }
    }
    ctx.B = &ctx.fam[0];
    size_t tangled_before = tangled;
    HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
    res.iterations = it;
    if (tangled < fewest) {
      fewest = tangled;
      res.best_iteration = fell = it;
    }
    /* no new fewest for HOC_OPT_STALL_SWEEPS sweeps: this attempt ends (the count
     * has been seen to fall again after 32 on t20 at order 10) */
    if (tangled && it - fell >= (ctx.exact ? HOC_OPT_EXACT_STALL_SWEEPS : HOC_OPT_STALL_SWEEPS) && it < last) {
      last = it;
      cut = 1;
    }
    if (tangled && tangled < best.tangled)
      HOC_TRY_GOTO(hoc_opt_snapshot_take(&best, mesh, tangled, f), done);
    /* untangling that stalls: a smoother regularised landscape (larger
     * delta) for a while; back to the small one as soon as it moves on */
    if (tangled && tangled >= tangled_before) {
      /* cycle 1e-3 -> 1e-2 -> 1e-1 -> 1e-3: a large delta smooths the
       * landscape, a small one pushes the last folds open (in the exact
       * phase too: the analytic cylinder's corner folds open only so) */
      /* Not in a local repair (free_elements): there the relaxed region
       * folds more than it opens and the count comes back no lower (the
       * aircraft at order 10, a red-green split of its 11 folds, exact
       * test from the start: 1 left in 53 sweeps without the raise, 2 in
       * 43 with it, its raises climbing to 53) */
      if (!ctx.touched && ++stalled >= HOC_OPT_EPS_STALL) {
        ctx.eps = ctx.eps < HOC_OPT_EPS_RAISE_BELOW ? ctx.eps * HOC_OPT_EPS_RAISE : HOC_OPT_EPS;
        stalled = 0;
        memset(ctx.dirty, 1, mesh->n_elems); /* every delta changes */
        HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
      }
    } else if (tangled < tangled_before && ctx.eps > HOC_OPT_EPS) {
      ctx.eps = HOC_OPT_EPS;
      stalled = 0;
      memset(ctx.dirty, 1, mesh->n_elems);
      HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
    } else {
      stalled = 0;
    }
    if (o.progress) {
      hoc_optimize_iteration info = {it, f, qmin, tangled, moved, hoc_opt_now() - t0, 1 + ctx.relax_uv};
      if (o.progress(o.progress_user, &info)) {
        status = HOC_ERROR(HOC_ERR_INTERRUPTED, "optimisation interrupted");
        goto done;
      }
    }
    size_t active = 0;
    for (size_t i = 0; i < mesh->n_nodes; ++i) active += ctx.active[i];
    if (!active || !moved) {
      res.converged = tangled == 0;
      if (tangled && !ctx.relax_uv && !ctx.touched) {
        last = it; /* the second attempt */
        cut = 1;
        continue;
      }
      break;
    }
    /* stagnation: untangled for the last 10 sweeps, over which f fell by
     * less than 5% and the worst element gained less than 0.005 (compared
     * with a tangled sweep, f is regularised and q is 0: no measure of
     * progress) */
    int h = HOC_OPT_STAGNATION_SWEEPS + 1, now = it % h, then = (it - HOC_OPT_STAGNATION_SWEEPS) % h;
    hist_f[now] = free_objective(&ctx, f);
    hist_q[now] = qmin;
    if (tangled) since = it;
    if (tangled == 0 && it - since > HOC_OPT_STAGNATION_SWEEPS &&
        hist_f[then] - hist_f[now] < HOC_OPT_STAGNATION_F * hist_f[then] &&
        qmin - hist_q[then] < HOC_OPT_STAGNATION_Q) {
      res.converged = 1;
      break;
    }
  }
  if (best.tangled != SIZE_MAX && tangled > best.tangled) {
    hoc_opt_snapshot_restore(&best, mesh); /* more tangled than once: the best state reached */
    HOC_TRY_GOTO(hoc_opt_eval_all(&ctx), done);
    memset(ctx.dirty, 1, mesh->n_elems);
    HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
  }
  /* The second phase: the exact fold tests (hoc_element_folded) find
   * folds between the samples (an optimiser that keeps sigma > 0 at samples
   * can pinch an edge between two), whether or not the samples still see
   * some elements tangled (gmsh's order-3 bottle: 3 by samples, 48 by the
   * exact test; this phase leaves 11 where waiting for the samples to say
   * 0 left the 48), unless the sweeps ran out. From
   * here on the tangle test is exact, as measuring's, and the untangling
   * residuals see the edges densely. Not from the start: there it blocks
   * steps through states that fold between samples on the way to a better
   * mesh (t20 at order 5 ended with min q 0.33 instead of 0.49). */
  if (!ctx.exact) {
    ctx.exact = 1;
    memset(ctx.dirty, 1, mesh->n_elems);
    size_t sampled = tangled;
    *limited = res.stopped_at_limit;
    HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
    /* (not after sweeps cut short by --max-iterations with elements still
     * tangled by samples: the caller asked for no more) */
    if (tangled > sampled && (!sampled || !res.stopped_at_limit)) {
      res.exact_phase = it + 1;
      HOC_TRY_GOTO(hoc_opt_snapshot_take(&best, mesh, tangled, f), done);
      fewest = tangled;
      res.converged = 0;
      ctx.relax_uv = 0;
      ctx.eps = HOC_OPT_EPS;
      stalled = 0;
      since = fell = it;
      cut = 0;
      last = it + HOC_OPT_LATER_SWEEPS(o.max_iterations);
      goto sweeps; /* (each sweep wakes the nodes around the folds) */
    }
  }
  /* the few folds the sweeps leave: the polish (not when the sweeps ran
   * out: --max-iterations asked for no more) */
  if (tangled && ctx.exact && !res.stopped_at_limit) {
    size_t before = tangled;
    HOC_TRY_GOTO(hoc_opt_snapshot_take(&pre, mesh, tangled, f), done);
    HOC_TRY_GOTO(hoc_opt_polish(&ctx), done);
    HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
    if (tangled < before) {
      res.polished += before - tangled;
      if (!tangled && !smoothing) {
        /* all valid now: sweeps again, which keep every element valid,
         * smooth the polished patches (their elements come out of the
         * search barely valid) */
        smoothing = 1;
        res.converged = 0;
        ctx.eps = HOC_OPT_EPS;
        stalled = 0;
        since = fell = it;
        cut = 0;
        last = it + HOC_OPT_LATER_SWEEPS(o.max_iterations);
        hoc_opt_wake_all(&ctx);
        goto sweeps;
      }
    } else { /* none untangled: the sweeps' state, whose shapes are better */
      hoc_opt_snapshot_restore(&pre, mesh);
      HOC_TRY_GOTO(hoc_opt_eval_all(&ctx), done);
      memset(ctx.dirty, 1, mesh->n_elems);
      HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
    }
  }
done:
  hoc_opt_snapshot_free(&pre);
  hoc_opt_snapshot_free(&best);
  res.objective_final = f;
  res.tangled_final = tangled;
  res.seconds = hoc_opt_now() - t0;
  if (result) *result = res;
  hoc_opt_scratch_free(scr, nthreads);
  hoc_opt_free(&ctx);
  return status;
}

hoc_status hoc_mesh_optimize(hoc_mesh *mesh, const hoc_optimize_options *options,
                             hoc_optimize_result *result) {
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "no mesh given");
  double t0 = hoc_opt_now();
  hoc_opt_snapshot start = {0}, first = {0};
  hoc_optimize_result a = {0}, b = {0};
  int limited = 0, limited_b;
  hoc_status status = hoc_opt_snapshot_take(&start, mesh, 0, 0);
  if (status == HOC_OK) status = hoc_opt_run(mesh, options, 0, 0, t0, &a, &limited);
  /* Left tangled (not for want of sweeps): a protected run from the start,
   * in which the first phase's steps may not fold an element between
   * samples that the exact test finds valid, kept if it leaves fewer
   * tangled. Not always: the unprotected first phase passes through such
   * folds on its way to better meshes (t20 at order 5: min q 0.49, 0.12
   * protected), but on gmsh's coarse meshes its folds between samples
   * outrun the exact phase (gmsh 5.0's order-3 bottle: 11 left, 7
   * protected, and 0 after four splits). Not above order 5: there every
   * trial of its first phase runs the exact tests, whose cost grows as
   * p^4 (the aircraft at order 10: 8-24 s a sweep of the exact phase,
   * 0.4-4 s of the first), and `hocad` splits what is left anyway. Not in
   * a local repair (free_elements): it runs the exact test from its first
   * sweep, as a protected run would, so that run would only repeat it. */
  if (status == HOC_OK && a.tangled_final && !limited && mesh->order <= HOC_OPT_PROTECT_MAX_ORDER &&
      !(options && options->free_elements)) {
    status = hoc_opt_snapshot_take(&first, mesh, a.tangled_final, a.objective_final);
    if (status == HOC_OK) {
      hoc_opt_snapshot_restore(&start, mesh);
      status = hoc_opt_run(mesh, options, 1, a.iterations, t0, &b, &limited_b);
    }
    if (status == HOC_OK && b.tangled_final < a.tangled_final) {
      b.protected_run = a.iterations + 1;
      b.tangled_initial = a.tangled_initial;
      b.objective_initial = a.objective_initial;
      a = b;
    } else if (first.param) {
      hoc_opt_snapshot_restore(&first, mesh); /* (also when the protected run failed) */
      if (status == HOC_OK) a.iterations = b.iterations; /* sweeps made, though not kept */
    }
  }
  a.seconds = hoc_opt_now() - t0;
  hoc_opt_snapshot_free(&start);
  hoc_opt_snapshot_free(&first);
  if (result && status == HOC_OK) *result = a;
  return status;
}

/* Gradient check -------------------------------------------------------- */

/* Local objective of block b with unknown `dof` moved by h (the nodes it
 * carries follow), positions and normals evaluated on the CAD. */
static hoc_status block_f_at(hoc_opt *o, size_t b, int dof, double h, hoc_opt_scratch *s, double *f) {
  double *st = o->step + o->B->bd_start[b];
  int nd = (int)(o->B->bd_start[b + 1] - o->B->bd_start[b]);
  for (int c = 0; c < nd; ++c) st[c] = c == dof ? h : 0;
  o->alpha[b] = 1;
  hoc_opt_set_trial_params(o, b);
  size_t n = 0;
  size_t nlist = o->B->bn_start[b + 1] - o->B->bn_start[b] + o->B->carry_start[b + 1] - o->B->carry_start[b];
  size_t *list = hoc_calloc(nlist + 1, sizeof *list);
  HOC_CHECK(list, HOC_ERR_MEMORY, "out of memory");
  for (size_t c = o->B->bn_start[b]; c < o->B->bn_start[b + 1]; ++c) list[n++] = o->B->bn_node[c];
  for (size_t j = o->B->carry_start[b]; j < o->B->carry_start[b + 1]; ++j) list[n++] = o->B->carry_node[j];
  hoc_status st2 = hoc_opt_eval_trials(o, list, n, 1);
  free(list);
  HOC_TRY(st2);
  hoc_opt_set_moving(o, b, 1);
  *f = 0;
  for (size_t a = o->B->be_start[b]; a < o->B->be_start[b + 1]; ++a) {
    size_t e = o->B->be_elem[a];
    hoc_opt_gather(o, e, s->x, s->n);
    int nr = hoc_opt_elem_residuals(o, e, s->x, s->n, NULL, s->r, NULL, NULL);
    for (int q = 0; q < nr; ++q) *f += s->r[q] * s->r[q];
  }
  hoc_opt_set_moving(o, b, 0);
  return HOC_OK;
}

hoc_status hoc_mesh_check_gradient(hoc_mesh *mesh, hoc_measure measure, int fix_curves,
                                   int samples, double *max_rel_error) {
  HOC_CHECK(mesh && max_rel_error, HOC_ERR_ARGUMENT, "NULL argument");
  HOC_CHECK(samples > 0, HOC_ERR_ARGUMENT, "need at least one sample");
  hoc_opt ctx = {0};
  hoc_opt_scratch *scr = NULL;
  hoc_status status = hoc_opt_setup(&ctx, mesh, measure, fix_curves, NULL, 0);
  if (status == HOC_OK) status = hoc_opt_eval_all(&ctx);
  if (status == HOC_OK) status = hoc_opt_scratch_alloc(&ctx, 1, &scr);
  if (status != HOC_OK) {
    hoc_opt_scratch_free(scr, 1);
    hoc_opt_free(&ctx);
    return status;
  }
  double f, qmin;
  size_t tangled;
  HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
  size_t stride = ctx.B->n_blocks > (size_t)samples ? ctx.B->n_blocks / (size_t)samples : 1;
  double worst = 0, gmax = 0;
  for (size_t b = 0; b < ctx.B->n_blocks; b += stride) {
    double fl;
    hoc_opt_block_model(&ctx, b, scr, &fl, scr->g, scr->H);
    int nd = (int)(ctx.B->bd_start[b + 1] - ctx.B->bd_start[b]);
    for (int d = 0; d < nd; ++d) {
      /* the node owning this unknown sets the scale of the step */
      size_t k = ctx.B->bn_node[ctx.B->bn_start[b]];
      for (size_t c = ctx.B->bn_start[b]; c < ctx.B->bn_start[b + 1]; ++c)
        if (ctx.B->node_off[ctx.B->bn_node[c]] <= d) k = ctx.B->bn_node[c];
      int dd = d - ctx.B->node_off[k];
      const double *dz = ctx.dz + 6 * k + 3 * dd;
      double speed = sqrt(dz[0] * dz[0] + dz[1] * dz[1] + dz[2] * dz[2]);
      if (!(speed > 0)) continue;
      double h = HOC_OPT_FD_STEP * ctx.hsize[k] / speed, gd = scr->g[d];
      /* fourth-order central difference */
      double fp, fm, fp2, fm2;
      HOC_TRY_GOTO(block_f_at(&ctx, b, d, h, scr, &fp), done);
      HOC_TRY_GOTO(block_f_at(&ctx, b, d, -h, scr, &fm), done);
      HOC_TRY_GOTO(block_f_at(&ctx, b, d, 2 * h, scr, &fp2), done);
      HOC_TRY_GOTO(block_f_at(&ctx, b, d, -2 * h, scr, &fm2), done);
      double fd = (8 * (fp - fm) - (fp2 - fm2)) / (12 * h);
      if (!isfinite(fd)) continue;
      /* per unit length, to compare unknowns of different nodes */
      worst = fmax(worst, fabs(fd - gd) / speed);
      gmax = fmax(gmax, fabs(gd) / speed);
    }
  }
  /* a norm-wise relative error, as PETSc's -snes_test_jacobian reports */
  *max_rel_error = gmax > 0 ? worst / gmax : worst;
done:
  hoc_opt_scratch_free(scr, 1);
  hoc_opt_free(&ctx);
  return status;
}
