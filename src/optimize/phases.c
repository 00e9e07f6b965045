/* The phases of a run of the optimiser: the sweeps, their stopping rules,
 * the second attempt, the exact phase, the polish and the smoothing after
 * it.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "optimize/optimize_impl.h"
#include "optimize/tunables.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* The part of f the free nodes can change (all of it without
 * free_elements): the stopping rules' measure of progress. */
static double free_objective(const hoc_opt *o, double f) {
  if (!o->adj.touched) return f;
  double fl = 0;
  for (size_t e = 0; e < o->m->n_elems; ++e)
    if (o->adj.touched[e]) fl += o->el.fe[e];
  return fl;
}

/* Above HOC_OPT_PROTECT_MAX_ORDER, in a whole-mesh run, the elements that
 * start valid (exact test) with q < HOC_OPT_FRAGILE_Q are fragile: no step
 * may fold them between the samples (hoc_opt_guarded), and they are never
 * relaxed (relaxed). Sets o->el.fragile from qe; returns how many. */
static size_t mark_fragile(hoc_opt *o) {
  const hoc_mesh *m = o->m;
  size_t n = 0;
  if (m->order <= HOC_OPT_PROTECT_MAX_ORDER || o->adj.touched) return 0;
  for (size_t e = 0; e < m->n_elems; ++e) {
    o->el.fragile[e] = o->el.qe[e] > 0 && o->el.qe[e] < HOC_OPT_FRAGILE_Q;
    n += o->el.fragile[e];
  }
  return n;
}

/* The phases of a run, in order. The sweeping phases share one loop of
 * sweeps (run_sweeps) and differ in the state they start from; what
 * follows each is chosen by end_sweeps and polish_phase.
 *   SAMPLED         the first sweeps: the tangle test looks at samples
 *                   (quadrature points, nodes, the order-2p lattice). A
 *                   local repair (free_elements) tests exactly from here on.
 *   SECOND_ATTEMPT  the sweeps of an attempt ran out, or stalled, with
 *                   elements still tangled: half as many sweeps again from
 *                   the best state reached, the (u, v) rule relaxed too
 *                   (relaxed_uv in step.c). At most one before the exact
 *                   phase and one from its start on (none from
 *                   HOC_OPT_EXACT_RELAX_UV_MIN_ORDER, where the exact
 *                   phase relaxes the (u, v) rule from its start).
 *   EXACT           the samples' verdict is in, but the exact fold tests of
 *                   measuring find more elements tangled: sweeps with the
 *                   exact tests in every verdict and dense edge residuals.
 *   POLISH          the pattern search (polish.c) on the few folds left.
 *   SMOOTHING       the polish left none tangled: sweeps that keep every
 *                   element valid smooth its barely valid patches. Once.
 *   DONE */
typedef enum phase {
  PHASE_SAMPLED,
  PHASE_SECOND_ATTEMPT,
  PHASE_EXACT,
  PHASE_POLISH,
  PHASE_SMOOTHING,
  PHASE_DONE
} phase;

/* The state of a run (hoc_opt_run). */
typedef struct run {
  hoc_opt ctx;
  hoc_mesh *mesh;
  hoc_optimize_options opts; /* the caller's, defaults filled in */
  hoc_opt_rules rules;
  hoc_opt_scratch *scr;      /* [nthreads] */
  int nthreads;
  int it0;                   /* sweeps are numbered from it0 + 1 ... */
  double t0;                 /* ... and seconds counted from t0 */
  hoc_optimize_result res;
  int limited;               /* the sampled phase used all its sweeps, elements still tangled */
  hoc_opt_journal best; /* the state with the fewest tangled elements */
  hoc_opt_journal pre;  /* the state before the polish */
  double f, qmin;            /* objective and smallest q at the last sweep_start */
  size_t tangled;            /* tangled elements at the last sweep_start */
  size_t fewest;             /* fewest tangled so far (res.best_iteration: when) */
  int it;                    /* the last sweep number used */
  int last;                  /* the last sweep of this attempt */
  int since;                 /* the sweep before the mesh's run of untangled sweeps began
                                (or this attempt did) */
  int fell;                  /* the last sweep of this attempt with a new fewest tangled */
  int stalled;               /* sweeps in a row without fewer tangled (the delta cycle) */
  int cut;                   /* this attempt was ended before its sweeps ran out */
  int smoothing;             /* the smoothing phase has begun */
  int second;                /* the sweeps are a second attempt's */
  int late;                  /* the rules' deadline passed: the run ends */
  int settled;               /* the last phase that ended for lack of progress left none
                                tangled (its smoothing converged) */
  /* free part of f and smallest q of the last sweeps, at [sweep % size] */
  double hist_f[HOC_OPT_STAGNATION_SWEEPS + 1], hist_q[HOC_OPT_STAGNATION_SWEEPS + 1];
  int hist_it[HOC_OPT_STAGNATION_SWEEPS + 1]; /* the sweep each was recorded at */
} run;

/* The sweeps of a new attempt, after sweep r->it: up to `sweeps` of them. */
static void new_attempt(run *r, int sweeps) {
  r->stalled = 0;
  r->since = r->fell = r->it;
  r->cut = 0;
  r->last = r->it + sweeps;
}

/* Every element's state again at the next sweep_start. */
static hoc_status restart_state(run *r) {
  memset(r->ctx.el.dirty, 1, r->mesh->n_elems);
  return hoc_opt_sweep_start(&r->ctx, &r->f, &r->qmin, &r->tangled);
}

/* The mesh as in saved state s, and every element's state from it. */
static hoc_status restore(run *r, hoc_opt_journal *s) {
  HOC_TRY(hoc_opt_journal_restore(&r->ctx, s));
  HOC_TRY(hoc_opt_eval_all(&r->ctx));
  return restart_state(r);
}

/* The run's start: every free node awake, the initial tangled count by the
 * exact test (as measuring counts), fragile elements, then the sampled
 * phase's state. A local repair (free_elements) has no sampled phase: it
 * repairs a few folds, and counted at the samples it settles on states
 * the exact test still finds folded. */
static hoc_status begin(run *r) {
  hoc_opt *o = &r->ctx;
  r->best.tangled = SIZE_MAX;
  for (size_t i = 0; i < r->mesh->n_nodes; ++i) {
    o->node.active[i] = o->adj.ndof[i] > 0;
    r->res.free_nodes += o->adj.ndof[i] > 0;
  }
  hoc_opt_wake_all(o);
  o->cfg.exact = 1;
  HOC_TRY(hoc_opt_sweep_start(o, &r->f, &r->qmin, &r->tangled));
  r->res.tangled_initial = r->tangled;
  r->res.diagnostics.fragile = mark_fragile(o);
  o->cfg.exact = o->adj.touched != NULL;
  HOC_TRY(restart_state(r));
  r->res.objective_initial = r->f;
  r->fewest = r->tangled;
  /* (the start's state is saved in the first sweep, after the screening) */
  r->it = r->it0;
  r->res.best_iteration = r->it0;
  new_attempt(r, r->opts.max_iterations);
  return HOC_OK;
}

/* Wakes the nodes of element e that may move. */
static void wake_element(run *r, size_t e) {
  hoc_opt *o = &r->ctx;
  for (int i = 0; i < o->np; ++i) {
    size_t node = r->mesh->conn[e * (size_t)o->np + (size_t)i];
    if (o->adj.ndof[node]) hoc_opt_wake_node(o, node);
  }
}

/* One sweep (number r->it): who may move, then every colour of the
 * natural blocks and of the single nodes. *moved: nodes moved. */
static hoc_status sweep(run *r, size_t *moved) {
  hoc_opt *o = &r->ctx;
  hoc_mesh *mesh = r->mesh;
  *moved = 0;
  int local = o->cfg.exact && r->tangled;
  int near_only = r->tangled && r->mesh->order >= r->rules.wake_near_min_order;
  if (local || near_only) hoc_opt_mark_near(o);
  if (!local && o->cfg.local) hoc_opt_wake_all(o); /* the nodes left awake elsewhere */
  o->cfg.wake_near_only = near_only;
  o->cfg.local = local;
  /* nodes near tangled elements and nodes of poor elements (those that set
   * the mesh's worst quality) never sleep */
  double qmean = 0;
  for (size_t e = 0; e < mesh->n_elems; ++e) qmean += o->el.qe[e];
  qmean /= (double)(mesh->n_elems ? mesh->n_elems : 1);
  for (size_t e = 0; e < mesh->n_elems; ++e)
    if (o->el.region[e] || o->el.qe[e] < HOC_OPT_POOR_Q_SHARE * qmean) wake_element(r, e);
  /* a step worth less than a small share of the average node's part of f
   * puts its block to sleep */
  o->cfg.min_gain = r->opts.tolerance * free_objective(o, r->f) /
                    (double)(r->res.free_nodes ? r->res.free_nodes : 1);
  o->cfg.wake_factor = r->tangled ? HOC_OPT_WAKE_UNTANGLING : HOC_OPT_WAKE_SMOOTHING;
  if (r->it == r->it0 + 1) {
    HOC_TRY(hoc_opt_screen(o));
    /* the start as the best state so far: taken once the screening's
     * memory is free (at high orders each is a large share of the mesh's) */
    if (r->tangled) HOC_TRY(hoc_opt_journal_take(&r->ctx, &r->best, r->tangled, r->f));
    hoc_opt_wake_all(o);
    for (size_t e = 0; e < mesh->n_elems; ++e)
      if (o->el.qe[e] < HOC_OPT_POOR_Q_SHARE * qmean) wake_element(r, e);
  }
  hoc_opt_frames_assign(o);
  /* the natural blocks, then every node on its own */
  for (int fam = 0; fam < 2; ++fam) {
    o->B = &o->fam[fam];
    for (int c = 0; c < o->B->n_colors; ++c) {
      size_t mc;
      HOC_TRY(hoc_opt_do_color(o, c, r->scr, r->nthreads, &mc));
      *moved += mc;
    }
  }
  o->B = &o->fam[0];
  return HOC_OK;
}

/* After a sweep's sweep_start: the fewest tangled and the best state, the
 * stall rule, and the regularisation's cycle (tunables.h). */
static hoc_status after_sweep(run *r, size_t tangled_before) {
  hoc_opt *o = &r->ctx;
  r->res.iterations = r->it;
  if (r->tangled < r->fewest) {
    r->fewest = r->tangled;
    r->res.best_iteration = r->fell = r->it;
  }
  int stall = o->cfg.exact ? HOC_OPT_EXACT_STALL_SWEEPS : HOC_OPT_STALL_SWEEPS;
  if (r->tangled && r->it - r->fell >= stall && r->it < r->last) {
    r->last = r->it;
    r->cut = 1;
  }
  if (r->tangled && r->tangled < r->best.tangled)
    HOC_TRY(hoc_opt_journal_take(&r->ctx, &r->best, r->tangled, r->f));
  /* untangling that stalls: the next delta of the cycle; back to the
   * smallest as soon as it moves on. Not in a local repair
   * (free_elements): there the relaxed region folds more than it opens,
   * and the count comes back no lower. */
  if (r->tangled && r->tangled >= tangled_before) {
    if (!o->adj.touched && ++r->stalled >= HOC_OPT_EPS_STALL) {
      o->cfg.eps =
          o->cfg.eps < HOC_OPT_EPS_RAISE_BELOW ? o->cfg.eps * HOC_OPT_EPS_RAISE : HOC_OPT_EPS;
      r->stalled = 0;
      HOC_TRY(restart_state(r)); /* every delta changes */
    }
  } else if (r->tangled < tangled_before && o->cfg.eps > HOC_OPT_EPS) {
    o->cfg.eps = HOC_OPT_EPS;
    r->stalled = 0;
    HOC_TRY(restart_state(r));
  } else {
    r->stalled = 0;
  }
  return HOC_OK;
}

/* Records this sweep's free f and smallest q; 1 if smoothing stagnates
 * (tunables.h). Compared with a tangled sweep, f is regularised and q is
 * 0: no measure of progress, so only untangled sweeps count. */
static int stagnated(run *r) {
  int size = HOC_OPT_STAGNATION_SWEEPS + 1, now = r->it % size;
  r->hist_f[now] = free_objective(&r->ctx, r->f);
  r->hist_q[now] = r->qmin;
  r->hist_it[now] = r->it;
  if (r->tangled) r->since = r->it;
  /* after a phase converged, a shorter window, its bounds scaled
   * (HOC_OPT_SETTLED_SWEEPS) */
  int window = r->settled ? r->rules.settled_sweeps : HOC_OPT_STAGNATION_SWEEPS,
      then = (r->it - window) % size;
  double share = (double)window / HOC_OPT_STAGNATION_SWEEPS;
  return r->tangled == 0 && r->it - r->since > window && r->hist_it[then] == r->it - window &&
         r->hist_f[then] - r->hist_f[now] < share * HOC_OPT_STAGNATION_F * r->hist_f[then] &&
         r->qmin - r->hist_q[then] < share * HOC_OPT_STAGNATION_Q;
}

/* The sweeps of a sweeping phase until they end: *used_up when the
 * attempt's sweeps ran out or the stall rule cut them short, else nothing
 * moves any more or smoothing stagnated. */
static hoc_status run_sweeps(run *r, int *used_up) {
  hoc_opt *o = &r->ctx;
  *used_up = 0;
  for (;;) {
    if (r->rules.deadline > 0 && hoc_now() > r->rules.deadline) {
      r->late = 1;
      if (r->rules.timed_out) *r->rules.timed_out = 1;
    }
    if (r->it >= r->last || r->late) {
      *used_up = 1;
      return HOC_OK;
    }
    ++r->it;
    size_t moved, tangled_before = r->tangled;
    HOC_TRY(sweep(r, &moved));
    HOC_TRY(hoc_opt_sweep_start(o, &r->f, &r->qmin, &r->tangled));
    HOC_TRY(after_sweep(r, tangled_before));
    if (r->opts.progress) {
      hoc_optimize_iteration info = {r->it,  r->f,  r->qmin,
                                     r->tangled, moved, hoc_now() - r->t0,
                                     1 + r->second};
      if (r->opts.progress(r->opts.progress_user, &info))
        return HOC_ERROR(HOC_ERR_INTERRUPTED, "optimisation interrupted");
    }
    size_t active = 0;
    for (size_t i = 0; i < r->mesh->n_nodes; ++i) active += o->node.active[i];
    if (!active || !moved) {
      r->res.converged = r->settled = r->tangled == 0;
      if (r->tangled && !o->cfg.relax_uv && !o->adj.touched) {
        r->last = r->it; /* used up: the second attempt */
        r->cut = 1;
        continue;
      }
      return HOC_OK;
    }
    if (stagnated(r)) {
      r->res.converged = r->settled = 1;
      return HOC_OK;
    }
  }
}

/* The second attempt, if the sweeps ran out with elements still tangled
 * and none was made in this phase: from the best state reached, with the
 * (u, v) rule relaxed too. Not in a local repair: its regularisation is
 * never raised, so nothing is relaxed and a second attempt would only go
 * over the first one's ground again. *started: whether it was. */
static hoc_status second_attempt(run *r, int *started) {
  hoc_opt *o = &r->ctx;
  *started = r->tangled && !o->cfg.relax_uv && r->best.tangled != SIZE_MAX && !o->adj.touched;
  if (!*started) return HOC_OK;
  o->cfg.relax_uv = 1;
  r->second = 1;
  o->cfg.eps = HOC_OPT_EPS;
  new_attempt(r, HOC_OPT_LATER_SWEEPS(r->opts.max_iterations));
  hoc_opt_wake_all(o);
  HOC_TRY(restore(r, &r->best));
  r->res.diagnostics.second_attempt = r->it + 1;
  return HOC_OK;
}

/* The exact phase, if the exact fold tests find more elements tangled
 * than the samples did: an optimiser that keeps sigma > 0 at samples can
 * pinch an edge between two, and on coarse meshes the samples may see a
 * few folds where the exact tests find many. Not after sweeps cut short by
 * max_iterations with elements still tangled by samples: the caller asked
 * for no more. Not from the start: the exact tests block steps through
 * states that fold between samples on the way to a better mesh (on thin
 * parts, a markedly lower final quality). *next: PHASE_EXACT or
 * PHASE_POLISH. */
static hoc_status exact_phase(run *r, phase *next) {
  hoc_opt *o = &r->ctx;
  o->cfg.exact = 1;
  size_t sampled = r->tangled;
  r->limited = r->res.stopped_at_limit;
  HOC_TRY(restart_state(r));
  *next = PHASE_POLISH;
  if (!(r->tangled > sampled && (!sampled || !r->res.stopped_at_limit))) return HOC_OK;
  r->res.diagnostics.exact_phase = r->it + 1;
  HOC_TRY(hoc_opt_journal_take(&r->ctx, &r->best, r->tangled, r->f));
  r->fewest = r->tangled;
  r->res.converged = 0;
  /* from HOC_OPT_EXACT_RELAX_UV_MIN_ORDER (tunables.h; r->rules) the
   * (u, v) rule is relaxed from the phase's start, as in a second attempt,
   * which then has nothing left to relax and is not made */
  o->cfg.relax_uv = r->mesh->order >= r->rules.exact_relax_uv_min_order;
  r->second = 0;
  o->cfg.eps = HOC_OPT_EPS;
  new_attempt(r, HOC_OPT_LATER_SWEEPS(r->opts.max_iterations));
  *next = PHASE_EXACT; /* (each sweep wakes the nodes around the folds) */
  return HOC_OK;
}

/* A sweeping phase's sweeps ended (used_up: ran out): the second attempt,
 * or the best state if the last has more tangled, then the exact phase or
 * the polish. */
static hoc_status end_sweeps(run *r, int used_up, phase *next) {
  if (r->late) { /* past the deadline: the best state, counted exactly, nothing more */
    *next = PHASE_DONE;
    if (r->best.tangled != SIZE_MAX && r->tangled > r->best.tangled)
      HOC_TRY(restore(r, &r->best));
    r->ctx.cfg.exact = 1;
    return restart_state(r);
  }
  if (used_up) {
    int started;
    HOC_TRY(second_attempt(r, &started));
    if (started) {
      *next = PHASE_SECOND_ATTEMPT;
      return HOC_OK;
    }
    r->res.stopped_at_limit = r->tangled && !r->cut;
    ++r->it; /* (the number of the sweep that found the sweeps used up is not reused) */
  }
  if (r->best.tangled != SIZE_MAX && r->tangled > r->best.tangled)
    HOC_TRY(restore(r, &r->best)); /* more tangled than once: the best state reached */
  if (!r->ctx.cfg.exact) return exact_phase(r, next);
  *next = PHASE_POLISH;
  return HOC_OK;
}

/* The few folds the sweeps leave: the polish (not when the sweeps ran out:
 * max_iterations asked for no more), kept if it untangles some, and the
 * smoothing after it if it untangles all (once). *next: PHASE_SMOOTHING or
 * PHASE_DONE. */
static hoc_status polish_phase(run *r, phase *next) {
  hoc_opt *o = &r->ctx;
  *next = PHASE_DONE;
  if (!(r->tangled && o->cfg.exact && !r->res.stopped_at_limit)) return HOC_OK;
  size_t before = r->tangled;
  HOC_TRY(hoc_opt_journal_take(&r->ctx, &r->pre, r->tangled, r->f));
  HOC_TRY(hoc_opt_polish(o));
  HOC_TRY(hoc_opt_sweep_start(o, &r->f, &r->qmin, &r->tangled));
  hoc_status status = HOC_OK;
  if (r->tangled >= before) /* none untangled: the sweeps' state, whose shapes are better */
    status = restore(r, &r->pre);
  hoc_opt_journal_free(o, &r->pre); /* (logs no more moves) */
  if (status != HOC_OK || r->tangled >= before) return status;
  r->res.diagnostics.polished += before - r->tangled;
  if (r->tangled || r->smoothing) return HOC_OK;
  /* all valid now: sweeps again, which keep every element valid, smooth
   * the polished patches (their elements come out of the search barely
   * valid) */
  r->smoothing = 1;
  r->res.converged = 0;
  o->cfg.eps = HOC_OPT_EPS;
  new_attempt(r, HOC_OPT_LATER_SWEEPS(r->opts.max_iterations));
  hoc_opt_wake_all(o);
  *next = PHASE_SMOOTHING;
  return HOC_OK;
}

void hoc_opt_rules_default(hoc_opt_rules *rules) {
  rules->wake_near_min_order = HOC_OPT_WAKE_NEAR_MIN_ORDER;
  rules->exact_relax_uv_min_order = HOC_OPT_EXACT_RELAX_UV_MIN_ORDER;
  rules->frame_pool_bytes = HOC_OPT_FRAME_POOL_BYTES;
  rules->settled_sweeps = HOC_OPT_SETTLED_SWEEPS;
  rules->deadline = 0;
  rules->timed_out = NULL;
}

/* One run of the optimiser from the mesh as it is (see hoc_mesh_optimize);
 * its sweeps are numbered from it0 + 1, its seconds from t0; *limited:
 * its sampled phase used all its sweeps with elements still tangled. */
hoc_status hoc_opt_run(hoc_mesh *mesh, const hoc_optimize_options *options, int protect, int it0,
                       double t0, hoc_optimize_result *result, int *limited) {
  return hoc_opt_run_rules(mesh, options, NULL, protect, it0, t0, result, limited);
}

hoc_status hoc_opt_run_rules(hoc_mesh *mesh, const hoc_optimize_options *options,
                             const hoc_opt_rules *rules, int protect, int it0, double t0,
                             hoc_optimize_result *result, int *limited) {
  *limited = 0;
  hoc_optimize_options opts;
  hoc_optimize_options_default(&opts);
  if (options) opts = *options;
  if (opts.max_iterations <= 0) opts.max_iterations = HOC_OPT_DEFAULT_MAX_ITERATIONS;
  if (!(opts.tolerance > 0)) opts.tolerance = HOC_OPT_DEFAULT_TOLERANCE;
  HOC_CHECK(opts.measure == HOC_MEASURE_SHAPE || opts.measure == HOC_MEASURE_ODDY,
            HOC_ERR_ARGUMENT, "unknown distortion measure %d", (int)opts.measure);
  HOC_CHECK(opts.max_iterations <= HOC_OPT_MAX_ITERATIONS_LIMIT, HOC_ERR_ARGUMENT,
            "too many iterations requested");
  HOC_CHECK(isfinite(opts.tolerance), HOC_ERR_ARGUMENT, "tolerance must be a finite number");
  HOC_CHECK(opts.free_rings >= 0, HOC_ERR_ARGUMENT, "free_rings must not be negative");
  run *r = hoc_calloc(1, sizeof *r);
  HOC_CHECK(r, HOC_ERR_MEMORY, "out of memory");
  r->mesh = mesh;
  r->opts = opts;
  if (rules) r->rules = *rules;
  else hoc_opt_rules_default(&r->rules);
  r->nthreads = omp_get_max_threads();
  r->it0 = it0;
  r->t0 = t0;
  hoc_opt *o = &r->ctx;
  /* every node on the CAD from the start (a mesh read as written may have
   * nodes off the surface) */
  hoc_status status = hoc_mesh_update_xyz(mesh);
  if (status == HOC_OK) mesh->off_cad = 0;
  if (status == HOC_OK)
    status = hoc_opt_setup(o, mesh, opts.measure, opts.fix_curves, opts.free_elements,
                           opts.free_rings);
  if (status == HOC_OK && r->rules.frame_pool_bytes != HOC_OPT_FRAME_POOL_BYTES)
    status = hoc_opt_frames_setup(o, r->rules.frame_pool_bytes);
  o->cfg.protect = protect; /* (setup clears the state) */
  if (status == HOC_OK) status = hoc_opt_eval_all(o);
  if (status == HOC_OK) status = hoc_opt_scratch_alloc(o, r->nthreads, &r->scr);
  if (status != HOC_OK) {
    hoc_opt_scratch_free(r->scr, r->nthreads);
    hoc_opt_free(o);
    free(r);
    return status;
  }
  status = begin(r);
  phase ph = PHASE_SAMPLED;
  while (status == HOC_OK && ph != PHASE_DONE) {
    switch (ph) {
    case PHASE_SAMPLED:
    case PHASE_SECOND_ATTEMPT:
    case PHASE_EXACT:
    case PHASE_SMOOTHING: {
      int used_up;
      status = run_sweeps(r, &used_up);
      if (status == HOC_OK) status = end_sweeps(r, used_up, &ph);
      break;
    }
    case PHASE_POLISH: status = polish_phase(r, &ph); break;
    case PHASE_DONE: break;
    }
  }
  hoc_opt_journal_free(o, &r->pre);
  hoc_opt_journal_free(o, &r->best);
  r->res.objective_final = r->f;
  r->res.tangled_final = r->tangled;
  r->res.seconds = hoc_now() - t0;
  if (result) *result = r->res;
  *limited = r->limited;
  hoc_opt_scratch_free(r->scr, r->nthreads);
  hoc_opt_free(o);
  free(r);
  return status;
}
