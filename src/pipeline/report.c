/* The pipelines' report: its stages, what it finds about the result (the
 * tangled elements and why, elements at CAD cusps) and its JSON.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "pipeline/pipeline.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A growing text buffer (findings, JSON). */
typedef struct text {
  char *s;
  size_t n, cap;
  int failed;
} text;

static void text_add(text *t, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;

static void text_add(text *t, const char *fmt, ...) {
  if (t->failed) return;
  for (;;) {
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(t->s ? t->s + t->n : NULL, t->s ? t->cap - t->n : 0, fmt, ap);
    va_end(ap);
    if (k < 0) {
      t->failed = 1;
      return;
    }
    if (t->s && t->n + (size_t)k < t->cap) {
      t->n += (size_t)k;
      return;
    }
    size_t cap = t->cap ? 2 * t->cap : 1024;
    while (cap < t->n + (size_t)k + 1)
      cap *= 2;
    char *s = realloc(t->s, cap);
    if (!s) {
      t->failed = 1;
      return;
    }
    t->s = s;
    t->cap = cap;
  }
}

/* The text, or HOC_ERR_MEMORY (and nothing) if it could not grow. */
static hoc_status text_take(text *t, char **out) {
  *out = NULL;
  if (t->failed || !t->s) {
    free(t->s);
    *t = (text){0};
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory writing the report");
  }
  *out = t->s;
  *t = (text){0};
  return HOC_OK;
}

static void json_string(text *t, const char *s) {
  text_add(t, "\"");
  for (; s && *s; ++s) {
    unsigned char c = (unsigned char)*s;
    if (c == '"' || c == '\\')
      text_add(t, "\\%c", c);
    else if (c < 0x20)
      text_add(t, "\\u%04x", c);
    else
      text_add(t, "%c", c);
  }
  text_add(t, "\"");
}

/* Report objects ---------------------------------------------------------- */

hoc_status hoc_report_create(const char *command, hoc_measure measure, hoc_report **report) {
  HOC_ALLOC(*report, 1);
  (*report)->command = command;
  (*report)->measure = measure;
  return HOC_OK;
}

void hoc_report_destroy(hoc_report **report) {
  if (!report || !*report) return;
  hoc_report *r = *report;
  free(r->quality);
  for (size_t i = 0; i < r->n_findings; ++i)
    free(r->finding[i]);
  hoc_mesh_destroy(&r->linear);
  hoc_mesh_destroy(&r->raised);
  free(r);
  *report = NULL;
}

size_t hoc_report_num_stages(const hoc_report *report) { return report ? (size_t)report->r.n : 0; }

const hoc_stage *hoc_report_stage(const hoc_report *report, size_t i) {
  return report && i < (size_t)report->r.n ? &report->r.s[i].stage : NULL;
}

const hoc_optimize_result *hoc_report_stage_result(const hoc_report *report, size_t i) {
  return report && i < (size_t)report->r.n && report->r.s[i].stage.optimized
             ? &report->r.s[i].result
             : NULL;
}

int hoc_report_refinements(const hoc_report *report) { return report ? report->r.refinements : 0; }

int hoc_report_remeshings(const hoc_report *report) { return report ? report->r.remeshings : 0; }

size_t hoc_report_tangled(const hoc_report *report) {
  return report && report->r.n ? report->r.s[report->r.n - 1].stage.stats.tangled : 0;
}

int hoc_report_num_failed_faces(const hoc_report *report) {
  return report ? report->failed_faces : 0;
}

size_t hoc_report_num_elements(const hoc_report *report) { return report ? report->elements : 0; }

size_t hoc_report_num_nodes(const hoc_report *report) { return report ? report->nodes : 0; }

double hoc_report_seconds(const hoc_report *report) { return report ? report->seconds : 0; }

const double *hoc_report_quality(const hoc_report *report) {
  return report ? report->quality : NULL;
}

size_t hoc_report_num_findings(const hoc_report *report) { return report ? report->n_findings : 0; }

const char *hoc_report_finding(const hoc_report *report, size_t i, hoc_event_kind *kind) {
  if (!report || i >= report->n_findings) return NULL;
  if (kind) *kind = report->finding_kind[i];
  return report->finding[i];
}

const hoc_mesh *hoc_report_linear(const hoc_report *report) {
  return report ? report->linear : NULL;
}

const hoc_mesh *hoc_report_raised(const hoc_report *report) {
  return report ? report->raised : NULL;
}

/* Findings ---------------------------------------------------------------- */

static hoc_status add_finding(hoc_report *report, hoc_event_kind kind, text *t) {
  HOC_ASSERT(report->n_findings < HOC_REPORT_MAX_FINDINGS);
  char *s;
  HOC_TRY(text_take(t, &s));
  report->finding_kind[report->n_findings] = kind;
  report->finding[report->n_findings++] = s;
  return HOC_OK;
}

/* The last optimised stage of r, or NULL. */
static const hoc_stage_record *optimized_stage(const hoc_stages *r) {
  for (int i = r->n - 1; i >= 0; --i)
    if (r->s[i].stage.optimized) return &r->s[i];
  return NULL;
}

/* Where tangled elements remain: which, and why. `opt` is the optimised
 * stage, or NULL if the mesh was not optimised. */
static hoc_status find_tangled(hoc_report *report, const hoc_mesh *mesh, const double *q,
                               const hoc_stage_record *opt, int from_cad,
                               hoc_pinch_table *pinches) {
  /* hoc_mesh_model can make a finer linear mesh; hoc_mesh_repair keeps its input's */
  const char *advice = from_cad
                           ? "try a smaller --size-min or --size, or a larger --curvature"
                           : "not with the input's elements: a finer input mesh there may help";
  size_t ne = hoc_mesh_num_elements(mesh), shown = 0, total = 0;
  for (size_t e = 0; e < ne; ++e)
    total += q[e] == 0.0;
  if (!total) return HOC_OK;
  /* elements across a fold of their face: no finer mesh of the same kind avoids those */
  size_t across = 0, at_cusp = 0, pinched = 0, either = 0; /* either: a fold or a pinch */
  unsigned char *tangled = NULL, *cusp = NULL;
  HOC_ALLOC(tangled, ne);
  hoc_status status = HOC_OK;
  HOC_ALLOC_GOTO(cusp, ne, done);
  for (size_t e = 0; e < ne; ++e)
    tangled[e] = q[e] == 0.0;
  HOC_TRY_GOTO(hoc_mesh_elements_at_cusps(mesh, HOC_PIPELINE_CUSP_DEGREES, tangled, cusp), done);
  for (size_t e = 0; e < ne; ++e) {
    int folds = 0, pinch = 0;
    if (q[e] != 0.0) continue;
    if (hoc_mesh_element_folds(mesh, e, &folds) != HOC_OK) folds = 0;
    HOC_TRY_GOTO(hoc_mesh_element_across_pinch(mesh, e, pinches, &pinch), done);
    across += folds;
    pinched += pinch;
    either += folds || pinch;
    at_cusp += cusp[e];
  }
  /* optimised, and every one across a fold or a pinch of its face */
  int all_across = opt && either == total;
  int all_at_cusp = opt && at_cusp == total && !either;
  text t = {0};
  const hoc_stage *s = opt ? &opt->stage : NULL;
  if (all_across && !pinched)
    text_add(&t,
             "%zu element(s) tangled across a fold of their face, where its normal phi_u x "
             "phi_v reverses (the CAD face folds on itself; a mesh whose edges do not follow the "
             "fold crosses it, a finer one with more elements):",
             total);
  else if (all_across)
    text_add(&t,
             "%zu element(s) tangled across a fold or a pinch of their face (%zu across a "
             "pinch: a line of the face's (u, v) that the CAD maps to one point, which an "
             "element across it passes through with its Jacobian vanishing there; only a mesh "
             "with nodes on the line avoids them):",
             total, pinched);
  else if (all_at_cusp)
    text_add(&t,
             "%zu element(s) tangled at a cusp of the CAD, where two of its curves meet under "
             "%g degrees (a curved corner keeps that angle at every size, so a finer mesh does "
             "not open it%s):",
             total, HOC_PIPELINE_CUSP_DEGREES,
             opt->result.stopped_at_limit ? "; more iterations may: raise --max-iterations" : "");
  else if (opt && !s->converged && opt->result.stopped_at_limit && s->iterations >= 10 &&
           2 * opt->result.best_iteration <= s->iterations)
    text_add(&t,
             "%zu element(s) could not be untangled with this linear mesh (the fewest tangled "
             "since iteration %d of %d; %s):",
             total, opt->result.best_iteration, s->iterations, advice);
  else if (opt && !s->converged && opt->result.stopped_at_limit)
    text_add(&t,
             "%zu element(s) still tangled after %d iteration(s) (the limit, with a second "
             "attempt: raise --max-iterations):",
             total, s->iterations);
  else if (opt)
    text_add(&t, "%zu element(s) could not be untangled with this linear mesh (%s):", total,
             advice);
  else
    text_add(&t, "%zu tangled element(s) (not optimized):", total);
  for (size_t e = 0; e < ne && shown < 20; ++e)
    if (q[e] == 0.0) {
      text_add(&t, " %zu (face %d)", e + 1, hoc_mesh_element_face_tag(mesh, e));
      ++shown;
    }
  text_add(&t, "%s", total > shown ? " ..." : "");
  if (across && !all_across)
    text_add(&t,
             "; %zu of them cross a fold of their face, where its normal phi_u x phi_v "
             "reverses, which a mesh whose edges do not follow it crosses",
             across);
  if (pinched && !all_across)
    text_add(&t,
             "; %zu of them cross a pinch of their face (a line of its (u, v) that the CAD maps "
             "to one point), which only a mesh with nodes on the line avoids",
             pinched);
  if (at_cusp && !all_at_cusp)
    text_add(&t,
             "; %zu of them are at a cusp of the CAD (two curves meeting under %g degrees), "
             "whose angle a finer mesh keeps",
             at_cusp, HOC_PIPELINE_CUSP_DEGREES);
  status = add_finding(report, HOC_EVENT_WARNING, &t);
done:
  free(tangled);
  free(cusp);
  return status;
}

/* Elements that end below 0.9 x the linear mesh's worst and have a corner at
 * a cusp of the CAD (see hoc_cusp: a cusp element's curved corner closes
 * where its straight one does not; raising grades its edges against that,
 * which can still fall short, e.g. on a mesh read from a file), or, at no
 * cusp, cross a pinch of their face (hoc_face_pinches: the curved element
 * passes through the pinch's point): say so, and what the rest of the mesh
 * reaches. */
static hoc_status find_poor(hoc_report *report, const hoc_stages *r, const hoc_mesh *mesh,
                            const double *q, hoc_pinch_table *pinches) {
  double bound = HOC_PIPELINE_POOR * r->s[0].stage.stats.min;
  double rest = 1, neither = 1; /* q <= 1: at no cusp; at no cusp and across no pinch */
  size_t ne = hoc_mesh_num_elements(mesh), low = 0, at_cusp = 0, at_pinch = 0;
  char list[512] = "", plist[512] = "";
  size_t len = 0, plen = 0;
  const hoc_stage_record *opt = optimized_stage(r);
  if (!opt || !opt->stage.converged) return HOC_OK; /* a low q may still be the optimiser's */
  if (r->n < 2 || !(r->s[r->n - 1].stage.stats.min < bound)) return HOC_OK; /* none below */
  for (size_t e = 0; e < ne; ++e) {
    if (q[e] == 0.0 || (q[e] >= bound && q[e] >= neither)) continue; /* changes nothing below */
    hoc_cusp c;
    int found = 0;
    if (hoc_mesh_element_cusp(mesh, e, HOC_PIPELINE_CUSP_DEGREES, &c, &found) != HOC_OK) found = 0;
    if (found) {
      if (!(q[e] < bound)) continue;
      ++low;
      if (++at_cusp <= 3 && len < sizeof list)
        len += (size_t)snprintf(list + len, sizeof list - len,
                                "%selement %zu at vertex %d (curves %d and %d, %.2g degrees)",
                                at_cusp > 1 ? "; " : "", e + 1, c.vertex_tag, c.curve_tags[0],
                                c.curve_tags[1], c.angle_degrees);
      continue;
    }
    rest = fmin(rest, q[e]);
    int across = 0;
    HOC_TRY(hoc_mesh_element_across_pinch(mesh, e, pinches, &across));
    if (across) {
      if (!(q[e] < bound)) continue;
      ++low;
      if (++at_pinch <= 3 && plen < sizeof plist)
        plen += (size_t)snprintf(plist + plen, sizeof plist - plen, "%selement %zu of face %d",
                                 at_pinch > 1 ? "; " : "", e + 1,
                                 hoc_mesh_element_face_tag(mesh, e));
      continue;
    }
    neither = fmin(neither, q[e]);
    low += q[e] < bound;
  }
  if (at_cusp) {
    text t = {0};
    text_add(&t,
             "%zu of the %zu element(s) below 0.9 x the linear mesh's min q (%.4f) have a corner "
             "at a cusp of the CAD, where two of its curves meet at under %g degrees (%s%s): "
             "following both curves, such an element closes there as the order grows; the "
             "elements at no cusp have min q %.4f",
             at_cusp, low, r->s[0].stage.stats.min, HOC_PIPELINE_CUSP_DEGREES, list,
             at_cusp > 3 ? "; ..." : "", rest);
    HOC_TRY(add_finding(report, HOC_EVENT_NOTE, &t));
  }
  if (at_pinch) {
    text t = {0};
    text_add(&t,
             "%zu of the %zu element(s) below 0.9 x the linear mesh's min q (%.4f) cross a "
             "pinch of their face, a line of its (u, v) that the CAD maps to one point (%s%s): "
             "curved through that point, such an element narrows there as the order grows; "
             "the elements at no cusp and across no pinch have min q %.4f",
             at_pinch, low, r->s[0].stage.stats.min, plist, at_pinch > 3 ? "; ..." : "",
             neither);
    HOC_TRY(add_finding(report, HOC_EVENT_NOTE, &t));
  }
  return HOC_OK;
}

hoc_status hoc_report_finish(hoc_report *report, const hoc_stages *r, const hoc_mesh *final,
                             int findings, double t0) {
  report->r = *r;
  report->elements = hoc_mesh_num_elements(final);
  report->nodes = hoc_mesh_num_nodes(final);
  free(report->quality);
  HOC_ALLOC(report->quality, report->elements);
  HOC_TRY(hoc_mesh_measure(final, report->measure, report->quality, NULL, NULL));
  /* each face's pinches searched once for both findings */
  hoc_pinch_table pinches = {0};
  HOC_TRY(hoc_pinch_table_init(&pinches, final->model, HOC_PIPELINE_PINCH_SHARE, HOC_PINCHES));
  hoc_status status = HOC_OK;
  if (findings & HOC_FIND_TANGLED)
    status = find_tangled(report, final, report->quality, optimized_stage(r),
                          !!(findings & HOC_FIND_FROM_CAD), &pinches);
  if (status == HOC_OK && (findings & HOC_FIND_POOR))
    status = find_poor(report, r, final, report->quality, &pinches);
  hoc_pinch_table_free(&pinches);
  report->seconds = hoc_now() - t0;
  return status;
}

/* JSON -------------------------------------------------------------------- */

hoc_status hoc_report_json(const hoc_report *report, const hoc_report_files *files, char **json) {
  HOC_CHECK(json, HOC_ERR_ARGUMENT, "JSON output is NULL");
  *json = NULL;
  HOC_CHECK(report, HOC_ERR_ARGUMENT, "no report given");
  const hoc_report_files none = {0};
  if (!files) files = &none;
  const hoc_stages *r = &report->r;
  text t = {0};
  text_add(&t, "{\n  \"command\": ");
  json_string(&t, report->command);
  text_add(&t, ",\n  \"model\": ");
  json_string(&t, files->model);
  if (files->mesh) {
    text_add(&t, ",\n  \"mesh\": ");
    json_string(&t, files->mesh);
  }
  text_add(&t, ",\n  \"measure\": \"%s\",\n  \"version\": \"%s\",\n  \"stages\": [",
           report->measure == HOC_MEASURE_ODDY ? "oddy" : "shape", hoc_version());
  for (int i = 0; i < r->n; ++i) {
    const hoc_stage *s = &r->s[i].stage;
    const hoc_optimize_result *res = &r->s[i].result;
    text_add(&t,
             "%s\n    {\"name\": \"%s\", \"order\": %d, \"elements\": %zu, \"min\": %.17g, "
             "\"max\": %.17g, \"mean\": %.17g, \"std\": %.17g, \"tangled\": %zu, "
             "\"seconds\": %.6f, \"measure_seconds\": %.6f",
             i ? "," : "", s->name, s->stats.order, s->stats.elements, s->stats.min, s->stats.max,
             s->stats.mean, s->stats.std, s->stats.tangled, s->seconds, s->stats.seconds);
    if (s->optimized)
      text_add(&t,
               ", \"iterations\": %d, \"converged\": %s, \"best_iteration\": %d, "
               "\"second_attempt\": %d, \"exact_phase\": %d, \"protected_run\": %d, "
               "\"polished\": %zu, \"fragile\": %zu, \"objective_initial\": %.17g, "
               "\"objective\": %.17g",
               s->iterations, s->converged ? "true" : "false", res->best_iteration,
               res->diagnostics.second_attempt, res->diagnostics.exact_phase,
               res->diagnostics.protected_run, res->diagnostics.polished, res->diagnostics.fragile,
               s->objective_initial, s->objective);
    text_add(&t, "}");
  }
  text_add(&t,
           "\n  ],\n  \"refinements\": %d,\n  \"remeshings\": %d,\n  \"nodes\": %zu,\n  "
           "\"seconds\": %.6f,\n  \"model_seconds\": %.6f,\n  \"write_seconds\": %.6f\n}\n",
           r->refinements, r->remeshings, report->nodes, report->seconds, files->model_seconds,
           files->write_seconds);
  return text_take(&t, json);
}

hoc_status hoc_report_write_json(const hoc_report *report, const hoc_report_files *files,
                                 const char *path) {
  HOC_CHECK(path && path[0], HOC_ERR_ARGUMENT, "no file name given");
  char *json;
  HOC_TRY(hoc_report_json(report, files, &json));
  hoc_status status = hoc_write_file_atomic(path, json, strlen(json));
  free(json);
  return status;
}
