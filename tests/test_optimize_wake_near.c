/* HOC_OPT_WAKE_NEAR_MIN_ORDER (tunables.h): from that order on, while
 * untangling, only blocks near a tangled element wake their neighbours on
 * every move; elsewhere a move must be significant, as when smoothing. Its
 * class: a fold or two left in a large mesh, where waking on every move
 * sends a wave of moves through the whole mesh each sweep.
 *
 * The case: a 12 x 12 grid of a plane raised to order 6, every face
 * node shaken by 0.02 of the node spacing (valid, a little to smooth
 * everywhere), and one element on the boundary folded for good: a node of
 * its edge on the CAD curve v = 0 pushed back past the edge's first
 * vertex, with fix_curves (curve nodes stay), so every sweep starts with
 * that fold left. A move wakes its neighbours if it gains `factor` times
 * min_gain = tolerance * f / (free nodes); with a fold left, f is mostly
 * the fold's regularised part, so in a mesh K times larger the threshold
 * is K times lower for the same moves. Tolerance 1e-3 gives this mesh
 * (5 329 nodes) the threshold of a mesh of half a million nodes at the
 * default 0.1.
 *
 * Measured: nodes outside HOC_OPT_NEAR_RINGS + 1 rings of the folded
 * element that move, summed over the sweeps of the first attempt (from
 * the mesh between sweeps, in the progress callback). With the rule they
 * are a tenth of those without it (the rule switched off through
 * hoc_opt_rules); the check asks for less than a third, and fails when the
 * rule is off, since both runs are then the same.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "optimize/optimize_impl.h"
#include "optimize/tunables.h"
#include "test_shake.h"
#include "test_util.h"

#include <limits.h>
#include <string.h>

/* Node i's parameters moved by d, its element copies too; its slots (on
 * the plane's single face, without seams) set to those. */
static void move_param(hoc_mesh *m, size_t i, const double *d) {
  size_t np = (size_t)m->np;
  m->param[2 * i] += d[0];
  m->param[2 * i + 1] += d[1];
  for (size_t e = 0; e < m->n_elems; ++e)
    for (size_t k = 0; k < np; ++k)
      if (m->conn[e * np + k] == i) {
        double *uv = m->elem_uv + 2 * (e * np + k);
        uv[0] += d[0];
        uv[1] += d[1];
        memcpy(m->slot_uv + 2 * m->elem_slot[e * np + k], uv, 2 * sizeof *uv);
      }
}

/* The element with an edge on v = 0 nearest u = 1/2, folded: the node of
 * that edge next to its first vertex pushed back past the vertex by 0.15
 * of the edge (on the plane's curve v = 0, t = u). Returns the element. */
static size_t fold_on_boundary(hoc_mesh *m) {
  size_t np = (size_t)m->np, fold = SIZE_MAX;
  int edge = -1;
  double best = HUGE_VAL;
  for (size_t e = 0; e < m->n_elems; ++e) {
    const double *uv = m->elem_uv + 2 * e * np;
    for (int j = 0; j < 3; ++j) {
      int k = (j + 1) % 3;
      double mid = fabs(0.5 * (uv[2 * j] + uv[2 * k]) - 0.5);
      if (uv[2 * j + 1] == 0 && uv[2 * k + 1] == 0 && mid < best) {
        best = mid;
        fold = e;
        edge = j;
      }
    }
  }
  CHECK(fold != SIZE_MAX);
  if (fold == SIZE_MAX) return 0;
  const double *uv = m->elem_uv + 2 * fold * np;
  double u0 = uv[2 * edge], u1 = uv[2 * ((edge + 1) % 3)];
  size_t k = 3 + (size_t)edge * (size_t)(m->order - 1); /* first node of the edge (gmsh order) */
  size_t i = m->conn[fold * np + k];
  CHECK(m->dim[i] == HOC_ON_CURVE);
  double d[2] = {u0 - 0.15 * (u1 - u0) - uv[2 * k], 0};
  move_param(m, i, d);
  return fold;
}

/* The far nodes that moved, from the mesh between sweeps. */
typedef struct watch {
  hoc_mesh *m;
  double *prev;               /* [n_nodes][2] parameters after the last sweep */
  const unsigned char *near;  /* [n_nodes] not far */
  size_t far_moves, far_nodes; /* first attempt: moves of far nodes; far nodes */
  int sweeps, folded;          /* first attempt: sweeps; of them, ending tangled */
} watch;

static int on_sweep(void *user, const hoc_optimize_iteration *it) {
  watch *w = user;
  size_t far = 0;
  for (size_t i = 0; i < w->m->n_nodes; ++i)
    far += !w->near[i] && (w->prev[2 * i] != w->m->param[2 * i] ||
                           w->prev[2 * i + 1] != w->m->param[2 * i + 1]);
  memcpy(w->prev, w->m->param, 2 * w->m->n_nodes * sizeof *w->prev);
  if (it->attempt == 1) { /* (the second starts from a snapshot: not a sweep's moves) */
    w->far_moves += far;
    w->sweeps++;
    w->folded += it->tangled > 0;
  }
  return 0;
}

/* One run on a copy of m0 with the rule on or off; the far nodes' moves. */
static size_t far_moves(const hoc_mesh *m0, const unsigned char *near, int rule) {
  hoc_mesh *m = NULL;
  CHECK_OK(hoc_mesh_copy(m0, &m));
  if (!m) return 0;
  watch w = {m, malloc(2 * m->n_nodes * sizeof(double)), near, 0, 0, 0, 0};
  CHECK(w.prev != NULL);
  if (!w.prev) {
    hoc_mesh_destroy(&m);
    return 0;
  }
  memcpy(w.prev, m->param, 2 * m->n_nodes * sizeof *w.prev);
  for (size_t i = 0; i < m->n_nodes; ++i) w.far_nodes += !near[i];
  hoc_optimize_options o;
  hoc_optimize_options_default(&o);
  o.fix_curves = 1;
  o.tolerance = 1e-3;
  o.max_iterations = 12;
  o.progress = on_sweep;
  o.progress_user = &w;
  hoc_opt_rules rules;
  hoc_opt_rules_default(&rules);
  if (!rule) rules.wake_near_min_order = INT_MAX;
  hoc_optimize_result r;
  int limited;
  CHECK_OK(hoc_opt_run_rules(m, &o, &rules, 0, 0, hoc_now(), &r, &limited));
  printf("rule %s: %zu moves of the %zu far nodes in %d sweeps with the fold left in %d; "
         "%.2f s\n",
         rule ? "on " : "off", w.far_moves, w.far_nodes, w.sweeps, w.folded, r.seconds);
  /* the fold stays: every sweep of the first attempt ends with it */
  CHECK(w.sweeps == o.max_iterations && w.folded == w.sweeps);
  free(w.prev);
  hoc_mesh_destroy(&m);
  return w.far_moves;
}

int main(void) {
  const int n = 12, order = 6;
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *m = NULL;
  unsigned char *elem = NULL, *near = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_PLANE, 1.0, 0, &model));
  if (model) CHECK_OK(hoc_mesh_grid_linear(model, n, n, &lin));
  if (lin) CHECK_OK(hoc_mesh_elevate(lin, order, HOC_NODES_EQUISPACED, &m));
  if (!m) goto out;
  shake(m, 0.02, 1.0 / (n * order), 1.0 / (n * order), 12345);
  hoc_quality_stats st;
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st));
  CHECK(st.tangled == 0); /* the shaking folds nothing */
  size_t fold = fold_on_boundary(m);
  CHECK_OK(hoc_mesh_update_xyz(m));
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st));
  printf("plane %d x %d at order %d: %zu nodes, element %zu folded (%zu tangled)\n", n, n,
         order, m->n_nodes, fold, st.tangled);
  CHECK(st.tangled == 1);
  elem = calloc(m->n_elems, 1);
  near = calloc(m->n_nodes, 1);
  CHECK(elem && near);
  if (!elem || !near) goto out;
  elem[fold] = 1;
  hoc_opt_grow_rings(m, elem, near, HOC_OPT_NEAR_RINGS + 1);
  size_t on = far_moves(m, near, 1), off = far_moves(m, near, 0);
  /* without the rule, waves of moves reach the far nodes sweep after
   * sweep; with it, a third as many at most */
  CHECK(3 * on < off);
out:
  free(elem);
  free(near);
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
  return test_report();
}
