/* The mesh's arrays through the public accessors (hoc_mesh_nodes,
 * hoc_mesh_node_entities, hoc_mesh_elements, hoc_mesh_element_faces) on an
 * order-3 mesh of a bundled model: each node lies where the CAD entity and
 * parameters given for it put it, each element's nodes follow gmsh's
 * ordering (two elements sharing an edge list its nodes in opposite
 * directions, face-interior nodes lie on the element's face), and the face
 * tags agree with hoc_mesh_element_face_tag.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "cad/cad.h"
#include "hocad.h"
#include "test_util.h"

#include <string.h>

/* The position the CAD gives for node i from its entity and parameters. */
static void cad_position(const hoc_model *m, int dim, int tag, const double par[2], double x[3]) {
  if (dim == 0) {
    memcpy(x, m->vertices[hoc_cad_vertex_index(m, tag)].xyz, sizeof(double[3]));
  } else if (dim == 1) {
    hoc_cad_curve_eval(m, hoc_cad_curve_index(m, tag), 1, par, x, NULL);
  } else {
    hoc_cad_face_eval(m, hoc_cad_face_index(m, tag), 1, par, x, NULL, NULL);
  }
}

int main(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(HOC_MODELS_DIR "/screw.step", &model));
  if (!model) return test_report();
  hoc_mesh_options opt;
  hoc_mesh_options_default(&opt);
  opt.order = 3;
  opt.optimize = 0;
  hoc_mesh *mesh = NULL;
  CHECK_OK(hoc_mesh_model(model, &opt, &mesh, NULL));
  if (!mesh) return test_report();

  const int p = 3, np = (p + 1) * (p + 2) / 2;
  size_t nn = hoc_mesh_num_nodes(mesh), ne = hoc_mesh_num_elements(mesh);
  double *xyz = malloc(nn * 3 * sizeof *xyz), *par = malloc(nn * 2 * sizeof *par);
  int *dim = malloc(nn * sizeof *dim), *tag = malloc(nn * sizeof *tag);
  size_t *conn = malloc(ne * np * sizeof *conn);
  int *face = malloc(ne * sizeof *face);
  CHECK_OK(hoc_mesh_nodes(mesh, xyz));
  CHECK_OK(hoc_mesh_node_entities(mesh, dim, tag, par));
  CHECK_OK(hoc_mesh_elements(mesh, conn));
  CHECK_OK(hoc_mesh_element_faces(mesh, face));
  /* every output of hoc_mesh_node_entities may be NULL */
  CHECK_OK(hoc_mesh_node_entities(mesh, NULL, NULL, NULL));

  double bbox[6];
  hoc_model_bbox(model, bbox);
  double diag = sqrt((bbox[3] - bbox[0]) * (bbox[3] - bbox[0]) +
                     (bbox[4] - bbox[1]) * (bbox[4] - bbox[1]) +
                     (bbox[5] - bbox[2]) * (bbox[5] - bbox[2]));
  double worst = 0;
  int counts[3] = {0, 0, 0}, bad_class = 0;
  for (size_t i = 0; i < nn; ++i) {
    if (dim[i] < 0 || dim[i] > 2) {
      ++bad_class;
      continue;
    }
    ++counts[dim[i]];
    double x[3];
    cad_position(model, dim[i], tag[i], par + 2 * i, x);
    for (int k = 0; k < 3; ++k) worst = fmax(worst, fabs(x[k] - xyz[3 * i + k]));
  }
  CHECK(bad_class == 0);
  CHECK(counts[0] == hoc_model_num_vertices(model)); /* screw: every vertex is a corner */
  CHECK(counts[1] > 0 && counts[2] > 0);
  CHECK(worst <= 1e-12 * diag);

  int face_ok = 1, range_ok = 1, interior_ok = 1;
  for (size_t e = 0; e < ne; ++e) {
    face_ok &= face[e] == hoc_mesh_element_face_tag(mesh, e);
    for (int k = 0; k < np; ++k) {
      size_t v = conn[e * np + k];
      range_ok &= v < nn;
      /* the interior node (k = 9 at order 3) lies inside the element's face */
      if (k == 9 && v < nn) interior_ok &= dim[v] == 2 && tag[v] == face[e];
    }
  }
  CHECK(face_ok);
  CHECK(range_ok);
  CHECK(interior_ok);

  /* gmsh ordering: edge k joins corners k and k+1 and its p-1 nodes follow
   * at 3 + (p-1) k; an edge two elements share runs the other way in one */
  size_t shared = 0, mismatched = 0;
  for (size_t e = 0; e < ne; ++e)
    for (size_t f = e + 1; f < ne; ++f)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          const size_t *ce = conn + e * np, *cf = conn + f * np;
          if (ce[a] != cf[(b + 1) % 3] || ce[(a + 1) % 3] != cf[b]) continue;
          ++shared;
          for (int j = 0; j < p - 1; ++j)
            mismatched += ce[3 + (p - 1) * a + j] != cf[3 + (p - 1) * b + (p - 2 - j)];
        }
  CHECK(shared == 3 * ne / 2); /* a closed surface: every edge shared */
  CHECK(mismatched == 0);
  printf("%zu nodes (%d on vertices, %d on curves, %d in faces), %zu elements, %zu shared "
         "edges, farthest node %.2e from its entity\n",
         nn, counts[0], counts[1], counts[2], ne, shared, worst);

  CHECK_STATUS(hoc_mesh_nodes(NULL, xyz), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_mesh_nodes(mesh, NULL), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_mesh_elements(mesh, NULL), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_mesh_element_faces(mesh, NULL), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_mesh_node_entities(NULL, dim, tag, par), HOC_ERR_ARGUMENT);

  free(xyz);
  free(par);
  free(dim);
  free(tag);
  free(conn);
  free(face);
  hoc_mesh_destroy(&mesh);
  hoc_model_destroy(&model);
  return test_report();
}
