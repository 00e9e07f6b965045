/* The final polish of the elements the sweeps leave tangled: a
 * derivative-free pattern search around each, one node at a time, on the
 * exact verdict itself. Gauss-Newton on the regularised objective trades a
 * fold against the shape of the whole neighbourhood and can settle with a
 * fold of a few thousandths where the surface's parametrisation is very
 * uneven (a face whose speed across its ends is a small fraction of that in
 * its middle); the search looks at nothing but the patch's folds. A move is kept only if no
 * element of the patch that was valid turns tangled or folds in (u, v), the
 * nodes stay in order along their curves, and the patch has fewer tangled
 * elements or the same with less negative sigma.
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

/* Element e's margin in the trial state of `moving` nodes: positive if the
 * exact test finds it valid; else its smallest sigma over its corners'
 * area if that is negative, or HOC_OPT_POLISH_HIDDEN_FOLD for a fold
 * between the samples. (Not sigma / |D phi|^2, which a node moved far away
 * shrinks towards 0: the search would improve the margin by moving a node
 * out of its element.) */
static double polish_margin(const hoc_opt *o, size_t e, double *x, double *n) {
  hoc_opt_gather(o, e, x, n);
  double eta, ms = 0;
  double q = hoc_element_quality_test(o->t, o->measure, x, n, 1, &eta, &ms);
  if (q > 0) return ms > 0 ? ms : DBL_MIN;
  double s = hoc_element_min_sigma_area(o->t, x, n);
  return s < 0 ? s : HOC_OPT_POLISH_HIDDEN_FOLD;
}

/* Tangled count and the sum of negative margins of elements el[0..n). */
static void polish_score(const hoc_opt *o, const size_t *el, size_t n, double *margin, double *x,
                         double *nrm, size_t *count, double *neg) {
  *count = 0;
  *neg = 0;
  for (size_t a = 0; a < n; ++a) {
    margin[a] = polish_margin(o, el[a], x, nrm);
    if (margin[a] < 0) {
      ++*count;
      *neg += margin[a];
    }
  }
}

/* One patch: the free nodes of the elements sharing a corner with e0. */
static hoc_status polish_patch(hoc_opt *o, size_t e0, unsigned char *mark) {
  hoc_mesh *m = o->m;
  int np = o->np;
  hoc_status status = HOC_OK;
  hoc_growlist gn = {0}, ge = {0};
  double *margin = NULL, *trial = NULL, *x = NULL, *nrm = NULL, *uv = NULL;
  unsigned char *pv = NULL;
  /* the patch's nodes, then every element using one of them (in order) */
  for (int c = 0; c < 3 && status == HOC_OK; ++c) {
    size_t corner = m->conn[e0 * (size_t)np + (size_t)c];
    for (size_t a = o->adj.ne_start[corner]; a < o->adj.ne_start[corner + 1]; ++a) {
      size_t e = o->adj.ne_elem[a];
      for (int i = 0; i < np && status == HOC_OK; ++i) {
        size_t k = m->conn[e * (size_t)np + (size_t)i];
        if (!o->adj.ndof[k] || o->node.moving[k]) continue;
        o->node.moving[k] = 1; /* (as a mark while collecting) */
        status = hoc_grow_push(&gn, k);
      }
    }
  }
  for (size_t a = 0; a < gn.n && status == HOC_OK; ++a)
    for (size_t b = o->adj.ne_start[gn.v[a]]; b < o->adj.ne_start[gn.v[a] + 1] && status == HOC_OK;
         ++b) {
      size_t e = o->adj.ne_elem[b];
      if (mark[e]) continue;
      mark[e] = 1;
      status = hoc_grow_push(&ge, e);
    }
  for (size_t a = 0; a < gn.n; ++a)
    o->node.moving[gn.v[a]] = 0;
  for (size_t a = 0; a < ge.n; ++a)
    mark[ge.v[a]] = 0;
  if (status != HOC_OK || !gn.n) goto done; /* (every node fixed: nothing to move) */
  const size_t *nodes = gn.v, *el = ge.v, nn = gn.n, nel = ge.n;
  margin = malloc(2 * nel * sizeof *margin);
  pv = malloc(nel);
  x = malloc(3 * (size_t)np * sizeof *x);
  nrm = malloc(3 * (size_t)np * sizeof *nrm);
  uv = malloc(2 * (size_t)np * sizeof *uv);
  if (!(margin && pv && x && nrm && uv)) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  trial = margin + nel;
  size_t count;
  double neg;
  polish_score(o, el, nel, margin, x, nrm, &count, &neg);
  for (size_t a = 0; a < nel; ++a)
    pv[a] = (unsigned char)hoc_opt_param_valid(o, el[a], uv);
  size_t measures = nel;
  /* steps: a share of the node's local length, halved when no move helps */
  for (double share = HOC_OPT_POLISH_SHARE;
       share > HOC_OPT_POLISH_MIN_SHARE && count && measures < HOC_OPT_POLISH_MAX_MEASURES;) {
    int improved = 0;
    for (size_t a = 0; a < nn && count && measures < HOC_OPT_POLISH_MAX_MEASURES; ++a) {
      size_t k = nodes[a];
      int nd = o->adj.ndof[k];
      for (int dir = 0; dir < 2 * nd && count; ++dir) {
        int d = dir / 2;
        const double *dz = o->node.dz + 6 * k + 3 * d;
        double speed = sqrt(dz[0] * dz[0] + dz[1] * dz[1] + dz[2] * dz[2]);
        if (!(speed > 0)) continue;
        double h = (dir % 2 ? -1 : 1) * share * hoc_opt_hsize(o, k) / speed;
        status = hoc_opt_trial_reserve(o, &k, 1);
        if (status != HOC_OK) goto done;
        double *tp = hoc_opt_tpar(o, k);
        tp[0] = m->param[2 * k];
        tp[1] = m->param[2 * k + 1];
        tp[d] += h;
        if (m->dim[k] == HOC_ON_CURVE) {
          const hoc_cad_curve *c = &o->model->curves[m->entity[k]];
          if (!(c->period > 0) && (tp[0] < c->lo || tp[0] > c->hi)) continue;
        }
        status = hoc_opt_eval_trial(o, k);
        if (status != HOC_OK) goto done;
        o->node.moving[k] = 1;
        int ok = 1;
        for (size_t b = o->adj.nl_start[k]; b < o->adj.nl_start[k + 1] && ok; ++b)
          ok = hoc_opt_line_monotone(o, o->adj.nl_line[b]);
        size_t tc = 0;
        double tneg = 0;
        for (size_t b = 0; b < nel && ok; ++b) {
          const size_t *cn = m->conn + el[b] * (size_t)np;
          int touches = 0;
          for (int i = 0; i < np && !touches; ++i)
            touches = cn[i] == k;
          trial[b] = touches ? polish_margin(o, el[b], x, nrm) : margin[b];
          measures += (size_t)touches;
          if (trial[b] < 0) {
            ok = margin[b] < 0; /* a valid element stays valid */
            tc++;
            tneg += trial[b];
          }
          if (ok && touches && pv[b]) ok = hoc_opt_param_valid(o, el[b], uv);
        }
        ok = ok && (tc < count || (tc == count && tneg > neg + HOC_OPT_POLISH_GAIN * fabs(neg)));
        if (ok) {
          hoc_opt_commit(o, k);
          memcpy(margin, trial, nel * sizeof *margin);
          count = tc;
          neg = tneg;
          improved = 1;
        }
        o->node.moving[k] = 0;
      }
    }
    if (!improved) share *= 0.5;
  }
done:
  free(gn.v);
  free(ge.v);
  free(margin);
  free(pv);
  free(x);
  free(nrm);
  free(uv);
  return status;
}

/* The polish of every element still tangled by the exact test (at most
 * HOC_OPT_POLISH_MAX_TANGLED of them), in element order; the caller counts what it
 * untangled at its next hoc_opt_sweep_start. */
hoc_status hoc_opt_polish(hoc_opt *o) {
  hoc_mesh *m = o->m;
  size_t tangled = 0;
  for (size_t e = 0; e < m->n_elems; ++e)
    tangled += o->el.qe[e] == 0.0;
  if (!tangled || tangled > HOC_OPT_POLISH_MAX_TANGLED) return HOC_OK;
  double *x = malloc(6 * (size_t)o->np * sizeof *x);
  unsigned char *mark = calloc(m->n_elems, 1);
  if (!x || !mark) {
    free(x);
    free(mark);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  hoc_status status = HOC_OK;
  for (size_t e = 0; e < m->n_elems && status == HOC_OK; ++e) {
    if (o->el.qe[e] != 0.0 || polish_margin(o, e, x, x + 3 * o->np) > 0) continue;
    status = polish_patch(o, e, mark);
  }
  free(x);
  free(mark);
  /* every element again at the next hoc_opt_sweep_start */
  memset(o->el.dirty, 1, m->n_elems);
  return status;
}

hoc_status hoc_mesh_polish(hoc_mesh *mesh, hoc_measure measure, int fix_curves, size_t *untangled) {
  HOC_CHECK(mesh && untangled, HOC_ERR_ARGUMENT, "NULL argument");
  *untangled = 0;
  hoc_opt ctx = {0};
  double f, qmin;
  size_t before = 0, after = 0;
  hoc_status status = hoc_mesh_update_xyz(mesh);
  if (status == HOC_OK) status = hoc_opt_setup(&ctx, mesh, measure, fix_curves, NULL, 0);
  if (status == HOC_OK) status = hoc_opt_eval_all(&ctx);
  ctx.cfg.exact = 1;
  if (status == HOC_OK) status = hoc_opt_sweep_start(&ctx, &f, &qmin, &before);
  if (status == HOC_OK) status = hoc_opt_polish(&ctx);
  if (status == HOC_OK) status = hoc_opt_sweep_start(&ctx, &f, &qmin, &after);
  if (status == HOC_OK) *untangled = before > after ? before - after : 0;
  hoc_opt_free(&ctx);
  return status;
}
