/* The trial state of moving nodes: trial parameters from a step, their
 * CAD evaluation (positions, derivatives, slot parameters and normals),
 * the order of nodes along a curve, and the acceptance of a trial.
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

/* Unit normal of face f at uv from its derivatives, oriented like the mesh;
 * where the parametrisation is singular, from just inside the face. */
static hoc_status face_normal(const hoc_opt *o, int f, const double *uv, const double *du,
                              const double *dv, double *n) {
  double c[3], a[3], b[3];
  hoc_opt_cross(du, dv, c);
  double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  double scale = du[0] * du[0] + du[1] * du[1] + du[2] * du[2] + dv[0] * dv[0] +
                 dv[1] * dv[1] + dv[2] * dv[2];
  if (!(len > HOC_OPT_SINGULAR_NORMAL * scale)) {
    const hoc_cad_face *face = &o->model->faces[f];
    double p[2];
    for (int d = 0; d < 2; ++d) {
      double mid = 0.5 * (face->lo[d] + face->hi[d]);
      p[d] =
          uv[d] + HOC_OPT_NORMAL_OFFSET * (face->hi[d] - face->lo[d]) * (mid > uv[d] ? 1.0 : -1.0);
    }
    HOC_TRY(hoc_cad_face_eval(o->model, f, 1, p, NULL, a, b));
    hoc_opt_cross(a, b, c);
    len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
  }
  double s = (o->m->face_orient[f] < 0 ? -1.0 : 1.0) / (len > 0 ? len : 1.0);
  for (int k = 0; k < 3; ++k) n[k] = s * c[k];
  return HOC_OK;
}

/* *p reallocated to `want` items of `size` bytes; 0 when out of memory. */
static int grow(void **p, size_t want, size_t size) {
  void *q = hoc_realloc(*p, want, size);
  if (!q) return 0;
  *p = q;
  return 1;
}

hoc_status hoc_opt_trial_reserve(hoc_opt *o, const size_t *nodes, size_t n) {
  hoc_opt_trial *t = &o->trial;
  size_t slots = 0;
  for (size_t a = 0; a < n; ++a)
    slots += o->adj.ns_start[nodes[a] + 1] - o->adj.ns_start[nodes[a]];
  if (n > t->cap) {
    size_t cap = n; /* (exactly: every block is awake in the first sweep, whose colours set it) */
    HOC_CHECK(grow((void **)&t->tpar, 2 * cap, sizeof *t->tpar) &&
                  grow((void **)&t->txyz, 3 * cap, sizeof *t->txyz) &&
                  grow((void **)&t->tdz, 6 * cap, sizeof *t->tdz) &&
                  grow((void **)&t->tsbase, cap, sizeof *t->tsbase),
              HOC_ERR_MEMORY, "out of memory for the optimiser's trial state");
    t->cap = cap;
  }
  if (slots > t->scap) {
    size_t cap = slots;
    HOC_CHECK(grow((void **)&t->tslot_uv, 2 * cap, sizeof *t->tslot_uv) &&
                  grow((void **)&t->tnormal, 3 * cap, sizeof *t->tnormal),
              HOC_ERR_MEMORY, "out of memory for the optimiser's trial state");
    t->scap = cap;
  }
  slots = 0;
  for (size_t a = 0; a < n; ++a) {
    size_t k = nodes[a];
    t->tix[k] = (uint32_t)a;
    t->tsbase[a] = slots;
    slots += o->adj.ns_start[k + 1] - o->adj.ns_start[k];
  }
  return HOC_OK;
}

/* Parameters of node k's slot s for the trial: (u,v) of the slot, unwrapped
 * near the element's current value. */
void hoc_opt_trial_elem_uv(const hoc_opt *o, size_t k, size_t e, int kk, double *uv) {
  const hoc_mesh *m = o->m;
  const double *cur = m->elem_uv + 2 * (e * (size_t)o->np + (size_t)kk);
  if (m->dim[k] == HOC_ON_FACE) {
    /* the same displacement as the node's parameters */
    const double *tp = hoc_opt_tpar(o, k);
    uv[0] = cur[0] + (tp[0] - m->param[2 * k]);
    uv[1] = cur[1] + (tp[1] - m->param[2 * k + 1]);
    return;
  }
  size_t s = m->elem_slot[e * (size_t)o->np + (size_t)kk];
  const double *ts = o->trial.tslot_uv + 2 * hoc_opt_tslot(o, k, s);
  uv[0] = ts[0];
  uv[1] = ts[1];
  hoc_cad_face_unwrap_near(&o->model->faces[m->elem_face[e]], cur, uv);
}

/* A trial parameter is acceptable inside [lo, hi], or outside but closer to
 * it than the current value (a node outside its face's range, e.g. read from
 * a file, may come back). */
static int param_ok(double cur, double v, double lo, double hi) {
  if (v >= lo && v <= hi) return 1;
  double dv = v < lo ? lo - v : v - hi, dc = cur < lo ? lo - cur : cur > hi ? cur - hi : 0;
  return dv < dc;
}

/* Trial parameters of block b at step length alpha[b]: the block's nodes
 * and the nodes it carries. Returns 0 if one leaves a non-closed range. */
int hoc_opt_set_trial_params(hoc_opt *o, size_t b) {
  const hoc_mesh *m = o->m;
  const double *st = hoc_opt_step_of(o, b);
  double al = o->trial.alpha[hoc_opt_tb(o, b)];
  int inside = 1;
  for (size_t a = hoc_opt_bn_begin(o->B, b); a < hoc_opt_bn_end(o->B, b); ++a) {
    size_t k = o->B->bn_node[a];
    int off = hoc_opt_node_off(o->B, k);
    double *tp = hoc_opt_tpar(o, k);
    if (m->dim[k] == HOC_ON_FACE) {
      const hoc_cad_face *f = &o->model->faces[m->entity[k]];
      for (int d = 0; d < 2; ++d) {
        double v = m->param[2 * k + d] + al * st[off + d];
        tp[d] = v;
        if (!(f->period[d] > 0) && !param_ok(m->param[2 * k + d], v, f->lo[d], f->hi[d]))
          inside = 0;
      }
    } else {
      const hoc_cad_curve *c = &o->model->curves[m->entity[k]];
      double v = m->param[2 * k] + al * st[off];
      tp[0] = v;
      tp[1] = 0;
      if (!(c->period > 0) && !param_ok(m->param[2 * k], v, c->lo, c->hi)) inside = 0;
    }
  }
  for (size_t j = hoc_opt_carry_begin(o->B, b); j < hoc_opt_carry_end(o->B, b); ++j) {
    size_t c = o->B->carry_node[j];
    const hoc_cad_face *f = &o->model->faces[m->entity[c]];
    double *tp = hoc_opt_tpar(o, c);
    for (int d = 0; d < 2; ++d) {
      double v = m->param[2 * c + d] + al * hoc_opt_carry_w(o, j) * st[d];
      tp[d] = v;
      if (!(f->period[d] > 0) && !param_ok(m->param[2 * c + d], v, f->lo[d], f->hi[d])) inside = 0;
    }
  }
  return inside;
}

/* CAD evaluation of node i's trial parameters: position, derivatives, and
 * the parameters and normals of its slots. */
hoc_status hoc_opt_eval_trial(hoc_opt *o, size_t i) {
  hoc_mesh *m = o->m;
  const hoc_model *model = o->model;
  int ent = m->entity[i];
  double *tp = hoc_opt_tpar(o, i), *tx = hoc_opt_txyz(o, i), *tz = hoc_opt_tdz(o, i);
  size_t ts = o->trial.tsbase[o->trial.tix[i]]; /* the node's first trial slot */
  if (m->dim[i] == HOC_ON_FACE) {
    HOC_TRY(hoc_cad_face_eval(model, ent, 1, tp, tx, tz, tz + 3));
    o->trial.tslot_uv[2 * ts] = tp[0];
    o->trial.tslot_uv[2 * ts + 1] = tp[1];
    HOC_TRY(face_normal(o, ent, tp, tz, tz + 3, o->trial.tnormal + 3 * ts));
  } else {
    HOC_TRY(hoc_cad_curve_eval(model, ent, 1, tp, tx, tz));
    tz[3] = tz[4] = tz[5] = 0;
    for (size_t j = o->adj.ns_start[i]; j < o->adj.ns_start[i + 1]; ++j) {
      size_t s = o->adj.ns_slot[j], t = ts + (j - o->adj.ns_start[i]);
      int f = m->slot_face[s];
      double uv[2], du[3], dv[3];
      HOC_TRY(hoc_cad_curve_to_face(model, ent, f, 1, tp, uv));
      hoc_cad_face_unwrap_near(&model->faces[f], m->slot_uv + 2 * s, uv);
      HOC_TRY(hoc_cad_face_eval(model, f, 1, uv, NULL, du, dv));
      o->trial.tslot_uv[2 * t] = uv[0];
      o->trial.tslot_uv[2 * t + 1] = uv[1];
      HOC_TRY(face_normal(o, f, uv, du, dv, o->trial.tnormal + 3 * t));
      double *nw = o->trial.tnormal + 3 * t;
      const double *old = o->node.normal + 3 * s;
      /* a face that turns over within the model's tolerance of the node
       * (hoc_mesh_slot_normals), toward the node's elements on the face:
       * looked for where the normal turned against the slot's last one */
      int against = nw[0] * old[0] + nw[1] * old[1] + nw[2] * old[2] < 0;
      if (against && model->tolerance_known && model->tolerance > 0 && !m->slot_pole[s]) {
        double to[2] = {0, 0};
        int count = 0;
        for (size_t j2 = o->adj.ne_start[i]; j2 < o->adj.ne_start[i + 1]; ++j2) {
          size_t e = o->adj.ne_elem[j2];
          if (m->elem_face[e] != f) continue;
          hoc_mesh_add_inward(m, e, o->adj.ne_local[j2], to);
          ++count;
        }
        if (count) {
          to[0] /= count;
          to[1] /= count;
          HOC_TRY(hoc_mesh_turned_normal(m, f, uv, tx, to, model->tolerance, nw));
        }
      }
      /* a small move cannot turn the surface over: where the CAD normal
       * flips (a folded parametrisation at the boundary, beyond the
       * model's tolerance) the slot keeps its orientation */
      if (nw[0] * old[0] + nw[1] * old[1] + nw[2] * old[2] < 0)
        for (int d = 0; d < 3; ++d)
          nw[d] = -nw[d];
    }
  }
  return HOC_OK;
}

/* CAD evaluation of the trial parameters of the nodes in list[0..n) (no
 * node twice), on nthreads threads. */
hoc_status hoc_opt_eval_trials(hoc_opt *o, const size_t *list, size_t n, int nthreads) {
  hoc_par_error err = {0};
#pragma omp parallel for schedule(dynamic, 4)                                                      \
    num_threads(nthreads) if (hoc_opt_parallel(o, n) && o->model->thread_safe)
  for (size_t c = 0; c < n; ++c)
    hoc_par_error_catch(&err, hoc_opt_eval_trial(o, list[c]));
  return hoc_par_error_raise(&err);
}

/* Curve parameters t[0..p] of line l's nodes in order along the line
 * (trial values for moving nodes if `trial`), unwrapped from its first
 * end: 1 if strictly monotone in the line's direction *dir. */
static int line_params(const hoc_opt *o, size_t l, int trial, double *t, double *dir) {
  const hoc_mesh *m = o->m;
  int p = m->order;
  const size_t *ln = m->line_conn + l * (size_t)(p + 1);
  const hoc_cad_curve *c = &o->model->curves[m->line_curve[l]];
  double ta = m->line_t[2 * l], tb = m->line_t[2 * l + 1];
  *dir = tb > ta ? 1.0 : -1.0;
  for (int j = 0; j <= p; ++j) {
    int idx = j == 0 ? 0 : j == p ? 1 : j + 1;
    size_t i = ln[idx];
    if (m->dim[i] != HOC_ON_CURVE) {
      t[j] = j == 0 ? ta : tb; /* a vertex end: the line's own parameter */
    } else {
      t[j] = trial && o->node.moving[i] ? hoc_opt_tpar(o, i)[0] : m->param[2 * i];
      if (c->period > 0) {
        double guess = ta + (tb - ta) * j / p;
        t[j] -= c->period * floor((t[j] - guess) / c->period + 0.5);
      }
    }
    if (j > 0 && !(*dir * (t[j] - t[j - 1]) > 0)) return 0;
  }
  return 1;
}

/* 1 if dt/ds, the derivative along the line of its nodes' parameters
 * t[0..p] interpolated at the set's edge nodes, is negative somewhere on
 * it (times dir): its Bernstein coefficients, and halvings down to
 * 2^-HOC_OPT_LINE_DEPTH of the line where they do not decide. Ordered
 * nodes do not make an increasing t: a node bunched against its
 * neighbour makes the polynomial turn back between them, the line's map
 * to the curve folds there, and every element on the line
 * folds along its edge where no sample of the element lies. */
static int line_turns_back(const hoc_opt *o, const double *t, double dir) {
  int p = o->m->order;
  if (p < 2) return 0;
  double b[HOC_MAX_ORDER + 1], d[HOC_MAX_ORDER];
  for (int i = 0; i <= p; ++i) {
    b[i] = 0;
    for (int j = 0; j <= p; ++j) b[i] += o->t->Cn[i * (p + 1) + j] * t[j];
  }
  for (int i = 0; i < p; ++i) d[i] = dir * (b[i + 1] - b[i]);
  double where;
  return hoc_bernstein_negative(d, p - 1, 0, HOC_OPT_LINE_DEPTH, 0, 1, &where);
}

/* 1 if line l's nodes (trial values for moving nodes) are strictly
 * monotone along it and, unless its committed nodes already turn back,
 * their interpolated parameter does not turn back (line_turns_back). */
int hoc_opt_line_monotone(const hoc_opt *o, size_t l) {
  double t[HOC_MAX_ORDER + 1], dir;
  if (!line_params(o, l, 1, t, &dir)) return 0;
  if (!line_turns_back(o, t, dir)) return 1;
  return !line_params(o, l, 0, t, &dir) || line_turns_back(o, t, dir);
}

/* Accept node k's trial. */
void hoc_opt_commit(hoc_opt *o, size_t k) {
  hoc_mesh *m = o->m;
  int np = o->np;
  hoc_opt_journal_note(o, k); /* (before the first change of k's state) */
  for (size_t a = o->adj.ne_start[k]; a < o->adj.ne_start[k + 1]; ++a)
    o->el.dirty[o->adj.ne_elem[a]] = 1;
  for (size_t a = o->adj.ne_start[k]; a < o->adj.ne_start[k + 1]; ++a) {
    size_t e = o->adj.ne_elem[a];
    int kk = o->adj.ne_local[a];
    double uv[2];
    hoc_opt_trial_elem_uv(o, k, e, kk, uv);
    memcpy(m->elem_uv + 2 * (e * (size_t)np + (size_t)kk), uv, sizeof uv);
  }
  if (m->dim[k] == HOC_ON_CURVE) {
    const hoc_cad_curve *c = &o->model->curves[m->entity[k]];
    for (size_t a = o->adj.nl_start[k]; a < o->adj.nl_start[k + 1]; ++a) {
      size_t l = o->adj.nl_line[a];
      const size_t *ln = m->line_conn + l * (size_t)(m->order + 1);
      for (int end = 0; end < 2; ++end) {
        if (ln[end] != k) continue;
        double t = hoc_opt_tpar(o, k)[0], old = m->line_t[2 * l + end];
        if (c->period > 0) t -= c->period * floor((t - old) / c->period + 0.5);
        m->line_t[2 * l + end] = t;
      }
    }
  }
  size_t ts = o->trial.tsbase[o->trial.tix[k]];
  for (size_t j = o->adj.ns_start[k]; j < o->adj.ns_start[k + 1]; ++j) {
    size_t s = o->adj.ns_slot[j], t = ts + (j - o->adj.ns_start[k]);
    memcpy(m->slot_uv + 2 * s, o->trial.tslot_uv + 2 * t, 2 * sizeof(double));
    memcpy(o->node.normal + 3 * s, o->trial.tnormal + 3 * t, 3 * sizeof(double));
  }
  double p[2] = {hoc_opt_tpar(o, k)[0], hoc_opt_tpar(o, k)[1]};
  if (m->dim[k] == HOC_ON_FACE) {
    hoc_cad_face_wrap(&o->model->faces[m->entity[k]], p);
    /* the slot keeps the wrapped value too (elements hold unwrapped copies) */
    size_t s = o->adj.ns_slot[o->adj.ns_start[k]];
    memcpy(m->slot_uv + 2 * s, p, sizeof p);
  } else {
    const hoc_cad_curve *c = &o->model->curves[m->entity[k]];
    if (c->period > 0) p[0] -= c->period * floor((p[0] - c->lo) / c->period);
  }
  m->param[2 * k] = p[0];
  m->param[2 * k + 1] = p[1];
  memcpy(m->xyz + 3 * k, hoc_opt_txyz(o, k), 3 * sizeof(double));
  memcpy(o->node.dz + 6 * k, hoc_opt_tdz(o, k), 6 * sizeof(double));
}
