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
  if (!o->touched) return f;
  double fl = 0;
  for (size_t e = 0; e < o->m->n_elems; ++e)
    if (o->touched[e]) fl += o->fe[e];
  return fl;
}

/* Above HOC_OPT_PROTECT_MAX_ORDER, in a whole-mesh run, the elements that
 * start valid (exact test) with q < HOC_OPT_FRAGILE_Q are fragile: no step
 * may fold them between the samples (hoc_opt_guarded), and they are never
 * relaxed (relaxed). Sets o->fragile from qe; returns how many. */
static size_t mark_fragile(hoc_opt *o) {
  const hoc_mesh *m = o->m;
  size_t n = 0;
  if (m->order <= HOC_OPT_PROTECT_MAX_ORDER || o->touched) return 0;
  for (size_t e = 0; e < m->n_elems; ++e) {
    o->fragile[e] = o->qe[e] > 0 && o->qe[e] < HOC_OPT_FRAGILE_Q;
    n += o->fragile[e];
  }
  return n;
}

/* One run of the optimiser from the mesh as it is (see hoc_mesh_optimize);
 * its sweeps are numbered from it0 + 1, its seconds from t0; *limited:
 * its first phase used all its sweeps with elements still tangled. */
hoc_status hoc_opt_run(hoc_mesh *mesh, const hoc_optimize_options *options, int protect,
                               int it0, double t0, hoc_optimize_result *result, int *limited) {
  *limited = 0;
  hoc_optimize_options o;
  hoc_optimize_options_default(&o);
  if (options) o = *options;
  if (o.max_iterations <= 0) o.max_iterations = HOC_OPT_DEFAULT_MAX_ITERATIONS;
  if (!(o.tolerance > 0)) o.tolerance = HOC_OPT_DEFAULT_TOLERANCE;
  HOC_CHECK(o.measure == HOC_MEASURE_SHAPE || o.measure == HOC_MEASURE_ODDY, HOC_ERR_ARGUMENT,
            "unknown distortion measure %d", (int)o.measure);
  HOC_CHECK(o.max_iterations <= HOC_OPT_MAX_ITERATIONS_LIMIT, HOC_ERR_ARGUMENT, "too many iterations requested");
  HOC_CHECK(isfinite(o.tolerance), HOC_ERR_ARGUMENT, "tolerance must be a finite number");
  HOC_CHECK(o.free_rings >= 0, HOC_ERR_ARGUMENT, "free_rings must not be negative");
  hoc_opt ctx = {0};
  hoc_opt_scratch *scr = NULL;
  int nthreads = omp_get_max_threads();
  /* every node on the CAD from the start (a mesh read as written may have
   * nodes off the surface) */
  hoc_status status = hoc_mesh_update_xyz(mesh);
  if (status == HOC_OK) mesh->off_cad = 0;
  if (status == HOC_OK)
    status = hoc_opt_setup(&ctx, mesh, o.measure, o.fix_curves, o.free_elements, o.free_rings);
  ctx.protect = protect; /* (setup clears ctx) */
  if (status == HOC_OK) status = hoc_opt_eval_all(&ctx);
  if (status == HOC_OK) status = hoc_opt_scratch_alloc(&ctx, nthreads, &scr);
  if (status != HOC_OK) {
    hoc_opt_scratch_free(scr, nthreads);
    hoc_opt_free(&ctx);
    return status;
  }
  hoc_optimize_result res = {0};
  hoc_opt_snapshot best = {0}, pre = {0}; /* pre: the state before the polish */
  best.tangled = SIZE_MAX;
  for (size_t i = 0; i < mesh->n_nodes; ++i) {
    ctx.active[i] = ctx.ndof[i] > 0;
    res.free_nodes += ctx.ndof[i] > 0;
  }
  hoc_opt_wake_all(&ctx);
  double f, qmin;
  size_t tangled;
  /* the initial tangled count by the exact test (as measuring counts),
   * then the first phase's sampled state */
  ctx.exact = 1;
  HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
  res.tangled_initial = tangled;
  res.fragile = mark_fragile(&ctx);
  /* the first phase counts at the samples; a local repair (free_elements)
   * has no first phase: its few folds are counted by the exact test from
   * the start (the aircraft at order 10, a red-green split of its 11 folds:
   * 32 -> 1 so, where 32 -> 2 at the samples became 26 by the exact test
   * and went no lower than 11 in the exact phase) */
  ctx.exact = ctx.touched != NULL;
  memset(ctx.dirty, 1, mesh->n_elems);
  HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
  res.objective_initial = f;
  size_t fewest = tangled; /* and res.best_iteration = 0: when it was reached */
  if (tangled) HOC_TRY_GOTO(hoc_opt_snapshot_take(&best, mesh, tangled, f), done);
  /* last: the last sweep of this attempt; since: the sweep before the
   * mesh's run of untangled sweeps (or the second attempt) began */
  int stalled = 0, last = it0 + o.max_iterations, since = it0;
  int fell = it0; /* the last sweep of this attempt with a new fewest tangled */
  int smoothing = 0; /* sweeps after a polish that left none tangled */
  int cut = 0;  /* this attempt was ended before its sweeps ran out */
  double hist_f[HOC_OPT_STAGNATION_SWEEPS + 1], hist_q[HOC_OPT_STAGNATION_SWEEPS + 1];
  int it = it0;
  res.best_iteration = it0;
sweeps:
  for (;;) {
    ++it;
    if (it > last) {
      /* still tangled when the sweeps run out (or nothing moves): a second
       * attempt of half as many sweeps from the best state reached, with
       * the (u, v) rule relaxed too (relaxed_uv). Not in a local repair:
       * its regularisation is never raised, so nothing is relaxed and the
       * second attempt would only go over the first one's ground again
       * (the aircraft at order 10: sweeps 39-53 of a red-green split's
       * repair, no fewer tangled) */
      if (!tangled || ctx.relax_uv || best.tangled == SIZE_MAX || ctx.touched) {
        res.stopped_at_limit = tangled && !cut;
        break;
      }
      hoc_opt_snapshot_restore(&best, mesh);
      HOC_TRY_GOTO(hoc_opt_eval_all(&ctx), done);
      ctx.relax_uv = 1;
      ctx.eps = HOC_OPT_EPS;
      stalled = 0;
      since = fell = it - 1;
      cut = 0;
      last = it - 1 + HOC_OPT_LATER_SWEEPS(o.max_iterations);
      memset(ctx.dirty, 1, mesh->n_elems);
      hoc_opt_wake_all(&ctx);
      HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
      res.second_attempt = it;
    }
    size_t moved = 0;
    int local = ctx.exact && tangled;
    if (local) hoc_opt_mark_near(&ctx);
    else if (ctx.local) hoc_opt_wake_all(&ctx); /* the nodes left awake elsewhere */
    ctx.local = local;
    /* nodes near tangled elements and nodes of poor elements (q below half
     * the mean: those that set the mesh's worst quality) never sleep */
    double qmean = 0;
    for (size_t e = 0; e < mesh->n_elems; ++e) qmean += ctx.qe[e];
    qmean /= (double)(mesh->n_elems ? mesh->n_elems : 1);
    for (size_t e = 0; e < mesh->n_elems; ++e)
      if (ctx.region[e] || ctx.qe[e] < HOC_OPT_POOR_Q_SHARE * qmean)
        for (int i = 0; i < ctx.np; ++i) {
          size_t node = mesh->conn[e * (size_t)ctx.np + (size_t)i];
          if (ctx.ndof[node]) hoc_opt_wake_node(&ctx, node);
        }
    /* a step worth less than a small share of the average node's part of f
     * puts its block to sleep */
    ctx.min_gain =
        o.tolerance * free_objective(&ctx, f) / (double)(res.free_nodes ? res.free_nodes : 1);
    /* while untangling, every move wakes its neighbourhood (room is made by
     * moving nodes further out); then only significant ones do */
    ctx.wake_factor = tangled ? HOC_OPT_WAKE_UNTANGLING : HOC_OPT_WAKE_SMOOTHING;
    if (it == it0 + 1) {
      HOC_TRY_GOTO(hoc_opt_screen(&ctx), done);
      hoc_opt_wake_all(&ctx);
      for (size_t e = 0; e < mesh->n_elems; ++e)
        if (ctx.qe[e] < HOC_OPT_POOR_Q_SHARE * qmean)
          for (int i = 0; i < ctx.np; ++i) {
            size_t node = mesh->conn[e * (size_t)ctx.np + (size_t)i];
            if (ctx.ndof[node]) hoc_opt_wake_node(&ctx, node);
          }
    }
    /* the natural blocks, then every node on its own */
    for (int fam = 0; fam < 2; ++fam) {
      ctx.B = &ctx.fam[fam];
      for (int c = 0; c < ctx.B->n_colors; ++c) {
        size_t mc;
        HOC_TRY_GOTO(hoc_opt_do_color(&ctx, c, scr, nthreads, &mc), done);
        moved += mc;
      }
    }
    ctx.B = &ctx.fam[0];
    size_t tangled_before = tangled;
    HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
    res.iterations = it;
    if (tangled < fewest) {
      fewest = tangled;
      res.best_iteration = fell = it;
    }
    /* no new fewest for HOC_OPT_STALL_SWEEPS sweeps: this attempt ends (the count
     * has been seen to fall again after 32 on t20 at order 10) */
    if (tangled && it - fell >= (ctx.exact ? HOC_OPT_EXACT_STALL_SWEEPS : HOC_OPT_STALL_SWEEPS) && it < last) {
      last = it;
      cut = 1;
    }
    if (tangled && tangled < best.tangled)
      HOC_TRY_GOTO(hoc_opt_snapshot_take(&best, mesh, tangled, f), done);
    /* untangling that stalls: a smoother regularised landscape (larger
     * delta) for a while; back to the small one as soon as it moves on */
    if (tangled && tangled >= tangled_before) {
      /* cycle 1e-3 -> 1e-2 -> 1e-1 -> 1e-3: a large delta smooths the
       * landscape, a small one pushes the last folds open (in the exact
       * phase too: the analytic cylinder's corner folds open only so) */
      /* Not in a local repair (free_elements): there the relaxed region
       * folds more than it opens and the count comes back no lower (the
       * aircraft at order 10, a red-green split of its 11 folds, exact
       * test from the start: 1 left in 53 sweeps without the raise, 2 in
       * 43 with it, its raises climbing to 53) */
      if (!ctx.touched && ++stalled >= HOC_OPT_EPS_STALL) {
        ctx.eps = ctx.eps < HOC_OPT_EPS_RAISE_BELOW ? ctx.eps * HOC_OPT_EPS_RAISE : HOC_OPT_EPS;
        stalled = 0;
        memset(ctx.dirty, 1, mesh->n_elems); /* every delta changes */
        HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
      }
    } else if (tangled < tangled_before && ctx.eps > HOC_OPT_EPS) {
      ctx.eps = HOC_OPT_EPS;
      stalled = 0;
      memset(ctx.dirty, 1, mesh->n_elems);
      HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
    } else {
      stalled = 0;
    }
    if (o.progress) {
      hoc_optimize_iteration info = {it, f, qmin, tangled, moved, hoc_opt_now() - t0, 1 + ctx.relax_uv};
      if (o.progress(o.progress_user, &info)) {
        status = HOC_ERROR(HOC_ERR_INTERRUPTED, "optimisation interrupted");
        goto done;
      }
    }
    size_t active = 0;
    for (size_t i = 0; i < mesh->n_nodes; ++i) active += ctx.active[i];
    if (!active || !moved) {
      res.converged = tangled == 0;
      if (tangled && !ctx.relax_uv && !ctx.touched) {
        last = it; /* the second attempt */
        cut = 1;
        continue;
      }
      break;
    }
    /* stagnation: untangled for the last 10 sweeps, over which f fell by
     * less than 5% and the worst element gained less than 0.005 (compared
     * with a tangled sweep, f is regularised and q is 0: no measure of
     * progress) */
    int h = HOC_OPT_STAGNATION_SWEEPS + 1, now = it % h, then = (it - HOC_OPT_STAGNATION_SWEEPS) % h;
    hist_f[now] = free_objective(&ctx, f);
    hist_q[now] = qmin;
    if (tangled) since = it;
    if (tangled == 0 && it - since > HOC_OPT_STAGNATION_SWEEPS &&
        hist_f[then] - hist_f[now] < HOC_OPT_STAGNATION_F * hist_f[then] &&
        qmin - hist_q[then] < HOC_OPT_STAGNATION_Q) {
      res.converged = 1;
      break;
    }
  }
  if (best.tangled != SIZE_MAX && tangled > best.tangled) {
    hoc_opt_snapshot_restore(&best, mesh); /* more tangled than once: the best state reached */
    HOC_TRY_GOTO(hoc_opt_eval_all(&ctx), done);
    memset(ctx.dirty, 1, mesh->n_elems);
    HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
  }
  /* The second phase: the exact fold tests (hoc_element_folded) find
   * folds between the samples (an optimiser that keeps sigma > 0 at samples
   * can pinch an edge between two), whether or not the samples still see
   * some elements tangled (gmsh's order-3 bottle: 3 by samples, 48 by the
   * exact test; this phase leaves 11 where waiting for the samples to say
   * 0 left the 48), unless the sweeps ran out. From
   * here on the tangle test is exact, as measuring's, and the untangling
   * residuals see the edges densely. Not from the start: there it blocks
   * steps through states that fold between samples on the way to a better
   * mesh (t20 at order 5 ended with min q 0.33 instead of 0.49). */
  if (!ctx.exact) {
    ctx.exact = 1;
    memset(ctx.dirty, 1, mesh->n_elems);
    size_t sampled = tangled;
    *limited = res.stopped_at_limit;
    HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
    /* (not after sweeps cut short by --max-iterations with elements still
     * tangled by samples: the caller asked for no more) */
    if (tangled > sampled && (!sampled || !res.stopped_at_limit)) {
      res.exact_phase = it + 1;
      HOC_TRY_GOTO(hoc_opt_snapshot_take(&best, mesh, tangled, f), done);
      fewest = tangled;
      res.converged = 0;
      ctx.relax_uv = 0;
      ctx.eps = HOC_OPT_EPS;
      stalled = 0;
      since = fell = it;
      cut = 0;
      last = it + HOC_OPT_LATER_SWEEPS(o.max_iterations);
      goto sweeps; /* (each sweep wakes the nodes around the folds) */
    }
  }
  /* the few folds the sweeps leave: the polish (not when the sweeps ran
   * out: --max-iterations asked for no more) */
  if (tangled && ctx.exact && !res.stopped_at_limit) {
    size_t before = tangled;
    HOC_TRY_GOTO(hoc_opt_snapshot_take(&pre, mesh, tangled, f), done);
    HOC_TRY_GOTO(hoc_opt_polish(&ctx), done);
    HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
    if (tangled < before) {
      res.polished += before - tangled;
      if (!tangled && !smoothing) {
        /* all valid now: sweeps again, which keep every element valid,
         * smooth the polished patches (their elements come out of the
         * search barely valid) */
        smoothing = 1;
        res.converged = 0;
        ctx.eps = HOC_OPT_EPS;
        stalled = 0;
        since = fell = it;
        cut = 0;
        last = it + HOC_OPT_LATER_SWEEPS(o.max_iterations);
        hoc_opt_wake_all(&ctx);
        goto sweeps;
      }
    } else { /* none untangled: the sweeps' state, whose shapes are better */
      hoc_opt_snapshot_restore(&pre, mesh);
      HOC_TRY_GOTO(hoc_opt_eval_all(&ctx), done);
      memset(ctx.dirty, 1, mesh->n_elems);
      HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
    }
  }
done:
  hoc_opt_snapshot_free(&pre);
  hoc_opt_snapshot_free(&best);
  res.objective_final = f;
  res.tangled_final = tangled;
  res.seconds = hoc_opt_now() - t0;
  if (result) *result = res;
  hoc_opt_scratch_free(scr, nthreads);
  hoc_opt_free(&ctx);
  return status;
}
