/* hoc_mesh to and from files: MSH 4.1 and 2.2 (nodes classified on the CAD
 * entities, parametric coordinates on request) and VTU.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "core/hash.h"
#include "io/io.h"
#include "mesh/mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The mesh with equispaced nodes (what MSH and VTU mean by a Lagrange
 * element), converted if needed; *owned is set when a new mesh was made. */
static hoc_status equispaced_view(const hoc_mesh *mesh, const hoc_mesh **view, hoc_mesh **owned) {
  *owned = NULL;
  *view = mesh;
  if (mesh->nodeset == HOC_NODES_EQUISPACED || mesh->order <= 2) return HOC_OK;
  HOC_TRY(hoc_mesh_convert_nodeset(mesh, HOC_NODES_EQUISPACED, owned));
  *view = *owned;
  return HOC_OK;
}

hoc_status hoc_mesh_write_msh(const hoc_mesh *mesh, const char *path) {
  return hoc_mesh_write_msh_with(mesh, path, NULL);
}

hoc_status hoc_mesh_write_msh_with(const hoc_mesh *mesh, const char *path,
                                   const hoc_msh_options *options) {
  HOC_CHECK(mesh && path && path[0], HOC_ERR_ARGUMENT, "no mesh or no file name");
  HOC_CHECK(mesh->order <= 10, HOC_ERR_UNSUPPORTED,
            "gmsh's MSH format has no triangle of order %d (at most 10): write a .vtu instead",
            mesh->order);
  const hoc_mesh *m;
  hoc_mesh *owned;
  HOC_TRY(equispaced_view(mesh, &m, &owned));
  const hoc_model *model = m->model;
  hoc_status status = HOC_OK;
  int *ptag = NULL, *ctag = NULL, *cstart = NULL, *cbnd = NULL, *ftag = NULL, *fstart = NULL,
      *fbnd = NULL, *ndim = NULL, *ntag = NULL, *tface = NULL, *lcurve = NULL;
  double *pxyz = NULL, *cbox = NULL, *fbox = NULL;
  int nv = model->n_vertices, nc = model->n_curves, nf = model->n_faces;
  HOC_ALLOC_GOTO(ptag, (size_t)nv + 1, done);
  HOC_ALLOC_GOTO(pxyz, 3 * (size_t)nv + 1, done);
  HOC_ALLOC_GOTO(ctag, (size_t)nc + 1, done);
  HOC_ALLOC_GOTO(cbox, 6 * (size_t)nc + 1, done);
  HOC_ALLOC_GOTO(cstart, (size_t)nc + 1, done);
  HOC_ALLOC_GOTO(cbnd, 2 * (size_t)nc + 1, done);
  HOC_ALLOC_GOTO(ftag, (size_t)nf + 1, done);
  HOC_ALLOC_GOTO(fbox, 6 * (size_t)nf + 1, done);
  HOC_ALLOC_GOTO(fstart, (size_t)nf + 1, done);
  for (int v = 0; v < nv; ++v) {
    ptag[v] = model->vertices[v].tag;
    memcpy(pxyz + 3 * v, model->vertices[v].xyz, 3 * sizeof *pxyz);
  }
  int nb = 0;
  for (int c = 0; c < nc; ++c) {
    const hoc_cad_curve *cv = &model->curves[c];
    ctag[c] = cv->tag;
    memcpy(cbox + 6 * c, cv->bbox, 6 * sizeof *cbox);
    cstart[c] = nb;
    if (cv->v0 >= 0) cbnd[nb++] = model->vertices[cv->v0].tag;
    if (cv->v1 >= 0 && cv->v1 != cv->v0) cbnd[nb++] = -model->vertices[cv->v1].tag;
  }
  cstart[nc] = nb;
  int nfb = 0;
  for (int f = 0; f < nf; ++f) nfb += model->faces[f].n_curves;
  HOC_ALLOC_GOTO(fbnd, (size_t)nfb + 1, done);
  nfb = 0;
  for (int f = 0; f < nf; ++f) {
    const hoc_cad_face *fc = &model->faces[f];
    ftag[f] = fc->tag;
    memcpy(fbox + 6 * f, fc->bbox, 6 * sizeof *fbox);
    fstart[f] = nfb;
    for (int k = 0; k < fc->n_curves; ++k) fbnd[nfb++] = fc->curves[k];
  }
  fstart[nf] = nfb;
  HOC_ALLOC_GOTO(ndim, m->n_nodes + 1, done);
  HOC_ALLOC_GOTO(ntag, m->n_nodes + 1, done);
  for (size_t i = 0; i < m->n_nodes; ++i) {
    ndim[i] = m->dim[i];
    ntag[i] = m->dim[i] == HOC_ON_FACE    ? model->faces[m->entity[i]].tag
              : m->dim[i] == HOC_ON_CURVE ? model->curves[m->entity[i]].tag
                                          : model->vertices[m->entity[i]].tag;
  }
  HOC_ALLOC_GOTO(tface, m->n_elems + 1, done);
  for (size_t e = 0; e < m->n_elems; ++e) tface[e] = model->faces[m->elem_face[e]].tag;
  HOC_ALLOC_GOTO(lcurve, m->n_lines + 1, done);
  for (size_t l = 0; l < m->n_lines; ++l) lcurve[l] = model->curves[m->line_curve[l]].tag;
  hoc_msh_write_data d = {0};
  d.n_points = nv;
  d.point_tag = ptag;
  d.point_xyz = pxyz;
  d.n_curves = nc;
  d.curve_tag = ctag;
  d.curve_bbox = cbox;
  d.curve_bnd_start = cstart;
  d.curve_bnd = cbnd;
  d.n_surfaces = nf;
  d.surface_tag = ftag;
  d.surface_bbox = fbox;
  d.surface_bnd_start = fstart;
  d.surface_bnd = fbnd;
  d.n_nodes = m->n_nodes;
  d.xyz = m->xyz;
  d.param = m->param;
  d.node_dim = ndim;
  d.node_entity_tag = ntag;
  d.order = m->order;
  d.n_tris = m->n_elems;
  d.tri_nodes = m->conn;
  d.tri_surface_tag = tface;
  d.n_lines = m->n_lines;
  d.line_nodes = m->line_conn;
  d.line_curve_tag = lcurve;
  status = hoc_msh_write(path, &d, options);
done:
  free(ptag);
  free(pxyz);
  free(ctag);
  free(cbox);
  free(cstart);
  free(cbnd);
  free(ftag);
  free(fbox);
  free(fstart);
  free(fbnd);
  free(ndim);
  free(ntag);
  free(tface);
  free(lcurve);
  hoc_mesh_destroy(&owned);
  return status;
}

hoc_status hoc_mesh_write_vtu(const hoc_mesh *mesh, const double *quality, const char *path) {
  HOC_CHECK(mesh && path && path[0], HOC_ERR_ARGUMENT, "no mesh or no file name");
  const hoc_mesh *m;
  hoc_mesh *owned;
  HOC_TRY(equispaced_view(mesh, &m, &owned));
  hoc_status status = HOC_OK;
  double *q = NULL;
  unsigned char *tg = NULL;
  int *ftag = NULL;
  HOC_ALLOC_GOTO(tg, m->n_elems, done);
  HOC_ALLOC_GOTO(ftag, m->n_elems, done);
  if (!quality) {
    HOC_ALLOC_GOTO(q, m->n_elems, done);
    HOC_TRY_GOTO(hoc_mesh_measure(mesh, HOC_MEASURE_SHAPE, q, NULL, NULL), done);
    quality = q;
  }
  for (size_t e = 0; e < m->n_elems; ++e) {
    tg[e] = quality[e] == 0.0;
    ftag[e] = m->model->faces[m->elem_face[e]].tag;
  }
  hoc_vtu_data d = {0};
  d.order = m->order;
  d.n_points = m->n_nodes;
  d.xyz = m->xyz;
  d.n_cells = m->n_elems;
  d.cells = m->conn;
  d.quality = quality;
  d.tangled = tg;
  d.face_tag = ftag;
  status = hoc_vtu_write(path, &d);
done:
  free(q);
  free(tg);
  free(ftag);
  hoc_mesh_destroy(&owned);
  return status;
}

/* A node on face A that triangles of face B also use (gmsh 4.8 and 5.0 do this
 * where two faces' triangulations share an edge that is on no CAD curve,
 * e.g. two faces bounded by the same two curves: its high-order edge node
 * is made once, on the first face) gets a copy on face B, without
 * parameters, so that it is located on B like any node the file gives no
 * parameters. Grows the raw arrays and dim/ent. */
static hoc_status own_face_nodes(const hoc_model *model, hoc_msh_raw *raw, const int *tface,
                                 signed char **dim, int **ent) {
  size_t np = (size_t)(raw->order + 1) * (size_t)(raw->order + 2) / 2, n = raw->n_nodes, extra = 0;
  for (size_t e = 0; e < raw->n_tris; ++e)
    for (size_t k = 0; k < np; ++k) {
      size_t i = raw->tri_nodes[e * np + k];
      extra += (*dim)[i] == HOC_ON_FACE && (*ent)[i] != tface[e];
    }
  if (!extra) return HOC_OK;
  hoc_hash h = {0};
  HOC_TRY(hoc_hash_init(&h, extra));
  hoc_status status = HOC_OK;
  uint64_t nf = (uint64_t)model->n_faces;
  size_t m = n;
  for (size_t e = 0; e < raw->n_tris; ++e)
    for (size_t k = 0; k < np; ++k) {
      size_t *i = &raw->tri_nodes[e * np + k], s;
      if ((*dim)[*i] != HOC_ON_FACE || (*ent)[*i] == tface[e]) continue;
      HOC_TRY_GOTO(hoc_hash_insert(&h, (uint64_t)*i * nf + (uint64_t)tface[e], m, NULL, &s), done);
      m += s == m;
    }
  size_t *tag = hoc_realloc(raw->node_tag, m, sizeof *tag);
  if (tag) raw->node_tag = tag;
  double *xyz = hoc_realloc(raw->xyz, 3 * m, sizeof *xyz);
  if (xyz) raw->xyz = xyz;
  double *par = hoc_realloc(raw->param, 2 * m, sizeof *par);
  if (par) raw->param = par;
  unsigned char *has = hoc_realloc(raw->has_param, m, 1);
  if (has) raw->has_param = has;
  signed char *d2 = hoc_realloc(*dim, m, 1);
  if (d2) *dim = d2;
  int *e2 = hoc_realloc(*ent, m, sizeof *e2);
  if (e2) *ent = e2;
  if (!tag || !xyz || !par || !has || !d2 || !e2) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  /* raw's per-node arrays other than these are not used past this point */
  for (size_t e = 0; e < raw->n_tris; ++e)
    for (size_t k = 0; k < np; ++k) {
      size_t *i = &raw->tri_nodes[e * np + k];
      if ((*dim)[*i] != HOC_ON_FACE || (*ent)[*i] == tface[e]) continue;
      size_t c = hoc_hash_get(&h, (uint64_t)*i * nf + (uint64_t)tface[e]);
      raw->node_tag[c] = raw->node_tag[*i];
      memcpy(raw->xyz + 3 * c, raw->xyz + 3 * *i, 3 * sizeof *raw->xyz);
      raw->param[2 * c] = raw->param[2 * c + 1] = 0;
      raw->has_param[c] = 0;
      (*dim)[c] = HOC_ON_FACE;
      (*ent)[c] = tface[e];
      *i = c;
    }
  raw->n_nodes = m;
done:
  hoc_hash_free(&h);
  return status;
}

hoc_status hoc_mesh_read_msh(hoc_model *model, const char *path, hoc_mesh **mesh) {
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "mesh output is NULL");
  *mesh = NULL;
  HOC_CHECK(model && path && path[0], HOC_ERR_ARGUMENT, "no model or no file name");
  hoc_msh_raw raw = {0};
  HOC_TRY(hoc_msh_read(path, &raw));
  hoc_status status = HOC_OK;
  signed char *dim = NULL;
  int *ent = NULL, *tface = NULL, *lcurve = NULL;
  size_t *lconn = NULL;
  if (raw.n_tris == 0) {
    status = HOC_ERROR(HOC_ERR_MISMATCH, "'%s' holds no surface triangles", path);
    goto done;
  }
  HOC_ALLOC_GOTO(dim, raw.n_nodes, done);
  HOC_ALLOC_GOTO(ent, raw.n_nodes, done);
  for (size_t i = 0; i < raw.n_nodes; ++i) {
    int d = raw.node_dim[i], tag = raw.node_entity_tag[i];
    int e = d == 0 ? hoc_cad_vertex_index(model, tag)
            : d == 1 ? hoc_cad_curve_index(model, tag)
            : d == 2 ? hoc_cad_face_index(model, tag)
                     : -1;
    if (e < 0) {
      status = HOC_ERROR(HOC_ERR_MISMATCH,
                         "node %zu of '%s' lies on entity (dim %d, tag %d), which the model does "
                         "not have: the mesh was not made on this model",
                         raw.node_tag[i], path, d, tag);
      goto done;
    }
    dim[i] = (signed char)d;
    ent[i] = e;
  }
  HOC_ALLOC_GOTO(tface, raw.n_tris, done);
  for (size_t e = 0; e < raw.n_tris; ++e) {
    tface[e] = hoc_cad_face_index(model, raw.tri_surface_tag[e]);
    if (tface[e] < 0) {
      status = HOC_ERROR(HOC_ERR_MISMATCH,
                         "triangles of '%s' lie on surface %d, which the model does not have", path,
                         raw.tri_surface_tag[e]);
      goto done;
    }
  }
  HOC_TRY_GOTO(own_face_nodes(model, &raw, tface, &dim, &ent), done);
  size_t nl = 0;
  HOC_ALLOC_GOTO(lconn, raw.n_lines * (size_t)(raw.order + 1) + 1, done);
  HOC_ALLOC_GOTO(lcurve, raw.n_lines + 1, done);
  for (size_t l = 0; l < raw.n_lines; ++l) {
    int c = hoc_cad_curve_index(model, raw.line_curve_tag[l]);
    if (c < 0) continue; /* lines on curves the model lacks are not ours to check */
    memcpy(lconn + nl * (size_t)(raw.order + 1), raw.line_nodes + l * (size_t)(raw.order + 1),
           (size_t)(raw.order + 1) * sizeof *lconn);
    lcurve[nl++] = c;
  }
  hoc_mesh_source src = {0};
  src.order = raw.order;
  src.nodeset = HOC_NODES_EQUISPACED;
  src.n_nodes = raw.n_nodes;
  src.xyz = raw.xyz;
  src.param = raw.param;
  src.has_param = raw.has_param;
  src.dim = dim;
  src.entity = ent;
  src.n_elems = raw.n_tris;
  src.conn = raw.tri_nodes;
  src.elem_face = tface;
  src.n_lines = nl;
  src.line_conn = lconn;
  src.line_curve = lcurve;
  src.node_tag = raw.node_tag;
  /* measured as written, and within hoc_mesh_assemble's bounds for a
   * given mesh (hoc_mesh_given_limit; 1% of the model's size for a
   * high-order node inside a face, which gmsh leaves off the surface where
   * its own projection fails) */
  src.keep_xyz = 1;
  src.given = 1;
  status = hoc_mesh_assemble(model, &src, mesh);
done:
  free(dim);
  free(ent);
  free(tface);
  free(lconn);
  free(lcurve);
  hoc_msh_raw_free(&raw);
  return status;
}
