/* The drivers of the method end to end: hoc_mesh_model (`hocad mesh`: a
 * linear mesh, raised, optimised, remeshed finer or split where it stays
 * tangled), hoc_mesh_repair (`hocad optimize`: a given high-order mesh
 * optimised and split) and hoc_mesh_quality_report (`hocad quality`).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "pipeline/pipeline.h"
#include "mesh/mesh.h"
#include "quality/quality.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

hoc_status hoc_run_event(const hoc_run *run, hoc_event_kind kind, const char *fmt, ...) {
  if (!run->o.event) return HOC_OK;
  va_list ap;
  va_start(ap, fmt);
  int n = vsnprintf(NULL, 0, fmt, ap);
  va_end(ap);
  char *msg = n >= 0 ? malloc((size_t)n + 1) : NULL;
  if (!msg) return HOC_ERROR(HOC_ERR_MEMORY, "out of memory for a message");
  va_start(ap, fmt);
  vsnprintf(msg, (size_t)n + 1, fmt, ap);
  va_end(ap);
  hoc_event ev = {.kind = kind, .message = msg};
  int cancel = run->o.event(run->o.event_user, &ev);
  free(msg);
  return cancel ? HOC_ERROR(HOC_ERR_INTERRUPTED, "interrupted by the event callback") : HOC_OK;
}

hoc_status hoc_run_stage(const hoc_run *run, hoc_stages *r, const char *name, const hoc_mesh *mesh,
                         double seconds, const double *q, const hoc_optimize_result *result) {
  HOC_CHECK(r->n < HOC_PIPELINE_MAX_STAGES, HOC_ERR_INTERNAL, "more than %d stages",
            HOC_PIPELINE_MAX_STAGES);
  hoc_stage_record *s = &r->s[r->n];
  *s = (hoc_stage_record){0}; /* a slot reused after a refinement keeps nothing */
  s->stage.name = name;
  s->stage.seconds = seconds;
  if (q) {
    hoc_quality_stats_from(q, hoc_mesh_num_elements(mesh), hoc_mesh_order(mesh), &s->stage.stats);
  } else {
    HOC_TRY(hoc_mesh_measure(mesh, run->o.measure, NULL, NULL, &s->stage.stats));
  }
  if (result) {
    s->stage.optimized = 1;
    s->stage.iterations = result->iterations;
    s->stage.converged = result->converged;
    s->stage.objective_initial = result->objective_initial;
    s->stage.objective = result->objective_final;
    s->result = *result;
  }
  r->n++;
  if (!run->o.event) return HOC_OK;
  hoc_event ev = {.kind = HOC_EVENT_STAGE, .message = name, .stage = &s->stage};
  return run->o.event(run->o.event_user, &ev)
             ? HOC_ERROR(HOC_ERR_INTERRUPTED, "interrupted by the event callback")
             : HOC_OK;
}

void hoc_run_start_repairs(hoc_run *run, double first) {
  if (run->deadline > 0 || run->o.repair_time < 0) return;
  run->budget = run->o.repair_time > 0
                    ? run->o.repair_time
                    : HOC_PIPELINE_REPAIR_GROWTH * first + HOC_PIPELINE_REPAIR_SECONDS;
  run->deadline = hoc_now() + run->budget;
}

int hoc_run_late(const hoc_run *run) {
  int late = run->deadline > 0 && hoc_now() >= run->deadline;
  if (late && run->cut) *run->cut = 1;
  return late;
}

hoc_status hoc_run_note_late(const hoc_run *run) {
  if (!run->cut || !*run->cut) return HOC_OK;
  if (run->o.repair_time > 0)
    return hoc_run_event(run, HOC_EVENT_NOTE,
                         "the repairs took the %g s given them (repair time): no further "
                         "repair is made, and the attempt with the fewest tangled elements "
                         "is kept",
                         run->budget);
  return hoc_run_event(run, HOC_EVENT_NOTE,
                       "the repairs took the %.0f s given them (%d x the time to the first "
                       "optimised mesh + %d s): no further repair is made, and the attempt "
                       "with the fewest tangled elements is kept",
                       run->budget, HOC_PIPELINE_REPAIR_GROWTH, HOC_PIPELINE_REPAIR_SECONDS);
}

/* Options ----------------------------------------------------------------- */

void hoc_mesh_options_default(hoc_mesh_options *options) {
  if (!options) return;
  memset(options, 0, sizeof *options);
  options->order = 3;
  options->nodeset = HOC_NODES_EQUISPACED;
  options->measure = HOC_MEASURE_SHAPE;
  options->optimize = 1;
  options->refinements = -1;
  options->grading = 1;
}

/* Check the options both pipelines use; run gets a copy (defaults if
 * options is NULL). */
static hoc_status run_start(hoc_run *run, const hoc_mesh_options *options) {
  if (options)
    run->o = *options;
  else
    hoc_mesh_options_default(&run->o);
  const hoc_mesh_options *o = &run->o;
  HOC_CHECK(o->measure == HOC_MEASURE_SHAPE || o->measure == HOC_MEASURE_ODDY, HOC_ERR_ARGUMENT,
            "unknown distortion measure %d", (int)o->measure);
  HOC_CHECK(o->max_iterations >= 0, HOC_ERR_ARGUMENT, "max_iterations %d is negative",
            o->max_iterations);
  HOC_CHECK(o->refinements >= -1, HOC_ERR_ARGUMENT,
            "refinements %d out of range (-1 for the default, or 0 and above)", o->refinements);
  HOC_CHECK(!isnan(o->repair_time), HOC_ERR_ARGUMENT, "repair_time is not a number");
  run->deadline = run->budget = 0;
  run->cut = NULL;
  return HOC_OK;
}

/* Free the meshes *to[0..2] and move *from[0..2] into them (leaving NULL). */
static void move_meshes(hoc_mesh **to[3], hoc_mesh **from[3]) {
  for (int i = 0; i < 3; ++i) {
    hoc_mesh_destroy(to[i]);
    *to[i] = *from[i];
    *from[i] = NULL;
  }
}

/* Faces the linear mesher skipped: a warning naming them (up to 30). */
static hoc_status warn_failed_faces(const hoc_run *run, const hoc_mesh *lin) {
  int nfail = hoc_mesh_num_failed_faces(lin);
  if (!nfail) return HOC_OK;
  char faces[400];
  size_t len = 0;
  faces[0] = '\0';
  for (int i = 0; i < nfail && i < 30 && len < sizeof faces; ++i)
    len +=
        (size_t)snprintf(faces + len, sizeof faces - len, " %d", hoc_mesh_failed_face_tag(lin, i));
  char slow[160] = "";
  if (lin->timed_out_faces)
    snprintf(slow, sizeof slow,
             "; gmsh's mesher did not finish %d of them in %g s (--mesher-timeout)",
             lin->timed_out_faces, lin->mesher_timeout);
  return hoc_run_event(run, HOC_EVENT_WARNING,
                       "%d face(s) could not be meshed (the rest is processed): faces%s%s%s",
                       nfail, faces, nfail > 30 ? " ..." : "", slow);
}

/* A linear mesh graded down to short CAD curves and thin faces
 * (mesh/grading.c). */
static hoc_status note_graded(const hoc_run *run, const hoc_mesh *lin) {
  if (lin->graded_budget > 0)
    return hoc_run_event(run, HOC_EVENT_NOTE,
                         "gmsh did not finish the linear mesh graded down to short curves and "
                         "thin faces in %.1f s (%g x its first meshing + %g s): its first mesh "
                         "is kept",
                         lin->graded_budget, (double)HOC_LINEAR_GRADED_GROWTH,
                         HOC_LINEAR_GRADED_SECONDS);
  if (!lin->graded_curves && !lin->graded_faces) return HOC_OK;
  char curves[96] = "", faces[96] = "";
  if (lin->graded_curves)
    snprintf(curves, sizeof curves, "%d CAD curve(s) shorter than a tenth of the edges around them",
             lin->graded_curves);
  if (lin->graded_faces)
    snprintf(faces, sizeof faces, "%d face(s) narrower than a tenth of their edges",
             lin->graded_faces);
  return hoc_run_event(run, HOC_EVENT_NOTE,
                       "the linear mesh is graded down to %s%s%s: %zu triangles (gmsh's own "
                       "mesh: %zu, min q %.4f)",
                       curves, *curves && *faces ? " and " : "", faces, lin->n_elems,
                       lin->ungraded_elements, lin->ungraded_min_q);
}

/* Faces smaller than the default minimum size, meshed with it lowered
 * (HOC_LINEAR_SMALL_FACE_EDGES); a mesh made again without gmsh's
 * extension of sizes into the faces (HOC_LINEAR_UNEXTENDED). */
static hoc_status note_small_faces(const hoc_run *run, const hoc_mesh *lin) {
  if (lin->unextended_elements)
    HOC_TRY(hoc_run_event(run, HOC_EVENT_NOTE,
                          "gmsh's linear mesh had %zu triangles, more than twice what the faces "
                          "hold at the minimum size (it extends the edges of curves shorter than "
                          "that into the faces): made again without that extension",
                          lin->unextended_elements));
  if (!lin->small_faces) return HOC_OK;
  return hoc_run_event(run, HOC_EVENT_NOTE,
                       "%d face(s) smaller than the minimum size had no triangles: the linear "
                       "mesh is made with the minimum size %g (--size-min sets it)",
                       lin->small_faces, lin->small_min);
}

/* Edges of the linear mesh swapped (mesh/swap.c). */
static hoc_status note_swapped(const hoc_run *run, const hoc_mesh *lin) {
  if (!lin->swapped_edges) return HOC_OK;
  return hoc_run_event(run, HOC_EVENT_NOTE,
                       "%zu edge(s) of the linear mesh swapped, each where that raised the "
                       "smaller q of its two triangles: min q %.4f -> %.4f",
                       lin->swapped_edges, lin->swap_min_q[0], lin->swap_min_q[1]);
}

/* Pinches the linear mesh is cut along (mesh/pinch.c). */
static hoc_status note_cut(const hoc_run *run, const hoc_mesh *lin) {
  if (!lin->cut_pinches) return HOC_OK;
  return hoc_run_event(run, HOC_EVENT_NOTE,
                       "the linear mesh is cut along %d pinch(es): lines of a face's (u, v) "
                       "that the CAD maps to one point, which is a node, no triangle across "
                       "the line",
                       lin->cut_pinches);
}

/* Triangles the assembly dropped at collapsed sides (mesh/collapse.c). */
static hoc_status note_collapsed(const hoc_run *run, const hoc_mesh *lin) {
  if (!lin->n_collapsed) return HOC_OK;
  return hoc_run_event(run, HOC_EVENT_NOTE,
                       "%zu linear triangle(s) with two corners at one point (a face side of "
                       "zero length the model does not mark as collapsed) dropped; the side "
                       "is one node",
                       lin->n_collapsed);
}

/* hoc_mesh_model ---------------------------------------------------------- */

/* The meshes of one run of hoc_mesh_model. */
typedef struct model_meshes {
  hoc_mesh *lin, *ho, *written, *raised;
  /* the remeshing attempt with the fewest tangled elements so far (the
   * earlier on a tie), while another is tried */
  hoc_mesh *kept_lin, *kept_ho, *kept_raised;
} model_meshes;

static hoc_status check_model_options(const hoc_model *model, const hoc_mesh_options *o) {
  HOC_CHECK(o->order >= 1 && o->order <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT,
            "order %d out of range 1..%d", o->order, HOC_MAX_ORDER);
  HOC_CHECK(o->nodeset == HOC_NODES_EQUISPACED || o->nodeset == HOC_NODES_FEKETE ||
                o->nodeset == HOC_NODES_WARP_BLEND,
            HOC_ERR_ARGUMENT, "unknown node set %d", (int)o->nodeset);
  HOC_CHECK(isfinite(o->size) && o->size >= 0 && isfinite(o->size_min) && o->size_min >= 0 &&
                isfinite(o->curvature) && o->curvature >= 0,
            HOC_ERR_ARGUMENT, "sizes and curvature must be finite and >= 0 (0: choose)");
  HOC_CHECK(!(o->size_min > 0 && o->size > 0 && o->size_min > o->size), HOC_ERR_ARGUMENT,
            "minimum size %g exceeds size %g", o->size_min, o->size);
  HOC_CHECK(!o->linear || o->linear->model == model, HOC_ERR_MISMATCH,
            "the given linear mesh is on another model");
  return HOC_OK;
}

/* Per face of the mesh whose element qualities are q: elements tangled
 * (tangled[f], may be NULL) and min q (min[f]). */
static void face_quality(const hoc_mesh *m, const double *q, size_t *tangled, double *min) {
  size_t ne = hoc_mesh_num_elements(m);
  int nf = hoc_model_num_faces(m->model);
  for (int f = 0; f < nf; ++f) {
    if (tangled) tangled[f] = 0;
    min[f] = INFINITY;
  }
  for (size_t e = 0; e < ne; ++e) {
    int f = m->elem_face[e];
    if (tangled) tangled[f] += q[e] == 0.0;
    if (!(q[e] >= min[f])) min[f] = q[e];
  }
}

/* The q of a raise placed at the feet on the faces flagged in feet_faces
 * (hoc_mesh_elevate_feet), known from two others of the same source: qf
 * on those faces' elements (a placement at the feet on at least those
 * faces), qs (straight) on the others; measured again on the others that
 * have nodes on curves along those faces. */
static hoc_status raise_quality(const hoc_run *run, const hoc_mesh *m,
                                const unsigned char *feet_faces, const double *qf, double *qs) {
  size_t ne = hoc_mesh_num_elements(m), np = (size_t)m->np;
  unsigned char *curves = hoc_calloc((size_t)m->model->n_curves + 1, 1);
  unsigned char *again = hoc_calloc(ne + 1, 1);
  hoc_status status = HOC_OK;
  if (!curves || !again) status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  if (status == HOC_OK) hoc_mesh_feet_curves(m, feet_faces, curves);
  for (size_t e = 0; e < ne && status == HOC_OK; ++e) {
    if (feet_faces[m->elem_face[e]]) {
      qs[e] = qf[e];
      continue;
    }
    for (size_t k = 3; k < np; ++k) {
      size_t i = m->conn[e * np + k];
      if (m->dim[i] == HOC_ON_CURVE && curves[m->entity[i]]) again[e] = 1;
    }
  }
  if (status == HOC_OK) status = hoc_mesh_measure_some(m, run->o.measure, again, qs);
  free(curves);
  free(again);
  return status;
}

/* The interior nodes of out's elements with an edge on a CAD curve (out:
 * a raise of in; none on the faces flagged in skip, which may be NULL)
 * blended with those edges (hoc_mesh_blend_interior), element by element
 * where that makes the element valid or raises its q; qs: the elements'
 * q, updated (with skip: measured again first, the mesh may be the feet's
 * rebuilt one). */
static hoc_status blend_interior(const hoc_run *run, const hoc_mesh *in, hoc_mesh *out,
                                 const unsigned char *skip, double *qs) {
  size_t ne = hoc_mesh_num_elements(out), np = (size_t)out->np, n_flag = 0, n_keep = 0;
  int p = out->order;
  unsigned char *flag = hoc_calloc(ne + 1, 1), *keep = hoc_calloc(ne + 1, 1);
  double *qb = hoc_calloc(ne + 1, sizeof *qb);
  hoc_mesh *copy = NULL;
  hoc_status status = HOC_OK;
  if (!flag || !keep || !qb) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (size_t e = 0; e < ne; ++e) {
    if (skip && skip[out->elem_face[e]]) continue;
    for (size_t k = 3; k < 3 * (size_t)p && !flag[e]; ++k)
      flag[e] = out->dim[out->conn[e * np + k]] == HOC_ON_CURVE;
    n_flag += flag[e];
  }
  if (!n_flag) goto done;
  if (skip) HOC_TRY_GOTO(hoc_mesh_measure_some(out, run->o.measure, flag, qs), done);
  HOC_TRY_GOTO(hoc_mesh_copy(out, &copy), done);
  HOC_TRY_GOTO(hoc_mesh_blend_interior(in, copy, flag), done);
  HOC_TRY_GOTO(hoc_mesh_measure_some(copy, run->o.measure, flag, qb), done);
  for (size_t e = 0; e < ne; ++e) {
    keep[e] = flag[e] && (qs[e] > 0 ? qb[e] > qs[e] : qb[e] > 0);
    n_keep += keep[e];
  }
  if (!n_keep) goto done;
  HOC_TRY_GOTO(hoc_mesh_blend_interior(in, out, keep), done);
  for (size_t e = 0; e < ne; ++e)
    if (keep[e]) qs[e] = qb[e];
done:
  hoc_mesh_destroy(&copy);
  free(flag);
  free(keep);
  free(qb);
  return status;
}

hoc_status hoc_pipeline_raise(const hoc_run *run, const hoc_mesh *in, int order, hoc_mesh **out,
                              double *q) {
  hoc_nodeset set = run->o.nodeset;
  hoc_measure measure = run->o.measure;
  HOC_TRY(hoc_mesh_elevate(in, order, set, out));
  size_t ne = hoc_mesh_num_elements(in);
  int nf = hoc_model_num_faces(in->model);
  hoc_mesh *feet = NULL;
  size_t *tangled = hoc_calloc(2 * (size_t)nf + 1, sizeof *tangled);
  double *min = hoc_calloc(3 * (size_t)nf + 1, sizeof *min);
  unsigned char *flag = hoc_calloc((size_t)nf + 1, 1), *take = hoc_calloc((size_t)nf + 1, 1);
  unsigned char *elems = hoc_calloc(ne + 1, 1);
  double *qs = hoc_calloc(2 * ne + 1, sizeof *qs), *qf = NULL;
  hoc_status status = HOC_OK;
  if (!tangled || !min || !flag || !take || !elems || !qs) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  qf = qs + ne;
  HOC_TRY_GOTO(hoc_mesh_measure(*out, measure, qs, NULL, NULL), done);
  if (order < 2) goto done;
  /* interior nodes that follow the edges on curves, where that helps;
   * the feet are compared with that */
  if (order >= 3) HOC_TRY_GOTO(blend_interior(run, in, *out, NULL, qs), done);
  /* the feet are tried on the faces whose straight elements tangle or
   * lose q against the source's (HOC_PIPELINE_FOOT_GAIN) */
  HOC_TRY_GOTO(hoc_mesh_measure(in, measure, qf, NULL, NULL), done);
  face_quality(in, qf, NULL, min + 2 * nf);
  face_quality(*out, qs, tangled, min);
  int n_flag = 0;
  for (int f = 0; f < nf; ++f) {
    flag[f] =
        tangled[f] > 0 || min[f] < min[2 * nf + f] - HOC_PIPELINE_FOOT_GAIN * fabs(min[2 * nf + f]);
    n_flag += flag[f];
  }
  if (!n_flag) goto done;
  HOC_TRY_GOTO(hoc_mesh_elevate_feet_from(in, *out, flag, &feet), done);
  for (size_t e = 0; e < ne; ++e)
    elems[e] = flag[in->elem_face[e]];
  HOC_TRY_GOTO(hoc_mesh_measure_some(feet, measure, elems, qf), done);
  face_quality(feet, qf, tangled + nf, min + nf);
  int n_take = 0;
  for (int f = 0; f < nf; ++f) {
    take[f] = flag[f] && (tangled[nf + f] < tangled[f] ||
                          (tangled[nf + f] == tangled[f] &&
                           min[nf + f] > min[f] + HOC_PIPELINE_FOOT_GAIN * fabs(min[f])));
    n_take += take[f];
  }
  if (!n_take) goto done;
  if (n_take == n_flag) {
    hoc_mesh_destroy(out);
    *out = feet;
    feet = NULL;
  } else {
    HOC_TRY_GOTO(hoc_mesh_take_feet(*out, feet, take), done);
  }
  HOC_TRY_GOTO(raise_quality(run, *out, take, qf, qs), done);
  /* the other faces' elements along curves whose nodes went to the feet:
   * blended again with their edges there */
  if (order >= 3) HOC_TRY_GOTO(blend_interior(run, in, *out, take, qs), done);
done:
  if (status == HOC_OK && q) memcpy(q, qs, ne * sizeof *q);
  if (status != HOC_OK) hoc_mesh_destroy(out);
  hoc_mesh_destroy(&feet);
  free(tangled);
  free(min);
  free(flag);
  free(take);
  free(elems);
  free(qs);
  return status;
}

/* The linear mesh of an attempt: the given one's corners, or the linear
 * mesher's with face bounds lo->face_size; *unlowered_min and
 * prev_elements as in mesh_model_run. */
static hoc_status linear_mesh(const hoc_run *run, hoc_model *model, hoc_linear_options *lo,
                              double unlowered_min, size_t prev_elements, hoc_mesh **lin) {
  const hoc_mesh_options *o = &run->o;
  if (o->linear) {
    /* a given linear mesh (e.g. gmsh's, to compare elevation on one mesh) */
    if (hoc_mesh_order(o->linear) != 1)
      return hoc_mesh_elevate(o->linear, 1, HOC_NODES_EQUISPACED, lin);
    return hoc_mesh_copy(o->linear, lin);
  }
  HOC_TRY(hoc_run_event(run, HOC_EVENT_PROGRESS, "meshing %d faces", hoc_model_num_faces(model)));
  HOC_TRY(hoc_mesh_generate_linear(model, lo, lin));
  /* the lowered minimum lets the curvature sizing go finer on every
   * face, not only on those meshed again (the aircraft at order 7:
   * 192 990 elements from 7 818); halving the edges of every face
   * would at most quadruple the mesh, so beyond that it is undone */
  if (lo->size_min < unlowered_min &&
      hoc_mesh_num_elements(*lin) > HOC_PIPELINE_REMESH_GROWTH * prev_elements) {
    hoc_status status = hoc_run_event(
        run, HOC_EVENT_NOTE,
        "with the minimum size %g the faces made %zu elements, more than four times the %zu "
        "before: meshing them again with the minimum size %g",
        lo->size_min, hoc_mesh_num_elements(*lin), prev_elements, unlowered_min);
    hoc_mesh_destroy(lin);
    HOC_TRY(status);
    lo->size_min = unlowered_min;
    HOC_TRY(hoc_mesh_generate_linear(model, lo, lin));
  }
  /* triangles gmsh made inverted on the CAD: their faces meshed again */
  return hoc_repair_linear(run, model, lo, lin);
}

/* The start of a high order's optimisation from the optimised coarse
 * order (HOC_PIPELINE_COARSE_FROM): *ho (the direct raise, measured)
 * becomes lin raised to the coarse order, optimised (every phase to
 * convergence: hoc_repair_optimize_start), and raised to the order asked,
 * unless that leaves elements tangled at the coarse order
 * (then the direct raise, made again). */
static hoc_status coarse_start(const hoc_run *run, hoc_stages *r, const hoc_mesh *lin,
                               hoc_mesh **ho) {
  const hoc_mesh_options *o = &run->o;
  hoc_mesh *coarse = NULL, *raised = NULL;
  double *q = NULL;
  hoc_status status = HOC_OK;
  HOC_TRY(hoc_run_event(run, HOC_EVENT_PROGRESS, "optimising at order %d first",
                        HOC_PIPELINE_COARSE_ORDER));
  /* the direct raise is measured already: made again only if needed */
  hoc_mesh_destroy(ho);
  HOC_TRY_GOTO(hoc_pipeline_raise(run, lin, HOC_PIPELINE_COARSE_ORDER, &coarse, NULL), done);
  HOC_TRY_GOTO(hoc_repair_optimize_start(run, r, "coarse", coarse), done);
  if (hoc_stages_last(r)->stage.stats.tangled) {
    HOC_TRY_GOTO(hoc_run_event(run, HOC_EVENT_NOTE,
                               "order %d left %zu element(s) tangled: order %d starts from the "
                               "straight elements",
                               HOC_PIPELINE_COARSE_ORDER, hoc_stages_last(r)->stage.stats.tangled,
                               o->order),
                 done);
    HOC_TRY_GOTO(hoc_pipeline_raise(run, lin, o->order, ho, NULL), done);
    goto done;
  }
  double t0 = hoc_now();
  HOC_ALLOC_GOTO(q, hoc_mesh_num_elements(coarse) + 1, done);
  HOC_TRY_GOTO(hoc_pipeline_raise(run, coarse, o->order, &raised, q), done);
  HOC_TRY_GOTO(hoc_run_stage(run, r, "re-raised", raised, hoc_now() - t0, q, NULL), done);
  hoc_mesh_destroy(ho);
  *ho = raised;
  raised = NULL;
done:
  free(q);
  hoc_mesh_destroy(&raised);
  hoc_mesh_destroy(&coarse);
  return status;
}

/* The attempts of hoc_mesh_model: *final becomes the result (one of m's
 * meshes), *r its stages. */
static hoc_status mesh_model_run(hoc_run *run, hoc_model *model, model_meshes *m,
                                 hoc_stages *r, hoc_mesh **final) {
  const hoc_mesh_options *o = &run->o;
  double t_start = hoc_now();
  hoc_mesh **attempt[3] = {&m->lin, &m->ho, &m->raised};
  hoc_mesh **kept[3] = {&m->kept_lin, &m->kept_ho, &m->kept_raised};
  hoc_stages kept_r = {0};
  double *face_size = NULL, *q = NULL;
  hoc_status status = HOC_OK;
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.size_max = o->size;
  lo.size_min = o->size_min;
  lo.curvature = o->curvature;
  lo.order = o->order;
  lo.mesher_timeout = o->mesher_timeout;
  lo.grading = o->grading;
  /* the minimum size before a remeshing lowered it, and the elements of
   * the linear mesh before that remeshing */
  double unlowered_min = lo.size_min;
  size_t prev_elements = 0;
  double first_lin = 0; /* the first linear mesh's time */
  for (;;) {
    lo.face_size = face_size;
    double t0 = hoc_now();
    if (m->kept_ho) {
      /* a remeshing, in a time of its own and within the repairs': one
       * gmsh cannot make (an error, a crash, no end in that time, faces
       * lost) ends the remeshings, and the mesh kept so far is split */
      double end = t0 + HOC_PIPELINE_REMESH_GROWTH * first_lin + HOC_PIPELINE_REMESH_SECONDS;
      model->mesher_deadline = run->deadline > 0 ? fmin(end, run->deadline) : end;
      hoc_status made = linear_mesh(run, model, &lo, unlowered_min, prev_elements, &m->lin);
      model->mesher_deadline = 0;
      if (made == HOC_OK &&
          hoc_mesh_num_failed_faces(m->lin) > hoc_mesh_num_failed_faces(m->kept_lin))
        made = HOC_ERROR(HOC_ERR_MESH, "gmsh's mesher failed on %d face(s) more",
                         hoc_mesh_num_failed_faces(m->lin) -
                             hoc_mesh_num_failed_faces(m->kept_lin));
      if (made == HOC_ERR_INTERRUPTED || made == HOC_ERR_MEMORY) {
        status = made;
        goto done;
      }
      if (made != HOC_OK) {
        hoc_mesh_destroy(&m->lin);
        HOC_TRY_GOTO(hoc_run_event(run, HOC_EVENT_NOTE,
                                   "meshing the faces again failed (%s): splitting the mesh "
                                   "after %d remeshing(s)",
                                   hoc_last_error(), kept_r.remeshings),
                     done);
        int splits = r->refinements, remade = r->remeshings;
        move_meshes(attempt, kept);
        *r = kept_r;
        r->refinements = splits;
        r->remeshings = remade;
        if (!hoc_run_late(run)) status = hoc_repair_refine_tangled(run, r, 2, &m->ho, NULL, 0);
        *final = m->ho;
        break;
      }
    } else {
      HOC_TRY_GOTO(linear_mesh(run, model, &lo, unlowered_min, prev_elements, &m->lin), done);
    }
    double t_lin = hoc_now() - t0;
    if (!m->kept_ho) first_lin = t_lin;
    HOC_TRY_GOTO(warn_failed_faces(run, m->lin), done);
    HOC_TRY_GOTO(note_collapsed(run, m->lin), done);
    HOC_TRY_GOTO(note_small_faces(run, m->lin), done);
    HOC_TRY_GOTO(note_graded(run, m->lin), done);
    HOC_TRY_GOTO(note_swapped(run, m->lin), done);
    HOC_TRY_GOTO(note_cut(run, m->lin), done);
    HOC_TRY_GOTO(hoc_run_stage(run, r, "linear", m->lin, t_lin, NULL, NULL), done);
    *final = m->lin;
    if (o->order > 1) {
      HOC_TRY_GOTO(hoc_run_event(run, HOC_EVENT_PROGRESS, "raising %zu elements to order %d",
                                 hoc_mesh_num_elements(m->lin), o->order),
                   done);
      t0 = hoc_now();
      free(q);
      HOC_ALLOC_GOTO(q, hoc_mesh_num_elements(m->lin) + 1, done);
      HOC_TRY_GOTO(hoc_pipeline_raise(run, m->lin, o->order, &m->ho, q), done);
      HOC_TRY_GOTO(hoc_run_stage(run, r, "high-order", m->ho, hoc_now() - t0, q, NULL),
                   done);
      *final = m->ho;
    }
    /* order 1: triangles inverted on the CAD that gmsh's algorithms all
     * leave (see linear_mesh) are untangled by the optimiser at p = 1, in
     * the faces' parameters; a valid linear mesh stays gmsh's */
    if (o->optimize && o->order == 1 && hoc_stages_last(r)->stage.stats.tangled) {
      HOC_TRY_GOTO(hoc_mesh_copy(m->lin, &m->ho), done);
      HOC_TRY_GOTO(hoc_repair_optimize(run, r, "optimized", m->ho, NULL), done);
      *final = m->ho;
    }
    if (o->optimize && o->order > 1) {
      /* the raised mesh before optimisation, for pictures */
      if (o->keep_stages)
        HOC_TRY_GOTO(hoc_pipeline_raise(run, m->lin, o->order, &m->raised, NULL), done);
      if (o->order >= HOC_PIPELINE_COARSE_FROM) {
        HOC_TRY_GOTO(coarse_start(run, r, m->lin, &m->ho), done);
        *final = m->ho;
      }
      HOC_TRY_GOTO(hoc_repair_optimize(run, r, "optimized", m->ho, NULL), done);
    }
    /* elements left tangled: their faces meshed again finer, from the
     * start; in a given linear mesh, or once the remeshing is spent, the
     * elements split as hoc_mesh_repair splits them */
    if (!o->optimize || o->order < 2 || !hoc_stages_last(r)->stage.stats.tangled ||
        o->refinements < 1)
      break;
    hoc_run_start_repairs(run, hoc_now() - t_start);
    /* first the local repair, on a copy: splitting the tangled elements
     * (as below, once remeshing is spent) keeps the rest of the mesh; it
     * is kept if it leaves none tangled (the bottle at order 2: two
     * elements at its thread's end, which two remeshings only make worse).
     * From HOC_PIPELINE_REMESH_FIRST_FROM on, the remeshing comes first
     * unless no finer mesh opens the elements (see there) */
    int split_done = 0, unrefinable = 0, spent = o->linear || r->remeshings >= o->refinements;
    if (!spent && !hoc_run_late(run)) {
      HOC_TRY_GOTO(hoc_repair_tangled_unrefinable(run, m->ho, &unrefinable), done);
      if (unrefinable || o->order < HOC_PIPELINE_REMESH_FIRST_FROM) {
        status = hoc_repair_split_first(run, r, &m->ho, unrefinable, &split_done);
        *final = m->ho;
        if (status != HOC_OK || split_done) break;
      }
    }
    if (spent || hoc_run_late(run)) {
      size_t now_tangled = hoc_stages_last(r)->stage.stats.tangled;
      if (m->kept_ho && hoc_stages_last(&kept_r)->stage.stats.tangled < now_tangled) {
        int made = r->refinements, remade = r->remeshings;
        HOC_TRY_GOTO(hoc_run_event(run, HOC_EVENT_NOTE,
                                   "the last mesh has more tangled elements (%zu) than the one "
                                   "after %d remeshing(s) (%zu): %s that one",
                                   now_tangled, kept_r.remeshings,
                                   hoc_stages_last(&kept_r)->stage.stats.tangled,
                                   hoc_run_late(run) ? "keeping" : "going on from"),
                     done);
        move_meshes(attempt, kept);
        *r = kept_r;
        r->refinements = made;
        r->remeshings = remade;
      }
      if (!hoc_run_late(run)) status = hoc_repair_refine_tangled(run, r, 2, &m->ho, NULL, 0);
      *final = m->ho;
      break;
    }
    hoc_stages attempt_r = *r;
    HOC_TRY_GOTO(hoc_repair_refine_faces(run, r, model, m->lin, m->ho, &face_size), done);
    /* and unless size_min was given, let the curvature sizing go ten
     * times finer (the bottle's thread curls through 130 degrees within
     * 0.03 at its end, where the default minimum of 0.4 kept it coarse) */
    prev_elements = hoc_mesh_num_elements(m->lin);
    if (!(o->size_min > 0)) {
      double size_max, size_min;
      hoc_linear_sizes(model, &lo, &size_max, &size_min);
      unlowered_min = size_min;
      lo.size_min = size_min / HOC_PIPELINE_REMESH_MIN_SIZE;
    }
    if (!m->kept_ho || hoc_stages_last(&attempt_r)->stage.stats.tangled <
                           hoc_stages_last(&kept_r)->stage.stats.tangled) {
      move_meshes(kept, attempt);
      kept_r = attempt_r;
    } else {
      hoc_mesh_destroy(&m->raised);
      hoc_mesh_destroy(&m->ho);
      hoc_mesh_destroy(&m->lin);
    }
  }
  if (status == HOC_OK) status = hoc_run_note_late(run);
  if (status == HOC_OK && *final == m->ho && o->optimize && o->order > 1) {
    status = hoc_repair_smooth_low(run, r, &m->ho);
    *final = m->ho;
  }
  /* files hold equispaced nodes: measure what is written */
  if (status == HOC_OK && o->equispaced && o->nodeset != HOC_NODES_EQUISPACED && o->order >= 3) {
    double t0 = hoc_now();
    HOC_TRY_GOTO(hoc_mesh_convert(*final, HOC_NODES_EQUISPACED, &m->written), done);
    HOC_TRY_GOTO(hoc_run_stage(run, r, "written", m->written, hoc_now() - t0, NULL, NULL),
                 done);
    *final = m->written;
  }
done:
  free(face_size);
  free(q);
  return status;
}

hoc_status hoc_mesh_model(hoc_model *model, const hoc_mesh_options *options, hoc_mesh **mesh,
                          hoc_report **report) {
  if (mesh) *mesh = NULL;
  if (report) *report = NULL;
  HOC_CHECK(model, HOC_ERR_ARGUMENT, "no model given");
  hoc_run run;
  double t0 = hoc_now();
  int cut = 0;
  HOC_TRY(run_start(&run, options));
  run.cut = &cut;
  HOC_TRY(check_model_options(model, &run.o));
  if (run.o.refinements < 0)
    run.o.refinements = run.o.linear ? HOC_PIPELINE_SPLITS_GIVEN_LINEAR : HOC_PIPELINE_REMESHINGS;
  model_meshes m = {0};
  hoc_stages r = {0};
  hoc_mesh *final = NULL;
  hoc_report *rep = NULL;
  hoc_status status = mesh_model_run(&run, model, &m, &r, &final);
  if (status == HOC_OK) status = hoc_report_create("mesh", run.o.measure, &rep);
  if (status == HOC_OK) {
    int find = HOC_FIND_TANGLED | HOC_FIND_FROM_CAD;
    if (run.o.optimize && run.o.order > 1) find |= HOC_FIND_POOR;
    rep->failed_faces = hoc_mesh_num_failed_faces(m.lin);
    status = hoc_report_finish(rep, &r, final, find, t0);
  }
  if (status == HOC_OK && run.o.keep_stages) {
    /* the linear mesh is the result itself at order 1: the report has a copy */
    if (m.lin == final)
      status = hoc_mesh_copy(m.lin, &rep->linear);
    else {
      rep->linear = m.lin;
      m.lin = NULL;
    }
    rep->raised = m.raised;
    m.raised = NULL;
  }
  if (status == HOC_OK && mesh) {
    /* the result leaves m, which frees the rest */
    hoc_mesh **slots[3] = {&m.lin, &m.ho, &m.written};
    for (int i = 0; i < 3; ++i)
      if (*slots[i] == final) *slots[i] = NULL;
    *mesh = final;
  }
  if (status == HOC_OK && report) {
    *report = rep;
    rep = NULL;
  }
  hoc_report_destroy(&rep);
  hoc_mesh_destroy(&m.raised);
  hoc_mesh_destroy(&m.written);
  hoc_mesh_destroy(&m.ho);
  hoc_mesh_destroy(&m.lin);
  hoc_mesh_destroy(&m.kept_raised);
  hoc_mesh_destroy(&m.kept_ho);
  hoc_mesh_destroy(&m.kept_lin);
  return status;
}

/* hoc_mesh_repair --------------------------------------------------------- */

hoc_status hoc_mesh_repair(const hoc_mesh *in, const hoc_mesh_options *options, hoc_mesh **mesh,
                           hoc_report **report) {
  if (mesh) *mesh = NULL;
  if (report) *report = NULL;
  HOC_CHECK(in, HOC_ERR_ARGUMENT, "no mesh given");
  hoc_run run;
  int cut = 0;
  HOC_TRY(run_start(&run, options));
  run.cut = &cut;
  if (run.o.refinements < 0) run.o.refinements = HOC_PIPELINE_SPLITS_REPAIR;
  hoc_mesh *cur = NULL, *start = NULL;
  hoc_report *rep = NULL;
  hoc_stages r = {0};
  hoc_status status = HOC_OK;
  double t0 = hoc_now();
  HOC_TRY_GOTO(hoc_mesh_copy(in, &cur), done);
  HOC_TRY_GOTO(hoc_run_stage(&run, &r, "input", cur, hoc_now() - t0, NULL, NULL), done);
  HOC_TRY_GOTO(hoc_repair_optimize_starts(&run, &r, &cur, run.o.refinements > 0 ? &start : NULL),
               done);
  if (hoc_stages_last(&r)->stage.stats.tangled && run.o.refinements > 0) {
    hoc_run_start_repairs(&run, hoc_now() - t0);
    HOC_TRY_GOTO(hoc_repair_refine_tangled(&run, &r, 1, &cur, start, 0), done);
    HOC_TRY_GOTO(hoc_run_note_late(&run), done);
  }
  hoc_mesh_destroy(&start);
  HOC_TRY_GOTO(hoc_report_create("optimize", run.o.measure, &rep), done);
  HOC_TRY_GOTO(hoc_report_finish(rep, &r, cur, HOC_FIND_TANGLED, t0), done);
  if (mesh) {
    *mesh = cur;
    cur = NULL;
  }
  if (report) {
    *report = rep;
    rep = NULL;
  }
done:
  hoc_report_destroy(&rep);
  hoc_mesh_destroy(&start);
  hoc_mesh_destroy(&cur);
  return status;
}

/* hoc_mesh_quality_report ------------------------------------------------- */

hoc_status hoc_mesh_quality_report(const hoc_mesh *mesh, hoc_measure measure, hoc_report **report) {
  HOC_CHECK(report, HOC_ERR_ARGUMENT, "report output is NULL");
  *report = NULL;
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "no mesh given");
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.measure = measure;
  hoc_run run;
  HOC_TRY(run_start(&run, &o));
  hoc_stages r = {0};
  hoc_report *rep = NULL;
  double t0 = hoc_now();
  hoc_status status = hoc_run_stage(&run, &r, "input", mesh, hoc_now() - t0, NULL, NULL);
  if (status == HOC_OK) status = hoc_report_create("quality", measure, &rep);
  if (status == HOC_OK) status = hoc_report_finish(rep, &r, mesh, HOC_FIND_NOTHING, t0);
  if (status == HOC_OK)
    *report = rep;
  else
    hoc_report_destroy(&rep);
  return status;
}
