/* hocad mesh, rule 12, and hocad optimize, rule 4: the repairs' time.
 * Where elements stay tangled after the first optimisation, the repairs
 * (splits, remeshings, their optimisations) end at a time; an optimisation
 * under way then stops at its best state and no repair starts.
 *
 * The optimiser (hoc_mesh_optimize_until): with a deadline already past,
 * t20 raised to order 2 is left as it was (no sweep, no later phase),
 * while without one its sweeps untangle it. The pipelines: t20 at order 5
 * with one sweep leaves elements tangled; with a repair time of a
 * nanosecond neither hoc_mesh_model (its own linear mesh, or a given one)
 * nor hoc_mesh_repair splits or meshes anything again, and each says why
 * in a note; with a day, the given linear mesh is split in both chains.
 * Cut part-way: the event of the first split waits out the repair time,
 * so the split's optimisation starts late; it stops at once, and no
 * further split follows.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"
#include "optimize/optimize.h"
#include "test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Counts the notes saying the repairs' time is over, and the repairs;
 * with wait > 0, the first repair's event sleeps that many seconds. */
typedef struct seen {
  int late, repairs, sweeps_after;
  double wait;
} seen;

static int on_event(void *user, const hoc_event *ev) {
  seen *s = user;
  if (!ev->message) return 0;
  if (ev->kind == HOC_EVENT_NOTE && strstr(ev->message, "the repairs took the")) s->late++;
  if (ev->kind == HOC_EVENT_ITERATION && s->repairs > 0) s->sweeps_after++;
  if (ev->kind == HOC_EVENT_REPAIR && s->repairs++ == 0 && s->wait > 0) {
    struct timespec t = {(time_t)s->wait, (long)(1e9 * (s->wait - (time_t)s->wait))};
    nanosleep(&t, NULL);
  }
  return 0;
}

static hoc_mesh *raised(hoc_model *model, int order) {
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = order;
  o.optimize = 0;
  hoc_mesh *mesh = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, NULL));
  return mesh;
}

static void test_optimizer(hoc_model *model) {
  hoc_mesh *in = raised(model, 2), *a = NULL, *b = NULL;
  if (!in) return;
  CHECK_OK(hoc_mesh_copy(in, &a));
  CHECK_OK(hoc_mesh_copy(in, &b));
  hoc_optimize_result ra, rb;
  int late_a = -1, late_b = -1;
  /* 1e-9: a time long past (hoc_now counts from the boot or the epoch) */
  CHECK_OK(hoc_mesh_optimize_until(a, NULL, 0, 1e-9, &ra, &late_a));
  CHECK_OK(hoc_mesh_optimize_until(b, NULL, 0, 0, &rb, &late_b));
  printf("t20 order 2: deadline past: %d sweeps, %zu -> %zu tangled; none: %d sweeps, "
         "%zu -> %zu\n",
         ra.iterations, ra.tangled_initial, ra.tangled_final, rb.iterations, rb.tangled_initial,
         rb.tangled_final);
  CHECK(ra.tangled_initial > 0);
  CHECK(late_a == 1 && ra.iterations == 0 && ra.tangled_final == ra.tangled_initial);
  CHECK(ra.diagnostics.second_attempt == 0 && ra.diagnostics.exact_phase == 0);
  CHECK(ra.diagnostics.protected_run == 0 && ra.diagnostics.polished == 0);
  size_t nn = hoc_mesh_num_nodes(in);
  double *xa = malloc(3 * nn * sizeof *xa), *xi = malloc(3 * nn * sizeof *xi);
  if (xa && xi) {
    CHECK_OK(hoc_mesh_nodes(a, xa));
    CHECK_OK(hoc_mesh_nodes(in, xi));
    CHECK(!memcmp(xa, xi, 3 * nn * sizeof *xa)); /* no node moved */
  }
  free(xa);
  free(xi);
  CHECK(late_b == 0 && rb.iterations > 0 && rb.tangled_final < rb.tangled_initial);
  hoc_mesh_destroy(&a);
  hoc_mesh_destroy(&b);
  hoc_mesh_destroy(&in);
}

/* hoc_mesh_model at order 5 with one sweep (lin: a given linear mesh, or
 * NULL), the repair time and splits per chain given; *s: what it said. */
static hoc_report *mesh_model(hoc_model *model, const hoc_mesh *lin, double repair_time,
                              int refinements, seen *s) {
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = 5;
  o.linear = lin;
  o.max_iterations = 1;
  o.refinements = refinements;
  o.repair_time = repair_time;
  o.event = on_event;
  o.event_user = s;
  hoc_mesh *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  if (r) CHECK(hoc_report_num_elements(r) == hoc_mesh_num_elements(mesh));
  hoc_mesh_destroy(&mesh);
  return r;
}

static void test_mesh_model(hoc_model *model) {
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_generate_linear(model, NULL, &lin));
  seen s[3] = {{0}};
  hoc_report *r[3] = {mesh_model(model, lin, 1e-9, 1, &s[0]),
                      mesh_model(model, NULL, 1e-9, 1, &s[1]),
                      mesh_model(model, lin, 86400, 1, &s[2])};
  for (int i = 0; i < 2; ++i) {
    if (!r[i]) continue;
    printf("t20 order 5, one sweep, %s linear mesh, repair time 1 ns: %d refinement(s), "
           "%d remeshing(s), %zu tangled, %d note(s) of the time\n",
           i ? "its own" : "a given", hoc_report_refinements(r[i]), hoc_report_remeshings(r[i]),
           hoc_report_tangled(r[i]), s[i].late);
    CHECK(hoc_report_tangled(r[i]) > 0);
    CHECK(hoc_report_refinements(r[i]) == 0 && hoc_report_remeshings(r[i]) == 0);
    CHECK(s[i].repairs == 0 && s[i].late == 1);
    CHECK(!strcmp(hoc_report_stage(r[i], hoc_report_num_stages(r[i]) - 1)->name, "optimized"));
  }
  if (r[2]) {
    printf("the given linear mesh, a day: %d refinement(s), %d note(s) of the time\n",
           hoc_report_refinements(r[2]), s[2].late);
    CHECK(hoc_report_refinements(r[2]) == 2 && s[2].late == 0);
  }
  for (int i = 0; i < 3; ++i)
    hoc_report_destroy(&r[i]);
  hoc_mesh_destroy(&lin);
}

/* The time runs out while the first split is optimised: its event waits
 * past the limit (the limit counts from before it). Without the wait the
 * same run sweeps after its first split and splits again. */
static void test_cut_midway(hoc_model *model) {
  enum { WAITED, NOT };
  const double limit = 3.0;
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_generate_linear(model, NULL, &lin));
  seen s[2] = {{.wait = limit + 0.2}, {.wait = 0}};
  hoc_report *r[2] = {mesh_model(model, lin, limit, 2, &s[WAITED]),
                      mesh_model(model, lin, 86400, 2, &s[NOT])};
  if (r[WAITED] && r[NOT]) {
    printf("t20 order 5, the first split's event waiting %.1f s past a %.0f s limit: %d "
           "refinement(s), %d sweep(s) after it, %d note(s) of the time; without the wait: "
           "%d refinement(s), %d sweep(s)\n",
           s[WAITED].wait, limit, hoc_report_refinements(r[WAITED]), s[WAITED].sweeps_after,
           s[WAITED].late, hoc_report_refinements(r[NOT]), s[NOT].sweeps_after);
    CHECK(hoc_report_refinements(r[WAITED]) == 1 && s[WAITED].repairs == 1);
    CHECK(s[WAITED].sweeps_after == 0 && s[WAITED].late == 1);
    CHECK(hoc_report_remeshings(r[WAITED]) == 0);
    CHECK(hoc_report_refinements(r[NOT]) > 1 && s[NOT].sweeps_after > 0 && s[NOT].late == 0);
  }
  for (int i = 0; i < 2; ++i)
    hoc_report_destroy(&r[i]);
  hoc_mesh_destroy(&lin);
}

static void test_repair(hoc_model *model) {
  hoc_mesh *in = raised(model, 5), *out = NULL;
  if (!in) return;
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.max_iterations = 1;
  o.keep_nodes = 1;
  o.repair_time = 1e-9;
  seen s = {0};
  o.event = on_event;
  o.event_user = &s;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_repair(in, &o, &out, &r));
  if (r) {
    printf("hoc_mesh_repair, order 5, one sweep, repair time 1 ns: %d refinement(s), %zu "
           "tangled\n",
           hoc_report_refinements(r), hoc_report_tangled(r));
    CHECK(hoc_report_tangled(r) > 0 && hoc_report_refinements(r) == 0);
    CHECK(s.repairs == 0 && s.late == 1);
  }
  /* not a number: refused */
  o.repair_time = NAN;
  hoc_mesh_destroy(&out);
  CHECK_STATUS(hoc_mesh_repair(in, &o, &out, NULL), HOC_ERR_ARGUMENT);
  CHECK(!out);
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&out);
  hoc_mesh_destroy(&in);
}

int main(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(HOC_MODELS_DIR "/gmsh_t20_component8.step", &model));
  if (model) {
    test_optimizer(model);
    test_mesh_model(model);
    test_cut_midway(model);
    test_repair(model);
  }
  hoc_model_destroy(&model);
  return test_report();
}
