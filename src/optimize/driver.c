/* hoc_mesh_optimize: a run, and a protected run when the first leaves
 * elements tangled; the snapshots of the mesh state both keep.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "optimize/optimize.h"
#include "optimize/optimize_impl.h"
#include "optimize/tunables.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

void hoc_optimize_options_default(hoc_optimize_options *o) {
  if (!o) return;
  memset(o, 0, sizeof *o);
  o->measure = HOC_MEASURE_SHAPE;
  o->max_iterations = HOC_OPT_DEFAULT_MAX_ITERATIONS;
  o->tolerance = HOC_OPT_DEFAULT_TOLERANCE;
}

void hoc_opt_snapshot_free(hoc_opt_snapshot *s) {
  free(s->param);
  free(s->line_t);
  free(s->slot_uv.at);
  free(s->slot_uv.uv);
  free(s->elem_uv.at);
  free(s->elem_uv.uv);
}

/* Copy src of n doubles into *dst (allocated on first use). */
static hoc_status keep(double **dst, const double *src, size_t n) {
  if (!*dst) *dst = hoc_realloc(NULL, n + 1, sizeof **dst);
  HOC_CHECK(*dst, HOC_ERR_MEMORY, "out of memory for the best mesh reached");
  memcpy(*dst, src, n * sizeof **dst);
  return HOC_OK;
}

/* uv[2] of item `at` into the list (grown as needed). */
static hoc_status keep_uv(hoc_opt_uv_list *l, size_t at, const double *uv) {
  if (l->n == l->cap) {
    size_t cap = l->cap ? 2 * l->cap : 1024;
    size_t *a = hoc_realloc(l->at, cap, sizeof *a);
    if (a) l->at = a;
    double *v = a ? hoc_realloc(l->uv, 2 * cap, sizeof *v) : NULL;
    if (v) l->uv = v;
    HOC_CHECK(a && v, HOC_ERR_MEMORY, "out of memory for the best mesh reached");
    l->cap = cap;
  }
  l->at[l->n] = at;
  memcpy(l->uv + 2 * l->n, uv, 2 * sizeof *uv);
  l->n++;
  return HOC_OK;
}

hoc_status hoc_opt_snapshot_take(hoc_opt_snapshot *s, const hoc_mesh *m, size_t tangled, double f) {
  HOC_TRY(keep(&s->param, m->param, 2 * m->n_nodes));
  HOC_TRY(keep(&s->line_t, m->line_t, 2 * m->n_lines));
  s->slot_uv.n = s->elem_uv.n = 0;
  /* (compared bit for bit, so that restoring gives the same bits back) */
  for (size_t k = 0; k < m->n_slots; ++k) {
    const double *uv = m->slot_uv + 2 * k;
    if (memcmp(uv, m->param + 2 * m->slot_node[k], 2 * sizeof *uv))
      HOC_TRY(keep_uv(&s->slot_uv, k, uv));
  }
  size_t n = m->n_elems * (size_t)m->np;
  for (size_t j = 0; j < n; ++j) {
    const double *uv = m->elem_uv + 2 * j;
    if (memcmp(uv, m->slot_uv + 2 * m->elem_slot[j], 2 * sizeof *uv))
      HOC_TRY(keep_uv(&s->elem_uv, j, uv));
  }
  s->tangled = tangled;
  s->objective = f;
  return HOC_OK;
}

hoc_status hoc_opt_snapshot_restore(const hoc_opt_snapshot *s, hoc_mesh *m) {
  unsigned char *moved;
  HOC_ALLOC(moved, m->n_nodes + 1);
  for (size_t i = 0; i < m->n_nodes; ++i)
    moved[i] = memcmp(m->param + 2 * i, s->param + 2 * i, 2 * sizeof *s->param) != 0;
  memcpy(m->param, s->param, 2 * m->n_nodes * sizeof *s->param);
  memcpy(m->line_t, s->line_t, 2 * m->n_lines * sizeof *s->line_t);
  for (size_t k = 0; k < m->n_slots; ++k)
    memcpy(m->slot_uv + 2 * k, m->param + 2 * m->slot_node[k], 2 * sizeof *m->slot_uv);
  for (size_t a = 0; a < s->slot_uv.n; ++a)
    memcpy(m->slot_uv + 2 * s->slot_uv.at[a], s->slot_uv.uv + 2 * a, 2 * sizeof *m->slot_uv);
  size_t n = m->n_elems * (size_t)m->np;
  for (size_t j = 0; j < n; ++j)
    memcpy(m->elem_uv + 2 * j, m->slot_uv + 2 * m->elem_slot[j], 2 * sizeof *m->elem_uv);
  for (size_t a = 0; a < s->elem_uv.n; ++a)
    memcpy(m->elem_uv + 2 * s->elem_uv.at[a], s->elem_uv.uv + 2 * a, 2 * sizeof *m->elem_uv);
  hoc_status status = hoc_mesh_update_xyz_of(m, moved);
  free(moved);
  return status;
}

hoc_status hoc_mesh_optimize(hoc_mesh *mesh, const hoc_optimize_options *options,
                             hoc_optimize_result *result) {
  return hoc_mesh_optimize_rules(mesh, options, NULL, result);
}

hoc_status hoc_mesh_optimize_until(hoc_mesh *mesh, const hoc_optimize_options *options, int full,
                                   double deadline, hoc_optimize_result *result, int *timed_out) {
  if (timed_out) *timed_out = 0;
  hoc_opt_rules rules;
  hoc_opt_rules_default(&rules);
  if (full) rules.settled_sweeps = HOC_OPT_STAGNATION_SWEEPS;
  rules.deadline = deadline;
  rules.timed_out = timed_out;
  return hoc_mesh_optimize_rules(mesh, options, &rules, result);
}

hoc_status hoc_mesh_optimize_rules(hoc_mesh *mesh, const hoc_optimize_options *options,
                                   const hoc_opt_rules *rules, hoc_optimize_result *result) {
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "no mesh given");
  double t0 = hoc_now();
  hoc_opt_snapshot start = {0}, first = {0};
  hoc_optimize_result a = {0}, b = {0};
  int limited = 0, limited_b;
  /* the start is kept only where a protected run may follow (below) */
  int may_protect = mesh->order <= HOC_OPT_PROTECT_MAX_ORDER && !(options && options->free_elements);
  hoc_status status = may_protect ? hoc_opt_snapshot_take(&start, mesh, 0, 0) : HOC_OK;
  if (status == HOC_OK) status = hoc_opt_run_rules(mesh, options, rules, 0, 0, t0, &a, &limited);
  /* Left tangled (not for want of sweeps): a protected run from the start,
   * in which the sampled phase's steps may not fold an element between
   * samples that the exact test finds valid, kept if it leaves fewer
   * tangled. Not the first choice: the unprotected sampled phase passes
   * through such folds on its way to better meshes (on thin parts a
   * markedly higher final min q); but on coarse meshes its folds between
   * samples can outrun the exact phase, and the protected run leaves
   * fewer. Not above HOC_OPT_PROTECT_MAX_ORDER (tunables.h), and not in a
   * local repair (free_elements): it runs the exact test from its first
   * sweep, as a protected run would, so that run would only repeat it. */
  int late = rules && rules->deadline > 0 && hoc_now() > rules->deadline;
  if (status == HOC_OK && a.tangled_final && !limited && may_protect && !late) {
    status = hoc_opt_snapshot_take(&first, mesh, a.tangled_final, a.objective_final);
    if (status == HOC_OK) status = hoc_opt_snapshot_restore(&start, mesh);
    if (status == HOC_OK) status =
        hoc_opt_run_rules(mesh, options, rules, 1, a.iterations, t0, &b, &limited_b);
    if (status == HOC_OK && b.tangled_final < a.tangled_final) {
      b.diagnostics.protected_run = a.iterations + 1;
      b.tangled_initial = a.tangled_initial;
      b.objective_initial = a.objective_initial;
      a = b;
    } else if (first.param) {
      /* (also when the protected run failed) */
      hoc_status restored = hoc_opt_snapshot_restore(&first, mesh);
      if (status == HOC_OK) a.iterations = b.iterations; /* sweeps made, though not kept */
      if (status == HOC_OK) status = restored;
    }
  }
  /* the pole slots' directions as the moved corners set them */
  if (status == HOC_OK) hoc_mesh_pole_params_follow(mesh);
  a.seconds = hoc_now() - t0;
  hoc_opt_snapshot_free(&start);
  hoc_opt_snapshot_free(&first);
  if (result && status == HOC_OK) *result = a;
  return status;
}
