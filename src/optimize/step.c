/* One colour of a sweep: a damped Gauss-Newton step per active block on
 * its local objective, then a common backtracking line search whose trials
 * keep every rule (no valid element tangled, no fold in (u, v) at a face's
 * boundary, nodes in order along their curves).
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

/* Local objective of block b at the current state: f, gradient g[nd] and
 * Gauss-Newton matrix H[nd][nd] in its unknowns. */
void hoc_opt_block_model(const hoc_opt *o, size_t b, hoc_opt_scratch *s, double *f, double *g,
                         double *H) {
  const hoc_mesh *m = o->m;
  int np = o->np, nd = (int)(o->B->bd_start[b + 1] - o->B->bd_start[b]);
  int carries = hoc_opt_carry_end(o->B, b) > hoc_opt_carry_begin(o->B, b);
  *f = 0;
  memset(g, 0, (size_t)nd * sizeof *g);
  memset(H, 0, (size_t)nd * (size_t)nd * sizeof *H);
  for (size_t a = hoc_opt_be_begin(o->B, b); a < hoc_opt_be_end(o->B, b); ++a) {
    size_t e = o->B->be_elem[a];
    const size_t *cn = m->conn + e * (size_t)np;
    /* the block's nodes and those it carries: the columns of J it needs */
    for (int i = 0; i < np; ++i) {
      size_t node = cn[i];
      s->w[i] = 1;
      if (o->B->node_block[node] == b) {
        s->off[i] = hoc_opt_node_off(o->B, node);
        s->nd[i] = o->adj.ndof[node];
      } else if (carries && (s->w[i] = hoc_opt_carry_weight(o, b, node)) > 0) {
        s->off[i] = 0;
        s->nd[i] = 2;
      } else {
        s->nd[i] = 0;
      }
    }
    hoc_opt_gather(o, e, s->x, s->n);
    int nr = hoc_opt_elem_residuals(o, e, s->x, s->n, hoc_opt_frames_of(o, e), s->nd, s->r, s->J,
                                    NULL);
    double *Jz = s->Jz; /* [nr][nd] */
    memset(Jz, 0, (size_t)nr * (size_t)nd * sizeof *Jz);
    for (int i = 0; i < np; ++i) {
      size_t node = cn[i];
      int off = s->off[i], nd_i = s->nd[i];
      double w = s->w[i];
      if (!nd_i) continue;
      const double *dz = o->node.dz + 6 * node;
      for (int q = 0; q < nr; ++q) {
        const double *j = s->J + 3 * ((size_t)q * np + (size_t)i);
        Jz[q * nd + off] += w * (j[0] * dz[0] + j[1] * dz[1] + j[2] * dz[2]);
        if (nd_i == 2) Jz[q * nd + off + 1] += w * (j[0] * dz[3] + j[1] * dz[4] + j[2] * dz[5]);
      }
    }
    for (int q = 0; q < nr; ++q) {
      double r = s->r[q];
      const double *jz = Jz + q * nd;
      *f += r * r;
      for (int c = 0; c < nd; ++c) {
        g[c] += 2 * r * jz[c];
        for (int d = 0; d <= c; ++d) H[c * nd + d] += 2 * jz[c] * jz[d];
      }
    }
  }
  for (int c = 0; c < nd; ++c)
    for (int d = c + 1; d < nd; ++d) H[c * nd + d] = H[d * nd + c];
}

/* Solve (H + mu diag(H)) x = -g by Cholesky, raising mu until it works.
 * L: [nd][nd] scratch. Returns 0 if no step could be found. */
static int damped_solve(int nd, const double *H, const double *g, double *L, double *x) {
  double dmax = 0;
  for (int c = 0; c < nd; ++c) dmax = fmax(dmax, H[c * nd + c]);
  if (!(dmax > 0)) return 0;
  for (double mu = HOC_OPT_MU_FIRST; mu < HOC_OPT_MU_LAST; mu *= HOC_OPT_MU_GROWTH) {
    int ok = 1;
    for (int c = 0; c < nd && ok; ++c)
      for (int d = 0; d <= c; ++d) {
        double v = H[c * nd + d];
        if (c == d) v += mu * fmax(H[c * nd + c], HOC_OPT_DIAG_FLOOR * dmax);
        for (int k = 0; k < d; ++k) v -= L[c * nd + k] * L[d * nd + k];
        if (c == d) {
          if (!(v > 0)) {
            ok = 0;
            break;
          }
          L[c * nd + c] = sqrt(v);
        } else {
          L[c * nd + d] = v / L[d * nd + d];
        }
      }
    if (!ok) continue;
    for (int c = 0; c < nd; ++c) { /* L y = -g */
      double v = -g[c];
      for (int k = 0; k < c; ++k) v -= L[c * nd + k] * x[k];
      x[c] = v / L[c * nd + c];
    }
    for (int c = nd - 1; c >= 0; --c) { /* L^T x = y */
      double v = x[c];
      for (int k = c + 1; k < nd; ++k) v -= L[k * nd + c] * x[k];
      x[c] = v / L[c * nd + c];
    }
    return 1;
  }
  return 0;
}

/* While untangling stalls (a raised regularisation), the valid neighbours
 * of tangled elements may pass through sigma = 0 for a while: some folds
 * only open by moving their neighbourhood through an invalid state.
 * Fragile elements never (mark_fragile). Above HOC_OPT_PROTECT_MAX_ORDER
 * only in the exact phase: in the sampled phase of a high order, the
 * relaxed region folds between the samples more than it opens, and the
 * exact phase cannot open those folds again. In the exact phase the last
 * folds may need it (a single fold left on a periodic face at order 10
 * opens only so). */
static int relaxed(const hoc_opt *o, size_t e) {
  return o->el.region[e] && o->cfg.eps > HOC_OPT_EPS_RAISED && !o->el.fragile[e] &&
         (o->m->order <= HOC_OPT_PROTECT_MAX_ORDER || o->cfg.exact);
}

/* In the second attempt (relax_uv), and from HOC_OPT_EXACT_RELAX_UV_MIN_ORDER
 * in the exact phase, relaxed elements on a face's boundary may also fold
 * in (u, v): on a regular parametrisation that is the same fold as in 3D,
 * and the (u, v) rule would otherwise hold them where the 3D rule lets go.
 * Not on faces with a pole, where (u, v) folds without the surface
 * folding. Not in the sampled phase's first attempt: there, on thin parts
 * at high orders, it trades one fold for several. */
static int relaxed_uv(const hoc_opt *o, size_t e) {
  if (!o->cfg.relax_uv || !relaxed(o, e)) return 0;
  const hoc_cad_face *f = &o->model->faces[o->m->elem_face[e]];
  return !(f->pole[0] || f->pole[1] || f->pole[2] || f->pole[3]);
}

/* Local objective of block b at its trial (nodes flagged moving); 0 if the
 * trial breaks a rule. */
static int block_trial_flagged(const hoc_opt *o, size_t b, hoc_opt_scratch *s, double fmax,
                               double *f) {
  const hoc_mesh *m = o->m;
  *f = 0;
  for (size_t a = hoc_opt_bn_begin(o->B, b); a < hoc_opt_bn_end(o->B, b); ++a) {
    size_t k = o->B->bn_node[a];
    if (m->dim[k] != HOC_ON_CURVE) continue;
    for (size_t c = o->adj.nl_start[k]; c < o->adj.nl_start[k + 1]; ++c)
      if (!hoc_opt_line_monotone(o, o->adj.nl_line[c])) return 0;
  }
  for (size_t a = hoc_opt_be_begin(o->B, b); a < hoc_opt_be_end(o->B, b); ++a) {
    size_t e = o->B->be_elem[a];
    hoc_opt_gather(o, e, s->x, s->n);
    if (o->el.pvalid[e] && o->adj.on_boundary[e] && !relaxed_uv(o, e) &&
        !hoc_opt_param_valid(o, e, s->uv))
      return 0;
    const double *fr = hoc_opt_frames_of(o, e);
    if (fr) {
      double *tf = s->fr + (a - hoc_opt_be_begin(o->B, b)) * 9 * (size_t)o->fc.npts;
      hoc_opt_frames_trial(o, e, fr, tf);
      fr = tf;
    }
    double smin;
    int nr = hoc_opt_elem_residuals(o, e, s->x, s->n, fr, NULL, s->r, NULL, &smin);
    if (o->el.valid[e] && !relaxed(o, e) && !(smin > 0)) return 0;
    for (int q = 0; q < nr; ++q) *f += s->r[q] * s->r[q];
  }
  if (!isfinite(*f) || !(*f <= fmax)) return 0;
  /* a candidate: the dense part of the tangle test (nodes, validation
   * lattice) for the elements that must stay valid */
  for (size_t a = hoc_opt_be_begin(o->B, b); a < hoc_opt_be_end(o->B, b); ++a) {
    size_t e = o->B->be_elem[a];
    if (!o->el.valid[e] || relaxed(o, e)) continue;
    int exact = o->cfg.exact || (hoc_opt_guarded(o, e) && o->el.xvalid[e]);
    if (hoc_opt_frames_of(o, e)) {
      const double *tf = s->fr + (a - hoc_opt_be_begin(o->B, b)) * 9 * (size_t)o->fc.npts;
      if (hoc_element_frames_tangled(o->t, tf, o->nq, o->fc.npts)) return 0;
      if (!exact) continue;
      hoc_opt_gather(o, e, s->x, s->n);
      if (hoc_element_folded(o->t, s->x, s->n)) return 0;
      continue;
    }
    hoc_opt_gather(o, e, s->x, s->n);
    if (hoc_element_nodes_tangled(o->t, s->x, s->n, exact)) return 0;
  }
  return 1;
}

/* The kept frames of block b's elements become its trial's (accepted). */
static void frames_accept(hoc_opt *o, size_t b, const hoc_opt_scratch *s) {
  size_t size = 9 * (size_t)o->fc.npts;
  for (size_t a = hoc_opt_be_begin(o->B, b); a < hoc_opt_be_end(o->B, b); ++a) {
    double *fr = hoc_opt_frames_of(o, o->B->be_elem[a]);
    if (fr) memcpy(fr, s->fr + (a - hoc_opt_be_begin(o->B, b)) * size, size * sizeof *fr);
  }
}

static int block_trial(hoc_opt *o, size_t b, hoc_opt_scratch *s, double fmax, double *f) {
  hoc_opt_set_moving(o, b, 1);
  int ok = block_trial_flagged(o, b, s, fmax, f);
  if (ok) frames_accept(o, b, s);
  hoc_opt_set_moving(o, b, 0);
  return ok;
}

/* Block b touches a tangled element or one next to it. */
static int near_tangled(const hoc_opt *o, size_t b) {
  for (size_t a = hoc_opt_be_begin(o->B, b); a < hoc_opt_be_end(o->B, b); ++a)
    if (o->el.region[o->B->be_elem[a]] || !o->el.valid[o->B->be_elem[a]]) return 1;
  return 0;
}

/* Block b moves a node within HOC_OPT_NEAR_RINGS of a tangled element. */
static int near_fold(const hoc_opt *o, size_t b) {
  for (size_t a = hoc_opt_bn_begin(o->B, b); a < hoc_opt_bn_end(o->B, b); ++a)
    if (o->node.near[o->B->bn_node[a]]) return 1;
  return 0;
}

/* The line search of blocks list[0..nt) of a colour, whose trials hold
 * n_eval nodes: accepted blocks are committed and appended to
 * o->trial.committed (*n_committed), *moved counts their nodes. */
static hoc_status line_search(hoc_opt *o, size_t *list, size_t nt, size_t n_eval,
                              hoc_opt_scratch *scr, int nthreads, size_t *n_committed,
                              size_t *moved) {
  hoc_mesh *m = o->m;
  size_t *elist = hoc_calloc(n_eval + 1, sizeof *elist);
  HOC_CHECK(elist, HOC_ERR_MEMORY, "out of memory");
  hoc_status status = HOC_OK;
  for (int attempt = 0; attempt < HOC_OPT_LINE_SEARCH_TRIES && nt; ++attempt) {
    size_t ne_list = 0;
    for (size_t a = 0; a < nt; ++a) {
      size_t b = list[a];
      for (size_t c = hoc_opt_bn_begin(o->B, b); c < hoc_opt_bn_end(o->B, b); ++c)
        elist[ne_list++] = o->B->bn_node[c];
      for (size_t j = hoc_opt_carry_begin(o->B, b); j < hoc_opt_carry_end(o->B, b); ++j)
        elist[ne_list++] = o->B->carry_node[j];
    }
    HOC_TRY_GOTO(hoc_opt_trial_reserve(o, elist, ne_list), end);
    for (size_t a = 0; a < nt; ++a) {
      size_t b = list[a];
      for (int tries = 0; tries < HOC_OPT_RANGE_HALVINGS && !hoc_opt_set_trial_params(o, b);
           ++tries)
        o->trial.alpha[hoc_opt_tb(o, b)] *= HOC_OPT_BACKTRACK;
    }
    HOC_TRY_GOTO(hoc_opt_eval_trials(o, elist, ne_list, nthreads), end);
#pragma omp parallel for schedule(dynamic, HOC_OPT_PARALLEL_CHUNK) num_threads(nthreads)          \
    if (hoc_opt_parallel(o, nt))
    for (size_t a = 0; a < nt; ++a) {
      size_t b = list[a], tb = hoc_opt_tb(o, b);
      hoc_opt_scratch *s = &scr[omp_get_thread_num()];
      double f;
      int ok = block_trial(
          o, b, s, o->trial.f0[tb] + HOC_OPT_ARMIJO * o->trial.alpha[tb] * o->trial.slope[tb], &f);
      if (ok) {
        for (size_t c = hoc_opt_bn_begin(o->B, b); c < hoc_opt_bn_end(o->B, b); ++c)
          hoc_opt_commit(o, o->B->bn_node[c]);
        for (size_t j = hoc_opt_carry_begin(o->B, b); j < hoc_opt_carry_end(o->B, b); ++j)
          hoc_opt_commit(o, o->B->carry_node[j]);
        o->trial.fnew[tb] = f;
        o->trial.state[tb] = 2;
      } else {
        o->trial.alpha[tb] *= HOC_OPT_BACKTRACK;
      }
    }
    size_t keep = 0;
    for (size_t a = 0; a < nt; ++a) {
      size_t b = list[a], tb = hoc_opt_tb(o, b);
      if (o->trial.state[tb] != 2) {
        list[keep++] = b;
        continue;
      }
      o->trial.state[tb] = 0;
      o->trial.committed[(*n_committed)++] = b;
      size_t nodes = hoc_opt_bn_end(o->B, b) - hoc_opt_bn_begin(o->B, b);
      *moved += nodes;
      /* only a significant move wakes the neighbourhood (small ones would
       * spread waves of smaller ones through the whole mesh) */
      double factor = o->cfg.wake_factor;
      if (o->cfg.wake_near_only && !near_fold(o, b)) factor = HOC_OPT_WAKE_SMOOTHING;
      if (o->trial.f0[tb] - o->trial.fnew[tb] < factor * o->cfg.min_gain * (double)nodes &&
          !near_tangled(o, b))
        continue;
      /* wake every node of the elements it touches (itself included) */
      for (size_t c = hoc_opt_be_begin(o->B, b); c < hoc_opt_be_end(o->B, b); ++c) {
        const size_t *cn = m->conn + o->B->be_elem[c] * (size_t)o->np;
        for (int i = 0; i < o->np; ++i)
          hoc_opt_wake_node(o, cn[i]);
      }
    }
    nt = keep;
  }
  for (size_t a = 0; a < nt; ++a) o->trial.state[hoc_opt_tb(o, list[a])] = 0; /* gave up: asleep */
end:
  free(elist);
  return status;
}

/* One colour: a Gauss-Newton step per active block, then a common
 * backtracking line search. *moved counts the nodes moved. */
hoc_status hoc_opt_do_color(hoc_opt *o, int color, hoc_opt_scratch *scr, int nthreads,
                            size_t *moved) {
  size_t n = hoc_opt_select_active(o, color);
  *moved = 0;
  if (!n) return HOC_OK;
  size_t *list = o->trial.list;
#pragma omp parallel for schedule(dynamic, HOC_OPT_PARALLEL_CHUNK) num_threads(nthreads)          \
    if (hoc_opt_parallel(o, n))
  for (size_t a = 0; a < n; ++a) {
    size_t b = list[a];
    hoc_opt_scratch *s = &scr[omp_get_thread_num()];
    for (size_t c = hoc_opt_bn_begin(o->B, b); c < hoc_opt_bn_end(o->B, b); ++c)
      o->node.active[o->B->bn_node[c]] = 0;
    int nd = (int)(o->B->bd_start[b + 1] - o->B->bd_start[b]);
    double f;
    hoc_opt_block_model(o, b, s, &f, s->g, s->H);
    size_t tb = hoc_opt_tb(o, b);
    o->trial.f0[tb] = f;
    o->trial.state[tb] = 0;
    double *st = hoc_opt_step_of(o, b);
    if (!damped_solve(nd, s->H, s->g, s->L, st)) continue;
    double slope = 0;
    for (int c = 0; c < nd; ++c) slope += s->g[c] * st[c];
    /* limit every node's displacement to a quarter of its local size */
    double alpha = 1, len_max = 0;
    for (size_t c = hoc_opt_bn_begin(o->B, b); c < hoc_opt_bn_end(o->B, b); ++c) {
      size_t k = o->B->bn_node[c];
      const double *dz = o->node.dz + 6 * k, *sk = st + hoc_opt_node_off(o->B, k);
      double dx[3];
      for (int d = 0; d < 3; ++d)
        dx[d] = dz[d] * sk[0] + (o->adj.ndof[k] == 2 ? dz[3 + d] * sk[1] : 0);
      double len = sqrt(dx[0] * dx[0] + dx[1] * dx[1] + dx[2] * dx[2]);
      len_max = fmax(len_max, len / hoc_opt_hsize(o, k));
    }
    if (len_max > HOC_OPT_STEP_CAP) alpha = HOC_OPT_STEP_CAP / len_max;
    if (!(slope < 0) || !isfinite(slope) || !(len_max * alpha > HOC_OPT_STEP_MIN)) continue;
    o->trial.slope[tb] = slope;
    o->trial.alpha[tb] = alpha;
    o->trial.state[tb] = 1;
  }
  size_t nt = 0;
  for (size_t a = 0; a < n; ++a)
    if (o->trial.state[hoc_opt_tb(o, list[a])] == 1) list[nt++] = list[a];
  /* the line search in parts whose trials hold at most HOC_OPT_TRIAL_NODES
   * nodes (the blocks of a colour share no element: their line searches
   * are independent, and the parts give the result of one) */
  size_t n_committed = 0;
  hoc_status status = HOC_OK;
  for (size_t c0 = 0; c0 < nt && status == HOC_OK;) {
    size_t c1 = c0, n_eval = 0;
    for (; c1 < nt; ++c1) {
      size_t b = list[c1];
      size_t k = hoc_opt_bn_end(o->B, b) - hoc_opt_bn_begin(o->B, b) + hoc_opt_carry_end(o->B, b) -
                 hoc_opt_carry_begin(o->B, b);
      if (c1 > c0 && n_eval + k > HOC_OPT_TRIAL_NODES) break;
      n_eval += k;
    }
    status = hoc_opt_journal_reserve(o, n_eval);
    if (status == HOC_OK)
    status = line_search(o, list + c0, c1 - c0, n_eval, scr, nthreads, &n_committed, moved);
    c0 = c1;
  }
  if (status != HOC_OK) return status;
    /* validity may have been gained where blocks moved */
#pragma omp parallel for schedule(dynamic, HOC_OPT_PARALLEL_CHUNK) num_threads(nthreads)          \
    if (hoc_opt_parallel(o, n_committed))
  for (size_t a = 0; a < n_committed; ++a) {
    size_t b = o->trial.committed[a];
    hoc_opt_scratch *s = &scr[omp_get_thread_num()];
    for (size_t c = hoc_opt_be_begin(o->B, b); c < hoc_opt_be_end(o->B, b); ++c) {
      size_t e = o->B->be_elem[c];
      if (!o->el.valid[e] || !o->el.xvalid[e]) {
        hoc_opt_gather(o, e, s->x, s->n);
        if (!o->el.valid[e])
          o->el.valid[e] = (unsigned char)!hoc_element_tangled(o->t, s->x, s->n, o->cfg.exact);
        o->el.xvalid[e] = o->el.valid[e] && (o->cfg.exact || !hoc_opt_guarded(o, e) ||
                                             !hoc_element_folded(o->t, s->x, s->n));
      }
      if (!o->el.pvalid[e]) o->el.pvalid[e] = (unsigned char)hoc_opt_param_valid(o, e, s->uv);
    }
  }
  return HOC_OK;
}

hoc_status hoc_opt_scratch_alloc(const hoc_opt *o, int nthreads, hoc_opt_scratch **out) {
  hoc_opt_scratch *s = hoc_calloc((size_t)nthreads, sizeof *s);
  HOC_CHECK(s, HOC_ERR_MEMORY, "out of memory");
  size_t np = (size_t)o->np, nq = (size_t)o->nq, nd = (size_t)(o->max_nd ? o->max_nd : 1);
  int failed = 0;
  for (int i = 0; i < nthreads; ++i) {
    s[i].x = hoc_calloc(3 * np, sizeof(double));
    s[i].n = hoc_calloc(3 * np, sizeof(double));
    size_t nr = nq + np + (size_t)o->t->nv + 1; /* + 1: a fold point */
    s[i].r = hoc_calloc(nr, sizeof(double));
    s[i].J = hoc_calloc(3 * nr * np, sizeof(double));
    s[i].uv = hoc_calloc(2 * np, sizeof(double));
    s[i].Jz = hoc_calloc(nr * nd, sizeof(double));
    s[i].H = hoc_calloc(nd * nd, sizeof(double));
    s[i].g = hoc_calloc(nd, sizeof(double));
    s[i].L = hoc_calloc(nd * nd, sizeof(double));
    s[i].w = hoc_calloc(np, sizeof(double));
    s[i].off = hoc_calloc(np, sizeof(int));
    s[i].nd = hoc_calloc(np, 1);
    s[i].fr = hoc_calloc(o->max_foot * 9 * (size_t)o->fc.npts + 1, sizeof(double));
    if (!s[i].x || !s[i].n || !s[i].r || !s[i].J || !s[i].uv || !s[i].Jz || !s[i].H || !s[i].g ||
        !s[i].L || !s[i].w || !s[i].off || !s[i].nd || !s[i].fr)
      failed = 1;
  }
  *out = s;
  if (failed) return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  return HOC_OK;
}

void hoc_opt_scratch_free(hoc_opt_scratch *s, int nthreads) {
  if (!s) return;
  for (int i = 0; i < nthreads; ++i) {
    free(s[i].x);
    free(s[i].n);
    free(s[i].r);
    free(s[i].J);
    free(s[i].uv);
    free(s[i].Jz);
    free(s[i].H);
    free(s[i].g);
    free(s[i].L);
    free(s[i].w);
    free(s[i].off);
    free(s[i].nd);
    free(s[i].fr);
  }
  free(s);
}
