/* The optimiser's blocks: the two families (the natural blocks of the
 * high-order mesh, and single nodes), the nodes a vertex block carries,
 * the colouring that lets blocks of a colour move in parallel, and the
 * queues of blocks woken since their colour last ran.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "optimize/optimize_impl.h"
#include "optimize/tunables.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* The items of a list as 32-bit indices (the list is freed, and NULL
 * returned when out of memory). */
static uint32_t *narrow(hoc_growlist *g) {
  uint32_t *w = hoc_realloc(NULL, g->n ? g->n : 1, sizeof *w);
  for (size_t i = 0; w && i < g->n; ++i) w[i] = (uint32_t)g->v[i];
  free(g->v);
  g->v = NULL;
  return w;
}

/* The weight of a carried node from its code kk * np + i: the barycentric
 * coordinate for corner kk of local node i. */
static double carry_weight(const hoc_quality_tables *t, unsigned code) {
  size_t i = code % (unsigned)t->np;
  unsigned kk = code / (unsigned)t->np;
  double r = t->rs[2 * i], s = t->rs[2 * i + 1];
  return kk == 0 ? 1 - r - s : kk == 1 ? r : s;
}

double hoc_opt_carry_w(const hoc_opt *o, size_t j) {
  return carry_weight(o->t, o->B->carry_code[j]);
}

/* Blocks of family 0: vertices, edges, element interiors; of family 1:
 * single nodes. Their nodes, footprints, unknowns and carried nodes. */
hoc_status hoc_opt_build_blocks(hoc_opt *o, int family) {
  hoc_opt_blockset *B = &o->fam[family];
  hoc_mesh *m = o->m;
  size_t nn = m->n_nodes, ne = m->n_elems, np = (size_t)o->np;
  int p = m->order;
  HOC_ALLOC(B->node_block, nn);
  if (family == 0) HOC_ALLOC(B->node_off, nn); /* (single nodes: offset 0) */
  for (size_t i = 0; i < nn; ++i) B->node_block[i] = HOC_OPT_NO_BLOCK;
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
          if (!o->adj.ndof[i] || B->node_block[i] != HOC_OPT_NO_BLOCK) continue;
          B->node_block[i] = (uint32_t)start.n;
          HOC_TRY_GOTO(hoc_grow_push(&start, nodes.n), done);
          HOC_TRY_GOTO(hoc_grow_push(&nodes, i), done);
        }
        continue;
      }
      const size_t *cn = m->conn + e * np;
      if (kind == 0) {
        for (int k = 0; k < 3; ++k) {
          size_t i = cn[k];
          if (!o->adj.ndof[i] || B->node_block[i] != HOC_OPT_NO_BLOCK) continue;
          B->node_block[i] = (uint32_t)start.n;
          HOC_TRY_GOTO(hoc_grow_push(&start, nodes.n), done);
          HOC_TRY_GOTO(hoc_grow_push(&nodes, i), done);
        }
      } else if (kind == 1) {
        /* an edge seen from its second element has its nodes in a block already */
        for (int k = 0; k < 3 && p > 1; ++k) {
          size_t first = nodes.n;
          for (int j = 0; j < p - 1; ++j) {
            size_t i = cn[3 + k * (p - 1) + j];
            if (!o->adj.ndof[i] || B->node_block[i] != HOC_OPT_NO_BLOCK) continue;
            if (nodes.n == first) HOC_TRY_GOTO(hoc_grow_push(&start, nodes.n), done);
            B->node_block[i] = (uint32_t)(start.n - 1);
            HOC_TRY_GOTO(hoc_grow_push(&nodes, i), done);
          }
        }
      } else {
        size_t first = nodes.n;
        for (size_t k = 3 * (size_t)p; k < np; ++k) {
          size_t i = cn[k];
          if (!o->adj.ndof[i] || B->node_block[i] != HOC_OPT_NO_BLOCK) continue;
          if (nodes.n == first) HOC_TRY_GOTO(hoc_grow_push(&start, nodes.n), done);
          B->node_block[i] = (uint32_t)(start.n - 1);
          HOC_TRY_GOTO(hoc_grow_push(&nodes, i), done);
        }
      }
    }
  size_t nb = start.n;
  B->n_blocks = nb;
  HOC_TRY_GOTO(hoc_grow_push(&start, nodes.n), done);
  /* (single nodes: block b is node bn_node[b], its elements the node's) */
  if (family == 1) {
    free(start.v);
    start.v = NULL;
  } else {
  B->bn_start = narrow(&start);
  }
  B->bn_node = narrow(&nodes);
  if ((family == 0 && !B->bn_start) || !B->bn_node) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  start.v = nodes.v = NULL;
  /* unknowns */
  B->bd_start = hoc_calloc(nb + 1, sizeof *B->bd_start);
  if (!B->bd_start) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (size_t b = 0; b < nb; ++b) {
    int off = 0;
    for (size_t a = hoc_opt_bn_begin(B, b); a < hoc_opt_bn_end(B, b); ++a) {
      if (B->node_off) B->node_off[B->bn_node[a]] = (uint16_t)off;
      off += o->adj.ndof[B->bn_node[a]];
    }
    B->bd_start[b + 1] = B->bd_start[b] + (uint32_t)off;
    if (off > B->max_nd) B->max_nd = off;
  }
  /* footprints: the elements of the block's nodes (a single node's are
   * its own in the adjacency) */
  int own = family == 1;
  for (size_t k = 0; k < nn && own; ++k) /* (an element twice in a node's list: not its own) */
    for (size_t a = o->adj.ne_start[k]; a + 1 < o->adj.ne_start[k + 1] && own; ++a)
      own = o->adj.ne_elem[a] != o->adj.ne_elem[a + 1];
  if (own) {
    B->ne_start = o->adj.ne_start;
    B->be_elem = o->adj.ne_elem;
  } else {
    hoc_growlist fs = {0}, fe = {0};
    for (size_t b = 0; b < nb && status == HOC_OK; ++b) {
      status = hoc_grow_push(&fs, fe.n);
      for (size_t a = hoc_opt_bn_begin(B, b); a < hoc_opt_bn_end(B, b) && status == HOC_OK; ++a) {
        size_t i = B->bn_node[a];
        for (size_t c = o->adj.ne_start[i]; c < o->adj.ne_start[i + 1] && status == HOC_OK; ++c) {
          size_t e = o->adj.ne_elem[c];
          int seen = 0;
          for (size_t d = fs.v[b]; d < fe.n && !seen; ++d) seen = fe.v[d] == e;
          if (!seen) status = hoc_grow_push(&fe, e);
        }
      }
    }
    if (status == HOC_OK) status = hoc_grow_push(&fs, fe.n);
    B->be_start = narrow(&fs);
    B->be_elem = narrow(&fe);
    if (status == HOC_OK && (!B->be_start || !B->be_elem))
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    if (status != HOC_OK) goto done;
  }
  /* carried nodes of face-interior vertex blocks (single nodes carry none) */
  if (family == 0) {
    hoc_growlist cs = {0}, cn = {0};
    uint16_t *code = NULL; /* each carried node's weight (hoc_opt_carry_w) */
    size_t ccap = 0;
    size_t *last = hoc_realloc(NULL, nn + 1, sizeof *last); /* block that last took the node */
    if (!last) status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    for (size_t i = 0; last && i <= nn; ++i)
      last[i] = SIZE_MAX;
    for (size_t b = 0; b < nb && status == HOC_OK; ++b) {
      status = hoc_grow_push(&cs, cn.n);
      size_t k = B->bn_node[hoc_opt_bn_begin(B, b)];
      int vertex = family == 0 && hoc_opt_bn_end(B, b) - hoc_opt_bn_begin(B, b) == 1 && p >= 2 &&
                   o->adj.ndof[k] == 2;
      for (size_t a = o->adj.ne_start[k]; a < o->adj.ne_start[k + 1] && vertex; ++a)
        vertex = o->adj.ne_local[a] < 3;
      if (!vertex) continue;
      for (size_t a = o->adj.ne_start[k]; a < o->adj.ne_start[k + 1] && status == HOC_OK; ++a) {
        size_t e = o->adj.ne_elem[a];
        int kk = o->adj.ne_local[a];
        for (size_t i = 3; i < np && status == HOC_OK; ++i) {
          size_t node = m->conn[e * np + i];
          if (o->adj.ndof[node] != 2 || m->entity[node] != m->entity[k] || last[node] == b)
            continue;
          uint16_t c = (uint16_t)((size_t)kk * np + i);
          if (!(carry_weight(o->t, c) > HOC_OPT_CARRY_MIN_WEIGHT)) continue;
          last[node] = b;
          status = hoc_grow_push(&cn, node);
          if (status != HOC_OK) break;
          if (cn.n > ccap) {
            ccap = cn.cap;
            uint16_t *c2 = hoc_realloc(code, ccap, sizeof *c2);
            if (!c2) {
              status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
              break;
            }
            code = c2;
          }
          code[cn.n - 1] = c;
        }
      }
    }
    free(last);
    if (status == HOC_OK) status = hoc_grow_push(&cs, cn.n);
    if (status == HOC_OK && code) {
      uint16_t *c2 = hoc_realloc(code, cn.n ? cn.n : 1, sizeof *c2);
      if (c2) code = c2; /* (a failed shrink keeps the larger block) */
    }
    B->carry_code = code;
    B->carry_start = narrow(&cs);
    B->carry_node = narrow(&cn);
    if (status == HOC_OK && (!B->carry_start || !B->carry_node))
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
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
      for (size_t a = hoc_opt_be_begin(B, b); a < hoc_opt_be_end(B, b); ++a) {
        const size_t *cn = m->conn + B->be_elem[a] * np;
        for (size_t k = 0; k < np; ++k) {
          uint32_t b2 = B->node_block[cn[k]];
          if (b2 != HOC_OPT_NO_BLOCK && color[b2] >= 0) stamp[color[b2]] = b + 1;
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
    B->color_start = hoc_calloc((size_t)max_colors + 1, sizeof *B->color_start);
    B->color_block = hoc_calloc(nb + 1, sizeof *B->color_block);
    if (status == HOC_OK && (!B->color_start || !B->color_block))
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    if (status == HOC_OK) {
      for (size_t b = 0; b < nb; ++b) B->color_start[color[b] + 1]++;
      hoc_opt_csr_finish_counts((size_t)max_colors, B->color_start);
      for (size_t b = 0; b < nb; ++b) B->color_block[B->color_start[color[b]]++] = (uint32_t)b;
      hoc_opt_csr_restore((size_t)max_colors, B->color_start);
      B->cpos = hoc_calloc(nb + 1, sizeof *B->cpos);
      B->cbd = hoc_calloc(nb + 1, sizeof *B->cbd);
      if (!B->cpos || !B->cbd) status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    }
    for (int c = 0; c < max_colors && status == HOC_OK; ++c) {
      size_t first = B->color_start[c], nd = 0;
      for (size_t a = first; a < B->color_start[c + 1]; ++a) {
        size_t b = B->color_block[a];
        B->cpos[b] = (uint32_t)(a - first);
        B->cbd[b] = (uint32_t)nd;
        nd += B->bd_start[b + 1] - B->bd_start[b];
      }
      if (B->color_start[c + 1] - first > B->max_color) B->max_color = B->color_start[c + 1] - first;
      if (nd > B->max_color_nd) B->max_color_nd = nd;
    }
    if (status == HOC_OK && max_colors > UINT16_MAX)
      status = HOC_ERROR(HOC_ERR_ARGUMENT, "mesh too irregular for the optimiser (%d colours)",
                         max_colors);
    if (status == HOC_OK) {
      B->block_color = hoc_realloc(NULL, nb + 1, sizeof *B->block_color);
      if (!B->block_color) status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      for (size_t b = 0; b < nb && B->block_color; ++b)
        B->block_color[b] = (uint16_t)color[b];
    }
    if (status == HOC_OK) {
      B->queue_head = hoc_calloc((size_t)max_colors + 1, sizeof *B->queue_head);
      B->queue_next = hoc_calloc(nb + 1, sizeof *B->queue_next);
      B->queued = hoc_calloc(nb + 1, 1);
      B->scan_all = hoc_calloc((size_t)max_colors + 1, 1);
      if (!B->queue_head || !B->queue_next || !B->queued || !B->scan_all)
        status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      for (int c = 0; c < max_colors && status == HOC_OK; ++c) {
        B->queue_head[c] = HOC_OPT_NO_BLOCK;
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

double hoc_opt_carry_weight(const hoc_opt *o, size_t b, size_t node) {
  for (size_t j = hoc_opt_carry_begin(o->B, b); j < hoc_opt_carry_end(o->B, b); ++j)
    if (o->B->carry_node[j] == node) return hoc_opt_carry_w(o, j);
  return 0;
}

void hoc_opt_set_moving(hoc_opt *o, size_t b, unsigned char v) {
  for (size_t a = hoc_opt_bn_begin(o->B, b); a < hoc_opt_bn_end(o->B, b); ++a)
    o->node.moving[o->B->bn_node[a]] = v;
  for (size_t j = hoc_opt_carry_begin(o->B, b); j < hoc_opt_carry_end(o->B, b); ++j)
    o->node.moving[o->B->carry_node[j]] = v;
}

static int block_active(const hoc_opt *o, size_t b) {
  int act = 0, near = !o->cfg.local;
  for (size_t a = hoc_opt_bn_begin(o->B, b); a < hoc_opt_bn_end(o->B, b); ++a) {
    act |= o->node.active[o->B->bn_node[a]];
    near |= o->node.near[o->B->bn_node[a]];
  }
  return act && near;
}

/* Node k is active again: its blocks of both families go on their colours'
 * queues. */
void hoc_opt_wake_node(hoc_opt *o, size_t k) {
  o->node.active[k] = 1;
  for (int f = 0; f < 2; ++f) {
    hoc_opt_blockset *B = &o->fam[f];
    if (B->node_block[k] == HOC_OPT_NO_BLOCK) continue;
    size_t b = B->node_block[k];
    if (B->queued[b]) continue;
    B->queued[b] = 1;
    int c = B->block_color[b];
    B->queue_next[b] = B->queue_head[c];
    B->queue_head[c] = (uint32_t)b;
  }
}

/* Every block may be active (after a change of every node's flag). */
void hoc_opt_wake_all(hoc_opt *o) {
  for (int f = 0; f < 2; ++f)
    memset(o->fam[f].scan_all, 1, (size_t)o->fam[f].n_colors);
}

/* Flags the nodes within HOC_OPT_NEAR_RINGS rings of a tangled element. */
void hoc_opt_mark_near(hoc_opt *o) {
  for (size_t e = 0; e < o->m->n_elems; ++e) o->el.near_e[e] = !o->el.valid[e];
  hoc_opt_grow_rings(o->m, o->el.near_e, o->node.near, HOC_OPT_NEAR_RINGS);
}

/* The blocks of a colour with an active node into o->trial.list (in an order that
 * does not matter: blocks of one colour share no element); returns their
 * number. Empties the colour's queue. */
size_t hoc_opt_select_active(hoc_opt *o, int color) {
  hoc_opt_blockset *B = o->B;
  size_t n = 0;
  for (size_t b = B->queue_head[color], next; b != HOC_OPT_NO_BLOCK; b = next) {
    next = B->queue_next[b];
    B->queued[b] = 0;
    if (!B->scan_all[color] && block_active(o, b)) o->trial.list[n++] = b;
  }
  B->queue_head[color] = HOC_OPT_NO_BLOCK;
  if (B->scan_all[color]) {
    B->scan_all[color] = 0;
    for (size_t a = B->color_start[color]; a < B->color_start[color + 1]; ++a)
      if (block_active(o, B->color_block[a])) o->trial.list[n++] = B->color_block[a];
  }
  return n;
}
