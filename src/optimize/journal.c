/* Journals: a run's saved states (the best one reached while untangling,
 * the one before the polish) kept as the old values of the nodes that
 * moved since, not as a copy of every node. After the first sweeps few
 * nodes move (the exact phase moves only those near a fold), and at order
 * 10 a copy of every node's parameters is a large share of the mesh
 * (nist_ftc_07: 97 MB). A journal whose log would outgrow a quarter of
 * such a copy takes the copy instead (hoc_opt_snapshot) and logs no more.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "optimize/optimize_impl.h"
#include "optimize/tunables.h"

#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Doubles node k's entry holds: its parameters, its slots' parameters, its
 * element copies' parameters, and the line ends it is. */
static size_t entry_size(const hoc_opt *o, size_t k) {
  return 2 + 2 * (size_t)(o->adj.ns_start[k + 1] - o->adj.ns_start[k]) +
         2 * (size_t)(o->adj.ne_start[k + 1] - o->adj.ne_start[k]) +
         2 * (size_t)(o->adj.nl_start[k + 1] - o->adj.nl_start[k]);
}

/* A pair of the mesh's numbers into v (to_mesh = 0) or back. */
static void move2(double *pair, double *v, int to_mesh) {
  if (to_mesh) memcpy(pair, v, 2 * sizeof *v);
  else memcpy(v, pair, 2 * sizeof *v);
}

/* Copies node k's state into v (to_mesh = 0) or v into node k's state
 * (to_mesh = 1); a line end's entry is (end, t) for the ends that are k. */
static void transfer(hoc_opt *o, size_t k, double *v, int to_mesh) {
  hoc_mesh *m = o->m;
  size_t np = (size_t)o->np, lp = (size_t)m->order + 1;
  move2(m->param + 2 * k, v, to_mesh);
  v += 2;
  for (size_t j = o->adj.ns_start[k]; j < o->adj.ns_start[k + 1]; ++j, v += 2)
    move2(m->slot_uv + 2 * (size_t)o->adj.ns_slot[j], v, to_mesh);
  for (size_t a = o->adj.ne_start[k]; a < o->adj.ne_start[k + 1]; ++a, v += 2)
    move2(m->elem_uv + 2 * ((size_t)o->adj.ne_elem[a] * np + o->adj.ne_local[a]), v, to_mesh);
  for (size_t a = o->adj.nl_start[k]; a < o->adj.nl_start[k + 1]; ++a, v += 2) {
    size_t l = o->adj.nl_line[a];
    const size_t *ln = m->line_conn + l * lp;
    if (!to_mesh) {
      int end = ln[0] == k ? 0 : ln[1] == k ? 1 : -1;
      v[0] = end;
      v[1] = end >= 0 ? m->line_t[2 * l + (size_t)end] : 0;
    } else if (v[0] >= 0) {
      m->line_t[2 * l + (size_t)v[0]] = v[1];
    }
  }
}

/* Appends node k's current state to j's log (serial, or inside the
 * caller's critical section). */
static hoc_status append(hoc_opt *o, hoc_opt_journal *j, size_t k) {
  size_t need = entry_size(o, k);
  if (j->n == j->cap) {
    size_t cap = j->cap ? 2 * j->cap : 1024;
    size_t *nd = hoc_realloc(j->node, cap, sizeof *nd);
    if (nd) j->node = nd;
    size_t *off = nd ? hoc_realloc(j->off, cap + 1, sizeof *off) : NULL;
    if (off) j->off = off;
    HOC_CHECK(nd && off, HOC_ERR_MEMORY, "out of memory for the best mesh reached");
    j->cap = cap;
  }
  if (j->nv + need > j->vcap) {
    size_t cap = j->vcap ? 2 * j->vcap : 8192;
    while (cap < j->nv + need)
      cap *= 2;
    double *v = hoc_realloc(j->vals, cap, sizeof *v);
    HOC_CHECK(v, HOC_ERR_MEMORY, "out of memory for the best mesh reached");
    j->vals = v;
    j->vcap = cap;
  }
  j->node[j->n] = k;
  j->off[j->n] = j->nv;
  transfer(o, k, j->vals + j->nv, 0);
  j->nv += need;
  j->n++;
  j->saved[k] = 1;
  return HOC_OK;
}

/* The log's bytes past which j takes a copy of every node instead. */
static size_t log_limit(const hoc_opt *o) {
  return 2 * sizeof(double) * o->m->n_nodes / HOC_OPT_JOURNAL_SHARE;
}

static size_t log_bytes(const hoc_opt_journal *j) {
  return j->n * 2 * sizeof(size_t) + j->nv * sizeof(double);
}

/* j stops logging: the current state of every node is copied, the log
 * keeps what moved before. */
static hoc_status freeze(hoc_opt *o, hoc_opt_journal *j) {
  HOC_TRY(hoc_opt_snapshot_take(&j->copy, o->m, j->tangled, j->objective));
  j->frozen = 1;
  return HOC_OK;
}

hoc_status hoc_opt_journal_take(hoc_opt *o, hoc_opt_journal *j, size_t tangled, double f) {
  if (!o->journal_entry_max)
    for (size_t k = 0; k < o->m->n_nodes; ++k)
      if (entry_size(o, k) > o->journal_entry_max) o->journal_entry_max = entry_size(o, k);
  if (!j->saved) {
    j->saved = hoc_calloc(o->m->n_nodes + 1, 1);
    HOC_CHECK(j->saved, HOC_ERR_MEMORY, "out of memory for the best mesh reached");
  }
  for (size_t a = 0; a < j->n; ++a)
    j->saved[j->node[a]] = 0;
  j->n = j->nv = 0;
  hoc_opt_snapshot_free(&j->copy);
  memset(&j->copy, 0, sizeof j->copy);
  j->frozen = j->broken = 0;
  j->tangled = tangled;
  j->objective = f;
  int at = -1;
  for (int i = 0; i < HOC_OPT_JOURNALS; ++i) {
    if (o->journal[i] == j) at = i;
    if (at < 0 && !o->journal[i]) at = i;
  }
  HOC_CHECK(at >= 0, HOC_ERR_INTERNAL, "too many saved states of the optimiser");
  o->journal[at] = j;
  return HOC_OK;
}

void hoc_opt_journal_note(hoc_opt *o, size_t k) {
  for (int i = 0; i < HOC_OPT_JOURNALS; ++i) {
    hoc_opt_journal *j = o->journal[i];
    if (!j || j->frozen || j->saved[k]) continue;
    /* (out of memory, the journal cannot give its state back: restoring
     * it fails; broken is read and written in the critical section) */
    if (omp_in_parallel()) {
#pragma omp critical(hoc_opt_journal)
      if (!j->broken && append(o, j, k) != HOC_OK) j->broken = 1;
    } else if (!j->broken) {
      hoc_status s = append(o, j, k);
      if (s == HOC_OK && log_bytes(j) > log_limit(o)) s = freeze(o, j);
      if (s != HOC_OK) j->broken = 1;
    }
  }
}

hoc_status hoc_opt_journal_reserve(hoc_opt *o, size_t nodes) {
  for (int i = 0; i < HOC_OPT_JOURNALS; ++i) {
    hoc_opt_journal *j = o->journal[i];
    if (!j || j->frozen || j->broken) continue;
    /* (an entry of a node holds at most 2 + 2 * (slots + elements + lines)
     * doubles: bounded by the node with most of them) */
    if (log_bytes(j) + nodes * (2 * sizeof(size_t) + o->journal_entry_max * sizeof(double)) >
        log_limit(o))
      HOC_TRY(freeze(o, j));
  }
  return HOC_OK;
}

hoc_status hoc_opt_journal_restore(hoc_opt *o, hoc_opt_journal *j) {
  hoc_mesh *m = o->m;
  HOC_CHECK(!j->broken, HOC_ERR_MEMORY, "out of memory for the best mesh reached");
  /* the other journals log what this one is about to change */
  for (int i = 0; i < HOC_OPT_JOURNALS; ++i) {
    hoc_opt_journal *other = o->journal[i];
    if (!other || other == j || other->frozen) continue;
    for (size_t a = 0; a < j->n; ++a)
      hoc_opt_journal_note(o, j->node[a]);
    if (j->frozen)
      for (size_t k = 0; k < m->n_nodes; ++k)
        if (memcmp(m->param + 2 * k, j->copy.param + 2 * k, 2 * sizeof(double)))
          hoc_opt_journal_note(o, k);
  }
  if (j->frozen) HOC_TRY(hoc_opt_snapshot_restore(&j->copy, m));
  unsigned char *moved;
  HOC_ALLOC(moved, m->n_nodes + 1);
  memset(moved, 0, m->n_nodes);
  for (size_t a = 0; a < j->n; ++a) {
    size_t k = j->node[a];
    const double *v = j->vals + j->off[a];
    moved[k] = memcmp(m->param + 2 * k, v, 2 * sizeof(double)) != 0;
    transfer(o, k, j->vals + j->off[a], 1);
  }
  hoc_status status = hoc_mesh_update_xyz_of(m, moved);
  free(moved);
  HOC_TRY(status);
  /* the mesh is the saved state again */
  return hoc_opt_journal_take(o, j, j->tangled, j->objective);
}

void hoc_opt_journal_free(hoc_opt *o, hoc_opt_journal *j) {
  for (int i = 0; i < HOC_OPT_JOURNALS; ++i)
    if (o->journal[i] == j) o->journal[i] = NULL;
  free(j->saved);
  free(j->node);
  free(j->off);
  free(j->vals);
  hoc_opt_snapshot_free(&j->copy);
  memset(j, 0, sizeof *j);
  j->tangled = SIZE_MAX;
}
