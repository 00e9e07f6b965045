/* What the pipelines do where the linear mesh has inverted triangles (mesh
 * their faces again with gmsh's other algorithms), where the optimiser
 * leaves elements tangled or poor (split them in two chains of splits, mesh
 * their faces again finer, optimise the poor ones once more), and the two
 * starts of hoc_mesh_repair.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "optimize/optimize.h"
#include "pipeline/pipeline.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The optimiser's sweeps as events. */
static int iteration_event(void *user, const hoc_optimize_iteration *it) {
  const hoc_run *run = user;
  if (!run->o.event) return 0;
  char msg[256];
  snprintf(msg, sizeof msg,
           "iteration %3d: objective %.6g, min q %.4f, %zu tangled, %zu nodes moved (%.1f s)%s",
           it->iteration, it->objective, it->min_q, it->tangled, it->moved, it->seconds,
           it->attempt == 2 ? ", second attempt" : "");
  hoc_event ev = {.kind = HOC_EVENT_ITERATION, .message = msg, .iteration = it};
  return run->o.event(run->o.event_user, &ev);
}

/* hoc_repair_optimize, stopping at the repairs' deadline; full: every
 * phase converges by the first phase's rule (hoc_mesh_optimize_until). */
static hoc_status optimize_stage(const hoc_run *run, hoc_stages *r, const char *name, hoc_mesh *mesh,
                                 const unsigned char *free, int full) {
  const hoc_mesh_options *o = &run->o;
  if (o->check_gradient) {
    double err;
    HOC_TRY(hoc_mesh_check_gradient(mesh, o->measure, o->fix_curves, 200, &err));
    char msg[160];
    snprintf(msg, sizeof msg,
             "gradient check: largest relative difference to central differences %.2e (%s)", err,
             err < 1e-4 ? "ok" : "MISMATCH");
    hoc_event ev = {.kind = HOC_EVENT_CHECK, .message = msg, .value = err};
    if (o->event && o->event(o->event_user, &ev))
      return HOC_ERROR(HOC_ERR_INTERRUPTED, "interrupted by the event callback");
  }
  hoc_optimize_options oo;
  hoc_optimize_options_default(&oo);
  oo.measure = o->measure;
  oo.fix_curves = o->fix_curves;
  if (o->max_iterations) oo.max_iterations = o->max_iterations;
  oo.progress = iteration_event;
  oo.progress_user = (void *)run;
  oo.free_elements = free;
  oo.free_rings = HOC_PIPELINE_LOCAL_RINGS;
  HOC_TRY(hoc_run_event(run, HOC_EVENT_PROGRESS, "optimizing %zu elements",
                        hoc_mesh_num_elements(mesh)));
  hoc_optimize_result res;
  double t0 = hoc_now();
  int timed_out = 0;
  HOC_TRY(hoc_mesh_optimize_until(mesh, &oo, full, run->deadline, &res, &timed_out));
  if (timed_out && run->cut) *run->cut = 1;
  if (res.diagnostics.polished)
    HOC_TRY(hoc_run_event(run, HOC_EVENT_NOTE,
                          "the final polish untangled %zu element(s) the sweeps left",
                          res.diagnostics.polished));
  return hoc_run_stage(run, r, name, mesh, hoc_now() - t0, NULL, &res);
}

hoc_status hoc_repair_optimize(const hoc_run *run, hoc_stages *r, const char *name, hoc_mesh *mesh,
                               const unsigned char *free) {
  return optimize_stage(run, r, name, mesh, free, 0);
}

hoc_status hoc_repair_optimize_start(const hoc_run *run, hoc_stages *r, const char *name,
                                     hoc_mesh *mesh) {
  return optimize_stage(run, r, name, mesh, NULL, 1);
}

/* The CAD tags of the faces holding flagged elements, each once, in element
 * order (at most 20, then " ..."), each after a space. */
static void faces_text(const hoc_mesh *mesh, const unsigned char *flag, char *buf, size_t size) {
  size_t ne = hoc_mesh_num_elements(mesh), len = 0;
  int shown[20], n_shown = 0, more = 0;
  buf[0] = '\0';
  for (size_t e = 0; e < ne; ++e) {
    if (!flag[e]) continue;
    int tag = hoc_mesh_element_face_tag(mesh, e), seen = 0;
    for (int k = 0; k < n_shown && !seen; ++k)
      seen = shown[k] == tag;
    if (seen) continue;
    if (n_shown == 20) {
      more = 1;
      break;
    }
    shown[n_shown++] = tag;
    if (len < size) len += (size_t)snprintf(buf + len, size - len, " %d", tag);
  }
  if (more && len < size) snprintf(buf + len, size - len, " ...");
}

/* Where the optimiser leaves tangled elements of *mesh: split them in four
 * (their neighbours as `kind` says, to keep the mesh conforming; children
 * placed straight between their corners) and optimise again: *fine, with
 * the stages r (its first n_keep stages kept, then "split" and
 * "optimized"). The mesh split is `base` (the same elements as mesh, e.g.
 * the start mesh was optimised from), or mesh itself if base is NULL; if
 * fine_start is not NULL, it receives a copy of the split mesh before its
 * optimisation. */
static hoc_status split_tangled(const hoc_run *run, hoc_stages *r, int n_keep, hoc_split_kind kind,
                                const hoc_mesh *mesh, const hoc_mesh *base, hoc_mesh **fine,
                                hoc_mesh **fine_start) {
  size_t ne = hoc_mesh_num_elements(mesh), total = 0;
  unsigned char *tangled = NULL, *pieces = NULL, *children = NULL;
  hoc_status status = HOC_OK;
  HOC_ALLOC_GOTO(tangled, ne, done);
  double t0 = hoc_now();
  /* a split of the optimised mesh is optimised locally: its children and
   * the rings around them (HOC_PIPELINE_LOCAL_RINGS) */
  int local = !base;
  if (local) HOC_ALLOC_GOTO(pieces, ne, done);
  HOC_TRY_GOTO(hoc_mesh_measure(mesh, run->o.measure, NULL, tangled, NULL), done);
  HOC_TRY_GOTO(hoc_mesh_split(base ? base : mesh, tangled, kind, fine, pieces), done);
  if (local) {
    size_t nf = hoc_mesh_num_elements(*fine), j = 0;
    HOC_ALLOC_GOTO(children, nf, done);
    for (size_t e = 0; e < ne; j += pieces[e++])
      for (size_t c = j; c < j + pieces[e] && c < nf; ++c)
        children[c] = pieces[e] > 1;
  }
  for (size_t e = 0; e < ne; ++e)
    total += tangled[e];
  r->refinements++;
  char faces[320];
  faces_text(mesh, tangled, faces, sizeof faces);
  HOC_TRY_GOTO(hoc_run_event(run, HOC_EVENT_REPAIR,
                             "%zu element(s) still tangled; splitting them and their neighbours "
                             "%s (%zu -> %zu elements) and optimising %s again (refinement %d): "
                             "faces%s",
                             total,
                             kind == HOC_SPLIT_RED_GREEN ? "red-green" : "at their longest edges",
                             ne, hoc_mesh_num_elements(*fine),
                             local ? "the new elements and two rings around them" : "the mesh",
                             r->refinements, faces),
               done);
  r->n = n_keep; /* the stages before the optimisation stay */
  HOC_TRY_GOTO(hoc_run_stage(run, r, "split", *fine, hoc_now() - t0, NULL, NULL), done);
  if (fine_start) HOC_TRY_GOTO(hoc_mesh_copy(*fine, fine_start), done);
  HOC_TRY_GOTO(hoc_repair_optimize(run, r, "optimized", *fine, children), done);
done:
  free(tangled);
  free(pieces);
  free(children);
  if (status != HOC_OK) {
    hoc_mesh_destroy(fine);
    if (fine_start) hoc_mesh_destroy(fine_start);
  }
  return status;
}

/* Destroy *m unless it is one of keep[n]. */
static void drop_mesh(hoc_mesh **m, hoc_mesh *const *keep, int n) {
  for (int i = 0; i < n; ++i)
    if (*m == keep[i]) {
      *m = NULL;
      return;
    }
  hoc_mesh_destroy(m);
}

/* Two chains of splits from the optimised mesh *mesh, taken in turn: one
 * red-green (keeps shapes, but its two-way cuts make slivers thinner), one
 * at longest edges (cuts slivers across), each at most `refinements`
 * splits and each going on from its own latest result. Stops once a result
 * has no tangled element. Given `start`, the mesh *mesh was optimised from
 * (the same elements), the longest-edge chain splits that and then each of
 * its own split meshes as they were before their optimisation (the
 * elements that stay tangled flagged by the optimised ones): corners an
 * optimisation moved into a sliver that folds in (u, v) give children
 * folded the same way, split straight between them (gmsh's aircraft,
 * face 69: from the optimised meshes 4, 4, 8 tangled in three splits, from
 * the starts 6, 8, 4, 0 in four; gmsh 4.8's 6, 6, 5, 1, 1, 0 in six, hence
 * hoc_mesh_repair's default of 6). *mesh and *r become the result with the
 * fewest tangled elements (the earlier on a tie); r->refinements goes on
 * counting with every split made; the split results' stages keep r's
 * first n_keep stages. A trial gives no closing note (its caller decides
 * what it keeps). */
hoc_status hoc_repair_refine_tangled(const hoc_run *run, hoc_stages *r, int n_keep, hoc_mesh **mesh,
                                     const hoc_mesh *start, int trial) {
  static const hoc_split_kind kinds[2] = {HOC_SPLIT_RED_GREEN, HOC_SPLIT_LONGEST_EDGE};
  hoc_mesh *base = *mesh, *best = base, *cur[2] = {base, base};
  hoc_mesh *own_start = NULL; /* the longest-edge chain's latest split mesh, unoptimised */
  hoc_stages best_r = *r, chain_r[2] = {*r, *r};
  hoc_status status = HOC_OK;
  int made = r->refinements, made_before = made, levels = run->o.refinements;
  for (int level = 0; level < levels && status == HOC_OK; ++level)
    for (int k = 0; k < 2 && status == HOC_OK && hoc_stages_last(&best_r)->stage.stats.tangled &&
                    !hoc_run_late(run);
         ++k) {
      hoc_mesh *fine = NULL, *fine_start = NULL;
      int from_start = k == 1 && start;
      chain_r[k].refinements = made;
      /* the last level's split mesh is never split again: no copy of it */
      int more = level + 1 < levels;
      status = split_tangled(run, &chain_r[k], n_keep, kinds[k], cur[k], from_start ? start : NULL,
                             &fine, from_start && more ? &fine_start : NULL);
      made = chain_r[k].refinements;
      if (status != HOC_OK) break;
      if (from_start) {
        hoc_mesh_destroy(&own_start);
        start = own_start = fine_start;
      }
      hoc_mesh *keep[4] = {base, best, cur[1 - k], fine};
      drop_mesh(&cur[k], keep, 4);
      cur[k] = fine;
      if (hoc_stages_last(&chain_r[k])->stage.stats.tangled <
          hoc_stages_last(&best_r)->stage.stats.tangled) {
        hoc_mesh *keep2[3] = {base, cur[0], cur[1]};
        drop_mesh(&best, keep2, 3);
        best = fine;
        best_r = chain_r[k];
      }
    }
  hoc_mesh_destroy(&own_start);
  int improved = best != base;
  for (int k = 0; k < 2; ++k) {
    hoc_mesh *keep[3] = {base, best, k ? cur[0] : NULL};
    drop_mesh(&cur[k], keep, 3);
  }
  if (improved) hoc_mesh_destroy(&base);
  *mesh = best;
  *r = best_r;
  r->refinements = made;
  if (status == HOC_OK && !trial && improved)
    status = hoc_run_event(run, HOC_EVENT_NOTE,
                           "kept the mesh of refinement %d of %d, which has the fewest tangled "
                           "elements",
                           best_r.refinements, made);
  else if (status == HOC_OK && !trial && made > made_before)
    status = hoc_run_event(run, HOC_EVENT_NOTE,
                           "splitting left no fewer tangled elements: kept the mesh before it");
  return status;
}

hoc_status hoc_repair_split_first(const hoc_run *run, hoc_stages *r, hoc_mesh **ho, int unrefinable,
                                  int *done) {
  *done = 0;
  int keep_fewest = unrefinable != 0;
  int folds = unrefinable & (HOC_UNREFINABLE_FOLDS | HOC_UNREFINABLE_PINCHES),
      cusps = unrefinable & HOC_UNREFINABLE_CUSPS;
  char at_cusps[80] = "";
  if (cusps)
    snprintf(at_cusps, sizeof at_cusps,
             "at cusps of the CAD (two curves meeting under %g degrees)",
             HOC_PIPELINE_CUSP_DEGREES);
  const char *across = (unrefinable & HOC_UNREFINABLE_PINCHES)
                           ? (unrefinable & HOC_UNREFINABLE_FOLDS)
                                 ? "on faces that fold (their normal reverses inside them) or "
                                   "pinch (a line of their (u, v) maps to one point)"
                                 : "on faces that pinch (a line of their (u, v) maps to one point)"
                           : "on faces that fold (their normal reverses inside them)";
  char where[320];
  snprintf(where, sizeof where, "%s%s%s, %s", folds ? across : "",
           folds && cusps ? " or " : "", at_cusps,
           !cusps  ? "which a finer mesh crosses with more elements"
           : folds ? "which a finer mesh crosses with more elements or meets at the same angle"
                   : "whose angle a finer mesh keeps");
  if (unrefinable & HOC_UNREFINABLE_EACH) {
    *done = 1;
    return hoc_run_event(run, HOC_EVENT_REPAIR,
                         "the tangled elements are %s, and each crosses a fold or a pinch or "
                         "has a corner at a cusp itself: neither split nor meshed again (the "
                         "optimised mesh is kept)",
                         where);
  }
  hoc_mesh *copy = NULL;
  HOC_TRY(hoc_mesh_copy(*ho, &copy));
  hoc_stages trial = *r;
  hoc_status status =
      keep_fewest
          ? hoc_run_event(run, HOC_EVENT_REPAIR,
                          "the tangled elements are %s: at most %d split(s) per chain instead "
                          "of meshing the faces again (the result with the fewest tangled is "
                          "kept)",
                          where, HOC_PIPELINE_FOLD_SPLITS)
          : hoc_run_event(run, HOC_EVENT_REPAIR,
                          "splitting the tangled elements first (kept if that leaves none "
                          "tangled)");
  hoc_run fold_run = *run;
  if (keep_fewest && fold_run.o.refinements > HOC_PIPELINE_FOLD_SPLITS)
    fold_run.o.refinements = HOC_PIPELINE_FOLD_SPLITS;
  if (status == HOC_OK) status = hoc_repair_refine_tangled(&fold_run, &trial, 2, &copy, NULL, 1);
  size_t left = status != HOC_OK ? 0 : hoc_stages_last(&trial)->stage.stats.tangled;
  if (status == HOC_OK && keep_fewest) {
    int made = trial.refinements;
    size_t before = hoc_stages_last(r)->stage.stats.tangled;
    if (left < before) {
      hoc_mesh_destroy(ho);
      *ho = copy;
      *r = trial;
    } else {
      hoc_mesh_destroy(&copy);
      r->refinements = made;
    }
    *done = 1;
    return left < before ? hoc_run_event(run, HOC_EVENT_NOTE,
                                         "kept the mesh of refinement %d, which has the fewest "
                                         "tangled elements (%zu)",
                                         made, left)
                         : hoc_run_event(run, HOC_EVENT_NOTE,
                                         "splitting left no fewer tangled elements: kept the "
                                         "mesh before it");
  }
  if (status == HOC_OK && !left) {
    hoc_mesh_destroy(ho);
    *ho = copy;
    *r = trial;
    *done = 1;
    return hoc_run_event(run, HOC_EVENT_NOTE,
                         "kept the mesh of refinement %d, which has no tangled element",
                         trial.refinements);
  }
  if (status == HOC_OK && left < hoc_stages_last(r)->stage.stats.tangled && hoc_run_late(run)) {
    /* no remeshing follows: the fewer tangled are kept */
    hoc_mesh_destroy(ho);
    *ho = copy;
    *r = trial;
    return HOC_OK;
  }
  hoc_mesh_destroy(&copy);
  r->refinements = trial.refinements; /* made, though not kept */
  if (status == HOC_OK && !hoc_run_late(run))
    status =
        hoc_run_event(run, HOC_EVENT_NOTE,
                      "splitting left %zu tangled at best: meshing the faces again instead", left);
  return status;
}

hoc_status hoc_repair_refine_faces(const hoc_run *run, hoc_stages *r, const hoc_model *model,
                                   const hoc_mesh *lin, const hoc_mesh *ho, double **face_size) {
  size_t ne = hoc_mesh_num_elements(ho);
  unsigned char *tangled = NULL;
  hoc_status status = HOC_OK;
  HOC_ALLOC_GOTO(tangled, ne, done);
  if (!*face_size) HOC_ALLOC_GOTO(*face_size, (size_t)hoc_model_num_faces(model) + 1, done);
  HOC_TRY_GOTO(hoc_mesh_measure(ho, run->o.measure, NULL, tangled, NULL), done);
  HOC_TRY_GOTO(hoc_mesh_refine_bounds(lin, tangled, HOC_PIPELINE_REMESH_EDGE, *face_size), done);
  r->refinements++;
  r->remeshings++;
  size_t total = 0;
  for (size_t e = 0; e < ne; ++e)
    total += tangled[e];
  char faces[320];
  faces_text(ho, tangled, faces, sizeof faces);
  HOC_TRY_GOTO(hoc_run_event(run, HOC_EVENT_REPAIR,
                             "%zu element(s) still tangled; meshing their faces again with edges "
                             "half as long (remeshing %d of at most %d, refinement %d): faces%s",
                             total, r->remeshings, run->o.refinements, r->refinements, faces),
               done);
  r->n = 0;
done:
  free(tangled);
  return status;
}

/* Elements an untangled optimised mesh *mesh has below 0.9 x the linear
 * mesh's min q (HOC_PIPELINE_POOR, the bound hocad aims at): their nodes and
 * those of the rings around them optimised once more, alone (a stage
 * "smoothed"). Kept only if that raises the min q: the objective is a sum
 * over the elements, not their minimum. (The aircraft at order 10: its
 * splits next to a CAD curve 0.002 long, at the wing root, left 0.00197
 * against a linear 0.00230; this gives 0.00219 in 7 s.) */
hoc_status hoc_repair_smooth_low(const hoc_run *run, hoc_stages *r, hoc_mesh **mesh) {
  const hoc_stage *last = &hoc_stages_last(r)->stage;
  double bound = HOC_PIPELINE_POOR * r->s[0].stage.stats.min;
  if (!last->optimized || last->stats.tangled || !(last->stats.min < bound)) return HOC_OK;
  size_t ne = hoc_mesh_num_elements(*mesh), n_low = 0;
  double *q = NULL;
  unsigned char *low = NULL;
  hoc_mesh *copy = NULL;
  hoc_status status = HOC_OK;
  HOC_ALLOC_GOTO(low, ne, done);
  HOC_ALLOC_GOTO(q, ne, done);
  HOC_TRY_GOTO(hoc_mesh_measure(*mesh, run->o.measure, q, NULL, NULL), done);
  HOC_TRY_GOTO(hoc_mesh_copy(*mesh, &copy), done);
  for (size_t e = 0; e < ne; ++e) {
    low[e] = q[e] < bound;
    n_low += low[e];
  }
  hoc_stages trial = *r;
  HOC_TRY_GOTO(hoc_run_event(run, HOC_EVENT_REPAIR,
                             "%zu element(s) below 0.9 x the linear mesh's min q (%.4f); "
                             "optimising them and two rings around them once more",
                             n_low, r->s[0].stage.stats.min),
               done);
  hoc_run unbounded = *run; /* (rule 7 is not one of the bounded repairs) */
  unbounded.deadline = 0;
  HOC_TRY_GOTO(hoc_repair_optimize(&unbounded, &trial, "smoothed", copy, low), done);
  const hoc_stage *sm = &hoc_stages_last(&trial)->stage;
  if (!sm->stats.tangled && sm->stats.min > last->stats.min) {
    hoc_mesh_destroy(mesh);
    *mesh = copy;
    copy = NULL;
    *r = trial;
  } else {
    HOC_TRY_GOTO(hoc_run_event(run, HOC_EVENT_NOTE,
                               "that did not raise the min q (%.4f): kept the mesh before",
                               sm->stats.min),
                 done);
  }
done:
  hoc_mesh_destroy(&copy);
  free(q);
  free(low);
  return status;
}

/* The input's high-order nodes placed afresh from its corners, as
 * hoc_mesh_model places them (hoc_pipeline_raise), in *alt with a
 * "re-placed" stage, unless that tangles clearly more elements (over 10%
 * more) than the input (then *alt stays NULL).
 * Other meshers' placement (gmsh's SetOrder projects each node on the CAD)
 * can leave folds the optimiser does not undo from there, and the other way
 * round: hoc_mesh_repair tries both. */
static hoc_status replace_nodes(const hoc_run *run, hoc_stages *r, const hoc_mesh *mesh,
                                hoc_mesh **alt) {
  double t0 = hoc_now();
  hoc_mesh *lin = NULL;
  double *q = hoc_calloc(hoc_mesh_num_elements(mesh) + 1, sizeof *q);
  hoc_status s = q ? hoc_mesh_elevate(mesh, 1, HOC_NODES_EQUISPACED, &lin)
                   : HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  hoc_run same = *run; /* the input's node set */
  same.o.nodeset = hoc_mesh_nodeset(mesh);
  if (s == HOC_OK) s = hoc_pipeline_raise(&same, lin, hoc_mesh_order(mesh), alt, q);
  hoc_mesh_destroy(&lin);
  if (s == HOC_OK) s = hoc_run_stage(run, r, "re-placed", *alt, hoc_now() - t0, q, NULL);
  free(q);
  if (s != HOC_OK) {
    hoc_mesh_destroy(alt);
    return s;
  }
  size_t in = r->s[0].stage.stats.tangled;
  if (hoc_stages_last(r)->stage.stats.tangled > in + in / HOC_PIPELINE_REPLACED_SLACK) {
    /* clearly worse: not used */
    r->n--;
    hoc_mesh_destroy(alt);
  }
  return HOC_OK;
}

/* hoc_repair_optimize on mesh, a copy of it before kept in *start (if that
 * is not NULL): the start the result came from. */
static hoc_status optimize_keep_start(const hoc_run *run, hoc_stages *r, hoc_mesh *mesh,
                                      hoc_mesh **start) {
  if (start) HOC_TRY(hoc_mesh_copy(mesh, start));
  hoc_status status = hoc_repair_optimize(run, r, "optimized", mesh, NULL);
  if (status != HOC_OK && start) hoc_mesh_destroy(start);
  return status;
}

/* Optimise *mesh, or where a re-placed start exists, that first and, if it
 * stays tangled, the input's own nodes too: the result with fewer tangled
 * elements (then the lower objective) is kept in *mesh, and, if start is
 * not NULL, the mesh it was optimised from in *start (for the splits). */
hoc_status hoc_repair_optimize_starts(const hoc_run *run, hoc_stages *r, hoc_mesh **mesh,
                                      hoc_mesh **start) {
  hoc_mesh *alt = NULL, *alt_start = NULL;
  hoc_status status = HOC_OK;
  if (!run->o.keep_nodes && r->s[0].stage.stats.tangled && hoc_mesh_order(*mesh) > 1)
    HOC_TRY(replace_nodes(run, r, *mesh, &alt));
  if (!alt) return optimize_keep_start(run, r, *mesh, start);
  if ((status = optimize_keep_start(run, r, alt, start)) != HOC_OK ||
      !hoc_stages_last(r)->stage.stats.tangled) {
    hoc_mesh_destroy(mesh);
    *mesh = alt;
    return status;
  }
  if (start) { /* the re-placed start, until the input's own wins */
    alt_start = *start;
    *start = NULL;
  }
  hoc_stage_record from_alt = r->s[--r->n];
  if ((status = optimize_keep_start(run, r, *mesh, start)) != HOC_OK) {
    hoc_mesh_destroy(&alt);
    hoc_mesh_destroy(&alt_start);
    return status;
  }
  const hoc_stage *own = &hoc_stages_last(r)->stage;
  int alt_wins = from_alt.stage.stats.tangled < own->stats.tangled ||
                 (from_alt.stage.stats.tangled == own->stats.tangled &&
                  from_alt.stage.objective < own->objective);
  status = hoc_run_event(run, HOC_EVENT_NOTE,
                         "optimised from the re-placed nodes (%zu tangled left) and from the "
                         "input's own (%zu): kept the %s",
                         from_alt.stage.stats.tangled, own->stats.tangled,
                         alt_wins ? "re-placed start's result" : "input's");
  if (alt_wins) {
    r->s[r->n - 1] = from_alt;
    hoc_mesh_destroy(mesh);
    *mesh = alt;
    if (start) {
      hoc_mesh_destroy(start);
      *start = alt_start;
    }
  } else {
    hoc_mesh_destroy(&alt);
    hoc_mesh_destroy(&alt_start);
    r->s[r->n - 2] = r->s[r->n - 1]; /* the re-placed start was not used */
    r->n--;
  }
  return status;
}

/* Inverted linear triangles ------------------------------------------------ */

/* Elements of the order-1 mesh `lin` of each kind (hoc_inverted_kind), and
 * per face index those inverted on the CAD away from a fold (on_cad) and
 * its elements (elems). kind: [elements]; on_cad, elems: [faces] or NULL. */
static hoc_status linear_kinds(const hoc_run *run, const hoc_mesh *lin, unsigned char *kind,
                               size_t *on_cad, size_t *elems, size_t count[4]) {
  size_t ne = hoc_mesh_num_elements(lin);
  unsigned char *tangled = NULL;
  hoc_status status = HOC_OK;
  HOC_ALLOC_GOTO(tangled, ne, done);
  HOC_TRY_GOTO(hoc_mesh_measure(lin, run->o.measure, NULL, tangled, NULL), done);
  HOC_TRY_GOTO(hoc_mesh_inverted_kinds(lin, tangled, kind), done);
  int nf = lin->model->n_faces;
  for (int f = 0; on_cad && f < nf; ++f)
    on_cad[f] = elems[f] = 0;
  for (int k = 0; k < 4; ++k)
    count[k] = 0;
  for (size_t e = 0; e < ne; ++e) {
    count[kind[e]]++;
    if (!on_cad) continue;
    elems[lin->elem_face[e]]++;
    on_cad[lin->elem_face[e]] += kind[e] == HOC_INVERTED_ON_CAD;
  }
done:
  free(tangled);
  return status;
}

/* The CAD tags of the faces with flagged elements (faces_text) for the
 * elements of kind `k`. */
static hoc_status kind_faces(const hoc_mesh *mesh, const unsigned char *kind, unsigned char k,
                             char *buf, size_t size) {
  size_t ne = hoc_mesh_num_elements(mesh);
  unsigned char *flag = NULL;
  HOC_ALLOC(flag, ne);
  for (size_t e = 0; e < ne; ++e)
    flag[e] = kind[e] == k;
  faces_text(mesh, flag, buf, size);
  free(flag);
  return HOC_OK;
}

static const char *algorithm_name(int a) {
  return a == HOC_GMSH_MESH_ADAPT ? "MeshAdapt" : a == HOC_GMSH_DELAUNAY ? "Delaunay" : "default";
}

hoc_status hoc_repair_linear(const hoc_run *run, hoc_model *model, const hoc_linear_options *lo,
                             hoc_mesh **lin) {
  static const int others[] = HOC_PIPELINE_LINEAR_ALGORITHMS;
  enum { N_OTHERS = sizeof others / sizeof *others };
  int nf = model->n_faces;
  size_t ne = hoc_mesh_num_elements(*lin), count[4], left;
  unsigned char *kind = NULL;
  size_t *on_cad = NULL, *elems = NULL, *best = NULL, *t_on_cad = NULL, *t_elems = NULL;
  int *choice = NULL, *tried = NULL, *held = NULL;
  hoc_mesh *trial = NULL;
  hoc_status status = HOC_OK;
  char faces[320];
  if (!ne) return HOC_OK;
  HOC_ALLOC_GOTO(kind, ne, done);
  HOC_ALLOC_GOTO(on_cad, (size_t)nf + 1, done);
  HOC_ALLOC_GOTO(elems, (size_t)nf + 1, done);
  HOC_TRY_GOTO(linear_kinds(run, *lin, kind, on_cad, elems, count), done);
  if (count[HOC_INVERTED_ACROSS_FOLD]) {
    HOC_TRY_GOTO(kind_faces(*lin, kind, HOC_INVERTED_ACROSS_FOLD, faces, sizeof faces), done);
    HOC_TRY_GOTO(hoc_run_event(run, HOC_EVENT_NOTE,
                               "%zu linear element(s) cross a fold of their face, where its "
                               "normal phi_u x phi_v reverses (no straight triangle across it "
                               "is valid): faces%s",
                               count[HOC_INVERTED_ACROSS_FOLD], faces),
                 done);
  }
  if (!count[HOC_INVERTED_ON_CAD]) goto done;
  HOC_TRY_GOTO(kind_faces(*lin, kind, HOC_INVERTED_ON_CAD, faces, sizeof faces), done);
  HOC_TRY_GOTO(hoc_run_event(run, HOC_EVENT_REPAIR,
                             "%zu linear element(s) inverted on the CAD: their faces' linear "
                             "meshes made with gmsh's MeshAdapt and Delaunay algorithms too "
                             "(per face, the mesh with the fewest is kept): faces%s",
                             count[HOC_INVERTED_ON_CAD], faces),
               done);
  HOC_ALLOC_GOTO(best, (size_t)nf + 1, done);
  HOC_ALLOC_GOTO(t_on_cad, (size_t)nf + 1, done);
  HOC_ALLOC_GOTO(t_elems, (size_t)nf + 1, done);
  HOC_ALLOC_GOTO(choice, (size_t)nf + 1, done);
  HOC_ALLOC_GOTO(tried, (size_t)nf + 1, done);
  HOC_ALLOC_GOTO(held, (size_t)nf + 1, done); /* the algorithms *lin was meshed with */
  for (int f = 0; f < nf; ++f)
    best[f] = on_cad[f];
  left = count[HOC_INVERTED_ON_CAD];
  for (int a = 0; a < N_OTHERS && left; ++a) {
    for (int f = 0; f < nf; ++f)
      tried[f] = best[f] ? others[a] : choice[f];
    size_t te = 0;
    hoc_status s = hoc_mesh_generate_linear_with(model, lo, tried, &trial);
    if (s == HOC_OK) {
      te = hoc_mesh_num_elements(trial);
      unsigned char *tk = hoc_calloc(te ? te : 1, 1);
      s = tk ? linear_kinds(run, trial, tk, t_on_cad, t_elems, count)
             : HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      free(tk);
    }
    if (s == HOC_ERR_INTERRUPTED || s == HOC_ERR_MEMORY) {
      status = s;
      goto done;
    }
    if (s != HOC_OK) { /* gmsh could not: the faces keep their meshes */
      hoc_mesh_destroy(&trial);
      HOC_TRY_GOTO(hoc_run_event(run, HOC_EVENT_NOTE, "gmsh's %s algorithm failed: %s",
                                 algorithm_name(others[a]), hoc_last_error()),
                   done);
      continue;
    }
    /* a face meshed anew keeps the new mesh only with fewer inverted
     * elements and some elements (a face left empty has none) */
    int same = 1;
    for (int f = 0; f < nf; ++f) {
      if (tried[f] != choice[f] && t_elems[f] && t_on_cad[f] < best[f]) {
        left -= best[f] - t_on_cad[f];
        best[f] = t_on_cad[f];
        choice[f] = tried[f];
      }
      same = same && tried[f] == choice[f];
    }
    if (same) { /* the trial is the mesh of the choices so far */
      hoc_mesh_destroy(lin);
      *lin = trial;
      trial = NULL;
      memcpy(held, choice, (size_t)nf * sizeof *held);
    }
    hoc_mesh_destroy(&trial);
  }
  int held_choice = 1;
  for (int f = 0; f < nf; ++f)
    held_choice = held_choice && held[f] == choice[f];
  if (!held_choice) {
    HOC_TRY_GOTO(hoc_mesh_generate_linear_with(model, lo, choice, &trial), done);
    hoc_mesh_destroy(lin);
    *lin = trial;
    trial = NULL;
  }
  {
    char text[400];
    size_t len = 0;
    text[0] = '\0';
    for (int f = 0; f < nf && len < sizeof text; ++f)
      if (choice[f])
        len += (size_t)snprintf(text + len, sizeof text - len, "%sface %d with %s (%zu -> %zu)",
                                len ? ", " : "", model->faces[f].tag, algorithm_name(choice[f]),
                                on_cad[f], best[f]);
    if (len)
      HOC_TRY_GOTO(hoc_run_event(run, HOC_EVENT_NOTE,
                                 "meshed again: %s; %zu linear element(s) inverted on the CAD "
                                 "left",
                                 text, left),
                   done);
    else
      HOC_TRY_GOTO(hoc_run_event(run, HOC_EVENT_NOTE,
                                 "gmsh's other algorithms left no fewer inverted elements: kept "
                                 "the mesh"),
                   done);
  }
done:
  hoc_mesh_destroy(&trial);
  free(kind);
  free(on_cad);
  free(elems);
  free(best);
  free(t_on_cad);
  free(t_elems);
  free(choice);
  free(tried);
  free(held);
  return status;
}

hoc_status hoc_repair_tangled_unrefinable(const hoc_run *run, const hoc_mesh *mesh, int *why) {
  enum { TANGLED = 1, FOLDS = 2, OFF_CUSP = 4, PINCHED = 8 }; /* per face */
  *why = 0;
  size_t ne = hoc_mesh_num_elements(mesh);
  int nf = mesh->model->n_faces;
  unsigned char *tangled = NULL, *state = NULL, *at_cusp = NULL;
  /* pinches: lines that map to one point (within the collapse distance);
   * necks: lines whose image is short (HOC_PIPELINE_PINCH_SHARE) */
  hoc_pinch_table pinches = {0}, necks = {0};
  hoc_status status = HOC_OK;
  HOC_ALLOC_GOTO(tangled, ne, done);
  HOC_ALLOC_GOTO(at_cusp, ne + 1, done);
  HOC_ALLOC_GOTO(state, (size_t)nf + 1, done);
  HOC_TRY_GOTO(
      hoc_pinch_table_init(&pinches, mesh->model, HOC_PIPELINE_PINCH_SHARE, HOC_PINCHES), done);
  pinches.spread = hoc_mesh_collapse_distance(mesh->model);
  HOC_TRY_GOTO(
      hoc_pinch_table_init(&necks, mesh->model, HOC_PIPELINE_PINCH_SHARE, HOC_PINCHES), done);
  HOC_TRY_GOTO(hoc_mesh_measure(mesh, run->o.measure, NULL, tangled, NULL), done);
  HOC_TRY_GOTO(hoc_mesh_elements_at_cusps(mesh, HOC_PIPELINE_CUSP_DEGREES, tangled, at_cusp),
               done);
  int any = 0, each = 1; /* each tangled element across a fold or a pinch, or at a cusp */
  for (size_t e = 0; e < ne; ++e) {
    if (!tangled[e]) continue;
    any = 1;
    int f = mesh->elem_face[e], folds = 0, pinch = 0, neck = 0;
    state[f] |= TANGLED | (at_cusp[e] ? 0 : OFF_CUSP);
    if (at_cusp[e]) continue;
    HOC_TRY_GOTO(hoc_mesh_element_across_pinch(mesh, e, &pinches, &pinch), done);
    if (pinch) state[f] |= PINCHED;
    /* across a neck, a fold's image is short: a split's children meet it
     * at a node (surf114_face3.brep) */
    if (each && !pinch) HOC_TRY_GOTO(hoc_mesh_element_across_pinch(mesh, e, &necks, &neck), done);
    if (each && !pinch && !neck) HOC_TRY_GOTO(hoc_mesh_element_folds(mesh, e, &folds), done);
    each = each && (pinch || folds);
  }
  for (size_t e = 0; e < ne; ++e) {
    int f = mesh->elem_face[e], folds = 0;
    if (!(state[f] & TANGLED) || (state[f] & FOLDS)) continue;
    HOC_TRY_GOTO(hoc_mesh_element_folds(mesh, e, &folds), done);
    if (folds) state[f] |= FOLDS;
  }
  int kinds = 0;
  for (int f = 0; f < nf && any; ++f) {
    if (!(state[f] & TANGLED)) continue;
    if (state[f] & (FOLDS | PINCHED))
      kinds |= (state[f] & FOLDS ? HOC_UNREFINABLE_FOLDS : 0) |
               (state[f] & PINCHED ? HOC_UNREFINABLE_PINCHES : 0);
    else if (!(state[f] & OFF_CUSP))
      kinds |= HOC_UNREFINABLE_CUSPS;
    else
      any = 0; /* a face a finer mesh may serve */
  }
  *why = any ? kinds | (each ? HOC_UNREFINABLE_EACH : 0) : 0;
done:
  hoc_pinch_table_free(&pinches);
  hoc_pinch_table_free(&necks);
  free(tangled);
  free(state);
  free(at_cusp);
  return status;
}
