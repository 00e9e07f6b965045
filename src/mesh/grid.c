/* Structured linear triangulation of a single-face model's parameter
 * domain, for tests on analytic surfaces (seams and poles included).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Classify the point phi(u,v): a vertex, a curve (with t) or the face. */
static hoc_status classify(const hoc_model *model, const double uv[2], double tol, int *dim,
                           int *entity, double *t) {
  double x[3];
  HOC_TRY(hoc_cad_face_eval(model, 0, 1, uv, x, NULL, NULL));
  for (int v = 0; v < model->n_vertices; ++v) {
    const double *p = model->vertices[v].xyz;
    if (fabs(p[0] - x[0]) + fabs(p[1] - x[1]) + fabs(p[2] - x[2]) < tol) {
      *dim = HOC_ON_VERTEX;
      *entity = v;
      return HOC_OK;
    }
  }
  for (int c = 0; c < model->n_curves; ++c) {
    const hoc_cad_curve *cv = &model->curves[c];
    if (cv->degenerate) continue;
    double tc, y[3];
    HOC_TRY(model->ops->curve_project(model->ctx, cv, 1, x, &tc));
    if (tc < cv->lo - 1e-12 || tc > cv->hi + 1e-12) continue;
    HOC_TRY(hoc_cad_curve_eval(model, c, 1, &tc, y, NULL));
    if (fabs(y[0] - x[0]) + fabs(y[1] - x[1]) + fabs(y[2] - x[2]) < tol) {
      *dim = HOC_ON_CURVE;
      *entity = c;
      *t = tc;
      return HOC_OK;
    }
  }
  *dim = HOC_ON_FACE;
  *entity = 0;
  return HOC_OK;
}

hoc_status hoc_mesh_grid_linear(hoc_model *model, int nu, int nv, hoc_mesh **mesh) {
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "mesh output is NULL");
  *mesh = NULL;
  HOC_CHECK(model && model->n_faces == 1, HOC_ERR_ARGUMENT, "grid meshes need a one-face model");
  HOC_CHECK(nu >= 3 && nv >= 1 && nu <= 4096 && nv <= 4096, HOC_ERR_ARGUMENT,
            "grid size %d x %d out of range", nu, nv);
  const hoc_cad_face *f = &model->faces[0];
  int pu = f->period[0] > 0, pv = f->period[1] > 0;
  int niu = pu ? nu : nu + 1, niv = pv ? nv : nv + 1; /* distinct grid lines */
  size_t n_grid = (size_t)niu * (size_t)niv;
  double tol = 1e-9 * model->diagonal;
  size_t *id = hoc_calloc(n_grid, sizeof *id);
  double *xyz = hoc_calloc(3 * n_grid, sizeof *xyz), *par = hoc_calloc(2 * n_grid, sizeof *par);
  signed char *dim = hoc_calloc(n_grid, sizeof *dim);
  int *ent = hoc_calloc(n_grid, sizeof *ent);
  size_t *conn = hoc_calloc(2 * (size_t)nu * (size_t)nv * 3, sizeof *conn);
  int *ef = hoc_calloc(2 * (size_t)nu * (size_t)nv, sizeof *ef);
  size_t *vertex_node = hoc_calloc((size_t)model->n_vertices + 1, sizeof *vertex_node);
  hoc_status status = HOC_OK;
  if (!id || !xyz || !par || !dim || !ent || !conn || !ef || !vertex_node) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (int v = 0; v < model->n_vertices; ++v) vertex_node[v] = SIZE_MAX;
  size_t n = 0;
  for (int j = 0; j < niv; ++j)
    for (int i = 0; i < niu; ++i) {
      double uv[2] = {f->lo[0] + (f->hi[0] - f->lo[0]) * i / nu,
                      f->lo[1] + (f->hi[1] - f->lo[1]) * j / nv};
      int d, e;
      double t = 0;
      HOC_TRY_GOTO(classify(model, uv, tol, &d, &e, &t), done);
      if (d == HOC_ON_VERTEX && vertex_node[e] != SIZE_MAX) {
        id[(size_t)j * niu + i] = vertex_node[e];
        continue;
      }
      if (d == HOC_ON_VERTEX) vertex_node[e] = n;
      id[(size_t)j * niu + i] = n;
      dim[n] = (signed char)d;
      ent[n] = e;
      par[2 * n] = d == HOC_ON_FACE ? uv[0] : t;
      par[2 * n + 1] = d == HOC_ON_FACE ? uv[1] : 0;
      HOC_TRY_GOTO(hoc_cad_face_eval(model, 0, 1, uv, xyz + 3 * n, NULL, NULL), done);
      ++n;
    }
  size_t ne = 0;
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      size_t a = id[(size_t)j * niu + i], b = id[(size_t)j * niu + (i + 1) % niu],
             c = id[(size_t)((j + 1) % niv) * niu + i],
             d = id[(size_t)((j + 1) % niv) * niu + (i + 1) % niu];
      size_t tri[2][3] = {{a, b, d}, {a, d, c}};
      for (int k = 0; k < 2; ++k) {
        size_t *t3 = tri[k];
        if (t3[0] == t3[1] || t3[1] == t3[2] || t3[0] == t3[2]) continue; /* collapsed at a pole */
        memcpy(conn + 3 * ne, t3, sizeof tri[k]);
        ef[ne++] = 0;
      }
    }
  hoc_mesh_source src = {0};
  src.order = 1;
  src.nodeset = HOC_NODES_EQUISPACED;
  src.n_nodes = n;
  src.xyz = xyz;
  src.param = par;
  src.dim = dim;
  src.entity = ent;
  src.n_elems = ne;
  src.conn = conn;
  src.elem_face = ef;
  status = hoc_mesh_assemble(model, &src, mesh);
done:
  free(id);
  free(xyz);
  free(par);
  free(dim);
  free(ent);
  free(conn);
  free(ef);
  free(vertex_node);
  return status;
}
