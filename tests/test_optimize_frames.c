/* The pool of element frames (optimize/objective.c, hoc_opt_frames): from
 * order 6 a block's model reads its elements' frames from the pool and an
 * accepted step moves them by its nodes' changes. A mesh with more
 * elements than the pool holds lends its places at each sweep's start to
 * the elements of awake nodes (hoc_opt_frames_assign); its class is the
 * large mesh at a high order, whose frames would be gigabytes.
 *
 * The case: a torus (two seams) raised to order 6, its face nodes moved
 * at random by up to 0.15 of their spacing (some elements fold),
 * and a pool of 12 elements. Sweeps in which the awake nodes are those of
 * a window of elements that slides along the mesh: at each sweep's start,
 * after the places are lent, every kept frame must be the frame of the
 * element's nodes as they are, bit for bit. A place lent without its
 * frames computed, or kept frames its nodes have moved from, fail that.
 * Then whole runs with that pool on one thread and on two: the same mesh
 * bit for bit (the places follow the awake nodes, not the threads), as
 * valid and about as good as a run with a pool of every element.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "optimize/optimize_impl.h"
#include "test_shake.h"
#include "test_util.h"

#include <omp.h>
#include <string.h>

typedef struct outcome {
  hoc_optimize_result r;
  hoc_quality_stats st;
  hoc_mesh *mesh;
} outcome;

static void optimise(const hoc_mesh *start, size_t pool_bytes, int threads, outcome *out) {
  memset(out, 0, sizeof *out);
  CHECK_OK(hoc_mesh_copy(start, &out->mesh));
  if (!out->mesh) return;
  hoc_opt_rules rules;
  hoc_opt_rules_default(&rules);
  rules.frame_pool_bytes = pool_bytes;
  int limited = 0, before = omp_get_max_threads();
  omp_set_num_threads(threads);
  CHECK_OK(hoc_opt_run_rules(out->mesh, NULL, &rules, 0, 0, hoc_now(), &out->r, &limited));
  omp_set_num_threads(before);
  CHECK_OK(hoc_mesh_measure(out->mesh, HOC_MEASURE_SHAPE, NULL, NULL, &out->st));
}

enum { NP_MAX = (HOC_MAX_ORDER + 1) * (HOC_MAX_ORDER + 2) / 2 };

/* Kept frames that differ from their elements' nodes; *kept: how many. */
static size_t stale_frames(const hoc_opt *o, size_t *kept) {
  size_t bad = 0, n = 9 * (size_t)o->fc.npts;
  double x[3 * NP_MAX], nr[3 * NP_MAX];
  double *fr = malloc(n * sizeof *fr);
  CHECK(fr != NULL);
  *kept = 0;
  for (size_t e = 0; fr && e < o->m->n_elems; ++e) {
    const double *pool = hoc_opt_frames_of(o, e);
    if (!pool) continue;
    ++*kept;
    hoc_opt_gather(o, e, x, nr);
    hoc_element_frames(o->t, x, nr, fr);
    bad += memcmp(fr, pool, n * sizeof *fr) != 0;
  }
  free(fr);
  return bad;
}

/* Sweeps in which the nodes of a sliding window of elements are awake. */
static void check_lent_places(hoc_mesh *m, size_t small) {
  hoc_opt o;
  hoc_opt_scratch *scr = NULL;
  int nthreads = omp_get_max_threads();
  CHECK_OK(hoc_opt_setup(&o, m, HOC_MEASURE_SHAPE, 0, NULL, 0));
  CHECK(o.fc.cap == m->n_elems && !o.fc.dynamic); /* the default pool holds them all */
  CHECK_OK(hoc_opt_frames_setup(&o, small));
  CHECK(o.fc.cap == 12 && o.fc.dynamic);
  CHECK_OK(hoc_opt_eval_all(&o));
  CHECK_OK(hoc_opt_scratch_alloc(&o, nthreads, &scr));
  double f, q;
  size_t tangled, lent = 0, stale = 0, moved_kept = 0;
  CHECK_OK(hoc_opt_sweep_start(&o, &f, &q, &tangled));
  unsigned char *held = calloc(m->n_elems, 1);
  CHECK(held != NULL);
  size_t np = (size_t)m->np, window = 16;
  for (size_t sweep = 0; sweep < 8 && held && scr; ++sweep) {
    memset(o.node.active, 0, m->n_nodes);
    for (size_t e = sweep * 8; e < sweep * 8 + window && e < m->n_elems; ++e)
      for (size_t i = 0; i < np; ++i) {
        size_t k = m->conn[e * np + i];
        o.node.active[k] = o.adj.ndof[k] > 0;
      }
    hoc_opt_wake_all(&o);
    hoc_opt_frames_assign(&o);
    size_t kept;
    stale += stale_frames(&o, &kept);
    CHECK(kept == 12);
    for (size_t e = 0; e < m->n_elems; ++e)
      if (hoc_opt_frames_of(&o, e) && !held[e]) held[e] = 1, ++lent;
    for (int fam = 0; fam < 2; ++fam) {
      o.B = &o.fam[fam];
      for (int c = 0; c < o.B->n_colors; ++c) {
        size_t mc;
        CHECK_OK(hoc_opt_do_color(&o, c, scr, nthreads, &mc));
      }
    }
    o.B = &o.fam[0];
    for (size_t e = 0; e < m->n_elems; ++e)
      moved_kept += o.el.dirty[e] && hoc_opt_frames_of(&o, e) != NULL;
    CHECK_OK(hoc_opt_sweep_start(&o, &f, &q, &tangled));
  }
  printf("torus, order %d, pool of 12: %zu elements held places over 8 sweeps, %zu kept "
         "elements moved, %zu stale frames at the sweeps' starts\n",
         m->order, lent, moved_kept, stale);
  CHECK(lent > 24 && moved_kept > 0 && stale == 0);
  free(held);
  hoc_opt_scratch_free(scr, nthreads);
  hoc_opt_free(&o);
}

int main(void) {
  const int nu = 10, nv = 5, order = 6;
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *m = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_TORUS, 2.0, 0.5, &model));
  if (model) CHECK_OK(hoc_mesh_grid_linear(model, nu, nv, &lin));
  if (lin) CHECK_OK(hoc_mesh_elevate(lin, order, HOC_NODES_EQUISPACED, &m));
  if (!m) goto out;
  const hoc_cad_face *f = &model->faces[0];
  shake(m, 0.15, (f->hi[0] - f->lo[0]) / (nu * order), (f->hi[1] - f->lo[1]) / (nv * order), 7);
  hoc_quality_stats st0;
  CHECK_OK(hoc_mesh_measure(m, HOC_MEASURE_SHAPE, NULL, NULL, &st0));
  printf("start: %zu tangled, min q %.4f\n", st0.tangled, st0.min);
  size_t small;
  {
    hoc_opt o;
    CHECK_OK(hoc_opt_setup(&o, m, HOC_MEASURE_SHAPE, 0, NULL, 0));
    small = 12 * 9 * (size_t)o.fc.npts * sizeof(double);
    hoc_opt_free(&o);
  }
  hoc_mesh *work = NULL;
  CHECK_OK(hoc_mesh_copy(m, &work));
  if (work) check_lent_places(work, small);
  hoc_mesh_destroy(&work);

  outcome all, lent, lent1;
  optimise(m, (size_t)1 << 30, 2, &all);
  optimise(m, small, 2, &lent);
  optimise(m, small, 1, &lent1);
  printf("whole runs from min q %.4f: pool of every element min q %.4f, mean %.4f, %d sweeps; "
         "pool of 12 min q %.4f, mean %.4f, %d sweeps\n",
         st0.min, all.st.min, all.st.mean, all.r.iterations, lent.st.min, lent.st.mean,
         lent.r.iterations);
  CHECK(all.st.tangled == 0 && lent.st.tangled == 0);
  CHECK(lent.st.min > st0.min && fabs(lent.st.min - all.st.min) < 0.1 * all.st.min);
  CHECK(fabs(lent.st.mean - all.st.mean) < 0.01);
  if (lent.mesh && lent1.mesh) {
    CHECK(lent.r.iterations == lent1.r.iterations);
    CHECK(memcmp(lent.mesh->param, lent1.mesh->param, 2 * m->n_nodes * sizeof(double)) == 0);
  }
  hoc_mesh_destroy(&all.mesh);
  hoc_mesh_destroy(&lent.mesh);
  hoc_mesh_destroy(&lent1.mesh);
out:
  hoc_mesh_destroy(&m);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
  printf("%d passed, %d failed\n", test_passed_, test_failed_);
  return test_failed_ != 0;
}
