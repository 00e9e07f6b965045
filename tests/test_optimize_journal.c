/* The optimiser's journals (optimize/journal.c): a run's saved state kept
 * as the old values of the nodes that moved since. Each case: a raised
 * analytic mesh with seams or poles, its optimised copy, and a journal of
 * the raised mesh into which the optimised state of some nodes is written
 * the way hoc_opt_commit writes it (each node noted before its first
 * change). The restore must give every array back bit for bit (positions
 * from the parameters again); a few nodes cost a log of their own values
 * only, every node a copy of the whole (the journal freezes). A restore
 * that missed a slot, an element's copy unwrapped across a seam, a line's
 * end or a position fails here, and so does a log that grew like a copy.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "optimize/optimize_impl.h"
#include "test_util.h"

#include <string.h>

static size_t differ(const double *a, const double *b, size_t n) {
  size_t d = 0;
  for (size_t i = 0; i < n; ++i)
    d += memcmp(a + i, b + i, sizeof *a) != 0;
  return d;
}

/* Node k's state from `from` into the mesh of o (as a commit writes it). */
static void move_node(hoc_opt *o, const hoc_mesh *from, size_t k) {
  hoc_mesh *m = o->m;
  size_t np = (size_t)m->np, lp = (size_t)m->order + 1;
  hoc_opt_journal_note(o, k);
  memcpy(m->param + 2 * k, from->param + 2 * k, 2 * sizeof(double));
  memcpy(m->xyz + 3 * k, from->xyz + 3 * k, 3 * sizeof(double));
  for (size_t j = o->adj.ns_start[k]; j < o->adj.ns_start[k + 1]; ++j) {
    size_t s = o->adj.ns_slot[j];
    memcpy(m->slot_uv + 2 * s, from->slot_uv + 2 * s, 2 * sizeof(double));
  }
  for (size_t a = o->adj.ne_start[k]; a < o->adj.ne_start[k + 1]; ++a) {
    size_t at = (size_t)o->adj.ne_elem[a] * np + o->adj.ne_local[a];
    memcpy(m->elem_uv + 2 * at, from->elem_uv + 2 * at, 2 * sizeof(double));
  }
  for (size_t a = o->adj.nl_start[k]; a < o->adj.nl_start[k + 1]; ++a) {
    size_t l = o->adj.nl_line[a];
    for (int end = 0; end < 2; ++end)
      if (m->line_conn[l * lp + (size_t)end] == k)
        m->line_t[2 * l + end] = from->line_t[2 * l + end];
  }
}

static size_t mesh_differs(const hoc_mesh *a, const hoc_mesh *b) {
  size_t nn = a->n_nodes, nev = a->n_elems * (size_t)a->np;
  return differ(a->param, b->param, 2 * nn) + differ(a->xyz, b->xyz, 3 * nn) +
         differ(a->slot_uv, b->slot_uv, 2 * a->n_slots) + differ(a->elem_uv, b->elem_uv, 2 * nev) +
         differ(a->line_t, b->line_t, 2 * a->n_lines);
}

static void check_case(const char *name, int shape, double a, double b, int nu, int nv, int order) {
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *m = NULL, *ref = NULL, *opt = NULL;
  hoc_opt o;
  int set_up = 0;
  hoc_opt_journal j = {0};
  CHECK_OK(hoc_cad_create_analytic(shape, a, b, &model));
  if (model) CHECK_OK(hoc_mesh_grid_linear(model, nu, nv, &lin));
  if (lin) CHECK_OK(hoc_mesh_elevate(lin, order, HOC_NODES_EQUISPACED, &m));
  if (m) CHECK_OK(hoc_mesh_copy(m, &ref));
  if (ref) CHECK_OK(hoc_mesh_copy(m, &opt));
  if (!opt) goto out;
  hoc_optimize_result r;
  CHECK_OK(hoc_mesh_optimize(opt, NULL, &r));
  size_t nn = m->n_nodes, moved = 0;
  for (size_t k = 0; k < nn; ++k)
    moved += memcmp(opt->param + 2 * k, m->param + 2 * k, 2 * sizeof(double)) != 0;
  CHECK(moved > 20);
  CHECK_OK(hoc_opt_setup(&o, m, HOC_MEASURE_SHAPE, 0, NULL, 0));
  set_up = 1;
  /* a few nodes: a log of their values, no copy */
  CHECK_OK(hoc_opt_journal_take(&o, &j, 3, 1.5));
  size_t few = 0;
  for (size_t k = 0; k < nn && few < 3; ++k)
    if (memcmp(opt->param + 2 * k, m->param + 2 * k, 2 * sizeof(double))) {
      move_node(&o, opt, k);
      move_node(&o, opt, k); /* (a second move logs nothing more) */
      ++few;
    }
  size_t logged = j.n, changed = mesh_differs(m, ref);
  int frozen_few = j.frozen;
  CHECK_OK(hoc_opt_journal_restore(&o, &j));
  size_t bad_few = mesh_differs(m, ref);
  CHECK(logged == few && !frozen_few && changed > 0 && bad_few == 0);
  CHECK(j.n == 0 && j.tangled == 3 && j.objective == 1.5);
  /* every node: the journal freezes (takes a copy), and still restores */
  for (size_t k = 0; k < nn; ++k)
    move_node(&o, opt, k);
  int frozen_all = j.frozen;
  size_t bad_opt = mesh_differs(m, opt);
  CHECK_OK(hoc_opt_journal_restore(&o, &j));
  size_t bad_all = mesh_differs(m, ref);
  CHECK(frozen_all && bad_opt == 0 && bad_all == 0);
  CHECK(!j.frozen && j.n == 0);
  printf("%s, order %d: %zu of %zu nodes moved; %zu logged (frozen %d), %zu numbers differ "
         "after the restore; all moved: frozen %d, %zu differ after the restore\n",
         name, order, moved, nn, logged, frozen_few, bad_few, frozen_all, bad_all);
out:
  if (set_up) {
    hoc_opt_journal_free(&o, &j);
    CHECK(o.journal[0] == NULL && o.journal[1] == NULL && j.tangled == SIZE_MAX);
    hoc_opt_free(&o);
  }
  hoc_mesh_destroy(&opt);
  hoc_mesh_destroy(&ref);
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

int main(void) {
  check_case("sphere (poles, a seam)", HOC_ANALYTIC_SPHERE, 1.0, 0, 12, 6, 4);
  check_case("torus (two seams)", HOC_ANALYTIC_TORUS, 2.0, 0.5, 12, 6, 3);
  check_case("cone (an apex, a seam)", HOC_ANALYTIC_CONE, 1.0, 2.0, 12, 4, 6);
  printf("%d passed, %d failed\n", test_passed_, test_failed_);
  return test_failed_ != 0;
}
