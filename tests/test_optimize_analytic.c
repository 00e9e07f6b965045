/* The optimiser on exact surfaces: deliberately tangled high-order meshes of
 * a sphere (poles, seam), a cylinder and a torus (two seams) come out valid
 * with every node exactly on the surface; analytic gradients match finite
 * differences; an optimum stays put; results do not depend on the thread
 * count.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "quality/quality.h"
#include "test_util.h"

#include <omp.h>
#include <string.h>

static double off_surface(hoc_analytic_kind kind, double a, double b, const double *x) {
  double rho = hypot(x[0], x[1]);
  switch (kind) {
  case HOC_ANALYTIC_SPHERE: return fabs(sqrt(rho * rho + x[2] * x[2]) - a);
  case HOC_ANALYTIC_CYLINDER: return fabs(rho - a);
  case HOC_ANALYTIC_TORUS: return fabs(hypot(rho - a, x[2]) - b);
  default: return fabs(x[2]);
  }
}

/* Move face node i of element e to parameters uv (all its element copies
 * and its slot follow). */
static void move_node(hoc_mesh *m, size_t e, int k, const double *uv) {
  int np = m->np;
  size_t i = m->conn[e * (size_t)np + (size_t)k];
  const double *cur = m->elem_uv + 2 * (e * (size_t)np + (size_t)k);
  double d[2] = {uv[0] - cur[0], uv[1] - cur[1]};
  m->param[2 * i] += d[0];
  m->param[2 * i + 1] += d[1];
  for (size_t f = 0; f < m->n_elems; ++f)
    for (int j = 0; j < np; ++j)
      if (m->conn[f * (size_t)np + j] == i) {
        m->elem_uv[2 * (f * (size_t)np + j)] += d[0];
        m->elem_uv[2 * (f * (size_t)np + j) + 1] += d[1];
      }
  size_t s = m->elem_slot[e * (size_t)np + (size_t)k];
  m->slot_uv[2 * s] = m->param[2 * i];
  m->slot_uv[2 * s + 1] = m->param[2 * i + 1];
}

/* Fold elements the way curved meshes fold: in every `every`-th element an
 * interior node is pushed past vertex 0, and the first node of edge 0 is
 * pushed past vertex 0 along its edge (folding both elements of the edge). */
static void tangle(hoc_mesh *m, int every) {
  int np = m->np, p = m->order;
  for (size_t e = 0; e < m->n_elems; e += (size_t)every) {
    const double *u = m->elem_uv + 2 * e * (size_t)np;
    if (np > 3 * p && m->dim[m->conn[e * (size_t)np + 3 * (size_t)p]] == HOC_ON_FACE) {
      double c[2] = {(u[0] + u[2] + u[4]) / 3, (u[1] + u[3] + u[5]) / 3};
      double to[2] = {c[0] + 1.4 * (u[0] - c[0]), c[1] + 1.4 * (u[1] - c[1])};
      move_node(m, e, 3 * p, to);
    }
    if (m->dim[m->conn[e * (size_t)np + 3]] == HOC_ON_FACE) {
      double to[2] = {u[0] - 0.15 * (u[2] - u[0]), u[1] - 0.15 * (u[3] - u[1])};
      move_node(m, e, 3, to);
    }
  }
  hoc_mesh_update_xyz(m);
}

/* A torus (radii a, b), its 16 x 6 grid and that raised to order 3. */
static void torus_p3(double a, double b, hoc_model **model, hoc_mesh **lin, hoc_mesh **m) {
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_TORUS, a, b, model));
  CHECK_OK(hoc_mesh_grid_linear(*model, 16, 6, lin));
  CHECK_OK(hoc_mesh_elevate(*lin, 3, HOC_NODES_EQUISPACED, m));
}

static void check_kind(hoc_analytic_kind kind, double a, double b, int nu, int nv, int p) {
  hoc_model *model;
  CHECK_OK(hoc_cad_create_analytic(kind, a, b, &model));
  hoc_mesh *lin, *m;
  CHECK_OK(hoc_mesh_grid_linear(model, nu, nv, &lin));
  CHECK_OK(hoc_mesh_elevate(lin, p, HOC_NODES_EQUISPACED, &m));
  tangle(m, 5);
  hoc_quality_stats before, after;
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &before));
  CHECK(before.tangled > 0);
  /* on a tangled mesh the regularised objective is still smooth except
   * where an element stands perpendicular to the surface (gamma flips): a
   * looser bound there, a tight one on the untangled mesh below */
  double gerr;
  CHECK_OK(hoc_mesh_check_gradient(m, HOC_MEASURE_SHAPE, 0, 50, &gerr));
  CHECK(gerr < 1e-3);
  if (!(gerr < 1e-3)) fprintf(stderr, "  gradient check (tangled): %g\n", gerr);
  hoc_optimize_result r;
  CHECK_OK(hoc_mesh_optimize(m, NULL, &r));
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &after));
  printf("kind %d p=%d: %zu tangled -> %zu, min q %.3f -> %.3f, %d iterations\n", (int)kind, p,
         before.tangled, after.tangled, before.min, after.min, r.iterations);
  CHECK(after.tangled == 0);
  CHECK(r.tangled_final == 0 && r.tangled_initial == before.tangled);
  /* the samples' untangling needs no second attempt; the exact phase
   * (folds between the samples: the cylinder's, at corners on its rims)
   * may */
  CHECK((r.diagnostics.second_attempt == 0 || (r.diagnostics.exact_phase && r.diagnostics.second_attempt > r.diagnostics.exact_phase)) &&
        !r.stopped_at_limit);
  CHECK(after.min > 0.3);
  CHECK_OK(hoc_mesh_check_gradient(m, HOC_MEASURE_SHAPE, 0, 50, &gerr));
  CHECK(gerr < 1e-6);
  if (!(gerr < 1e-6)) fprintf(stderr, "  gradient check (valid): %g\n", gerr);
  CHECK_OK(hoc_mesh_check_gradient(m, HOC_MEASURE_ODDY, 1, 50, &gerr));
  CHECK(gerr < 1e-6);
  double worst = 0;
  for (size_t i = 0; i < m->n_nodes; ++i) worst = fmax(worst, off_surface(kind, a, b, m->xyz + 3 * i));
  CHECK(worst <= 1e-13 * a);
  double dist;
  CHECK_OK(hoc_mesh_max_cad_distance(m, &dist));
  CHECK(dist == 0.0);
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* A mesh at the exact optimum stays put: one equilateral element on a plane
 * (eta = 1 everywhere, f = 0), raised to order 3, its apex a free vertex. */
static void check_optimum(void) {
  const double a = 2.0;
  hoc_model *model;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_PLANE, a, 0, &model));
  double xyz[9] = {0, 0, 0, a, 0, 0, 0.5 * a, 0.5 * sqrt(3.0) * a, 0};
  double par[6] = {0, 0, 0, 0, 0.5 * a, 0.5 * sqrt(3.0) * a};
  signed char dim[3] = {HOC_ON_VERTEX, HOC_ON_VERTEX, HOC_ON_FACE};
  int ent[3] = {0, 1, 0}, face[1] = {0};
  size_t conn[3] = {0, 1, 2};
  hoc_mesh_source src = {0};
  src.order = 1, src.n_nodes = 3, src.xyz = xyz, src.param = par, src.dim = dim, src.entity = ent;
  src.n_elems = 1, src.conn = conn, src.elem_face = face;
  hoc_mesh *lin, *m;
  CHECK_OK(hoc_mesh_assemble(model, &src, &lin));
  CHECK_OK(hoc_mesh_elevate(lin, 3, HOC_NODES_EQUISPACED, &m));
  double *before = malloc(3 * m->n_nodes * sizeof *before);
  memcpy(before, m->xyz, 3 * m->n_nodes * sizeof *before);
  hoc_optimize_result r;
  CHECK_OK(hoc_mesh_optimize(m, NULL, &r));
  CHECK(r.objective_initial < 1e-20);
  double moved = 0;
  for (size_t i = 0; i < 3 * m->n_nodes; ++i) moved = fmax(moved, fabs(m->xyz[i] - before[i]));
  CHECK(moved < 1e-12 * a);
  hoc_quality_stats st;
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st));
  CHECK_NEAR(st.min, 1.0, 1e-12);
  free(before);
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* Same input, 1 and 2 threads: bitwise the same result. */
static void check_threads(void) {
  hoc_model *model;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_TORUS, 3, 1, &model));
  hoc_mesh *lin, *m1, *m2;
  CHECK_OK(hoc_mesh_grid_linear(model, 16, 6, &lin));
  CHECK_OK(hoc_mesh_elevate(lin, 3, HOC_NODES_EQUISPACED, &m1));
  CHECK_OK(hoc_mesh_elevate(lin, 3, HOC_NODES_EQUISPACED, &m2));
  tangle(m1, 4);
  tangle(m2, 4);
  int saved = omp_get_max_threads();
  omp_set_num_threads(1);
  CHECK_OK(hoc_mesh_optimize(m1, NULL, NULL));
  omp_set_num_threads(2);
  CHECK_OK(hoc_mesh_optimize(m2, NULL, NULL));
  omp_set_num_threads(saved);
  CHECK(m1->n_nodes == m2->n_nodes);
  CHECK(!memcmp(m1->param, m2->param, 2 * m1->n_nodes * sizeof *m1->param));
  CHECK(!memcmp(m1->xyz, m2->xyz, 3 * m1->n_nodes * sizeof *m1->xyz));
  hoc_mesh_destroy(&m1);
  hoc_mesh_destroy(&m2);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* Sweeps that run out with elements still tangled: a second attempt of half
 * as many from the best state reached (relaxed (u, v) rule on the torus,
 * which has no pole); nodes stay on the surface, the count never ends above
 * the start, and a full run from there untangles. */
static void check_second_attempt(void) {
  const double a = 3, b = 1;
  hoc_model *model;
  hoc_mesh *lin, *m;
  torus_p3(a, b, &model, &lin, &m);
  tangle(m, 2);
  hoc_optimize_options o;
  hoc_optimize_options_default(&o);
  o.max_iterations = 2;
  hoc_optimize_result r;
  CHECK_OK(hoc_mesh_optimize(m, &o, &r));
  printf("second attempt: %zu tangled -> %zu in %d sweeps (second from sweep %d)\n",
         r.tangled_initial, r.tangled_final, r.iterations, r.diagnostics.second_attempt);
  CHECK(r.tangled_initial > 0);
  CHECK(r.tangled_final > 0 ? r.diagnostics.second_attempt == 3 && r.iterations == 3 : r.diagnostics.second_attempt == 0);
  CHECK(r.diagnostics.second_attempt > 0); /* this mesh needs more than two sweeps */
  CHECK(r.stopped_at_limit == (r.tangled_final > 0)); /* both attempts used their sweeps */
  CHECK(r.tangled_final <= r.tangled_initial);
  hoc_quality_stats st;
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st));
  CHECK(st.tangled == r.tangled_final);
  double worst = 0;
  for (size_t i = 0; i < m->n_nodes; ++i)
    worst = fmax(worst, off_surface(HOC_ANALYTIC_TORUS, a, b, m->xyz + 3 * i));
  CHECK(worst <= 1e-13 * a);
  CHECK_OK(hoc_mesh_optimize(m, NULL, &r));
  CHECK(r.tangled_final == 0);
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* The optimiser's final polish alone (hoc_mesh_polish): on a valid mesh it
 * moves nothing; an element folded a little (its interior node pushed past
 * the middle of an edge) comes out valid with every node on the surface and
 * no other element tangled; more than 32 tangled elements are left to the
 * sweeps and splits (nothing moves). */
static void check_polish(void) {
  const double a = 3, b = 1;
  hoc_model *model;
  hoc_mesh *lin, *m;
  torus_p3(a, b, &model, &lin, &m);
  size_t fixed = 99;
  double *before = malloc(3 * m->n_nodes * sizeof *before);
  memcpy(before, m->xyz, 3 * m->n_nodes * sizeof *before);
  CHECK_OK(hoc_mesh_polish(m, HOC_MEASURE_SHAPE, 0, &fixed));
  CHECK(fixed == 0);
  CHECK(!memcmp(before, m->xyz, 3 * m->n_nodes * sizeof *before));
  /* element 37's interior node (p = 3: local node 9) past edge 0's middle */
  size_t e = 37;
  const double *u = m->elem_uv + 2 * e * (size_t)m->np;
  double c[2] = {(u[0] + u[2] + u[4]) / 3, (u[1] + u[3] + u[5]) / 3};
  double mid[2] = {0.5 * (u[0] + u[2]), 0.5 * (u[1] + u[3])};
  double to[2] = {mid[0] + 0.3 * (mid[0] - c[0]), mid[1] + 0.3 * (mid[1] - c[1])};
  move_node(m, e, 9, to);
  CHECK_OK(hoc_mesh_update_xyz(m));
  unsigned char *tangled = malloc(m->n_elems);
  hoc_quality_stats st;
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, tangled, &st));
  CHECK(st.tangled == 1 && tangled[e]);
  CHECK_OK(hoc_mesh_polish(m, HOC_MEASURE_SHAPE, 0, &fixed));
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, tangled, &st));
  printf("polish: 1 folded element -> %zu tangled (%zu untangled), min q %.3f\n", st.tangled, fixed,
         st.min);
  CHECK(fixed == 1 && st.tangled == 0);
  double worst = 0;
  for (size_t i = 0; i < m->n_nodes; ++i)
    worst = fmax(worst, off_surface(HOC_ANALYTIC_TORUS, a, b, m->xyz + 3 * i));
  CHECK(worst <= 1e-13 * a);
  /* only the folded element's neighbourhood moved: its corners' elements */
  size_t moved = 0;
  for (size_t i = 0; i < m->n_nodes; ++i)
    moved += memcmp(before + 3 * i, m->xyz + 3 * i, 3 * sizeof *before) != 0;
  CHECK(moved > 0 && moved < m->n_nodes / 4);
  /* many folds: beyond the polish's budget, nothing moves */
  tangle(m, 1);
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st));
  CHECK(st.tangled > 32);
  memcpy(before, m->xyz, 3 * m->n_nodes * sizeof *before);
  CHECK_OK(hoc_mesh_polish(m, HOC_MEASURE_SHAPE, 0, &fixed));
  CHECK(fixed == 0);
  CHECK(!memcmp(before, m->xyz, 3 * m->n_nodes * sizeof *before));
  free(tangled);
  free(before);
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* free_elements: only the nodes of the flagged elements and of free_rings
 * rings around them move, bit for bit; a fold inside that region opens, a
 * fold outside it stays. */
static void check_local(void) {
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *m = NULL, *before = NULL;
  torus_p3(3.0, 1.0, &model, &lin, &m);
  if (!m) goto out;
  size_t ne = m->n_elems, np = (size_t)m->np, nn = m->n_nodes;
  tangle(m, (int)ne); /* element 0 only */
  CHECK_OK(hoc_mesh_copy(m, &before));
  unsigned char *flag = calloc(ne, 1), *ring = calloc(ne, 1), *mine = calloc(nn, 1);
  if (!flag || !ring || !mine || !before) goto done;
  /* the region: element 0, and (one ring) every element sharing a node with it */
  flag[0] = 1;
  for (size_t k = 0; k < np; ++k) mine[m->conn[k]] = 1;
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < np; ++k) ring[e] |= mine[m->conn[e * np + k]];
  memset(mine, 0, nn);
  for (size_t e = 0; e < ne; ++e)
    for (size_t k = 0; k < np && ring[e]; ++k) mine[m->conn[e * np + k]] = 1;
  hoc_optimize_options oo;
  hoc_optimize_options_default(&oo);
  oo.free_elements = flag;
  oo.free_rings = -1;
  hoc_optimize_result r;
  CHECK_STATUS(hoc_mesh_optimize(m, &oo, &r), HOC_ERR_ARGUMENT);
  oo.free_rings = 1;
  CHECK_OK(hoc_mesh_optimize(m, &oo, &r));
  hoc_quality_stats st;
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st));
  size_t moved_out = 0, moved_in = 0;
  for (size_t i = 0; i < nn; ++i) {
    int same = !memcmp(m->param + 2 * i, before->param + 2 * i, 2 * sizeof(double)) &&
               !memcmp(m->xyz + 3 * i, before->xyz + 3 * i, 3 * sizeof(double));
    if (mine[i]) moved_in += !same;
    else moved_out += !same;
  }
  printf("local: %zu tangled -> %zu, %zu nodes moved in the region, %zu outside it\n",
         r.tangled_initial, st.tangled, moved_in, moved_out);
  CHECK(r.tangled_initial > 0 && st.tangled == 0 && r.tangled_final == 0);
  CHECK(moved_in > 0 && moved_out == 0);
  /* a region away from the fold (the element farthest in the list, no
   * rings): the fold stays */
  hoc_mesh_destroy(&m);
  CHECK_OK(hoc_mesh_copy(before, &m));
  if (!m) goto done;
  memset(flag, 0, ne);
  flag[ne / 2] = 1;
  oo.free_rings = 0;
  CHECK_OK(hoc_mesh_optimize(m, &oo, &r));
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st));
  CHECK(st.tangled > 0 && r.tangled_final > 0);
  /* and it is not tried again: a local repair makes no second attempt
   * (nothing is relaxed in it) and no protected run (it runs the exact
   * test from its first sweep already), so it ends with its first run */
  printf("local, fold outside: %d sweeps, second attempt at %d, protected run at %d\n",
         r.iterations, r.diagnostics.second_attempt, r.diagnostics.protected_run);
  CHECK(r.diagnostics.second_attempt == 0 && r.diagnostics.protected_run == 0);
  int sweeps = r.iterations;
  hoc_mesh_destroy(&m);
  CHECK_OK(hoc_mesh_copy(before, &m));
  if (!m) goto done;
  oo.max_iterations = 1000;
  CHECK_OK(hoc_mesh_optimize(m, &oo, &r));
  CHECK(r.iterations == sweeps && r.tangled_final > 0);
done:
  free(flag);
  free(ring);
  free(mine);
out:
  hoc_mesh_destroy(&before);
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

/* Fragile elements (hoc_optimize_diagnostics.fragile): above order 5 a whole-mesh
 * run guards the elements that start valid with q < 0.1, as a protected run
 * guards every element: none may fold between the samples. A plane: a
 * needle (height 0.05 over an edge of length 2 between two fixed CAD
 * vertices, q about 0.06) and two fair elements (q about 0.73) over it: at
 * order 6 the needle is the one fragile element, at order 5 none is; either
 * way all come out valid by the exact test, the needle better than it went
 * in. */
static void check_fragile(void) {
  hoc_model *model;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_PLANE, 2.0, 0, &model));
  double xyz[12] = {0, 0, 0, 2, 0, 0, 1, 0.05, 0, 1, 1.8, 0};
  double par[8] = {0, 0, 2, 0, 1, 0.05, 1, 1.8};
  signed char dim[4] = {HOC_ON_VERTEX, HOC_ON_VERTEX, HOC_ON_FACE, HOC_ON_FACE};
  int ent[4] = {0, 1, 0, 0}, face[3] = {0, 0, 0};
  size_t conn[9] = {0, 1, 2, 0, 2, 3, 2, 1, 3};
  hoc_mesh_source src = {0};
  src.order = 1, src.n_nodes = 4, src.xyz = xyz, src.param = par, src.dim = dim, src.entity = ent;
  src.n_elems = 3, src.conn = conn, src.elem_face = face;
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_assemble(model, &src, &lin));
  for (int p = 5; p <= 6 && lin; ++p) {
    hoc_mesh *m = NULL;
    CHECK_OK(hoc_mesh_elevate(lin, p, HOC_NODES_EQUISPACED, &m));
    if (!m) break;
    double q0[3], q1[3];
    hoc_quality_stats st;
    CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q0, NULL, NULL));
    CHECK(q0[0] > 0 && q0[0] < 0.1 && q0[1] > 0.5 && q0[2] > 0.5);
    hoc_optimize_result r;
    CHECK_OK(hoc_mesh_optimize(m, NULL, &r));
    CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q1, NULL, &st));
    printf("fragile, order %d: %zu fragile; q %.4f %.4f %.4f -> %.4f %.4f %.4f, %d sweeps\n", p,
           r.diagnostics.fragile, q0[0], q0[1], q0[2], q1[0], q1[1], q1[2], r.iterations);
    CHECK(r.diagnostics.fragile == (p > 5 ? 1u : 0u));
    CHECK(st.tangled == 0 && r.tangled_final == 0);
    CHECK(q1[0] > q0[0]);
    hoc_mesh_destroy(&m);
  }
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

int main(void) {
  check_kind(HOC_ANALYTIC_SPHERE, 1.0, 0, 16, 8, 3);
  check_kind(HOC_ANALYTIC_CYLINDER, 1.0, 2.0, 12, 4, 3);
  check_kind(HOC_ANALYTIC_TORUS, 3.0, 1.0, 24, 8, 3);
  check_kind(HOC_ANALYTIC_SPHERE, 1.0, 0, 12, 6, 5);
  check_optimum();
  check_threads();
  check_second_attempt();
  check_polish();
  check_local();
  check_fragile();
  return test_report();
}
