/* From HOC_PIPELINE_COARSE_FROM on, hoc_mesh_model optimises at the coarse
 * order first and raises that optimum; the coarse optimisation runs every
 * phase to convergence by the first phase's rule (hoc_mesh_optimize_until's full:
 * the settled rule of tunables.h, HOC_OPT_SETTLED_SWEEPS, off). Its class:
 * the coarse optimum is the start of a costlier optimisation, which it
 * decides (which elements the high order leaves tangled, which faces are
 * meshed again); ending it a few sweeps short of converged saves little
 * at the coarse order and changes that start.
 *
 * The case: the bundled aircraft's linear mesh as gmsh makes it (the one
 * of tests/test_optimize_settled.c, in which the exact phase at order 3
 * opens folds after a converged sampled phase) given to hoc_mesh_model at
 * order 6. The coarse stage's sweeps must go on a whole stagnation window after
 * its last tangled sweep (63 sweeps, the last tangled the 49th; with the
 * settled rule 57); the run is stopped by the event callback once the
 * coarse stage is measured.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"
#include "mesh/mesh.h"
#include "optimize/tunables.h"
#include "pipeline/pipeline.h"
#include "test_util.h"

#include <stdio.h>
#include <string.h>

/* The sweeps of the coarse stage, as the events tell them. */
typedef struct sweeps {
  int last, last_tangled, coarse_seen, coarse_iterations, coarse_converged;
  size_t coarse_tangled;
} sweeps;

static int on_event(void *user, const hoc_event *ev) {
  sweeps *s = user;
  if (ev->kind == HOC_EVENT_ITERATION && ev->iteration) {
    s->last = ev->iteration->iteration;
    if (ev->iteration->tangled) s->last_tangled = ev->iteration->iteration;
  }
  if (ev->kind == HOC_EVENT_STAGE && ev->stage && !strcmp(ev->stage->name, "coarse")) {
    s->coarse_seen = 1;
    s->coarse_iterations = ev->stage->iterations;
    s->coarse_converged = ev->stage->converged;
    s->coarse_tangled = ev->stage->stats.tangled;
    return 1; /* the order-6 optimisation is not this test's */
  }
  return 0;
}

int main(void) {
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_model_open(HOC_MODELS_DIR "/D150_aircraft_fused.brep", &model));
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.order = HOC_PIPELINE_COARSE_ORDER;
  if (model) CHECK_OK(hoc_mesh_generate_linear_ungraded(model, &lo, &lin));
  if (!lin) goto out;
  sweeps s = {0};
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = HOC_PIPELINE_COARSE_FROM;
  o.linear = lin;
  o.event = on_event;
  o.event_user = &s;
  hoc_status st = hoc_mesh_model(model, &o, &mesh, &r);
  CHECK(st == HOC_ERR_INTERRUPTED);
  CHECK(s.coarse_seen);
  printf("coarse stage (order %d of %d): %d sweeps, last tangled sweep %d, %zu tangled, "
         "converged %d\n",
         HOC_PIPELINE_COARSE_ORDER, HOC_PIPELINE_COARSE_FROM, s.coarse_iterations,
         s.last_tangled, s.coarse_tangled, s.coarse_converged);
  /* the case's class: folds opened late, then the smoothing converged */
  CHECK(s.coarse_tangled == 0 && s.coarse_converged);
  CHECK(s.last_tangled > 1 && s.coarse_iterations == s.last);
  /* a whole stagnation window after the last tangled sweep, not the
   * settled rule's one */
  CHECK(s.coarse_iterations - s.last_tangled > HOC_OPT_STAGNATION_SWEEPS);
out:
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
  return test_report();
}
