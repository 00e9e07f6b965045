/* Linear surface mesh of the CAD model through gmsh, with every node's
 * classification and parameters.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "cad/gmsh_util.h"
#include "core/hash.h"
#include "mesh/mesh.h"

#include <gmshc.h>
#include <omp.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

void hoc_linear_options_default(hoc_linear_options *o) {
  if (!o) return;
  memset(o, 0, sizeof *o);
  o->order = 1;
}

void hoc_linear_sizes(const hoc_model *model, const hoc_linear_options *o, double *size_max,
                      double *size_min) {
  *size_max = o->size_max > 0 ? o->size_max : model->diagonal / 20;
  *size_min = o->size_min > 0 ? o->size_min : *size_max / 10;
}

/* Default elements per 2 pi of curvature radius: enough that the linear
 * mesh follows curved faces and the curved elements of order p stay valid. */
static double default_curvature(int order) {
  /* a linear mesh must follow curved faces with its own chords; curved
   * elements of order >= 2 follow them exactly and need fewer */
  return order <= 1 ? 12 : 8;
}

typedef struct growable {
  size_t n, cap;
  double *xyz, *par;
  signed char *dim;
  int *ent;
  size_t *tag;
} growable;

static hoc_status reserve(growable *g, size_t more) {
  if (g->n + more <= g->cap) return HOC_OK;
  size_t cap = g->cap ? g->cap : 1024;
  while (cap < g->n + more) cap *= 2;
  double *x = hoc_realloc(g->xyz, 3 * cap, sizeof *x);
  if (x) g->xyz = x;
  double *p = hoc_realloc(g->par, 2 * cap, sizeof *p);
  if (p) g->par = p;
  signed char *d = hoc_realloc(g->dim, cap, sizeof *d);
  if (d) g->dim = d;
  int *e = hoc_realloc(g->ent, cap, sizeof *e);
  if (e) g->ent = e;
  size_t *t = hoc_realloc(g->tag, cap, sizeof *t);
  if (t) g->tag = t;
  HOC_CHECK(x && p && d && e && t, HOC_ERR_MEMORY, "out of memory for %zu nodes", cap);
  g->cap = cap;
  return HOC_OK;
}

static void growable_free(growable *g) {
  free(g->xyz);
  free(g->par);
  free(g->dim);
  free(g->ent);
  free(g->tag);
}

/* Append the nodes classified on one entity (not its boundary). */
static hoc_status add_entity_nodes(growable *g, hoc_hash *index, int dim, int tag, int entity) {
  size_t *tags = NULL, nt = 0, nc = 0, npar = 0;
  double *coord = NULL, *par = NULL;
  int ierr = 0;
  gmshModelMeshGetNodes(&tags, &nt, &coord, &nc, &par, &npar, dim, tag, 0, dim > 0, &ierr);
  hoc_status status = HOC_OK;
  if (ierr || nc != 3 * nt || (dim > 0 && npar != (size_t)dim * nt)) {
    status = hoc_gmsh_error("reading mesh nodes");
    goto done;
  }
  HOC_TRY_GOTO(reserve(g, nt), done);
  for (size_t k = 0; k < nt; ++k) {
    size_t i = g->n;
    int found;
    HOC_TRY_GOTO(hoc_hash_insert(index, (uint64_t)tags[k], i, &found, NULL), done);
    if (found) continue; /* a node listed twice: keep its first classification */
    memcpy(g->xyz + 3 * i, coord + 3 * k, 3 * sizeof(double));
    g->par[2 * i] = dim > 0 ? par[(size_t)dim * k] : 0.0;
    g->par[2 * i + 1] = dim > 1 ? par[(size_t)dim * k + 1] : 0.0;
    g->dim[i] = (signed char)dim;
    g->ent[i] = entity;
    g->tag[i] = tags[k];
    g->n++;
  }
done:
  gmshFree(tags);
  gmshFree(coord);
  gmshFree(par);
  return status;
}

/* Append the elements of one type on one entity as node indices. */
static hoc_status add_entity_elements(int type, int nodes_per, int tag, const hoc_hash *index,
                                      size_t **conn, size_t *n, size_t *cap, int **owner,
                                      int owner_value) {
  size_t *etags = NULL, net = 0, *ntags = NULL, nnt = 0;
  int ierr = 0;
  gmshModelMeshGetElementsByType(type, &etags, &net, &ntags, &nnt, tag, 0, 1, &ierr);
  hoc_status status = HOC_OK;
  if (ierr || nnt != net * (size_t)nodes_per) {
    status = hoc_gmsh_error("reading mesh elements");
    goto done;
  }
  if (*n + net > *cap) {
    size_t c = *cap ? *cap : 1024;
    while (c < *n + net) c *= 2;
    size_t *c2 = hoc_realloc(*conn, c * (size_t)nodes_per, sizeof *c2);
    if (c2) *conn = c2;
    int *o2 = hoc_realloc(*owner, c, sizeof *o2);
    if (o2) *owner = o2;
    if (!c2 || !o2) {
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory for %zu elements", c);
      goto done;
    }
    *cap = c;
  }
  for (size_t e = 0; e < net; ++e) {
    for (int k = 0; k < nodes_per; ++k) {
      size_t i = hoc_hash_get(index, (uint64_t)ntags[e * (size_t)nodes_per + k]);
      if (i == SIZE_MAX) {
        status = HOC_ERROR(HOC_ERR_MESH, "gmsh element uses an unclassified node %zu",
                           ntags[e * (size_t)nodes_per + k]);
        goto done;
      }
      (*conn)[(*n + e) * (size_t)nodes_per + k] = i;
    }
    (*owner)[*n + e] = owner_value;
  }
  *n += net;
done:
  gmshFree(etags);
  gmshFree(ntags);
  return status;
}

/* One linear mesh with gmsh's current size settings (model and mesh
 * checked by the caller). */
static hoc_status generate_once(hoc_model *model, const hoc_linear_options *options,
                                hoc_mesh **mesh) {
  hoc_linear_options o;
  hoc_linear_options_default(&o);
  if (options) o = *options;
  HOC_CHECK(isfinite(o.size_max) && o.size_max >= 0, HOC_ERR_ARGUMENT,
            "mesh size must be a positive number");
  HOC_CHECK(isfinite(o.size_min) && o.size_min >= 0, HOC_ERR_ARGUMENT,
            "minimum mesh size must be a positive number");
  HOC_CHECK(isfinite(o.curvature) && o.curvature >= 0 && o.curvature <= 1000, HOC_ERR_ARGUMENT,
            "curvature elements per 2 pi must be in 0..1000");
  HOC_CHECK(o.order >= 1 && o.order <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT,
            "order %d out of range 1..%d", o.order, HOC_MAX_ORDER);
  double hmax, hmin;
  hoc_linear_sizes(model, &o, &hmax, &hmin);
  HOC_CHECK(hmin <= hmax, HOC_ERR_ARGUMENT, "minimum size %g exceeds maximum size %g", hmin, hmax);
  HOC_CHECK(hmax >= 1e-6 * model->diagonal, HOC_ERR_ARGUMENT,
            "mesh size %g is too small for a model of size %g (at most 10^6 edges across)", hmax,
            model->diagonal);
  double curv = o.curvature > 0 ? o.curvature : default_curvature(o.order);

  int ierr = 0;
  gmshModelMeshClear(NULL, 0, &ierr);
  gmshOptionSetNumber("Mesh.MeshSizeMax", hmax, &ierr);
  gmshOptionSetNumber("Mesh.MeshSizeMin", hmin, &ierr);
  gmshOptionSetNumber("Mesh.MeshSizeFromCurvature", curv, &ierr);
  gmshOptionSetNumber("Mesh.ElementOrder", 1, &ierr);
  if (o.progress && o.progress(o.progress_user, "linear mesh", 0.0))
    return HOC_ERROR(HOC_ERR_INTERRUPTED, "interrupted");
  hoc_quiet q;
  hoc_quiet_begin(&q);
  /* gmsh meshes faces in parallel when OpenMP allows, and then not always
   * the same mesh: one thread, so a model always gets the same mesh */
  int threads = omp_get_max_threads();
  omp_set_num_threads(1);
  gmshModelMeshGenerate(2, &ierr);
  omp_set_num_threads(threads);
  char kernel_msg[256];
  hoc_quiet_end(&q, kernel_msg, sizeof kernel_msg);
  if (ierr) {
    int ierr2 = 0;
    gmshModelMeshClear(NULL, 0, &ierr2);
    return HOC_ERROR(HOC_ERR_MESH, "gmsh could not mesh the surfaces%s%s",
                     kernel_msg[0] ? ": " : "", kernel_msg);
  }
  if (o.progress && o.progress(o.progress_user, "linear mesh", 0.9))
    return HOC_ERROR(HOC_ERR_INTERRUPTED, "interrupted");

  growable g = {0};
  hoc_hash index = {0};
  size_t *tri = NULL, n_tri = 0, cap_tri = 0, *lines = NULL, n_lines = 0, cap_lines = 0;
  int *tri_face = NULL, *line_curve = NULL, *failed = NULL, n_failed = 0;
  hoc_status status = HOC_OK;
  HOC_TRY_GOTO(hoc_hash_init(&index, 4096), done);
  for (int v = 0; v < model->n_vertices; ++v)
    HOC_TRY_GOTO(add_entity_nodes(&g, &index, 0, model->vertices[v].tag, v), done);
  for (int c = 0; c < model->n_curves; ++c)
    HOC_TRY_GOTO(add_entity_nodes(&g, &index, 1, model->curves[c].tag, c), done);
  for (int f = 0; f < model->n_faces; ++f)
    HOC_TRY_GOTO(add_entity_nodes(&g, &index, 2, model->faces[f].tag, f), done);
  failed = hoc_calloc((size_t)model->n_faces, sizeof *failed);
  if (!failed) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (int f = 0; f < model->n_faces; ++f) {
    size_t before = n_tri;
    HOC_TRY_GOTO(add_entity_elements(2, 3, model->faces[f].tag, &index, &tri, &n_tri, &cap_tri,
                                     &tri_face, f),
                 done);
    if (n_tri == before) failed[n_failed++] = f;
  }
  for (int c = 0; c < model->n_curves; ++c)
    HOC_TRY_GOTO(add_entity_elements(1, 2, model->curves[c].tag, &index, &lines, &n_lines,
                                     &cap_lines, &line_curve, c),
                 done);
  if (!n_tri) {
    status = HOC_ERROR(HOC_ERR_MESH, "gmsh produced no triangle on any of the %d faces%s%s",
                       model->n_faces, kernel_msg[0] ? ": " : "", kernel_msg);
    goto done;
  }
  hoc_mesh_source src = {0};
  src.order = 1;
  src.nodeset = HOC_NODES_EQUISPACED;
  src.n_nodes = g.n;
  src.xyz = g.xyz;
  src.param = g.par;
  src.dim = g.dim;
  src.entity = g.ent;
  src.n_elems = n_tri;
  src.conn = tri;
  src.elem_face = tri_face;
  src.n_lines = n_lines;
  src.line_conn = lines;
  src.line_curve = line_curve;
  src.node_tag = g.tag;
  HOC_TRY_GOTO(hoc_mesh_assemble(model, &src, 1e-6, mesh), done);
  (*mesh)->n_failed_faces = n_failed;
  (*mesh)->failed_faces = failed;
  failed = NULL;
done:
  growable_free(&g);
  hoc_hash_free(&index);
  free(tri);
  free(tri_face);
  free(lines);
  free(line_curve);
  free(failed);
  return status;
}

/* Mesh sizes of the refined entities for gmsh's size callback (gmsh 4.8
 * takes the smaller of the callback's size and its own). */
typedef struct sizing {
  int max_face_tag, max_curve_tag;
  double *face_size, *curve_size; /* [max tag + 1]; 0: no bound */
} sizing;

static double size_at(int dim, int tag, double x, double y, double z, void *data) {
  (void)x, (void)y, (void)z;
  const sizing *s = data;
  double h = 0;
  if (dim == 2 && tag >= 0 && tag <= s->max_face_tag) h = s->face_size[tag];
  if (dim == 1 && tag >= 0 && tag <= s->max_curve_tag) h = s->curve_size[tag];
  return h > 0 ? h : 1e22;
}

hoc_status hoc_mesh_generate_linear_gmsh(hoc_model *model, const hoc_linear_options *options,
                                         hoc_mesh **mesh) {
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "mesh output is NULL");
  *mesh = NULL;
  HOC_CHECK(model && model->is_gmsh, HOC_ERR_ARGUMENT,
            "linear meshing needs a model opened from a CAD file");
  if (!options || !options->face_size) return generate_once(model, options, mesh);
  /* faces meshed finer: the bound on the face and on its boundary curves */
  sizing s = {0};
  for (int f = 0; f < model->n_faces; ++f) {
    double h = options->face_size[f];
    HOC_CHECK(isfinite(h) && h >= 0, HOC_ERR_ARGUMENT,
              "size bound of face %d must be a finite number >= 0", model->faces[f].tag);
    if (model->faces[f].tag > s.max_face_tag) s.max_face_tag = model->faces[f].tag;
  }
  for (int c = 0; c < model->n_curves; ++c)
    if (model->curves[c].tag > s.max_curve_tag) s.max_curve_tag = model->curves[c].tag;
  s.face_size = hoc_calloc((size_t)s.max_face_tag + 1, sizeof *s.face_size);
  s.curve_size = hoc_calloc((size_t)s.max_curve_tag + 1, sizeof *s.curve_size);
  hoc_status status = HOC_OK;
  if (!s.face_size || !s.curve_size) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (int f = 0; f < model->n_faces; ++f) {
    double h = options->face_size[f];
    if (!(h > 0)) continue;
    s.face_size[model->faces[f].tag] = h;
    for (int k = 0; k < model->faces[f].n_curves; ++k) {
      int t = abs(model->faces[f].curves[k]);
      if (t <= s.max_curve_tag && (!(s.curve_size[t] > 0) || h < s.curve_size[t]))
        s.curve_size[t] = h;
    }
  }
  int ierr = 0;
  gmshModelMeshSetSizeCallback(size_at, &s, &ierr);
  status = ierr ? HOC_ERROR(HOC_ERR_MESH, "gmsh refused the mesh size callback")
                : generate_once(model, options, mesh);
  gmshModelMeshRemoveSizeCallback(&ierr);
done:
  free(s.face_size);
  free(s.curve_size);
  return status;
}

hoc_status hoc_mesh_generate_linear(hoc_model *model, const hoc_linear_options *options,
                                    hoc_mesh **mesh) {
  return hoc_mesh_generate_linear_gmsh(model, options, mesh);
}
