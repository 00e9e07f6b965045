/* The optimiser's snapshots of the mesh state (optimize/driver.c): kept
 * compactly (the nodes' parameters whole, slot and element parameters only
 * where they differ from their node's and slot's, no positions), restored
 * bit for bit. Each case: a raised analytic mesh with seams or poles, a
 * snapshot, an optimisation that moves its nodes, the restore; every array
 * the optimiser changes must come back as it was (positions evaluated from
 * the parameters again), and the snapshot must hold a small share of the
 * slots' and elements' parameters. A restore that left the positions, the
 * pole slots' own coordinates or the elements' copies unwrapped across a
 * seam as the optimisation left them fails here.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "optimize/optimize_impl.h"
#include "test_util.h"

#include <string.h>

/* Items of a and b (n doubles each) that differ bit for bit. */
static size_t differ(const double *a, const double *b, size_t n) {
  size_t d = 0;
  for (size_t i = 0; i < n; ++i) d += memcmp(a + i, b + i, sizeof *a) != 0;
  return d;
}

static void check_case(const char *name, int shape, double a, double b, int nu, int nv,
                       int order) {
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *m = NULL, *ref = NULL;
  hoc_opt_snapshot s = {0};
  CHECK_OK(hoc_cad_create_analytic(shape, a, b, &model));
  if (model) CHECK_OK(hoc_mesh_grid_linear(model, nu, nv, &lin));
  if (lin) CHECK_OK(hoc_mesh_elevate(lin, order, HOC_NODES_EQUISPACED, &m));
  if (m) CHECK_OK(hoc_mesh_copy(m, &ref));
  if (!ref) goto out;
  size_t nn = m->n_nodes, ns = m->n_slots, nev = m->n_elems * (size_t)m->np;
  CHECK_OK(hoc_opt_snapshot_take(&s, m, 1, 0));
  /* an optimisation moves the nodes, their slots and element copies */
  hoc_optimize_result r;
  CHECK_OK(hoc_mesh_optimize(m, NULL, &r));
  size_t moved = differ(m->param, ref->param, 2 * nn);
  CHECK(moved > 0 && differ(m->xyz, ref->xyz, 3 * nn) > 0);
  CHECK(differ(m->elem_uv, ref->elem_uv, 2 * nev) > 0);
  CHECK_OK(hoc_opt_snapshot_restore(&s, m));
  size_t bad = differ(m->param, ref->param, 2 * nn) + differ(m->xyz, ref->xyz, 3 * nn) +
               differ(m->slot_uv, ref->slot_uv, 2 * ns) +
               differ(m->elem_uv, ref->elem_uv, 2 * nev) +
               differ(m->line_t, ref->line_t, 2 * m->n_lines);
  printf("%s, order %d: %zu parameters moved; kept %zu of %zu slots' and %zu of %zu element "
         "copies' parameters; %zu numbers differ after the restore\n",
         name, order, moved, s.slot_uv.n, ns, s.elem_uv.n, nev, bad);
  CHECK(bad == 0);
  /* compact: a small share of the slots and element copies */
  CHECK(s.slot_uv.n > 0 && 4 * s.slot_uv.n < ns);
  CHECK(4 * s.elem_uv.n < nev);
  /* a second take reuses the lists and gives the same */
  size_t ks = s.slot_uv.n, ke = s.elem_uv.n;
  CHECK_OK(hoc_opt_snapshot_take(&s, m, 1, 0));
  CHECK(s.slot_uv.n == ks && s.elem_uv.n == ke);
out:
  hoc_opt_snapshot_free(&s);
  hoc_mesh_destroy(&ref);
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

int main(void) {
  check_case("sphere (poles, a seam)", HOC_ANALYTIC_SPHERE, 1.0, 0, 12, 6, 4);
  check_case("torus (two seams)", HOC_ANALYTIC_TORUS, 2.0, 0.5, 12, 6, 3);
  check_case("cone (an apex, a seam)", HOC_ANALYTIC_CONE, 1.0, 2.0, 12, 4, 6);
  printf("%d passed, %d failed\n", test_passed_, test_failed_);
  return test_failed_ != 0;
}
