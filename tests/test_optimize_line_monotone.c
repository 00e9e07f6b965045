/* A curve node's step may not make its line's parameter turn back
 * (hoc_opt_line_monotone, trial.c). Ordered nodes do not make an
 * increasing parameter: on an order-3 line with nodes at s = 0, 1/3, 2/3, 1
 * the parameters t = 0, 0.6, 0.62, 1 (a share of the line's span) are
 * strictly increasing, yet their cubic interpolant has dt/ds = -0.077 at
 * s = 0.539 (closed form: t(s) = 3.61 s - 6.84 s^2 + 4.23 s^3, whose
 * derivative is least at s = 6.84 / 12.69, 3.61 - 6.84^2 / 12.69), between
 * every sample of the elements on the line, and they fold along it. Seen
 * where curve nodes slide towards a cusp: on crescent_plate.step at
 * order 3 the exact phase found 8 elements folded along lines on curves
 * after the sampled phase, and the run took 143 sweeps; with the rule 1,
 * and 49 sweeps.
 *
 * Cases, on an order-3 grid of the analytic plane: evenly spaced trial
 * values pass; the turned-back ones fail (they pass without the rule);
 * unordered ones fail; turned-back trial values pass when the committed
 * line turns back already (a step may not be refused for the state it
 * starts from: the nodes would be frozen); the same at order 5 with
 * Fekete nodes (Gauss-Lobatto-Legendre on the line).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "mesh/mesh.h"
#include "optimize/optimize_impl.h"
#include "test_util.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* The first line whose interior nodes all lie on its curve; SIZE_MAX if
 * none. */
static size_t line_with_curve_nodes(const hoc_mesh *m) {
  size_t lp = (size_t)m->order + 1;
  for (size_t l = 0; l < m->n_lines; ++l) {
    int all = 1;
    for (size_t j = 2; j < lp; ++j) all &= m->dim[m->line_conn[l * lp + j]] == HOC_ON_CURVE;
    if (all) return l;
  }
  return SIZE_MAX;
}

/* Line l's interior nodes (in order from its end 0) at trial parameters
 * ta + share[j] (tb - ta), j = 1..p-1; returns hoc_opt_line_monotone. */
static int trial_at(hoc_opt *o, size_t l, const double *share) {
  const hoc_mesh *m = o->m;
  int p = m->order;
  size_t nodes[HOC_MAX_ORDER] = {0};
  double ta = m->line_t[2 * l], tb = m->line_t[2 * l + 1];
  for (int j = 1; j < p; ++j) nodes[j - 1] = m->line_conn[l * (size_t)(p + 1) + (size_t)j + 1];
  if (hoc_opt_trial_reserve(o, nodes, (size_t)(p - 1)) != HOC_OK) return -1;
  for (int j = 1; j < p; ++j) {
    o->node.moving[nodes[j - 1]] = 1;
    hoc_opt_tpar(o, nodes[j - 1])[0] = ta + share[j] * (tb - ta);
  }
  int ok = hoc_opt_line_monotone(o, l);
  for (int j = 1; j < p; ++j) o->node.moving[nodes[j - 1]] = 0;
  return ok;
}

/* Commits line l's interior nodes at the parameters of share (only the
 * curve parameter: what hoc_opt_line_monotone reads). */
static void commit_at(hoc_opt *o, size_t l, const double *share) {
  hoc_mesh *m = o->m;
  int p = m->order;
  double ta = m->line_t[2 * l], tb = m->line_t[2 * l + 1];
  for (int j = 1; j < p; ++j)
    m->param[2 * m->line_conn[l * (size_t)(p + 1) + (size_t)j + 1]] = ta + share[j] * (tb - ta);
}

static void check_order(int order, hoc_nodeset set) {
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *m = NULL;
  hoc_opt o;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_PLANE, 1.0, 0, &model));
  if (model) CHECK_OK(hoc_mesh_grid_linear(model, 3, 3, &lin));
  if (lin) CHECK_OK(hoc_mesh_elevate(lin, order, set, &m));
  if (!m) goto out;
  size_t l = line_with_curve_nodes(m);
  CHECK(l != SIZE_MAX);
  if (l == SIZE_MAX || hoc_opt_setup(&o, m, HOC_MEASURE_SHAPE, 0, NULL, 0) != HOC_OK) goto out;
  double s[HOC_MAX_ORDER + 1], even[HOC_MAX_ORDER + 1], back[HOC_MAX_ORDER + 1],
      swapped[HOC_MAX_ORDER + 1];
  CHECK_OK(hoc_edge_nodes(order, set, s));
  /* the node set's own positions: t linear in s */
  memcpy(even, s, sizeof s);
  /* the second and third nodes bunched at 0.6 and 0.62 of the span, the
   * rest where t = s would put them (still increasing) */
  memcpy(back, s, sizeof s);
  back[1] = 0.6;
  back[2] = 0.62;
  for (int j = 3; j < order; ++j) back[j] = fmax(s[j], 0.62 + 0.01 * j);
  memcpy(swapped, s, sizeof s);
  swapped[1] = s[2];
  swapped[2] = s[1];
  int ok_even = trial_at(&o, l, even), ok_back = trial_at(&o, l, back),
      ok_swapped = trial_at(&o, l, swapped);
  CHECK(ok_even == 1);
  CHECK(ok_back == 0);
  CHECK(ok_swapped == 0);
  /* committed turned back already: the step is not refused for it */
  commit_at(&o, l, back);
  back[2] = 0.63;
  int ok_from_back = trial_at(&o, l, back);
  CHECK(ok_from_back == 1);
  printf("order %d (%s): line %zu, evenly spaced %d, turned back %d, unordered %d, turned back "
         "from a committed line that turns back %d\n",
         order, set == HOC_NODES_EQUISPACED ? "equispaced" : "Fekete", l, ok_even, ok_back,
         ok_swapped, ok_from_back);
  hoc_opt_free(&o);
out:
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

int main(void) {
  check_order(3, HOC_NODES_EQUISPACED);
  check_order(5, HOC_NODES_FEKETE);
  printf("%d passed, %d failed\n", test_passed_, test_failed_);
  return test_failed_ != 0;
}
