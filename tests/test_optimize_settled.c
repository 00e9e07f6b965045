/* HOC_OPT_SETTLED_SWEEPS (tunables.h): once a phase's smoothing converged,
 * a later phase of the same run stagnates over a window of one untangled
 * sweep (the same rate as the stagnation rule's). Its class: the exact
 * phase repairs a few folds the samples missed in a mesh whose smoothing
 * had converged already; ten more untangled sweeps there smooth the whole
 * mesh once more for little.
 *
 * The case: the bundled aircraft (D150_aircraft_fused.brep), gmsh's linear
 * mesh (without hocad's grading toward its short curves, which removes
 * the slivers where these folds are) raised to order 3. Its sampled
 * phase converges, the exact tests then find folds, and the exact phase
 * opens them (in one sweep). With the rule its
 * sweeps end a few untangled sweeps after the folds open (4: f still
 * falls faster than the stagnation rule's rate for two); without it
 * (hoc_opt_rules) more than STAGNATION_SWEEPS later. Both results are
 * untangled, of nearly the same objective and quality. (The small analytic
 * grids of the other tests do not show the class: their nodes all fall
 * asleep within a few sweeps of any phase's start.)
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "optimize/optimize_impl.h"
#include "optimize/tunables.h"
#include "test_util.h"

#include <string.h>

/* One run of a copy of m0 with the given window: its result, and the
 * smallest and the mean q of the mesh it leaves. */
static void run(const hoc_mesh *m0, int settled_sweeps, hoc_optimize_result *r, double *qmin,
                double *qmean) {
  hoc_mesh *m = NULL;
  memset(r, 0, sizeof *r);
  *qmin = *qmean = 0;
  CHECK_OK(hoc_mesh_copy(m0, &m));
  if (!m) return;
  hoc_optimize_options o;
  hoc_optimize_options_default(&o);
  hoc_opt_rules rules;
  hoc_opt_rules_default(&rules);
  rules.settled_sweeps = settled_sweeps;
  int limited;
  CHECK_OK(hoc_opt_run_rules(m, &o, &rules, 0, 0, hoc_now(), r, &limited));
  hoc_quality_stats st = {0};
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st));
  *qmin = st.min;
  *qmean = st.mean;
  printf("window %2d: exact phase from sweep %d, untangled after sweep %d, %d sweeps, "
         "%zu tangled, objective %.6g, min q %.4f, mean q %.4f, %.2f s\n",
         settled_sweeps, r->diagnostics.exact_phase, r->best_iteration, r->iterations,
         r->tangled_final, r->objective_final, *qmin, *qmean, r->seconds);
  hoc_mesh_destroy(&m);
}

int main(void) {
  const int order = 3;
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *m = NULL;
  CHECK_OK(hoc_model_open(HOC_MODELS_DIR "/D150_aircraft_fused.brep", &model));
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.order = order;
  if (model) CHECK_OK(hoc_mesh_generate_linear_ungraded(model, &lo, &lin));
  if (lin) CHECK_OK(hoc_mesh_elevate(lin, order, HOC_NODES_EQUISPACED, &m));
  if (!m) goto out;
  hoc_optimize_result on, off;
  double on_min, on_mean, off_min, off_mean;
  run(m, HOC_OPT_SETTLED_SWEEPS, &on, &on_min, &on_mean);
  run(m, HOC_OPT_STAGNATION_SWEEPS, &off, &off_min, &off_mean);
  /* the case's class: an exact phase after a converged sampled phase (it
   * began before the sweeps ran out), which opens every fold */
  CHECK(on.diagnostics.exact_phase > 1 &&
        on.diagnostics.exact_phase < HOC_OPT_DEFAULT_MAX_ITERATIONS);
  CHECK(off.diagnostics.exact_phase == on.diagnostics.exact_phase);
  CHECK(on.tangled_final == 0 && on.converged && off.tangled_final == 0 && off.converged);
  CHECK(on.best_iteration == off.best_iteration);
  /* with the rule: a few untangled sweeps after the folds open, under
   * half a stagnation window; without it, a whole window */
  CHECK(on.iterations - on.best_iteration < HOC_OPT_STAGNATION_SWEEPS / 2);
  CHECK(off.iterations - off.best_iteration > HOC_OPT_STAGNATION_SWEEPS);
  /* for nearly the same mesh */
  CHECK(on.objective_final <= 1.01 * off.objective_final);
  CHECK(on_min >= 0.99 * off_min);
  CHECK(on_mean >= off_mean - 0.002);
out:
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
  return test_report();
}
