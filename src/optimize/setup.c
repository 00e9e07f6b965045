/* The optimiser's setup: the adjacency of nodes, elements, slots and
 * lines, each node's unknowns, the state arrays, and the derivatives of
 * every free node's position.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "core/geometry.h"
#include "optimize/optimize_impl.h"
#include "optimize/tunables.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

void hoc_opt_free(hoc_opt *o) {
  for (int f = 0; f < 2; ++f) {
    hoc_opt_blockset *b = &o->fam[f];
    void *q[] = {b->bn_start,    b->bn_node,    b->be_start,    b->be_start ? b->be_elem : NULL,
                 b->bd_start,    b->node_block, b->node_off,    b->carry_start,
                 b->carry_node,  b->carry_code, b->color_start, b->color_block,
                 b->block_color, b->queue_head, b->queue_next,  b->queued,
                 b->scan_all,    b->cpos,       b->cbd};
    for (size_t i = 0; i < sizeof q / sizeof *q; ++i)
      free(q[i]);
  }
  void *p[] = {
      o->adj.ndof,        o->adj.ne_start, o->adj.ne_elem,  o->adj.ne_local,    o->adj.ns_start,
      o->adj.ns_slot,     o->adj.nl_start, o->adj.nl_line,  o->node.dz,         o->node.normal,
      o->el.delta,        o->el.valid,     o->el.pvalid,    o->adj.on_boundary, o->el.region,
      o->el.was_region,   o->el.dirty,     o->el.delta_own, o->el.fe,           o->el.qe,
      o->adj.elem_h,      o->node.active,  o->node.moving,  o->trial.step,      o->trial.alpha,
      o->trial.f0,        o->trial.fnew,   o->trial.slope,  o->trial.state,     o->trial.list,
      o->trial.committed, o->trial.tpar,   o->trial.txyz,   o->trial.tdz,       o->trial.tslot_uv,
      o->trial.tnormal,   o->trial.tix,    o->trial.tsbase, o->el.xvalid,    o->node.near,    o->el.near_e,       o->adj.touched,
      o->el.has_fold,     o->el.fold_rs,   o->el.fragile,   o->fc.slot,         o->fc.pool,
      o->fc.owner,        o->fc.fresh,     o->fc.want};
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
    if (!node[i]) o->adj.ndof[i] = 0;
  memset(elem, 0, ne);
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < np && !elem[e]; ++k) elem[e] = o->adj.ndof[m->conn[e * np + k]] > 0;
  o->adj.touched = elem;
  free(node);
  return HOC_OK;
}

/* A compressed row of n rows and `total` items (start[n+1], items[total])
 * as 32-bit indices into *start32 and *items32; both given arrays freed. */
static hoc_status narrow_csr(size_t n, size_t total, size_t **start, size_t **items,
                             uint32_t **start32, uint32_t **items32) {
  *start32 = hoc_realloc(NULL, n + 1, sizeof **start32);
  *items32 = hoc_realloc(NULL, total + 1, sizeof **items32);
  for (size_t i = 0; *start32 && i <= n; ++i) (*start32)[i] = (uint32_t)(*start)[i];
  for (size_t i = 0; *items32 && i < total; ++i) (*items32)[i] = (uint32_t)(*items)[i];
  free(*start);
  free(*items);
  *start = *items = NULL;
  HOC_CHECK(*start32 && *items32, HOC_ERR_MEMORY, "out of memory for the optimiser's adjacency");
  return HOC_OK;
}

/* hoc_opt_csr_alloc into arrays of the caller's (nothing left allocated
 * on failure). */
static hoc_status csr_alloc_local(size_t n, size_t total, size_t **start, size_t **items) {
  hoc_status status = hoc_opt_csr_alloc(n, total, start, items);
  if (status != HOC_OK) {
    free(*start);
    free(*items);
    *start = *items = NULL;
  }
  return status;
}

/* Whether curve node i is at a pole of a face around it: a pinch's point
 * (mesh/pinch.c), which its curve only passes through: it stays there. */
static int at_pole(const hoc_opt *o, const hoc_mesh *m, size_t i) {
  for (uint32_t j = o->adj.ns_start[i]; j < o->adj.ns_start[i + 1]; ++j)
    if (m->slot_pole[o->adj.ns_slot[j]]) return 1;
  return 0;
}

hoc_status hoc_opt_setup(hoc_opt *o, hoc_mesh *m, hoc_measure measure, int fix_curves,
                        const unsigned char *free_elements, int free_rings) {
  memset(o, 0, sizeof *o);
  o->m = m;
  o->model = m->model;
  o->measure = measure;
  o->cfg.eps = HOC_OPT_EPS;
  HOC_TRY(hoc_quality_tables_get(m->order, m->nodeset, &o->t));
  o->np = o->t->np;
  o->nq = o->t->nq;
  size_t nn = m->n_nodes, ne = m->n_elems, np = (size_t)o->np;
  /* (node, element and list indices of the blocks and of a trial are
   * 32-bit: a block list has at most 3 entries per node of an element) */
  HOC_CHECK(nn < UINT32_MAX / 2 && ne * np < UINT32_MAX / 4 && m->n_slots < UINT32_MAX / 4 &&
                m->n_lines * ((size_t)m->order + 1) < UINT32_MAX / 4,
            HOC_ERR_ARGUMENT,
            "mesh too large for the optimiser (%zu nodes, %zu elements)", nn, ne);
  HOC_ALLOC(o->adj.ndof, nn);
  HOC_ALLOC(o->adj.ne_local, ne * np + 1);
  size_t *start = NULL, *items = NULL;
  HOC_TRY(csr_alloc_local(nn, ne * np, &start, &items));
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < np; ++k) start[m->conn[e * np + k] + 1]++;
  hoc_opt_csr_finish_counts(nn, start);
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < np; ++k) {
      size_t i = m->conn[e * np + k], pos = start[i]++;
      items[pos] = e;
      o->adj.ne_local[pos] = (uint16_t)k;
    }
  hoc_opt_csr_restore(nn, start);
  HOC_TRY(narrow_csr(nn, ne * np, &start, &items, &o->adj.ne_start, &o->adj.ne_elem));
  HOC_TRY(csr_alloc_local(nn, m->n_slots, &start, &items));
  for (size_t s = 0; s < m->n_slots; ++s) start[m->slot_node[s] + 1]++;
  hoc_opt_csr_finish_counts(nn, start);
  for (size_t s = 0; s < m->n_slots; ++s) items[start[m->slot_node[s]]++] = s;
  hoc_opt_csr_restore(nn, start);
  HOC_TRY(narrow_csr(nn, m->n_slots, &start, &items, &o->adj.ns_start, &o->adj.ns_slot));
  size_t lp = (size_t)m->order + 1;
  HOC_TRY(csr_alloc_local(nn, m->n_lines * lp, &start, &items));
  for (size_t l = 0; l < m->n_lines; ++l)
    for (size_t k = 0; k < lp; ++k) start[m->line_conn[l * lp + k] + 1]++;
  hoc_opt_csr_finish_counts(nn, start);
  for (size_t l = 0; l < m->n_lines; ++l)
    for (size_t k = 0; k < lp; ++k) items[start[m->line_conn[l * lp + k]]++] = l;
  hoc_opt_csr_restore(nn, start);
  HOC_TRY(narrow_csr(nn, m->n_lines * lp, &start, &items, &o->adj.nl_start, &o->adj.nl_line));
  for (size_t i = 0; i < nn; ++i) {
    if (o->adj.ne_start[i + 1] == o->adj.ne_start[i]) continue; /* used by no element */
    if (m->dim[i] == HOC_ON_FACE) o->adj.ndof[i] = 2;
    else if (m->dim[i] == HOC_ON_CURVE && !fix_curves &&
             !m->model->curves[m->entity[i]].degenerate && !at_pole(o, m, i))
      o->adj.ndof[i] = 1;
  }
  if (free_elements) HOC_TRY(restrict_free(o, free_elements, free_rings));
  /* the two families at once (each fills only its own blockset) */
  hoc_par_error err = {0};
#pragma omp parallel for schedule(static, 1) num_threads(2) if (omp_get_max_threads() > 1)
  for (int family = 0; family < 2; ++family)
    hoc_par_error_catch(&err, hoc_opt_build_blocks(o, family));
  HOC_TRY(hoc_par_error_raise(&err));
  o->B = &o->fam[0]; /* family 0 is current by default */
  o->max_nd = o->fam[0].max_nd > o->fam[1].max_nd ? o->fam[0].max_nd : o->fam[1].max_nd;
  /* the trial's per-block arrays hold the largest colour of either family */
  size_t nb = o->fam[0].max_color > o->fam[1].max_color ? o->fam[0].max_color : o->fam[1].max_color;
  size_t nd_total = o->fam[0].max_color_nd > o->fam[1].max_color_nd ? o->fam[0].max_color_nd
                                                                     : o->fam[1].max_color_nd;
  HOC_ALLOC(o->node.dz, 6 * nn);
  HOC_ALLOC(o->node.normal, 3 * m->n_slots + 3);
  HOC_ALLOC(o->el.delta, ne);
  HOC_ALLOC(o->el.valid, ne);
  HOC_ALLOC(o->el.xvalid, ne);
  HOC_ALLOC(o->el.fragile, ne);
  memset(o->el.fragile, 0, ne);
  HOC_ALLOC(o->el.pvalid, ne);
  HOC_ALLOC(o->adj.on_boundary, ne);
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < np; ++k)
      o->adj.on_boundary[e] |= m->dim[m->conn[e * np + k]] != HOC_ON_FACE;
  HOC_ALLOC(o->el.region, ne);
  HOC_ALLOC(o->el.was_region, ne);
  HOC_ALLOC(o->el.dirty, ne);
  HOC_ALLOC(o->el.delta_own, ne);
  HOC_ALLOC(o->el.has_fold, ne);
  HOC_ALLOC(o->el.fold_rs, 2 * ne);
  HOC_ALLOC(o->el.fe, ne);
  HOC_ALLOC(o->el.qe, ne);
  memset(o->el.dirty, 1, ne);
  HOC_ALLOC(o->adj.elem_h, ne);
  HOC_ALLOC(o->node.active, nn);
  HOC_ALLOC(o->node.near, nn);
  HOC_ALLOC(o->el.near_e, ne);
  HOC_ALLOC(o->node.moving, nn);
  HOC_ALLOC(o->trial.step, nd_total + 1);
  HOC_ALLOC(o->trial.alpha, nb + 1);
  HOC_ALLOC(o->trial.f0, nb + 1);
  HOC_ALLOC(o->trial.fnew, nb + 1);
  HOC_ALLOC(o->trial.slope, nb + 1);
  HOC_ALLOC(o->trial.state, nb + 1);
  HOC_ALLOC(o->trial.list, nb + 1);
  HOC_ALLOC(o->trial.committed, nb + 1);
  HOC_ALLOC(o->trial.tix, nn + 1);
  /* local length (hoc_opt_hsize): the longest edge of each element's corners */
  for (size_t e = 0; e < ne; ++e) {
    const size_t *cn = m->conn + e * np;
    double h = 0;
    for (int k = 0; k < 3; ++k)
      h = fmax(h, hoc_dist3(m->xyz + 3 * cn[k], m->xyz + 3 * cn[(k + 1) % 3]));
    o->adj.elem_h[e] = h;
  }
  for (int f = 0; f < 2; ++f)
    for (size_t b = 0; b < o->fam[f].n_blocks; ++b) {
      size_t foot = hoc_opt_be_end(&o->fam[f], b) - hoc_opt_be_begin(&o->fam[f], b);
      if (foot > o->max_foot) o->max_foot = foot;
    }
  return hoc_opt_frames_setup(o, HOC_OPT_FRAME_POOL_BYTES);
}

/* Nodes of one CAD evaluation call in hoc_opt_eval_all. */
enum { EVAL_PIECE = 1024 };

/* Derivatives dx/dz of every free node and the normals of every slot. */
hoc_status hoc_opt_eval_all(hoc_opt *o) {
  hoc_mesh *m = o->m;
  HOC_TRY(hoc_mesh_slot_normals(m, o->node.normal));
  /* face nodes grouped per face, curve nodes per curve */
  size_t nn = m->n_nodes;
  int nf = o->model->n_faces, nc = o->model->n_curves;
  size_t *start = hoc_calloc((size_t)(nf + nc) + 1, sizeof *start);
  size_t *order = hoc_calloc(nn + 1, sizeof *order);
  hoc_status status = HOC_OK;
  if (!start || !order) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (size_t i = 0; i < nn; ++i) {
    if (!o->adj.ndof[i]) continue;
    int g = m->dim[i] == HOC_ON_FACE ? m->entity[i] : nf + m->entity[i];
    start[g + 1]++;
  }
  hoc_opt_csr_finish_counts((size_t)(nf + nc), start);
  for (size_t i = 0; i < nn; ++i) {
    if (!o->adj.ndof[i]) continue;
    int g = m->dim[i] == HOC_ON_FACE ? m->entity[i] : nf + m->entity[i];
    order[start[g]++] = i;
  }
  hoc_opt_csr_restore((size_t)(nf + nc), start);
  size_t *piece = NULL, n_pieces = 0;
  HOC_TRY_GOTO(hoc_split_groups(start, nf + nc, EVAL_PIECE, &piece, &n_pieces), done);
  hoc_par_error err = {0};
#pragma omp parallel if (o->model->thread_safe)
  {
    /* each thread's work arrays for one piece (not the whole mesh's: at
     * high orders they would be a large share of the optimiser's memory) */
    double *pp = malloc(8 * EVAL_PIECE * sizeof *pp), *pa = pp ? pp + 2 * EVAL_PIECE : NULL,
           *pb = pp ? pp + 5 * EVAL_PIECE : NULL;
    if (!pp) hoc_par_error_catch(&err, HOC_ERROR(HOC_ERR_MEMORY, "out of memory"));
#pragma omp for schedule(dynamic, 1)
    for (size_t c = 0; c < n_pieces; ++c) {
      if (!pp) continue;
      int g = (int)piece[2 * c];
      size_t first = piece[2 * c + 1],
             n = start[g + 1] - first < EVAL_PIECE ? start[g + 1] - first : EVAL_PIECE;
      const size_t *nodes = order + first;
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
        memcpy(o->node.dz + 6 * nodes[k], pa + 3 * k, 3 * sizeof *pa);
        memcpy(o->node.dz + 6 * nodes[k] + 3, pb + 3 * k, 3 * sizeof *pb);
      }
    }
    free(pp);
  }
  free(piece);
  status = hoc_par_error_raise(&err);
done:
  free(start);
  free(order);
  return status;
}

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
