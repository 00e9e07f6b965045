/* Collapsed sides the kernel does not mark: a face side of zero length
 * (a pole of a revolved or B-spline surface) is bounded by a curve that
 * evaluates to one point. OpenCASCADE marks most such curves degenerate,
 * and gmsh then gives the side one node; an IGES or STEP writer may leave
 * the curve unmarked, and often with a vertex at each end, so gmsh meshes
 * it like any curve: nodes along it and at both ends, all at one point,
 * and the triangles along the side have two corners there (zero area,
 * q = 0, and no curved element with two corners at one point is valid).
 * hocad detects such curves itself (hoc_cad_finish: the curve's ends and
 * middle coincide) and makes the nodes at the point one node, as gmsh does
 * for a marked side; the pole slots (poles.c) then give each element
 * around it its own parameters there.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "core/geometry.h"
#include "mesh/mesh.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Nodes farther apart than this (relative to the model's diagonal) are
 * never merged, whatever their entities say: the degenerate test samples
 * a curve at three points only. */
static const double COLLAPSE_DISTANCE = 1e-6;

double hoc_mesh_collapse_distance(const hoc_model *model) {
  return COLLAPSE_DISTANCE * model->diagonal;
}

static size_t find(size_t *up, size_t i) {
  while (up[i] != i) {
    up[i] = up[up[i]];
    i = up[i];
  }
  return i;
}

/* The point of node i (its given position, else its entity's). */
static hoc_status node_point(const hoc_model *model, const hoc_mesh_source *src, size_t i,
                             double x[3]) {
  if (src->xyz) {
    memcpy(x, src->xyz + 3 * i, 3 * sizeof *x);
    return HOC_OK;
  }
  if (src->dim[i] == HOC_ON_VERTEX) {
    memcpy(x, model->vertices[src->entity[i]].xyz, 3 * sizeof *x);
    return HOC_OK;
  }
  return hoc_cad_curve_eval(model, src->entity[i], 1, src->param + 2 * i, x, NULL);
}

/* Is node i on degenerate curve c (on it, or on a vertex at its end)? */
static int on_collapsed(const hoc_model *model, const hoc_mesh_source *src, size_t i, int c) {
  return hoc_node_on_curve(model, src->dim[i], src->entity[i], c);
}

void hoc_mesh_collapse_free(hoc_mesh_collapse *c) {
  if (!c) return;
  free(c->xyz);
  free(c->param);
  free(c->has_param);
  free(c->dim);
  free(c->entity);
  free(c->conn);
  free(c->elem_face);
  free(c->line_conn);
  free(c->line_curve);
  free(c->node_tag);
  memset(c, 0, sizeof *c);
}

hoc_status hoc_mesh_collapse_sides(const hoc_model *model, hoc_mesh_source *src,
                                   hoc_mesh_collapse *c) {
  HOC_CHECK(model && src && c, HOC_ERR_ARGUMENT, "NULL argument");
  memset(c, 0, sizeof *c);
  if (src->order != 1 || !src->n_nodes) return HOC_OK;
  int n_degenerate = 0;
  for (int k = 0; k < model->n_curves; ++k) n_degenerate += !!model->curves[k].degenerate;
  if (!n_degenerate) return HOC_OK;

  size_t n = src->n_nodes;
  size_t *up = hoc_calloc(n, sizeof *up), *first = hoc_calloc((size_t)model->n_curves, sizeof *first),
         *to = NULL;
  int *degenerate = hoc_calloc((size_t)n_degenerate, sizeof *degenerate);
  hoc_status status = HOC_OK;
  if (!up || !first || !degenerate) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (size_t i = 0; i < n; ++i) up[i] = i;
  for (int k = 0, j = 0; k < model->n_curves; ++k) {
    first[k] = SIZE_MAX;
    if (model->curves[k].degenerate) degenerate[j++] = k;
  }
  /* each degenerate curve's nodes and end vertices' nodes: one node */
  double tol = hoc_mesh_collapse_distance(model), x[3], y[3];
  size_t merged = 0;
  for (size_t i = 0; i < n; ++i) {
    if (src->dim[i] == HOC_ON_FACE) continue;
    if (src->dim[i] == HOC_ON_CURVE && !model->curves[src->entity[i]].degenerate) continue;
    for (int j = 0; j < n_degenerate; ++j) {
      int k = degenerate[j];
      if (!on_collapsed(model, src, i, k)) continue;
      if (first[k] == SIZE_MAX) {
        first[k] = i;
        continue;
      }
      HOC_TRY_GOTO(node_point(model, src, i, x), done);
      HOC_TRY_GOTO(node_point(model, src, first[k], y), done);
      if (!(hoc_dist3(x, y) <= tol)) continue;
      size_t a = find(up, i), b = find(up, first[k]);
      if (a == b) continue;
      /* the root: a vertex node if there is one, else the first node */
      int a_vertex = src->dim[a] == HOC_ON_VERTEX, b_vertex = src->dim[b] == HOC_ON_VERTEX;
      if (a_vertex != b_vertex ? a_vertex : a < b)
        up[b] = a;
      else
        up[a] = b;
      ++merged;
    }
  }
  if (!merged) goto done;

  /* new numbering: roots and untouched nodes keep their order */
  HOC_ALLOC_GOTO(to, n, done);
  size_t kept = 0;
  for (size_t i = 0; i < n; ++i)
    if (find(up, i) == i) to[i] = kept++;
  for (size_t i = 0; i < n; ++i) to[i] = to[find(up, i)];
  int ok = 1;
  if (src->xyz) ok &= !!(c->xyz = hoc_calloc(3 * kept, sizeof *c->xyz));
  if (src->param) ok &= !!(c->param = hoc_calloc(2 * kept, sizeof *c->param));
  if (src->has_param) ok &= !!(c->has_param = hoc_calloc(kept, 1));
  if (src->node_tag) ok &= !!(c->node_tag = hoc_calloc(kept, sizeof *c->node_tag));
  ok &= !!(c->dim = hoc_calloc(kept, sizeof *c->dim));
  ok &= !!(c->entity = hoc_calloc(kept, sizeof *c->entity));
  ok &= !!(c->conn = hoc_calloc(3 * src->n_elems + 1, sizeof *c->conn));
  ok &= !!(c->elem_face = hoc_calloc(src->n_elems + 1, sizeof *c->elem_face));
  if (src->n_lines) {
    ok &= !!(c->line_conn = hoc_calloc(2 * src->n_lines, sizeof *c->line_conn));
    ok &= !!(c->line_curve = hoc_calloc(src->n_lines, sizeof *c->line_curve));
  }
  if (!ok) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (size_t i = 0; i < n; ++i) {
    if (find(up, i) != i) continue;
    size_t j = to[i];
    if (c->xyz) memcpy(c->xyz + 3 * j, src->xyz + 3 * i, 3 * sizeof *c->xyz);
    if (c->param) memcpy(c->param + 2 * j, src->param + 2 * i, 2 * sizeof *c->param);
    if (c->has_param) c->has_param[j] = src->has_param[i];
    if (c->node_tag) c->node_tag[j] = src->node_tag[i];
    c->dim[j] = src->dim[i];
    c->entity[j] = src->entity[i];
  }
  size_t ne = 0;
  for (size_t e = 0; e < src->n_elems; ++e) {
    size_t t[3];
    for (int k = 0; k < 3; ++k) t[k] = to[src->conn[3 * e + (size_t)k]];
    if (t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) continue;
    memcpy(c->conn + 3 * ne, t, sizeof t);
    c->elem_face[ne++] = src->elem_face[e];
  }
  size_t nl = 0;
  for (size_t l = 0; l < src->n_lines; ++l) {
    size_t a = to[src->line_conn[2 * l]], b = to[src->line_conn[2 * l + 1]];
    if (a == b) continue;
    c->line_conn[2 * nl] = a;
    c->line_conn[2 * nl + 1] = b;
    c->line_curve[nl++] = src->line_curve[l];
  }
  c->n_dropped = src->n_elems - ne;
  src->n_nodes = kept;
  src->xyz = c->xyz;
  src->param = c->param;
  src->has_param = c->has_param;
  src->node_tag = c->node_tag;
  src->dim = c->dim;
  src->entity = c->entity;
  src->n_elems = ne;
  src->conn = c->conn;
  src->elem_face = c->elem_face;
  src->n_lines = nl;
  src->line_conn = c->line_conn;
  src->line_curve = c->line_curve;
done:
  if (status != HOC_OK) hoc_mesh_collapse_free(c);
  free(up);
  free(first);
  free(degenerate);
  free(to);
  return status;
}
