/* hoc_mesh_model through the public header alone: the stages of
 * gmsh_t20_component8.step at order 3 in order, with consistent counts, the
 * result untangled with min q >= 0.9 x the linear mesh's; the report's q,
 * nodes and JSON agree with the mesh returned; a given linear mesh (the
 * mesher's own) gives the same mesh bit for bit; keep_stages keeps the
 * linear and raised meshes; Fekete nodes are written equispaced with a
 * "written" stage; from order 6 the optimisation starts at order 3.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"
#include "test_util.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static hoc_model *open_bundled(const char *name) {
  char path[1024];
  snprintf(path, sizeof path, "%s/%s", HOC_MODELS_DIR, name);
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(path, &model));
  return model;
}

/* The same nodes, in the same order, to the last bit (through the files
 * the library writes: the public header has no node accessor). */
static int same_msh(const hoc_mesh *a, const hoc_mesh *b) {
  if (hoc_mesh_write_msh(a, "pipeline_a.msh") != HOC_OK) return 0;
  if (hoc_mesh_write_msh(b, "pipeline_b.msh") != HOC_OK) return 0;
  FILE *fa = fopen("pipeline_a.msh", "rb"), *fb = fopen("pipeline_b.msh", "rb");
  int same = fa && fb;
  while (same) {
    int ca = fgetc(fa), cb = fgetc(fb);
    if (ca != cb) same = 0;
    if (ca == EOF || cb == EOF) break;
  }
  if (fa) fclose(fa);
  if (fb) fclose(fb);
  remove("pipeline_a.msh");
  remove("pipeline_b.msh");
  return same;
}

static void test_stages(hoc_model *model) {
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  CHECK(o.order == 3 && o.optimize == 1 && o.refinements == -1 && !o.linear && !o.event);
  hoc_mesh *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  if (!mesh || !r) goto done;
  static const char *names[3] = {"linear", "high-order", "optimized"};
  CHECK(hoc_report_num_stages(r) == 3);
  for (size_t i = 0; i < hoc_report_num_stages(r) && i < 3; ++i) {
    const hoc_stage *s = hoc_report_stage(r, i);
    CHECK(!strcmp(s->name, names[i]));
    CHECK(s->stats.order == (i ? 3 : 1));
    CHECK(s->stats.elements == hoc_mesh_num_elements(mesh));
    CHECK(s->optimized == (i == 2));
    CHECK((hoc_report_stage_result(r, i) != NULL) == (i == 2));
  }
  CHECK(hoc_report_stage(r, 3) == NULL);
  const hoc_stage *lin = hoc_report_stage(r, 0), *opt = hoc_report_stage(r, 2);
  const hoc_optimize_result *res = hoc_report_stage_result(r, 2);
  CHECK(opt->iterations > 0 && opt->iterations == res->iterations);
  CHECK(opt->converged && opt->objective < opt->objective_initial);
  CHECK(opt->stats.tangled == 0 && hoc_report_tangled(r) == 0);
  CHECK(opt->stats.min >= 0.9 * lin->stats.min);
  printf("t20 order 3: linear min q %.4f, optimized %.4f in %d sweeps\n", lin->stats.min,
         opt->stats.min, opt->iterations);
  CHECK(hoc_report_refinements(r) == 0 && hoc_report_remeshings(r) == 0);
  CHECK(hoc_report_num_failed_faces(r) == 0);
  CHECK(hoc_report_num_findings(r) == 0 && hoc_report_finding(r, 0, NULL) == NULL);
  CHECK(hoc_report_linear(r) == NULL && hoc_report_raised(r) == NULL);
  CHECK(hoc_mesh_order(mesh) == 3);

  /* the report's q is the returned mesh's */
  size_t ne = hoc_mesh_num_elements(mesh);
  CHECK(hoc_report_num_elements(r) == ne);
  CHECK(hoc_report_num_nodes(r) == hoc_mesh_num_nodes(mesh));
  /* the run's seconds hold its stages' and their measuring */
  double staged = 0;
  for (size_t i = 0; i < hoc_report_num_stages(r); ++i)
    staged += hoc_report_stage(r, i)->seconds + hoc_report_stage(r, i)->stats.seconds;
  CHECK(staged > 0 && hoc_report_seconds(r) >= staged);
  double *q = malloc(ne * sizeof *q);
  hoc_quality_stats st;
  CHECK_OK(hoc_mesh_measure(mesh, HOC_MEASURE_SHAPE, q, NULL, &st));
  const double *rq = hoc_report_quality(r);
  CHECK(rq && !memcmp(q, rq, ne * sizeof *q));
  CHECK(st.min == opt->stats.min && st.mean == opt->stats.mean && st.tangled == 0);
  free(q);

  /* the JSON: the stages and the caller's files */
  char *json = NULL;
  hoc_report_files files = {"t20.step", NULL, 0.5, 0.25};
  CHECK_OK(hoc_report_json(r, &files, &json));
  if (json) {
    CHECK(strstr(json, "\"command\": \"mesh\"") && strstr(json, "\"model\": \"t20.step\""));
    CHECK(!strstr(json, "\"mesh\":"));
    CHECK(strstr(json, "{\"name\": \"linear\"") < strstr(json, "{\"name\": \"high-order\""));
    CHECK(strstr(json, "{\"name\": \"high-order\"") < strstr(json, "{\"name\": \"optimized\""));
    char nodes[64];
    snprintf(nodes, sizeof nodes, "\"nodes\": %zu,", hoc_mesh_num_nodes(mesh));
    CHECK(strstr(json, nodes) != NULL);
    CHECK(strstr(json, "\"model_seconds\": 0.500000") && strstr(json, "\"best_iteration\""));
    char seconds[64];
    snprintf(seconds, sizeof seconds, "\"seconds\": %.6f,\n  \"model_seconds\"",
             hoc_report_seconds(r));
    CHECK(strstr(json, seconds) != NULL);
    free(json);
  }
  CHECK_OK(hoc_report_json(r, NULL, &json));
  if (json) CHECK(strstr(json, "\"model\": \"\"") != NULL);
  free(json);
  CHECK_OK(hoc_report_write_json(r, &files, "pipeline_report.json"));
  FILE *f = fopen("pipeline_report.json", "r");
  CHECK(f != NULL);
  if (f) fclose(f);
  remove("pipeline_report.json");

  /* the mesher's own linear mesh given: the same result, bit for bit */
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.order = 3;
  hoc_mesh *given = NULL, *again = NULL;
  hoc_report *r2 = NULL;
  CHECK_OK(hoc_mesh_generate_linear(model, &lo, &given));
  o.linear = given;
  o.keep_stages = 1;
  CHECK_OK(hoc_mesh_model(model, &o, &again, &r2));
  if (again && r2) {
    CHECK(same_msh(mesh, again));
    const hoc_mesh *kl = hoc_report_linear(r2), *kr = hoc_report_raised(r2);
    CHECK(kl && hoc_mesh_order(kl) == 1 && hoc_mesh_num_elements(kl) == ne);
    CHECK(kr && hoc_mesh_order(kr) == 3);
    hoc_quality_stats sr;
    if (kr) CHECK_OK(hoc_mesh_measure(kr, HOC_MEASURE_SHAPE, NULL, NULL, &sr));
    if (kr) CHECK(sr.min == hoc_report_stage(r2, 1)->stats.min);
  }
  hoc_report_destroy(&r2);
  CHECK(r2 == NULL);
  hoc_mesh_destroy(&again);
  hoc_mesh_destroy(&given);
done:
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
}

/* Order 1: the linear mesh alone; keep_stages copies it for the report. */
static void test_linear_only(hoc_model *model) {
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = 1;
  o.keep_stages = 1;
  hoc_mesh *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  if (mesh && r) {
    CHECK(hoc_report_num_stages(r) == 1 && !strcmp(hoc_report_stage(r, 0)->name, "linear"));
    CHECK(hoc_report_linear(r) && hoc_report_linear(r) != mesh && !hoc_report_raised(r));
    CHECK(same_msh(hoc_report_linear(r), mesh));
  }
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
}

/* Fekete nodes, written equispaced: a "written" stage after the optimised
 * one, the result equispaced (screw.step at order 3); without `equispaced`
 * the result keeps Fekete nodes. */
static void test_written(hoc_model *model) {
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.nodeset = HOC_NODES_FEKETE;
  o.equispaced = 1;
  hoc_mesh *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, NULL));
  CHECK(mesh && hoc_mesh_nodeset(mesh) == HOC_NODES_EQUISPACED);
  hoc_mesh_destroy(&mesh);
  CHECK_OK(hoc_mesh_model(model, &o, NULL, &r));
  size_t n = hoc_report_num_stages(r);
  CHECK(n == 4);
  if (n == 4) {
    CHECK(!strcmp(hoc_report_stage(r, 2)->name, "optimized"));
    CHECK(!strcmp(hoc_report_stage(r, 3)->name, "written"));
    CHECK(hoc_report_stage(r, 3)->stats.tangled == 0);
    CHECK(hoc_report_stage(r, 3)->stats.min >= 0.9 * hoc_report_stage(r, 0)->stats.min);
  }
  hoc_report_destroy(&r);
  o.equispaced = 0;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  CHECK(hoc_report_num_stages(r) == 3);
  CHECK(mesh && hoc_mesh_nodeset(mesh) == HOC_NODES_FEKETE);
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
}

/* From HOC_PIPELINE_COARSE_FROM (order 6) on, the optimisation starts
 * from the optimised order-3 mesh raised to the order asked: stages
 * "coarse" (order 3, optimised) and "re-raised" (order 6) come between the
 * direct raise and the optimised mesh, which is valid and keeps the
 * quality bound. */
static void test_coarse_start(hoc_model *model) {
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = 6;
  hoc_mesh *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  if (!mesh || !r) goto done;
  static const char *names[5] = {"linear", "high-order", "coarse", "re-raised", "optimized"};
  static const int orders[5] = {1, 6, 3, 6, 6};
  CHECK(hoc_report_num_stages(r) == 5);
  for (size_t i = 0; i < hoc_report_num_stages(r) && i < 5; ++i) {
    const hoc_stage *s = hoc_report_stage(r, i);
    CHECK(!strcmp(s->name, names[i]));
    CHECK(s->stats.order == orders[i]);
    CHECK(s->optimized == (i == 2 || i == 4));
  }
  const hoc_stage *lin = hoc_report_stage(r, 0), *fin = hoc_report_stage(r, 4);
  if (lin && fin) {
    CHECK(fin->stats.tangled == 0);
    CHECK(fin->stats.min >= 0.9 * lin->stats.min);
    printf("order 6 from order 3: min q %.4f (linear %.4f), mean %.4f\n", fin->stats.min,
           lin->stats.min, fin->stats.mean);
  }
done:
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
}

int main(void) {
  hoc_model *model = open_bundled("gmsh_t20_component8.step");
  if (model) {
    test_stages(model);
    test_linear_only(model);
  }
  hoc_model_destroy(&model);
  /* one model opened from a file at a time */
  if ((model = open_bundled("screw.step"))) {
    test_written(model);
    test_coarse_start(model);
  }
  hoc_model_destroy(&model);
  return test_report();
}
