/* hoc_mesh_repair through the public header: gmsh_t20_component8.step
 * raised to order 2 without optimising has tangled elements (the report
 * warns of them); the repair untangles it from nodes re-placed from its
 * corners (as tangled as the input: the same placement), or with
 * keep_nodes from the input's own, and leaves the input as it was. At
 * order 6 with one sweep the optimiser leaves elements tangled and both
 * chains of splits run, their stages and refinements reported.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"
#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int has_stage(const hoc_report *r, const char *name) {
  for (size_t i = 0; i < hoc_report_num_stages(r); ++i)
    if (!strcmp(hoc_report_stage(r, i)->name, name)) return 1;
  return 0;
}

/* A raised, unoptimised mesh: its tangled elements in the report's warning. */
static hoc_mesh *raised_mesh(hoc_model *model, int order, size_t *tangled) {
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = order;
  o.optimize = 0;
  hoc_mesh *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  *tangled = hoc_report_tangled(r);
  hoc_event_kind kind = HOC_EVENT_NOTE;
  const char *warning = hoc_report_finding(r, 0, &kind);
  if (*tangled) {
    char start[64];
    snprintf(start, sizeof start, "%zu tangled element(s) (not optimized):", *tangled);
    CHECK(warning && kind == HOC_EVENT_WARNING && !strncmp(warning, start, strlen(start)));
  }
  CHECK(hoc_report_num_stages(r) == 2);
  hoc_report_destroy(&r);
  return mesh;
}

static void test_untangle(hoc_model *model) {
  size_t tangled = 0;
  hoc_mesh *in = raised_mesh(model, 2, &tangled);
  if (!in) return;
  CHECK(tangled > 0);
  printf("t20 raised to order 2: %zu tangled\n", tangled);
  hoc_quality_stats before, after;
  CHECK_OK(hoc_mesh_measure(in, HOC_MEASURE_SHAPE, NULL, NULL, &before));
  hoc_mesh *out = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_repair(in, NULL, &out, &r));
  if (out && r) {
    CHECK(hoc_report_num_stages(r) == 3);
    CHECK(!strcmp(hoc_report_stage(r, 0)->name, "input"));
    CHECK(!strcmp(hoc_report_stage(r, 1)->name, "re-placed"));
    CHECK(!strcmp(hoc_report_stage(r, 2)->name, "optimized"));
    CHECK(hoc_report_stage(r, 0)->stats.tangled == tangled);
    CHECK(hoc_report_stage(r, 1)->stats.tangled == tangled);
    CHECK(hoc_report_tangled(r) == 0 && hoc_report_num_findings(r) == 0);
    CHECK(hoc_mesh_num_elements(out) == hoc_mesh_num_elements(in));
    hoc_quality_stats st;
    CHECK_OK(hoc_mesh_measure(out, HOC_MEASURE_SHAPE, NULL, NULL, &st));
    CHECK(st.tangled == 0 && st.min == hoc_report_stage(r, 2)->stats.min);
    char *json = NULL;
    CHECK_OK(hoc_report_json(r, NULL, &json));
    if (json) CHECK(strstr(json, "\"command\": \"optimize\"") != NULL);
    free(json);
  }
  CHECK_OK(hoc_mesh_measure(in, HOC_MEASURE_SHAPE, NULL, NULL, &after));
  CHECK(after.tangled == before.tangled && after.min == before.min && after.mean == before.mean);
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&out);

  /* the input's own nodes only */
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.keep_nodes = 1;
  CHECK_OK(hoc_mesh_repair(in, &o, &out, &r));
  CHECK(!has_stage(r, "re-placed") && hoc_report_num_stages(r) == 2);
  CHECK(hoc_report_tangled(r) == 0 && out);
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&out);
  hoc_mesh_destroy(&in);
}

/* A given linear mesh at order 5 and one sweep: elements left tangled,
 * split once in each chain (a given linear mesh is never meshed again). */
static void test_splits(hoc_model *model) {
  hoc_mesh *lin = NULL, *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_generate_linear(model, NULL, &lin));
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = 5;
  o.linear = lin;
  o.max_iterations = 1;
  o.refinements = 1;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  if (r) {
    printf("t20 order 5, one sweep: %d refinements, %zu tangled at the end\n",
           hoc_report_refinements(r), hoc_report_tangled(r));
    CHECK(hoc_report_refinements(r) == 2 && hoc_report_remeshings(r) == 0);
    CHECK(!strcmp(hoc_report_stage(r, 0)->name, "linear"));
    /* the result kept: the unsplit one (linear, high-order, optimized) or a
     * split one (linear, high-order, split, optimized) */
    size_t n = hoc_report_num_stages(r);
    CHECK(n == 3 || (n == 4 && !strcmp(hoc_report_stage(r, 2)->name, "split")));
    CHECK(!strcmp(hoc_report_stage(r, n - 1)->name, "optimized"));
    CHECK(hoc_report_num_elements(r) == hoc_mesh_num_elements(mesh));
    size_t zero = 0;
    const double *q = hoc_report_quality(r);
    for (size_t e = 0; e < hoc_report_num_elements(r); ++e)
      zero += q[e] == 0.0;
    CHECK(zero == hoc_report_tangled(r));
    CHECK((hoc_report_num_findings(r) > 0) == (zero > 0));
  }
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
  hoc_mesh_destroy(&lin);
}

int main(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(HOC_MODELS_DIR "/gmsh_t20_component8.step", &model));
  if (model) {
    test_untangle(model);
    test_splits(model);
  }
  hoc_model_destroy(&model);
  return test_report();
}
