/* hoc_mesh_check_gradient: the analytic gradient of each block's local
 * objective against fourth-order central differences through the CAD.
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

/* Local objective of block b with unknown `dof` moved by h (the nodes it
 * carries follow), positions and normals evaluated on the CAD. */
static hoc_status block_f_at(hoc_opt *o, size_t b, int dof, double h, hoc_opt_scratch *s,
                             double *f) {
  double *st = hoc_opt_step_of(o, b);
  int nd = (int)(o->B->bd_start[b + 1] - o->B->bd_start[b]);
  for (int c = 0; c < nd; ++c) st[c] = c == dof ? h : 0;
  o->trial.alpha[hoc_opt_tb(o, b)] = 1;
  size_t n = 0;
  size_t nlist = hoc_opt_bn_end(o->B, b) - hoc_opt_bn_begin(o->B, b) + hoc_opt_carry_end(o->B, b) -
                 hoc_opt_carry_begin(o->B, b);
  size_t *list = hoc_calloc(nlist + 1, sizeof *list);
  HOC_CHECK(list, HOC_ERR_MEMORY, "out of memory");
  for (size_t c = hoc_opt_bn_begin(o->B, b); c < hoc_opt_bn_end(o->B, b); ++c)
    list[n++] = o->B->bn_node[c];
  for (size_t j = hoc_opt_carry_begin(o->B, b); j < hoc_opt_carry_end(o->B, b); ++j)
    list[n++] = o->B->carry_node[j];
  hoc_status st2 = hoc_opt_trial_reserve(o, list, n);
  if (st2 == HOC_OK) {
    hoc_opt_set_trial_params(o, b);
    st2 = hoc_opt_eval_trials(o, list, n, 1);
  }
  free(list);
  HOC_TRY(st2);
  hoc_opt_set_moving(o, b, 1);
  *f = 0;
  for (size_t a = hoc_opt_be_begin(o->B, b); a < hoc_opt_be_end(o->B, b); ++a) {
    size_t e = o->B->be_elem[a];
    hoc_opt_gather(o, e, s->x, s->n);
    int nr = hoc_opt_elem_residuals(o, e, s->x, s->n, NULL, NULL, s->r, NULL, NULL);
    for (int q = 0; q < nr; ++q) *f += s->r[q] * s->r[q];
  }
  hoc_opt_set_moving(o, b, 0);
  return HOC_OK;
}

hoc_status hoc_mesh_check_gradient(hoc_mesh *mesh, hoc_measure measure, int fix_curves,
                                   int samples, double *max_rel_error) {
  HOC_CHECK(mesh && max_rel_error, HOC_ERR_ARGUMENT, "NULL argument");
  HOC_CHECK(samples > 0, HOC_ERR_ARGUMENT, "need at least one sample");
  hoc_opt ctx = {0};
  hoc_opt_scratch *scr = NULL;
  hoc_status status = hoc_opt_setup(&ctx, mesh, measure, fix_curves, NULL, 0);
  if (status == HOC_OK) status = hoc_opt_eval_all(&ctx);
  if (status == HOC_OK) status = hoc_opt_scratch_alloc(&ctx, 1, &scr);
  if (status != HOC_OK) {
    hoc_opt_scratch_free(scr, 1);
    hoc_opt_free(&ctx);
    return status;
  }
  double f, qmin;
  size_t tangled;
  HOC_TRY_GOTO(hoc_opt_sweep_start(&ctx, &f, &qmin, &tangled), done);
  size_t stride = ctx.B->n_blocks > (size_t)samples ? ctx.B->n_blocks / (size_t)samples : 1;
  double worst = 0, gmax = 0;
  for (size_t b = 0; b < ctx.B->n_blocks; b += stride) {
    double fl;
    hoc_opt_block_model(&ctx, b, scr, &fl, scr->g, scr->H);
    int nd = (int)(ctx.B->bd_start[b + 1] - ctx.B->bd_start[b]);
    for (int d = 0; d < nd; ++d) {
      /* the node owning this unknown sets the scale of the step */
      size_t k = ctx.B->bn_node[hoc_opt_bn_begin(ctx.B, b)];
      for (size_t c = hoc_opt_bn_begin(ctx.B, b); c < hoc_opt_bn_end(ctx.B, b); ++c)
        if (hoc_opt_node_off(ctx.B, ctx.B->bn_node[c]) <= d) k = ctx.B->bn_node[c];
      int dd = d - hoc_opt_node_off(ctx.B, k);
      const double *dz = ctx.node.dz + 6 * k + 3 * dd;
      double speed = sqrt(dz[0] * dz[0] + dz[1] * dz[1] + dz[2] * dz[2]);
      if (!(speed > 0)) continue;
      double h = HOC_OPT_FD_STEP * hoc_opt_hsize(&ctx, k) / speed, gd = scr->g[d];
      /* fourth-order central difference */
      double fp, fm, fp2, fm2;
      HOC_TRY_GOTO(block_f_at(&ctx, b, d, h, scr, &fp), done);
      HOC_TRY_GOTO(block_f_at(&ctx, b, d, -h, scr, &fm), done);
      HOC_TRY_GOTO(block_f_at(&ctx, b, d, 2 * h, scr, &fp2), done);
      HOC_TRY_GOTO(block_f_at(&ctx, b, d, -2 * h, scr, &fm2), done);
      double fd = (8 * (fp - fm) - (fp2 - fm2)) / (12 * h);
      if (!isfinite(fd)) continue;
      /* per unit length, to compare unknowns of different nodes */
      worst = fmax(worst, fabs(fd - gd) / speed);
      gmax = fmax(gmax, fabs(gd) / speed);
    }
  }
  /* a norm-wise relative error, as PETSc's -snes_test_jacobian reports */
  *max_rel_error = gmax > 0 ? worst / gmax : worst;
done:
  hoc_opt_scratch_free(scr, 1);
  hoc_opt_free(&ctx);
  return status;
}
