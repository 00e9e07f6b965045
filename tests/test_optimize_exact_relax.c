/* HOC_OPT_EXACT_RELAX_UV_MIN_ORDER (tunables.h): from that order on, the
 * exact phase relaxes the (u, v) rule from its start. Its class: folds the
 * samples missed, in elements next to a face's boundary, whose
 * neighbourhood the raised regularisation lets pass through sigma = 0 in
 * 3D while the (u, v) rule holds the same nodes; with the rule held, the
 * exact phase's sweeps stall until HOC_OPT_EXACT_STALL_SWEEPS end them and
 * a second attempt relaxes it anyway.
 *
 * The case: a 4 x 3 grid of a plane raised to order 6, every face node
 * moved at random by up to 0.1 of a cell in u and v (a fixed seed). The
 * sampled phase untangles what its samples see and leaves 9 elements that
 * the exact tests find folded, all with a node on the plane's boundary
 * curves (as 20 of the 24 elements have). With the rule (hoc_opt_run as
 * hoc_mesh_optimize runs it above order 5), the exact phase, from sweep
 * 12, untangles them after sweep 18. With the rule switched off
 * (hoc_opt_rules), the count stays at 7 to 9 until the stall rule ends the
 * phase 15 sweeps after its last fall, and the second attempt, from sweep
 * 28, untangles them after sweep 33. The checks on the first run fail
 * without the rule: its exact phase then stalls. The case was found by a
 * search over small plane grids (3 x 2, 4 x 2, 4 x 3; moves of 0.1 and
 * 0.15 of a cell; three seeds each): in all 18 the exact phase began, and
 * with the rule each reached the same final count (0 in 15, 1 or 2 in 3)
 * 12 to 36 sweeps sooner; this is one of the quickest.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "optimize/optimize_impl.h"
#include "optimize/tunables.h"
#include "test_shake.h"
#include "test_util.h"

#include <limits.h>
#include <string.h>

#define MAX_SWEEPS 256

/* After each sweep whose samples see no fold: the elements the exact test
 * finds tangled, and how many of them have a node on a CAD curve. */
typedef struct watch {
  hoc_mesh *m;
  unsigned char *tangled; /* [n_elems] scratch */
  size_t exact[MAX_SWEEPS], boundary[MAX_SWEEPS];
  int seen[MAX_SWEEPS];
} watch;

static int on_sweep(void *user, const hoc_optimize_iteration *it) {
  watch *w = user;
  if (it->tangled || it->iteration >= MAX_SWEEPS) return 0;
  const hoc_mesh *m = w->m;
  size_t np = (size_t)m->np, n = 0, b = 0;
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, w->tangled, NULL));
  for (size_t e = 0; e < m->n_elems; ++e) {
    if (!w->tangled[e]) continue;
    int on = 0;
    for (size_t k = 0; k < np; ++k) on |= m->dim[m->conn[e * np + k]] != HOC_ON_FACE;
    n++;
    b += on != 0;
  }
  w->exact[it->iteration] = n;
  w->boundary[it->iteration] = b;
  w->seen[it->iteration] = 1;
  return 0;
}

/* One run of a copy of m0, the rule on or off. */
static void run(const hoc_mesh *m0, int rule, hoc_optimize_result *r, watch *w) {
  hoc_mesh *m = NULL;
  memset(r, 0, sizeof *r);
  CHECK_OK(hoc_mesh_copy(m0, &m));
  if (!m) return;
  w->m = m;
  w->tangled = calloc(m->n_elems, 1);
  CHECK(w->tangled != NULL);
  hoc_optimize_options o;
  hoc_optimize_options_default(&o);
  o.progress = on_sweep;
  o.progress_user = w;
  hoc_opt_rules rules;
  hoc_opt_rules_default(&rules);
  if (!rule) rules.exact_relax_uv_min_order = INT_MAX;
  int limited;
  if (w->tangled) CHECK_OK(hoc_opt_run_rules(m, &o, &rules, 0, 0, hoc_now(), r, &limited));
  int x = r->diagnostics.exact_phase;
  size_t folds = x > 1 && x <= MAX_SWEEPS ? w->exact[x - 1] : 0,
         boundary = x > 1 && x <= MAX_SWEEPS ? w->boundary[x - 1] : 0;
  printf("rule %s: exact phase from sweep %d with %zu folds (%zu on the boundary); untangled "
         "after sweep %d; second attempt from sweep %d; %d sweeps, %zu tangled, %.2f s\n",
         rule ? "on " : "off", x, folds, boundary, r->best_iteration,
         r->diagnostics.second_attempt, r->iterations, r->tangled_final, r->seconds);
  /* the case's class: the samples say untangled, the exact tests find
   * folds, all in elements on the face's boundary */
  CHECK(x > 1 && x <= MAX_SWEEPS && w->seen[x - 1]);
  CHECK(folds > 0 && boundary == folds);
  free(w->tangled);
  hoc_mesh_destroy(&m);
}

int main(void) {
  const int nu = 4, nv = 3, order = 6;
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *m = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_PLANE, 1.0, 0, &model));
  if (model) CHECK_OK(hoc_mesh_grid_linear(model, nu, nv, &lin));
  if (lin) CHECK_OK(hoc_mesh_elevate(lin, order, HOC_NODES_EQUISPACED, &m));
  if (!m) goto out;
  shake(m, 0.1, 1.0 / nu, 1.0 / nv, 2);
  static watch on_w, off_w;
  hoc_optimize_result on, off;
  run(m, 1, &on, &on_w);
  run(m, 0, &off, &off_w);
  /* with the rule: the exact phase opens every fold without stalling
   * (before its stall rule could end it) and needs no second attempt */
  CHECK(on.tangled_final == 0 && on.converged);
  CHECK(on.best_iteration - on.diagnostics.exact_phase + 1 < HOC_OPT_EXACT_STALL_SWEEPS);
  CHECK(on.diagnostics.second_attempt == 0);
  /* without it: the exact phase stalls, and the second attempt (the rule
   * relaxed after all) opens the folds, later */
  CHECK(off.diagnostics.exact_phase == on.diagnostics.exact_phase);
  CHECK(off.diagnostics.second_attempt > off.diagnostics.exact_phase);
  CHECK(off.best_iteration > on.best_iteration);
out:
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
  return test_report();
}
