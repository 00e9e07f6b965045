/* hocad mesh, rule 4: elements left tangled at a cusp of the CAD are
 * split, never meshed again finer. At a corner where two curves meet under
 * 2 degrees the curved element keeps the cusp's angle at every size.
 *
 * crescent_plate.step at order 4 with one sweep leaves 3 elements tangled,
 * each with a corner at one of its two cusps: the repair splits them once
 * per chain and keeps the fewest tangled, with no remeshing (meshing the
 * faces again twice, as for elements a finer mesh may open, made 8 and 6
 * tangled and took ten times as long). The warning names the cusps.
 * gmsh_t20_component8.step at order 5
 * with one sweep has tangled elements away from its cusps too: a finer
 * mesh may serve those, and hoc_repair_tangled_unrefinable says so (no
 * repair run there).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"
#include "pipeline/pipeline.h"
#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DATA HOC_SOURCE_DIR "/tests/data/"

typedef struct seen {
  int at_cusps, remeshed;
} seen;

static int on_event(void *user, const hoc_event *ev) {
  seen *s = user;
  if (!ev->message || ev->kind != HOC_EVENT_REPAIR) return 0;
  if (strstr(ev->message, "at cusps of the CAD")) s->at_cusps++;
  if (strstr(ev->message, "with edges half as long")) s->remeshed++;
  return 0;
}

/* hoc_mesh_model at `order` with one sweep and at most `refinements`
 * repairs per kind; *s what it said, *why what
 * hoc_repair_tangled_unrefinable says of the result, *at_cusp how many of
 * its tangled elements have a corner at a cusp. */
static hoc_report *one_sweep(const char *path, int order, int refinements, seen *s, int *why,
                             size_t *at_cusp) {
  hoc_model *model = NULL;
  hoc_mesh *mesh = NULL;
  hoc_report *r = NULL;
  unsigned char *tangled = NULL;
  *why = -1;
  *at_cusp = 0;
  CHECK_OK(hoc_model_open(path, &model));
  if (!model) return NULL;
  hoc_run run = {0};
  hoc_mesh_options_default(&run.o);
  run.o.order = order;
  run.o.max_iterations = 1;
  run.o.refinements = refinements;
  run.o.event = on_event;
  run.o.event_user = s;
  CHECK_OK(hoc_mesh_model(model, &run.o, &mesh, &r));
  size_t ne = mesh ? hoc_mesh_num_elements(mesh) : 0;
  tangled = calloc(ne + 1, 1);
  if (mesh && tangled) {
    CHECK_OK(hoc_mesh_measure(mesh, run.o.measure, NULL, tangled, NULL));
    for (size_t e = 0; e < ne; ++e) {
      hoc_cusp c;
      int found = 0;
      if (tangled[e]) CHECK_OK(hoc_mesh_element_cusp(mesh, e, 2.0, &c, &found));
      *at_cusp += (size_t)found;
    }
    CHECK_OK(hoc_repair_tangled_unrefinable(&run, mesh, why));
  }
  free(tangled);
  hoc_mesh_destroy(&mesh);
  hoc_model_destroy(&model);
  return r;
}

int main(void) {
  seen s = {0};
  int why = -1;
  size_t at_cusp = 0;
  hoc_report *r = one_sweep(DATA "crescent_plate.step", 4, 2, &s, &why, &at_cusp);
  if (r) {
    printf("crescent_plate, order 4, one sweep: %zu tangled, %zu at a cusp; %d refinement(s), "
           "%d remeshing(s); unrefinable %d\n",
           hoc_report_tangled(r), at_cusp, hoc_report_refinements(r),
           hoc_report_remeshings(r), why);
    CHECK(hoc_report_tangled(r) > 0 && at_cusp == hoc_report_tangled(r));
    CHECK(why == HOC_UNREFINABLE_CUSPS && s.at_cusps == 1);
    CHECK(hoc_report_remeshings(r) == 0 && s.remeshed == 0);
    CHECK(hoc_report_refinements(r) == 2); /* one split per chain */
    int named = 0; /* the warning says where they are */
    for (size_t i = 0; i < hoc_report_num_findings(r); ++i) {
      hoc_event_kind kind = HOC_EVENT_NOTE;
      const char *text = hoc_report_finding(r, i, &kind);
      named += kind == HOC_EVENT_WARNING && strstr(text, "have a corner at a cusp of the CAD");
    }
    CHECK(named == 1);
  }
  hoc_report_destroy(&r);

  seen t = {0};
  r = one_sweep(HOC_MODELS_DIR "/gmsh_t20_component8.step", 5, 0, &t, &why, &at_cusp);
  if (r) {
    printf("t20, order 5, one sweep: %zu tangled, %zu at a cusp; unrefinable %d\n",
           hoc_report_tangled(r), at_cusp, why);
    CHECK(hoc_report_tangled(r) > at_cusp && why == 0 && t.at_cusps == 0);
  }
  hoc_report_destroy(&r);
  return test_report();
}
