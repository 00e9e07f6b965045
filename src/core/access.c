/* The mesh's arrays copied out for callers (hocad.h "Arrays of a mesh"):
 * what bindings such as the Python package turn into arrays of their own.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "core/error.h"
#include "mesh/mesh.h"

#include <string.h>

hoc_status hoc_mesh_nodes(const hoc_mesh *mesh, double *xyz) {
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "nodes: no mesh given");
  HOC_CHECK(xyz || !mesh->n_nodes, HOC_ERR_ARGUMENT, "nodes: no output array given");
  if (mesh->n_nodes) memcpy(xyz, mesh->xyz, 3 * mesh->n_nodes * sizeof *xyz);
  return HOC_OK;
}

hoc_status hoc_mesh_node_entities(const hoc_mesh *mesh, int *dim, int *tag, double *param) {
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "node entities: no mesh given");
  const hoc_model *model = mesh->model;
  for (size_t i = 0; i < mesh->n_nodes; ++i) {
    int d = mesh->dim[i], k = mesh->entity[i];
    if (dim) dim[i] = d;
    if (tag)
      tag[i] = d == HOC_ON_VERTEX  ? model->vertices[k].tag
               : d == HOC_ON_CURVE ? model->curves[k].tag
                                   : model->faces[k].tag;
  }
  if (param && mesh->n_nodes) memcpy(param, mesh->param, 2 * mesh->n_nodes * sizeof *param);
  return HOC_OK;
}

hoc_status hoc_mesh_elements(const hoc_mesh *mesh, size_t *nodes) {
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "elements: no mesh given");
  HOC_CHECK(nodes || !mesh->n_elems, HOC_ERR_ARGUMENT, "elements: no output array given");
  if (mesh->n_elems) memcpy(nodes, mesh->conn, mesh->n_elems * (size_t)mesh->np * sizeof *nodes);
  return HOC_OK;
}

hoc_status hoc_mesh_element_faces(const hoc_mesh *mesh, int *tags) {
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "element faces: no mesh given");
  HOC_CHECK(tags || !mesh->n_elems, HOC_ERR_ARGUMENT, "element faces: no output array given");
  for (size_t e = 0; e < mesh->n_elems; ++e) tags[e] = mesh->model->faces[mesh->elem_face[e]].tag;
  return HOC_OK;
}
