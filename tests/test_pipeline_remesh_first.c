/* hocad mesh, rule 4: from order 6 on, tangled elements on faces that do
 * not fold have their faces meshed again before any split.
 *
 * tests/data/wing_root_face.brep is one B-spline face of an aircraft wing
 * at its root (face 3 of wing_fuselage.step). Meshed at 1.4 times the
 * whole model's sizes (edges 64.316, minimum 6.4316; gmsh's mesh, not
 * graded) its order-3 optimum is valid, and raised to order 8 elements
 * fold that the order-8 optimisation leaves folded (2 after the polish):
 * the surface bends more within them than order 8 follows. With the rule,
 * its face is meshed again first (the curvature sizing goes finer) and
 * that mesh untangles; without it, a split of the elements comes first.
 * (At the model's own sizes, 45.94 and 4.594, this face untangles at
 * order 8 with no repair.)
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"
#include "test_util.h"

#include <stdio.h>
#include <string.h>

#define DATA HOC_SOURCE_DIR "/tests/data/"

/* The order of the first remeshing and the first split among the repair
 * events (0: none). */
typedef struct repairs {
  int n, remeshed_at, split_at;
} repairs;

static int on_event(void *user, const hoc_event *ev) {
  repairs *s = user;
  if (ev->kind != HOC_EVENT_REPAIR || !ev->message) return 0;
  s->n++;
  if (!s->remeshed_at && strstr(ev->message, "meshing their faces again")) s->remeshed_at = s->n;
  if (!s->split_at && strstr(ev->message, "split")) s->split_at = s->n;
  return 0;
}

int main(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(DATA "wing_root_face.brep", &model));
  if (!model) return test_report();
  repairs s = {0};
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = 8;
  o.size = 64.316;
  o.size_min = 6.4316;
  o.grading = 0;
  o.event = on_event;
  o.event_user = &s;
  hoc_mesh *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  if (r) {
    size_t n = hoc_report_num_stages(r);
    const hoc_stage *lin = hoc_report_stage(r, 0), *fin = hoc_report_stage(r, n - 1);
    CHECK(s.remeshed_at == 1);
    CHECK(!s.split_at || s.split_at > s.remeshed_at);
    CHECK(hoc_report_remeshings(r) >= 1);
    CHECK(fin->stats.tangled == 0);
    CHECK(fin->stats.min >= 0.9 * lin->stats.min);
    CHECK(fin->stats.mean >= lin->stats.mean - 0.02);
    printf("order 8: %d repair event(s), remeshing first at %d, split at %d; %zu elements, "
           "0 tangled: %s, min q %.4f (linear %.4f)\n",
           s.n, s.remeshed_at, s.split_at, hoc_mesh_num_elements(mesh),
           fin->stats.tangled ? "no" : "yes", fin->stats.min, lin->stats.min);
  }
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
  hoc_model_destroy(&model);
  return test_report();
}
