/* The pipelines' events and argument checks, through the public header:
 * on screw.step at order 3 the callback sees the progress, each stage in
 * the report's order and every optimiser sweep; a nonzero return at a
 * progress, stage or sweep event cancels with HOC_ERR_INTERRUPTED and
 * returns neither mesh nor report; the gradient check reports its value;
 * bad arguments fail with HOC_ERR_ARGUMENT and leave the outputs NULL.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"
#include "test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_SEEN = 4096 };

/* What the callback saw, and when it cancels: at the `cancel_at`-th event
 * of kind `cancel_kind` (0: never). */
typedef struct seen {
  int n;
  hoc_event_kind kind[MAX_SEEN];
  const char *stage[MAX_SEEN]; /* stage names (static strings) */
  int iteration[MAX_SEEN];
  char first_progress[128];
  int bad_message; /* a NULL message, or one with a newline */
  int bad_payload; /* a payload missing or where it does not belong */
  double check;    /* the gradient check's value, -1 if none */
  hoc_event_kind cancel_kind;
  int cancel_at, count;
} seen;

static int on_event(void *user, const hoc_event *ev) {
  seen *s = user;
  if (!ev->message || strchr(ev->message, '\n')) s->bad_message = 1;
  if ((ev->kind == HOC_EVENT_STAGE) != (ev->stage != NULL) ||
      (ev->kind == HOC_EVENT_ITERATION) != (ev->iteration != NULL))
    s->bad_payload = 1;
  if (s->n < MAX_SEEN) {
    s->kind[s->n] = ev->kind;
    s->stage[s->n] = ev->stage ? ev->stage->name : NULL;
    s->iteration[s->n] = ev->iteration ? ev->iteration->iteration : 0;
    s->n++;
  }
  if (ev->kind == HOC_EVENT_PROGRESS && !s->first_progress[0] && ev->message)
    snprintf(s->first_progress, sizeof s->first_progress, "%s", ev->message);
  if (ev->kind == HOC_EVENT_CHECK) s->check = ev->value;
  return s->cancel_at && ev->kind == s->cancel_kind && ++s->count == s->cancel_at;
}

static void test_events(hoc_model *model) {
  seen *s = calloc(1, sizeof *s);
  s->check = -1;
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.event = on_event;
  o.event_user = s;
  hoc_mesh *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  CHECK(!s->bad_message && !s->bad_payload);
  CHECK(!strcmp(s->first_progress, "meshing 10 faces"));
  /* the stages as the report has them, in order (nothing was dropped here) */
  size_t n_stage = 0;
  int sweeps = 0, last_it = 0, ordered = 1;
  for (int i = 0; i < s->n; ++i) {
    if (s->kind[i] == HOC_EVENT_STAGE) {
      const hoc_stage *st = hoc_report_stage(r, n_stage++);
      CHECK(st && !strcmp(st->name, s->stage[i]));
    }
    if (s->kind[i] == HOC_EVENT_ITERATION) {
      ordered &= s->iteration[i] == last_it + 1;
      last_it = s->iteration[i];
      ++sweeps;
    }
  }
  CHECK(n_stage == hoc_report_num_stages(r) && n_stage == 3);
  const hoc_stage *opt = hoc_report_stage(r, 2);
  CHECK(ordered && opt && sweeps == opt->iterations && sweeps > 0);
  CHECK(s->check == -1);
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);

  /* cancelled at the first progress event, stage and sweep */
  static const hoc_event_kind kinds[3] = {HOC_EVENT_PROGRESS, HOC_EVENT_STAGE, HOC_EVENT_ITERATION};
  for (int k = 0; k < 3; ++k) {
    memset(s, 0, sizeof *s);
    s->cancel_kind = kinds[k];
    s->cancel_at = k == 1 ? 2 : 1; /* the raised stage */
    mesh = (hoc_mesh *)1;
    r = (hoc_report *)1;
    CHECK_STATUS(hoc_mesh_model(model, &o, &mesh, &r), HOC_ERR_INTERRUPTED);
    CHECK(mesh == NULL && r == NULL && s->count == s->cancel_at);
    CHECK(hoc_last_error()[0] != '\0');
  }

  /* the gradient check before the optimisation */
  memset(s, 0, sizeof *s);
  s->check = -1;
  o.check_gradient = 1;
  o.max_iterations = 2;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, NULL));
  CHECK(s->check >= 0 && s->check < 1e-4);
  printf("screw order 3: gradient check %.2e\n", s->check);
  hoc_mesh_destroy(&mesh);

  /* hoc_mesh_repair cancelled at its first sweep */
  o.check_gradient = 0;
  o.optimize = 0;
  o.event = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, NULL));
  memset(s, 0, sizeof *s);
  o.event = on_event;
  s->cancel_kind = HOC_EVENT_ITERATION;
  s->cancel_at = 1;
  hoc_mesh *out = (hoc_mesh *)1;
  r = (hoc_report *)1;
  CHECK_STATUS(hoc_mesh_repair(mesh, &o, &out, &r), HOC_ERR_INTERRUPTED);
  CHECK(out == NULL && r == NULL && s->count == 1);
  hoc_mesh_destroy(&mesh);
  free(s);
}

/* Each bad option alone fails with HOC_ERR_ARGUMENT, outputs NULL. */
static void test_arguments(hoc_model *model) {
  hoc_mesh *mesh = (hoc_mesh *)1;
  hoc_report *r = (hoc_report *)1;
  CHECK_STATUS(hoc_mesh_model(NULL, NULL, &mesh, &r), HOC_ERR_ARGUMENT);
  CHECK(mesh == NULL && r == NULL);
  for (int k = 0; k < 11; ++k) {
    hoc_mesh_options o;
    hoc_mesh_options_default(&o);
    switch (k) {
    case 0: o.order = 0; break;
    case 1: o.order = HOC_MAX_ORDER + 1; break;
    case 2: o.nodeset = (hoc_nodeset)7; break;
    case 3: o.measure = (hoc_measure)5; break;
    case 4: o.size = -1; break;
    case 5: o.size = NAN; break;
    case 6: o.size_min = 2, o.size = 1; break;
    case 7: o.curvature = INFINITY; break;
    case 8: o.refinements = -2; break;
    case 9: o.max_iterations = -1; break;
    default: o.size_min = -3; break;
    }
    mesh = (hoc_mesh *)1;
    r = (hoc_report *)1;
    CHECK_STATUS(hoc_mesh_model(model, &o, &mesh, &r), HOC_ERR_ARGUMENT);
    CHECK(mesh == NULL && r == NULL);
  }
  hoc_mesh *out = (hoc_mesh *)1;
  CHECK_STATUS(hoc_mesh_repair(NULL, NULL, &out, NULL), HOC_ERR_ARGUMENT);
  CHECK(out == NULL);
  CHECK_STATUS(hoc_mesh_quality_report(NULL, HOC_MEASURE_SHAPE, &r), HOC_ERR_ARGUMENT);
  CHECK(r == NULL);

  /* a report of a real mesh, then its functions' own checks */
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.optimize = 0;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, NULL));
  CHECK_STATUS(hoc_mesh_quality_report(mesh, (hoc_measure)9, &r), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_mesh_quality_report(mesh, HOC_MEASURE_SHAPE, NULL), HOC_ERR_ARGUMENT);
  CHECK_OK(hoc_mesh_quality_report(mesh, HOC_MEASURE_ODDY, &r));
  CHECK(hoc_report_num_stages(r) == 1 && !strcmp(hoc_report_stage(r, 0)->name, "input"));
  CHECK(hoc_report_num_findings(r) == 0 && hoc_report_stage_result(r, 0) == NULL);
  char *json = (char *)1;
  CHECK_STATUS(hoc_report_json(NULL, NULL, &json), HOC_ERR_ARGUMENT);
  CHECK(json == NULL);
  CHECK_STATUS(hoc_report_json(r, NULL, NULL), HOC_ERR_ARGUMENT);
  CHECK_OK(hoc_report_json(r, NULL, &json));
  if (json)
    CHECK(strstr(json, "\"command\": \"quality\"") && strstr(json, "\"measure\": \"oddy\""));
  free(json);
  CHECK_STATUS(hoc_report_write_json(r, NULL, NULL), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_report_write_json(r, NULL, ""), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_report_write_json(r, NULL, "no_such_dir/r.json"), HOC_ERR_IO);
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);

  /* NULL reports: empty answers */
  CHECK(hoc_report_num_stages(NULL) == 0 && hoc_report_stage(NULL, 0) == NULL);
  CHECK(hoc_report_stage_result(NULL, 0) == NULL && hoc_report_quality(NULL) == NULL);
  CHECK(hoc_report_tangled(NULL) == 0 && hoc_report_refinements(NULL) == 0);
  CHECK(hoc_report_num_findings(NULL) == 0 && hoc_report_finding(NULL, 0, NULL) == NULL);
  CHECK(hoc_report_linear(NULL) == NULL && hoc_report_raised(NULL) == NULL);
  hoc_report_destroy(NULL);
  r = NULL;
  hoc_report_destroy(&r);
  hoc_mesh_options_default(NULL);
}

int main(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(HOC_MODELS_DIR "/screw.step", &model));
  if (model) {
    test_events(model);
    test_arguments(model);
  }
  hoc_model_destroy(&model);
  return test_report();
}
