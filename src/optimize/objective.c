/* The objective: element residuals (regularised on the tangled region),
 * the per-element state at the start of a sweep, and the screening that
 * puts nodes with nothing to gain to sleep before the first sweep.
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

enum { NP_MAX = (HOC_MAX_ORDER + 1) * (HOC_MAX_ORDER + 2) / 2 };

/* Positions and normals of element e's nodes: the trial state of nodes
 * flagged `moving`, else the current one. */
void hoc_opt_frames_trial(const hoc_opt *o, size_t e, const double *fr, double *out) {
  const hoc_mesh *m = o->m;
  size_t np = (size_t)o->np;
  const size_t *cn = m->conn + e * np, *sl = m->elem_slot + e * np;
  size_t moving = 0;
  for (size_t i = 0; i < np; ++i) moving += o->node.moving[cn[i]];
  if (4 * moving > np) {
    /* most of its nodes move (a vertex carrying its star): the frames from
     * the trial's nodes cost no more than moving them node by node */
    double x[3 * NP_MAX], n[3 * NP_MAX];
    hoc_opt_gather(o, e, x, n);
    hoc_element_frames(o->t, x, n, out);
    return;
  }
  const double *from = fr;
  for (size_t i = 0; i < np; ++i) {
    if (!o->node.moving[cn[i]]) continue;
    double dx[3], dn[3];
    const double *tx = hoc_opt_txyz(o, cn[i]),
                 *tn = o->trial.tnormal + 3 * hoc_opt_tslot(o, cn[i], sl[i]);
    for (int c = 0; c < 3; ++c) {
      dx[c] = tx[c] - m->xyz[3 * cn[i] + c];
      dn[c] = tn[c] - o->node.normal[3 * sl[i] + c];
    }
    hoc_element_frames_move(o->t, from, (int)i, dx, dn, out);
    from = out;
  }
  if (from != out) memcpy(out, fr, 9 * (size_t)o->fc.npts * sizeof *out);
}

hoc_status hoc_opt_frames_setup(hoc_opt *o, size_t bytes) {
  size_t ne = o->m->n_elems;
  free(o->fc.slot);
  free(o->fc.pool);
  free(o->fc.owner);
  free(o->fc.fresh);
  free(o->fc.want);
  memset(&o->fc, 0, sizeof o->fc);
  o->fc.npts = hoc_element_frame_points(o->t);
  size_t per = 9 * (size_t)o->fc.npts * sizeof(double);
  size_t want = 0;
  for (size_t e = 0; e < ne; ++e) want += !o->adj.touched || o->adj.touched[e];
  o->fc.cap = o->m->order >= HOC_OPT_FRAME_MIN_ORDER ? bytes / per : 0;
  if (o->fc.cap > want) o->fc.cap = want;
  o->fc.dynamic = o->fc.cap && o->fc.cap < want;
  HOC_ALLOC(o->fc.slot, ne + 1);
  if (o->fc.cap) {
    o->fc.pool = hoc_realloc(NULL, o->fc.cap * 9 * (size_t)o->fc.npts, sizeof *o->fc.pool);
    if (o->fc.dynamic && o->fc.pool) {
      o->fc.owner = hoc_realloc(NULL, o->fc.cap, sizeof *o->fc.owner);
      o->fc.fresh = hoc_realloc(NULL, o->fc.cap, sizeof *o->fc.fresh);
      o->fc.want = hoc_calloc(ne + 1, sizeof *o->fc.want);
    }
    if (!o->fc.pool || (o->fc.dynamic && (!o->fc.owner || !o->fc.fresh || !o->fc.want))) {
      free(o->fc.pool);
      free(o->fc.owner);
      free(o->fc.fresh);
      free(o->fc.want);
      o->fc.pool = NULL;
      o->fc.owner = o->fc.fresh = NULL;
      o->fc.want = NULL;
      o->fc.cap = 0; /* (not kept: every evaluation from the nodes) */
      o->fc.dynamic = 0;
    }
  }
  if (o->fc.dynamic) {
    for (size_t e = 0; e < ne; ++e) o->fc.slot[e] = SIZE_MAX;
    for (size_t k = 0; k < o->fc.cap; ++k) o->fc.owner[k] = SIZE_MAX;
    return HOC_OK;
  }
  /* every element a free node can change, in element order */
  size_t k = 0;
  for (size_t e = 0; e < ne; ++e)
    o->fc.slot[e] = k < o->fc.cap && (!o->adj.touched || o->adj.touched[e]) ? k++ : SIZE_MAX;
  return HOC_OK;
}

void hoc_opt_frames_assign(hoc_opt *o) {
  if (!o->fc.dynamic) return;
  const hoc_mesh *m = o->m;
  size_t ne = m->n_elems;
  unsigned char *want = o->fc.want; /* (all 0 between calls) */
  for (size_t k = 0; k < m->n_nodes; ++k)
    if (o->node.active[k])
      for (size_t a = o->adj.ne_start[k]; a < o->adj.ne_start[k + 1]; ++a)
        want[o->adj.ne_elem[a]] = 1;
  /* places of elements no longer wanted are free; the wanted keep theirs */
  size_t free_at = 0, n_fresh = 0;
  for (size_t k = 0; k < o->fc.cap; ++k) {
    size_t e = o->fc.owner[k];
    if (e != SIZE_MAX && !want[e]) {
      o->fc.slot[e] = SIZE_MAX;
      o->fc.owner[k] = SIZE_MAX;
    }
  }
  for (size_t e = 0; e < ne; ++e) {
    if (!want[e] || o->fc.slot[e] != SIZE_MAX) continue;
    while (free_at < o->fc.cap && o->fc.owner[free_at] != SIZE_MAX) ++free_at;
    if (free_at == o->fc.cap) break;
    o->fc.owner[free_at] = e;
    o->fc.slot[e] = free_at;
    o->fc.fresh[n_fresh++] = e;
  }
  memset(want, 0, ne);
#pragma omp parallel
  {
    double x[3 * NP_MAX], n[3 * NP_MAX];
#pragma omp for schedule(static)
    for (size_t a = 0; a < n_fresh; ++a) {
      size_t e = o->fc.fresh[a];
      hoc_opt_gather(o, e, x, n);
      hoc_element_frames(o->t, x, n, hoc_opt_frames_of(o, e));
    }
  }
}

void hoc_opt_gather(const hoc_opt *o, size_t e, double *x, double *n) {
  const hoc_mesh *m = o->m;
  size_t np = (size_t)o->np;
  const size_t *cn = m->conn + e * np, *sl = m->elem_slot + e * np;
  for (size_t i = 0; i < np; ++i) {
    int mv = o->node.moving[cn[i]];
    memcpy(x + 3 * i, mv ? hoc_opt_txyz(o, cn[i]) : m->xyz + 3 * cn[i], 3 * sizeof *x);
    memcpy(n + 3 * i,
           mv ? o->trial.tnormal + 3 * hoc_opt_tslot(o, cn[i], sl[i]) : o->node.normal + 3 * sl[i],
           3 * sizeof *n);
  }
}

/* Element not folded in the (u,v) plane: orient * det(D u(xi)) > 0 at its
 * nodes (trial state of `moving` nodes). uv: [np][2] scratch. */
int hoc_opt_param_valid(const hoc_opt *o, size_t e, double *uv) {
  const hoc_mesh *m = o->m;
  int np = o->np;
  const size_t *cn = m->conn + e * (size_t)np;
  memcpy(uv, m->elem_uv + 2 * e * (size_t)np, 2 * (size_t)np * sizeof *uv);
  for (int i = 0; i < np; ++i)
    if (o->node.moving[cn[i]]) hoc_opt_trial_elem_uv(o, cn[i], e, i, uv + 2 * i);
  double sign = m->face_orient[m->elem_face[e]] < 0 ? -1.0 : 1.0;
  for (int j = 0; j < np; ++j) {
    const double *g = o->t->Gn + 2 * (size_t)j * np;
    double a = 0, b = 0, c = 0, d = 0;
    for (int i = 0; i < np; ++i) {
      a += uv[2 * i] * g[2 * i];
      b += uv[2 * i] * g[2 * i + 1];
      c += uv[2 * i + 1] * g[2 * i];
      d += uv[2 * i + 1] * g[2 * i + 1];
    }
    if (!(sign * (a * d - b * c) > 0)) return 0;
  }
  return 1;
}

/* Smallest sigma and the size scale mean(|D phi|^2 / 2) of an element. */
static void sigma_stats(const hoc_opt *o, const double *x, const double *n, double *smin,
                        double *scale) {
  const hoc_quality_tables *t = o->t;
  int np = t->np;
  double mn = INFINITY, sum = 0;
  for (int q = 0; q < t->nq + np; ++q) {
    const double *G = q < t->nq ? t->G + 2 * (size_t)q * np : t->Gn + 2 * (size_t)(q - t->nq) * np;
    double a1[3] = {0, 0, 0}, a2[3] = {0, 0, 0}, nq[3] = {0, 0, 0}, c[3];
    for (int i = 0; i < np; ++i)
      for (int k = 0; k < 3; ++k) {
        a1[k] += G[2 * i] * x[3 * i + k];
        a2[k] += G[2 * i + 1] * x[3 * i + k];
      }
    if (q < t->nq) {
      for (int i = 0; i < np; ++i)
        for (int k = 0; k < 3; ++k) nq[k] += t->N[(size_t)q * np + i] * n[3 * i + k];
    } else {
      memcpy(nq, n + 3 * (q - t->nq), sizeof nq);
    }
    hoc_opt_cross(a1, a2, c);
    double cl = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
    double sig = c[0] * nq[0] + c[1] * nq[1] + c[2] * nq[2] > 0 ? cl : -cl;
    mn = fmin(mn, sig);
    if (q < t->nq)
      sum += t->w[q] * 0.5 * (a1[0] * a1[0] + a1[1] * a1[1] + a1[2] * a1[2] + a2[0] * a2[0] +
                              a2[1] * a2[1] + a2[2] * a2[2]);
  }
  *smin = mn;
  *scale = sum;
}

/* Residuals of element e's objective: the quadrature points, and in the
 * tangled region also the nodes and validation points (the tangle test
 * asks det > 0 there too) and, where only the exact tests find the element
 * folded, the point where they found it. r: [nq + np + nv + 1],
 * J: [nq + np + nv + 1][np][3] or NULL. Returns the count and sets
 * *smin to the smallest sigma / |D phi|^2 over the quadrature points. */
int hoc_opt_elem_residuals(const hoc_opt *o, size_t e, const double *x, const double *n,
                           const double *fr, const unsigned char *need, double *r, double *J,
                           double *smin) {
  int nq = o->nq, np = o->np;
  double s = fr ? hoc_element_residuals_frames(o->t, o->measure, fr, o->el.delta[e], need, r, J)
                : hoc_element_residuals(o->t, o->measure, x, n, o->el.delta[e], need, r, J);
  if (smin) *smin = s;
  if (!o->el.region[e]) return nq;
  hoc_element_node_residuals(o->t, o->measure, x, n, o->el.delta[e], o->cfg.exact, need, r + nq,
                             J ? J + 3 * (size_t)nq * (size_t)np : NULL);
  int count = nq + hoc_element_node_points(o->t, o->cfg.exact);
  if (!o->el.has_fold[e]) return count;
  /* weighted as one of the node residuals */
  hoc_element_point_residual(o->t, o->measure, x, n, o->el.delta[e], o->el.fold_rs + 2 * e,
                             1.0 / hoc_element_node_points(o->t, o->cfg.exact), need, r + count,
                             J ? J + 3 * (size_t)count * (size_t)np : NULL);
  return count + 1;
}

/* The normals of the curve and vertex slots of moved elements again, as
 * measuring takes them (hoc_mesh_slot_normals): where a face turns over
 * along its boundary within the model's tolerance, such a slot takes the
 * normal past the turn, found toward its elements' middles, so it changes
 * when they move though its node stays (docs/quality.md). The elements of
 * a slot whose normal changed are measured again. */
static hoc_status refresh_boundary_normals(hoc_opt *o) {
  hoc_mesh *m = o->m;
  size_t ne = m->n_elems, np = (size_t)o->np, n = 0;
  unsigned char *which = hoc_calloc(m->n_slots + 1, 1);
  HOC_CHECK(which, HOC_ERR_MEMORY, "out of memory");
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < np && o->el.dirty[e]; ++k) {
      size_t sl = m->elem_slot[e * np + k];
      if (m->dim[m->conn[e * np + k]] == HOC_ON_FACE || m->slot_pole[sl] || which[sl]) continue;
      which[sl] = 1;
      ++n;
    }
  double *old = n ? hoc_realloc(NULL, 3 * n, sizeof *old) : NULL;
  hoc_status status = n && !old ? HOC_ERROR(HOC_ERR_MEMORY, "out of memory") : HOC_OK;
  for (size_t sl = 0, j = 0; sl < m->n_slots && old; ++sl)
    if (which[sl]) memcpy(old + 3 * j++, o->node.normal + 3 * sl, 3 * sizeof *old);
  if (status == HOC_OK && n) status = hoc_mesh_slot_normals_of(m, which, o->node.normal);
  for (size_t sl = 0, j = 0; sl < m->n_slots && old && status == HOC_OK; ++sl) {
    if (!which[sl]) continue;
    if (memcmp(old + 3 * j++, o->node.normal + 3 * sl, 3 * sizeof *old)) {
      size_t i = m->slot_node[sl];
      for (size_t a = o->adj.ne_start[i]; a < o->adj.ne_start[i + 1]; ++a)
        o->el.dirty[o->adj.ne_elem[a]] = 1;
    }
  }
  free(old);
  free(which);
  return status;
}

/* Per-element state at the start of a sweep: validity, parametric
 * validity, regularisation; also f, q and the tangled count. */
hoc_status hoc_opt_sweep_start(hoc_opt *o, double *objective, double *min_q, size_t *tangled) {
  hoc_mesh *m = o->m;
  size_t ne = m->n_elems;
  HOC_TRY(refresh_boundary_normals(o));
  int np = o->np, nq = o->nq;
  double *fe = o->el.fe, *qe = o->el.qe;
  int failed = 0;
  size_t n_dirty = 0, n_changed = 0;
  for (size_t e = 0; e < ne; ++e) n_dirty += o->el.dirty[e];
  /* elements whose nodes moved: q, validity, their own regularisation */
#pragma omp parallel if (hoc_opt_parallel(o, n_dirty))
  {
    double *x = malloc((6 * (size_t)np + (size_t)nq + 2 * (size_t)np) * sizeof *x);
    if (!x) {
#pragma omp atomic write
      failed = 1;
    }
    double *n = x ? x + 3 * np : NULL, *uv = x ? x + 6 * np + nq : NULL;
#pragma omp for schedule(static)
    for (size_t e = 0; e < ne; ++e) {
      if (!x || !o->el.dirty[e]) continue;
      hoc_opt_gather(o, e, x, n);
      double *fr = hoc_opt_frames_of(o, e);
      if (fr) hoc_element_frames(o->t, x, n, fr);
      double eta;
      qe[e] = hoc_element_quality_test(o->t, o->measure, x, n, o->cfg.exact, &eta, NULL);
      o->el.valid[e] = qe[e] > 0;
      o->el.xvalid[e] = o->el.valid[e] &&
                        (o->cfg.exact || !hoc_opt_guarded(o, e) || !hoc_element_folded(o->t, x, n));
      o->el.pvalid[e] = (unsigned char)hoc_opt_param_valid(o, e, uv);
      o->el.delta_own[e] = 0;
      /* a fold the samples miss: a residual where the exact tests found it
       * (the samples' residuals cannot see it, and no step would open it) */
      o->el.has_fold[e] = o->cfg.exact && !o->el.valid[e] && !hoc_element_tangled(o->t, x, n, 0) &&
                       hoc_element_fold_point(o->t, x, n, o->el.fold_rs + 2 * e);
      if (!o->el.valid[e]) {
        double smin, scale;
        sigma_stats(o, x, n, &smin, &scale);
        double eps = o->cfg.eps * scale;
        o->el.delta_own[e] = smin < eps ? sqrt(eps * (eps - smin)) : 0;
        if (!(o->el.delta_own[e] > 0)) o->el.delta_own[e] = eps;
      }
    }
    free(x);
  }
  /* the tangled region: tangled elements and those sharing a node with one
   * take the largest regularisation around them (Escobar et al. regularise
   * the whole mesh with one delta; this keeps the rest of it exact) */
  memcpy(o->el.was_region, o->el.region, ne);
  memset(o->el.region, 0, ne);
  for (size_t e = 0; e < ne; ++e) o->el.delta[e] = o->el.delta_own[e];
  for (size_t e = 0; e < ne && !failed; ++e) {
    if (o->el.valid[e]) continue;
    for (int i = 0; i < np; ++i) {
      size_t node = m->conn[e * (size_t)np + (size_t)i];
      for (size_t a = o->adj.ne_start[node]; a < o->adj.ne_start[node + 1]; ++a) {
        size_t e2 = o->adj.ne_elem[a];
        o->el.region[e2] = 1;
        if (o->el.delta[e2] < o->el.delta_own[e]) o->el.delta[e2] = o->el.delta_own[e];
      }
    }
  }
  for (size_t e = 0; e < ne; ++e)
    n_changed += o->el.dirty[e] || o->el.region[e] || o->el.was_region[e];
  /* objective parts that changed: moved, or in or out of the region */
#pragma omp parallel if (hoc_opt_parallel(o, n_changed))
  {
    double *x =
        malloc((6 * (size_t)np + (size_t)nq + (size_t)np + (size_t)o->t->nv + 1) * sizeof *x);
    if (!x) {
#pragma omp atomic write
      failed = 1;
    }
    double *n = x ? x + 3 * np : NULL, *r = x ? x + 6 * np : NULL;
#pragma omp for schedule(static)
    for (size_t e = 0; e < ne; ++e) {
      if (!x || !(o->el.dirty[e] || o->el.region[e] || o->el.was_region[e])) continue;
      hoc_opt_gather(o, e, x, n);
      double f = 0;
      int nr = hoc_opt_elem_residuals(o, e, x, n, hoc_opt_frames_of(o, e), NULL, r, NULL, NULL);
      for (int q = 0; q < nr; ++q) f += r[q] * r[q];
      fe[e] = f;
    }
    free(x);
  }
  if (failed) return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  memset(o->el.dirty, 0, ne);
  double f = 0, qmin = INFINITY;
  size_t nt = 0;
  for (size_t e = 0; e < ne; ++e) {
    f += fe[e];
    qmin = fmin(qmin, qe[e]);
    nt += qe[e] == 0.0;
  }
  *objective = f;
  *min_q = ne ? qmin : 0;
  *tangled = nt;
  return HOC_OK;
}

/* A node's decision from its summed contributions c[5] (g0 g1 h00 h01
 * h11): awake if near a tangle or if its estimated gain is not below the
 * threshold. */
static unsigned char screen_node(const hoc_opt *o, size_t k, const double *c, int near) {
  double gain;
  if (o->adj.ndof[k] == 2) {
    double det = c[2] * c[4] - c[3] * c[3];
    gain = det > 0 ? 0.5 * (c[4] * c[0] * c[0] - 2 * c[3] * c[0] * c[1] + c[2] * c[1] * c[1]) / det
                   : INFINITY;
  } else {
    gain = c[2] > 0 ? 0.5 * c[0] * c[0] / c[2] : INFINITY;
  }
  return (unsigned char)(near || !(gain < o->cfg.min_gain));
}

/* Screening: every node's single-node Gauss-Newton decrease estimate
 * 0.5 g^T H^-1 g from one evaluation per element (instead of one per block
 * through each element); nodes whose estimate is below the gain threshold
 * (and not near a tangle) start asleep. A node inside one element is
 * decided there; the contributions of the nodes on the elements' edges are
 * stored and summed per node in element order, so the result does not
 * depend on the thread count. */
hoc_status hoc_opt_screen(hoc_opt *o) {
  hoc_mesh *m = o->m;
  size_t ne = m->n_elems, np = (size_t)o->np;
  /* the stored local nodes: the corners and edge nodes (the first 3p),
   * unless an element's inner node is shared (a mesh read as given) */
  size_t nb = 3 * (size_t)m->order < np ? 3 * (size_t)m->order : np;
  for (size_t e = 0; e < ne && nb < np; ++e)
    for (size_t i = nb; i < np && nb < np; ++i) {
      size_t k = m->conn[e * np + i];
      if (o->adj.ne_start[k + 1] - o->adj.ne_start[k] != 1) nb = np;
    }
  /* [ne][nb][g0 g1 h00 h01 h11], every entry written below (not zeroed) */
  double *contrib = hoc_realloc(NULL, 5 * ne * nb + 1, sizeof *contrib);
  HOC_CHECK(contrib, HOC_ERR_MEMORY, "out of memory");
  int nr_max = o->nq + o->np + o->t->nv + 1, failed = 0; /* + 1: a fold point */
#pragma omp parallel
  {
    double *x = malloc((6 * np + (size_t)nr_max + 3 * (size_t)nr_max * np) * sizeof *x);
    if (!x) {
#pragma omp atomic write
      failed = 1;
    }
    double *n = x ? x + 3 * np : NULL, *r = x ? x + 6 * np : NULL, *J = r ? r + nr_max : NULL;
    unsigned char *need = x ? malloc(np) : NULL; /* the free nodes' columns of J */
    if (x && !need) {
#pragma omp atomic write
      failed = 1;
    }
#pragma omp for schedule(static)
    for (size_t e = 0; e < ne; ++e) {
      if (!need || (o->adj.touched && !o->adj.touched[e])) continue; /* (no free node reads it) */
      const size_t *cn = m->conn + e * np;
      for (size_t i = 0; i < np; ++i) need[i] = o->adj.ndof[cn[i]] > 0;
      hoc_opt_gather(o, e, x, n);
      int nr = hoc_opt_elem_residuals(o, e, x, n, hoc_opt_frames_of(o, e), need, r, J, NULL);
      for (size_t i = 0; i < np; ++i) {
        const double *dz = o->node.dz + 6 * cn[i];
        double c[5] = {0, 0, 0, 0, 0};
        for (int q = 0; q < nr && need[i]; ++q) {
          const double *j = J + 3 * ((size_t)q * np + i);
          double z0 = j[0] * dz[0] + j[1] * dz[1] + j[2] * dz[2];
          double z1 = j[0] * dz[3] + j[1] * dz[4] + j[2] * dz[5];
          c[0] += 2 * r[q] * z0;
          c[1] += 2 * r[q] * z1;
          c[2] += 2 * z0 * z0;
          c[3] += 2 * z0 * z1;
          c[4] += 2 * z1 * z1;
        }
        if (i >= nb) {
          /* the node's only element: its sum is this (as in the loop below) */
          if (!need[i]) continue;
          double sum[5] = {0, 0, 0, 0, 0};
          for (int d = 0; d < 5; ++d) sum[d] += c[d];
          o->node.active[cn[i]] = screen_node(o, cn[i], sum, o->el.region[e] || !o->el.valid[e]);
          continue;
        }
        /* written once, never read first: a fresh page read before it is
         * written is copied from the zero page, and with two threads every
         * such copy flushes the other core's TLB */
        memcpy(contrib + 5 * (e * nb + i), c, sizeof c);
      }
    }
    free(need);
    free(x);
  }
  if (failed) {
    free(contrib);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
#pragma omp parallel for schedule(static)
  for (size_t k = 0; k < m->n_nodes; ++k) {
    if (!o->adj.ndof[k]) continue;
    size_t a0 = o->adj.ne_start[k];
    if (o->adj.ne_start[k + 1] - a0 == 1 && (size_t)o->adj.ne_local[a0] >= nb) continue;
    double c[5] = {0, 0, 0, 0, 0};
    int near = 0;
    for (size_t a = a0; a < o->adj.ne_start[k + 1]; ++a) {
      size_t e = o->adj.ne_elem[a];
      const double *ce = contrib + 5 * (e * nb + (size_t)o->adj.ne_local[a]);
      for (int d = 0; d < 5; ++d) c[d] += ce[d];
      near |= o->el.region[e] || !o->el.valid[e];
    }
    o->node.active[k] = screen_node(o, k, c, near);
  }
  free(contrib);
  return HOC_OK;
}
