/* hoc_mesh: allocation, accessors, positions and normals from parameters.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "core/geometry.h"
#include "mesh/mesh.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

hoc_status hoc_mesh_alloc(hoc_model *model, int order, size_t n_nodes, size_t n_elems,
                          hoc_mesh **out) {
  HOC_CHECK(out, HOC_ERR_ARGUMENT, "mesh output is NULL");
  *out = NULL;
  HOC_CHECK(model, HOC_ERR_ARGUMENT, "no model given");
  HOC_CHECK(order >= 1 && order <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT,
            "element order %d out of range 1..%d", order, HOC_MAX_ORDER);
  hoc_mesh *m;
  HOC_ALLOC(m, 1);
  m->model = model;
  m->order = order;
  m->np = (order + 1) * (order + 2) / 2;
  m->n_nodes = n_nodes;
  m->n_elems = n_elems;
  m->xyz = hoc_calloc(3 * n_nodes, sizeof *m->xyz);
  m->param = hoc_calloc(2 * n_nodes, sizeof *m->param);
  m->dim = hoc_calloc(n_nodes, sizeof *m->dim);
  m->entity = hoc_calloc(n_nodes, sizeof *m->entity);
  m->conn = hoc_calloc(n_elems * (size_t)m->np, sizeof *m->conn);
  m->elem_face = hoc_calloc(n_elems, sizeof *m->elem_face);
  m->elem_uv = hoc_calloc(2 * n_elems * (size_t)m->np, sizeof *m->elem_uv);
  m->elem_slot = hoc_calloc(n_elems * (size_t)m->np, sizeof *m->elem_slot);
  m->face_orient = hoc_calloc((size_t)model->n_faces, sizeof *m->face_orient);
  if (!m->xyz || !m->param || !m->dim || !m->entity || !m->conn || !m->elem_face ||
      !m->elem_uv || !m->elem_slot || !m->face_orient) {
    hoc_mesh_destroy(&m);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory for a mesh of %zu nodes and %zu elements",
                     n_nodes, n_elems);
  }
  *out = m;
  return HOC_OK;
}

/* *dst = a copy of n items of `size` bytes at src (NULL stays NULL);
 * returns 0 when out of memory. */
static int dup_array(void *dst, const void *src, size_t n, size_t size) {
  void **d = dst;
  *d = NULL;
  if (!src) return 1;
  *d = hoc_calloc(n ? n : 1, size);
  if (!*d) return 0;
  memcpy(*d, src, n * size);
  return 1;
}

hoc_status hoc_mesh_copy(const hoc_mesh *mesh, hoc_mesh **out) {
  HOC_CHECK(out, HOC_ERR_ARGUMENT, "mesh output is NULL");
  *out = NULL;
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "no mesh given");
  const hoc_mesh *s = mesh;
  hoc_mesh *m;
  HOC_ALLOC(m, 1);
  *m = *s;
  size_t np = (size_t)s->np, nf = (size_t)s->model->n_faces;
  int ok = dup_array(&m->xyz, s->xyz, 3 * s->n_nodes, sizeof *s->xyz) &
           dup_array(&m->param, s->param, 2 * s->n_nodes, sizeof *s->param) &
           dup_array(&m->dim, s->dim, s->n_nodes, sizeof *s->dim) &
           dup_array(&m->entity, s->entity, s->n_nodes, sizeof *s->entity) &
           dup_array(&m->conn, s->conn, s->n_elems * np, sizeof *s->conn) &
           dup_array(&m->elem_face, s->elem_face, s->n_elems, sizeof *s->elem_face) &
           dup_array(&m->elem_uv, s->elem_uv, 2 * s->n_elems * np, sizeof *s->elem_uv) &
           dup_array(&m->elem_slot, s->elem_slot, s->n_elems * np, sizeof *s->elem_slot) &
           dup_array(&m->slot_node, s->slot_node, s->n_slots, sizeof *s->slot_node) &
           dup_array(&m->slot_face, s->slot_face, s->n_slots, sizeof *s->slot_face) &
           dup_array(&m->slot_uv, s->slot_uv, 2 * s->n_slots, sizeof *s->slot_uv) &
           dup_array(&m->slot_pole, s->slot_pole, s->n_slots, sizeof *s->slot_pole) &
           dup_array(&m->line_conn, s->line_conn, s->n_lines * ((size_t)s->order + 1),
                     sizeof *s->line_conn) &
           dup_array(&m->line_curve, s->line_curve, s->n_lines, sizeof *s->line_curve) &
           dup_array(&m->line_t, s->line_t, 2 * s->n_lines, sizeof *s->line_t) &
           dup_array(&m->face_orient, s->face_orient, nf, sizeof *s->face_orient) &
           dup_array(&m->failed_faces, s->failed_faces, (size_t)s->n_failed_faces,
                     sizeof *s->failed_faces);
  if (!ok) {
    hoc_mesh_destroy(&m);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory for a copy of a mesh of %zu nodes",
                     mesh->n_nodes);
  }
  *out = m;
  return HOC_OK;
}

hoc_status hoc_mesh_copy_failed(const hoc_mesh *from, hoc_mesh *to) {
  free(to->failed_faces);
  to->failed_faces = NULL;
  to->n_failed_faces = 0;
  if (from->n_failed_faces) {
    HOC_ALLOC(to->failed_faces, (size_t)from->n_failed_faces);
    memcpy(to->failed_faces, from->failed_faces,
           (size_t)from->n_failed_faces * sizeof *to->failed_faces);
  }
  to->n_failed_faces = from->n_failed_faces;
  to->timed_out_faces = from->timed_out_faces;
  to->known_failed_faces = from->known_failed_faces;
  to->mesher_timeout = from->mesher_timeout;
  return HOC_OK;
}

hoc_status hoc_mesh_copy_record(const hoc_mesh *from, hoc_mesh *to) {
  HOC_TRY(hoc_mesh_copy_failed(from, to));
  to->n_collapsed = from->n_collapsed;
  to->graded_curves = from->graded_curves;
  to->graded_faces = from->graded_faces;
  to->ungraded_elements = from->ungraded_elements;
  to->ungraded_min_q = from->ungraded_min_q;
  to->graded_budget = from->graded_budget;
  to->swapped_edges = from->swapped_edges;
  memcpy(to->swap_min_q, from->swap_min_q, sizeof to->swap_min_q);
  to->small_faces = from->small_faces;
  to->small_min = from->small_min;
  to->unextended_elements = from->unextended_elements;
  to->cut_pinches = from->cut_pinches;
  return HOC_OK;
}

void hoc_mesh_destroy(hoc_mesh **mesh) {
  if (!mesh || !*mesh) return;
  hoc_mesh *m = *mesh;
  free(m->xyz);
  free(m->param);
  free(m->dim);
  free(m->entity);
  free(m->conn);
  free(m->elem_face);
  free(m->elem_uv);
  free(m->elem_slot);
  free(m->slot_node);
  free(m->slot_face);
  free(m->slot_uv);
  free(m->slot_pole);
  free(m->line_conn);
  free(m->line_curve);
  free(m->line_t);
  free(m->face_orient);
  free(m->failed_faces);
  free(m);
  *mesh = NULL;
}

size_t hoc_mesh_num_elements(const hoc_mesh *mesh) { return mesh ? mesh->n_elems : 0; }
size_t hoc_mesh_num_nodes(const hoc_mesh *mesh) { return mesh ? mesh->n_nodes : 0; }
int hoc_mesh_order(const hoc_mesh *mesh) { return mesh ? mesh->order : 0; }
hoc_nodeset hoc_mesh_nodeset(const hoc_mesh *mesh) {
  return mesh ? mesh->nodeset : HOC_NODES_EQUISPACED;
}
int hoc_mesh_num_failed_faces(const hoc_mesh *mesh) { return mesh ? mesh->n_failed_faces : 0; }
int hoc_mesh_failed_face_tag(const hoc_mesh *mesh, int i) {
  return mesh && i >= 0 && i < mesh->n_failed_faces ? mesh->model->faces[mesh->failed_faces[i]].tag
                                                     : -1;
}
int hoc_mesh_element_face_tag(const hoc_mesh *mesh, size_t e) {
  return mesh && e < mesh->n_elems ? mesh->model->faces[mesh->elem_face[e]].tag : -1;
}

hoc_status hoc_mesh_refine_bounds(const hoc_mesh *mesh, const unsigned char *elements,
                                  double factor, double *face_size) {
  HOC_CHECK(mesh && elements && face_size, HOC_ERR_ARGUMENT, "refine bounds: missing argument");
  HOC_CHECK(factor > 0 && factor < 1, HOC_ERR_ARGUMENT, "refine factor %g is not in (0, 1)",
            factor);
  for (size_t e = 0; e < mesh->n_elems; ++e) {
    if (!elements[e]) continue;
    /* longest straight edge between the element's corners */
    const size_t *c = mesh->conn + e * (size_t)mesh->np;
    double len = 0;
    for (int k = 0; k < 3; ++k) {
      const double *a = mesh->xyz + 3 * c[k], *b = mesh->xyz + 3 * c[(k + 1) % 3];
      double d2 = 0;
      for (int i = 0; i < 3; ++i) d2 += (b[i] - a[i]) * (b[i] - a[i]);
      len = fmax(len, sqrt(d2));
    }
    double h = factor * len, *bound = &face_size[mesh->elem_face[e]];
    if (h > 0 && (!(*bound > 0) || h < *bound)) *bound = h;
  }
  return HOC_OK;
}

/* Nodes grouped by entity: order[] lists node indices, start[e]..start[e+1]
 * those on entity e of dimension `dim`. */
static hoc_status group_nodes(const hoc_mesh *m, int dim, const unsigned char *which,
                              int n_entities, size_t **start_out, size_t **order_out) {
  size_t *start, *order;
  HOC_ALLOC(start, (size_t)n_entities + 1);
  order = hoc_calloc(m->n_nodes, sizeof *order);
  if (!order) {
    free(start);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  for (size_t i = 0; i < m->n_nodes; ++i)
    if (m->dim[i] == dim && (!which || which[i])) start[m->entity[i] + 1]++;
  for (int e = 0; e < n_entities; ++e) start[e + 1] += start[e];
  size_t *fill = hoc_calloc((size_t)n_entities + 1, sizeof *fill);
  if (!fill) {
    free(start);
    free(order);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  memcpy(fill, start, ((size_t)n_entities + 1) * sizeof *fill);
  for (size_t i = 0; i < m->n_nodes; ++i)
    if (m->dim[i] == dim && (!which || which[i])) order[fill[m->entity[i]]++] = i;
  free(fill);
  *start_out = start;
  *order_out = order;
  return HOC_OK;
}

/* Cusps ------------------------------------------------------------------- */

/* Unit tangent at CAD vertex `vertex` of curve c, pointing into the curve
 * towards parameter t_in (a point of the curve near the vertex). */
static hoc_status curve_tangent_at(const hoc_model *model, int c, int vertex, double t_in,
                                   double *d) {
  const hoc_cad_curve *cv = &model->curves[c];
  double t;
  if (cv->v0 == vertex && cv->v1 == vertex) /* closed: the end nearer t_in */
    t = fabs(t_in - cv->lo) <= fabs(cv->hi - t_in) ? cv->lo : cv->hi;
  else if (cv->v0 == vertex)
    t = cv->lo;
  else if (cv->v1 == vertex)
    t = cv->hi;
  else
    return HOC_ERROR(HOC_ERR_MISMATCH, "curve %d does not end at vertex %d", cv->tag,
                     model->vertices[vertex].tag);
  double x[3];
  HOC_TRY(hoc_cad_curve_eval(model, c, 1, &t, x, d));
  double s = t_in >= t ? 1.0 : -1.0, len = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
  for (int k = 0; k < 3; ++k) d[k] = len > 0 ? s * d[k] / len : 0.0;
  return HOC_OK;
}

hoc_status hoc_curves_angle_at(const hoc_model *model, int vertex, const int c[2],
                               const double t_in[2], double *angle) {
  double d[2][3];
  for (int j = 0; j < 2; ++j)
    HOC_TRY(curve_tangent_at(model, c[j], vertex, t_in[j], d[j]));
  double dot = d[0][0] * d[1][0] + d[0][1] * d[1][1] + d[0][2] * d[1][2];
  *angle = acos(dot > 1 ? 1 : dot < -1 ? -1 : dot);
  return HOC_OK;
}

/* Curve and curve parameter of the element edge from corner `from` to
 * corner `to`, seen next to `from`: from the edge node next to it (order >=
 * 2), else from the line joining the two corners. -1 if the edge is not on
 * a CAD curve. */
static int edge_curve(const hoc_mesh *m, size_t e, int from, int to, double *t_near) {
  const size_t *cn = m->conn + e * (size_t)m->np;
  int p = m->order;
  if (p >= 2) {
    /* gmsh order: edge k runs from corner k to corner k + 1 */
    int k = (to == (from + 1) % 3) ? from : to;
    int j = k == from ? 0 : p - 2;
    size_t w = cn[3 + k * (p - 1) + j];
    if (m->dim[w] != HOC_ON_CURVE) return -1;
    *t_near = m->param[2 * w];
    return m->entity[w];
  }
  size_t a = cn[from], b = cn[to];
  for (size_t l = 0; l < m->n_lines; ++l) {
    const size_t *ln = m->line_conn + l * 2;
    if ((ln[0] == a && ln[1] == b) || (ln[0] == b && ln[1] == a)) {
      *t_near = m->line_t[2 * l + (ln[0] == a ? 1 : 0)];
      return m->line_curve[l];
    }
  }
  return -1;
}

hoc_status hoc_mesh_element_cusp(const hoc_mesh *mesh, size_t e, double max_angle_degrees,
                                 hoc_cusp *cusp, int *found) {
  HOC_CHECK(mesh && cusp && found, HOC_ERR_ARGUMENT, "NULL argument");
  *found = 0;
  HOC_CHECK(e < mesh->n_elems, HOC_ERR_ARGUMENT, "element %zu out of range", e + 1);
  const size_t *cn = mesh->conn + e * (size_t)mesh->np;
  double best = max_angle_degrees;
  for (int k = 0; k < 3; ++k) {
    size_t v = cn[k];
    if (mesh->dim[v] != HOC_ON_VERTEX) continue;
    double t[2], angle;
    int c[2] = {edge_curve(mesh, e, k, (k + 1) % 3, &t[0]),
                edge_curve(mesh, e, k, (k + 2) % 3, &t[1])};
    if (c[0] < 0 || c[1] < 0) continue;
    HOC_TRY(hoc_curves_angle_at(mesh->model, mesh->entity[v], c, t, &angle));
    angle *= 180 / 3.14159265358979323846;
    if (angle < best) {
      best = angle;
      *found = 1;
      cusp->vertex_tag = mesh->model->vertices[mesh->entity[v]].tag;
      for (int j = 0; j < 2; ++j)
        cusp->curve_tags[j] = mesh->model->curves[c[j]].tag;
      cusp->angle_degrees = angle;
    }
  }
  return HOC_OK;
}

/* Whether element e has corners on curves a and b (two distinct corners). */
static int bridges(const hoc_mesh *m, size_t e, int a, int b) {
  const size_t *cn = m->conn + e * (size_t)m->np;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (i != j && hoc_node_on_curve(m->model, m->dim[cn[i]], m->entity[cn[i]], a) &&
          hoc_node_on_curve(m->model, m->dim[cn[j]], m->entity[cn[j]], b))
        return 1;
  return 0;
}

hoc_status hoc_mesh_elements_at_cusps(const hoc_mesh *mesh, double max_angle_degrees,
                                      const unsigned char *which, unsigned char *at_cusp) {
  HOC_CHECK(mesh && at_cusp, HOC_ERR_ARGUMENT, "NULL argument");
  size_t ne = mesh->n_elems, np = (size_t)mesh->np, n_pairs = 0;
  int pairs[2 * HOC_CUSP_PAIRS];
  unsigned char *near = NULL; /* a corner of an element at a cusp */
  HOC_ALLOC(near, mesh->n_nodes + 1);
  for (size_t e = 0; e < ne; ++e) {
    at_cusp[e] = 0;
    const size_t *cn = mesh->conn + e * np;
    if (mesh->dim[cn[0]] != HOC_ON_VERTEX && mesh->dim[cn[1]] != HOC_ON_VERTEX &&
        mesh->dim[cn[2]] != HOC_ON_VERTEX)
      continue;
    hoc_cusp c;
    int found = 0; /* a curve the kernel cannot evaluate: no cusp known */
    if (hoc_mesh_element_cusp(mesh, e, max_angle_degrees, &c, &found) != HOC_OK) found = 0;
    if (!found) continue;
    at_cusp[e] = !which || which[e];
    for (int k = 0; k < 3; ++k)
      near[cn[k]] = 1;
    int ab[2] = {hoc_cad_curve_index(mesh->model, c.curve_tags[0]),
                 hoc_cad_curve_index(mesh->model, c.curve_tags[1])};
    int known = ab[0] < 0 || ab[1] < 0;
    for (size_t p = 0; p < n_pairs && !known; ++p)
      known = pairs[2 * p] == ab[0] && pairs[2 * p + 1] == ab[1];
    if (!known && n_pairs < HOC_CUSP_PAIRS) {
      pairs[2 * n_pairs] = ab[0];
      pairs[2 * n_pairs++ + 1] = ab[1];
    }
  }
  for (size_t e = 0; e < ne; ++e) {
    const size_t *cn = mesh->conn + e * np;
    if (at_cusp[e] || (which && !which[e]) || !(near[cn[0]] || near[cn[1]] || near[cn[2]]))
      continue;
    for (size_t p = 0; p < n_pairs && !at_cusp[e]; ++p)
      at_cusp[e] = (unsigned char)bridges(mesh, e, pairs[2 * p], pairs[2 * p + 1]);
  }
  free(near);
  return HOC_OK;
}

enum { CHUNK = 1024 };

hoc_status hoc_split_groups(const size_t *start, int n_groups, size_t size, size_t **pieces,
                            size_t *n_pieces) {
  size_t n = 0;
  for (int g = 0; g < n_groups; ++g)
    n += (start[g + 1] - start[g] + size - 1) / size;
  size_t *piece;
  HOC_ALLOC(piece, 2 * n + 2);
  size_t k = 0;
  for (int g = 0; g < n_groups; ++g)
    for (size_t a = start[g]; a < start[g + 1]; a += size) {
      piece[2 * k] = (size_t)g;
      piece[2 * k + 1] = a;
      ++k;
    }
  *pieces = piece;
  *n_pieces = n;
  return HOC_OK;
}

/* Positions of the nodes of one dimension (those flagged in `which` if
 * not NULL) from their parameters; xyz[n][3]. */
static hoc_status eval_nodes(const hoc_mesh *m, int dim, const unsigned char *which, double *xyz) {
  const hoc_model *model = m->model;
  if (dim == HOC_ON_VERTEX) {
    for (size_t i = 0; i < m->n_nodes; ++i)
      if (m->dim[i] == HOC_ON_VERTEX && (!which || which[i]))
        memcpy(xyz + 3 * i, model->vertices[m->entity[i]].xyz, 3 * sizeof *xyz);
    return HOC_OK;
  }
  int n_ent = dim == HOC_ON_FACE ? model->n_faces : model->n_curves;
  size_t *start = NULL, *order = NULL, *chunk = NULL, n_chunks = 0;
  HOC_TRY(group_nodes(m, dim, which, n_ent, &start, &order));
  hoc_status status = hoc_split_groups(start, n_ent, CHUNK, &chunk, &n_chunks);
  hoc_par_error err = {0};
  if (status == HOC_OK) {
#pragma omp parallel if (n_chunks > 1 && model->thread_safe)
    {
      double *par = malloc(2 * CHUNK * sizeof *par), *x = malloc(3 * CHUNK * sizeof *x);
      if (!par || !x) hoc_par_error_catch(&err, HOC_ERROR(HOC_ERR_MEMORY, "out of memory"));
#pragma omp for schedule(dynamic, 1)
      for (size_t c = 0; c < n_chunks; ++c) {
        if (!par || !x) continue;
        int e = (int)chunk[2 * c];
        size_t a = chunk[2 * c + 1], n = start[e + 1] - a < CHUNK ? start[e + 1] - a : CHUNK;
        const size_t *nodes = order + a;
        hoc_status st;
        if (dim == HOC_ON_FACE) {
          for (size_t k = 0; k < n; ++k)
            memcpy(par + 2 * k, m->param + 2 * nodes[k], 2 * sizeof *par);
          st = hoc_cad_face_eval(model, e, n, par, x, NULL, NULL);
        } else {
          for (size_t k = 0; k < n; ++k)
            par[k] = m->param[2 * nodes[k]];
          st = hoc_cad_curve_eval(model, e, n, par, x, NULL);
        }
        if (st != HOC_OK) {
          hoc_par_error_catch(&err, st);
          continue;
        }
        for (size_t k = 0; k < n; ++k)
          memcpy(xyz + 3 * nodes[k], x + 3 * k, 3 * sizeof *x);
      }
      free(par);
      free(x);
    }
    status = hoc_par_error_raise(&err);
  }
  free(start);
  free(order);
  free(chunk);
  return status;
}

hoc_status hoc_mesh_update_xyz(hoc_mesh *m) {
  for (int dim = 0; dim <= 2; ++dim) HOC_TRY(eval_nodes(m, dim, NULL, m->xyz));
  return HOC_OK;
}

hoc_status hoc_mesh_update_xyz_of(hoc_mesh *m, const unsigned char *which) {
  for (int dim = 0; dim <= 2; ++dim) HOC_TRY(eval_nodes(m, dim, which, m->xyz));
  return HOC_OK;
}

hoc_status hoc_mesh_max_cad_distance(const hoc_mesh *mesh, double *distance) {
  HOC_CHECK(mesh && distance, HOC_ERR_ARGUMENT, "NULL argument");
  double *x;
  HOC_ALLOC(x, 3 * mesh->n_nodes);
  hoc_status status = HOC_OK;
  for (int dim = 0; dim <= 2 && status == HOC_OK; ++dim) status = eval_nodes(mesh, dim, NULL, x);
  double d = 0;
  for (size_t i = 0; i < mesh->n_nodes && status == HOC_OK; ++i) {
    double dx = x[3 * i] - mesh->xyz[3 * i], dy = x[3 * i + 1] - mesh->xyz[3 * i + 1],
           dz = x[3 * i + 2] - mesh->xyz[3 * i + 2];
    double di = sqrt(dx * dx + dy * dy + dz * dz);
    if (!(di <= d)) d = di; /* NaN propagates */
  }
  free(x);
  *distance = d;
  return status;
}

/* Parameters just inside the face from a point where the parametrisation is
 * singular: moved toward the middle by `step` of the face's range in each
 * direction. */
static void nudge_inside(const hoc_cad_face *f, const double *uv, double step, double *out) {
  for (int d = 0; d < 2; ++d) {
    double mid = 0.5 * (f->lo[d] + f->hi[d]), range = f->hi[d] - f->lo[d];
    out[d] = uv[d] + step * range * (mid > uv[d] ? 1.0 : (mid < uv[d] ? -1.0 : 0.0));
  }
}

/* Parameters just off the pole side from a pole slot's: the coordinate at
 * the pole moves a little toward the middle, the arbitrary one (the
 * direction of the element the slot belongs to) stays, so that the normal
 * there is the limit along that element's direction. Both move where both
 * are arbitrary. */
static void pole_inside(const hoc_cad_face *f, const double *uv, unsigned char pole,
                        double step, double *out) {
  if ((pole & 3) == 3) {
    nudge_inside(f, uv, step, out);
    return;
  }
  for (int d = 0; d < 2; ++d) {
    double mid = 0.5 * (f->lo[d] + f->hi[d]), range = f->hi[d] - f->lo[d];
    double way = mid > uv[d] ? 1.0 : (mid < uv[d] ? -1.0 : 0.0);
    /* a pinch: toward the element's side of it */
    if (pole & (HOC_POLE_BELOW << d)) way = -1.0;
    if (pole & (HOC_POLE_ABOVE << d)) way = 1.0;
    out[d] = uv[d];
    if (!(pole & (1 << d))) out[d] += step * range * way;
  }
}

/* Unit normal (oriented as the mesh) of face f at uv, from its derivatives
 * du, dv there; at a singular point not flagged as a pole (or a side where
 * a derivative stalls), look just inside the face, farther in until the
 * face is regular there. */
static hoc_status slot_normal(const hoc_model *model, int f, const double *uv,
                              const double *pole_uv, unsigned char pole, const double *a,
                              const double *b, double sign, double *normal) {
  const hoc_cad_face *face = &model->faces[f];
  double c[3];
  hoc_cross3(a, b, c);
  if (hoc_cad_face_singular(face, a, b)) {
    double p[2], a2[3], b2[3];
    for (double step = 1e-5; step <= 1.01e-2; step *= 10) {
      if (pole & HOC_POLE_SIDES)
        pole_inside(face, pole_uv, pole, 10 * step, p);
      else
        nudge_inside(face, uv, step, p);
      HOC_TRY(hoc_cad_face_eval(model, f, 1, p, NULL, a2, b2));
      hoc_cross3(a2, b2, c);
      if (!hoc_cad_face_singular(face, a2, b2)) break;
    }
  }
  double len = sqrt(hoc_dot3(c, c));
  double inv = len > 0 ? sign / len : 0.0;
  for (int d = 0; d < 3; ++d)
    normal[d] = c[d] * inv;
  return HOC_OK;
}

/* A curve or vertex slot and the way from it into its face: the mean of
 * its elements' centroids, in parameters relative to the slot's. */
typedef struct inward {
  size_t slot;
  double to[2];
  int count;
} inward;

static int inward_cmp(const void *key, const void *item) {
  size_t s = *(const size_t *)key, t = ((const inward *)item)->slot;
  return s < t ? -1 : s > t;
}

/* Oriented normal direction (not unit) of face f at uv; 0 where singular. */
static hoc_status face_direction(const hoc_mesh *m, int f, const double *uv, double *c) {
  double du[3], dv[3];
  HOC_TRY(hoc_cad_face_eval(m->model, f, 1, uv, NULL, du, dv));
  hoc_cross3(du, dv, c);
  double sign = m->face_orient[f] < 0 ? -1.0 : 1.0;
  int singular = hoc_cad_face_singular(&m->model->faces[f], du, dv);
  for (int d = 0; d < 3; ++d) c[d] = singular ? 0.0 : sign * c[d];
  return HOC_OK;
}

/* Bisection steps that find where the normal turns across between a slot
 * and its elements' middle (to 2^-30 of the way). */
enum { FOLD_BISECTIONS = 30 };

void hoc_mesh_add_inward(const hoc_mesh *m, size_t e, size_t k, double *to) {
  const double *uv = m->elem_uv + 2 * e * (size_t)m->np;
  for (int d = 0; d < 2; ++d) to[d] += (uv[d] + uv[2 + d] + uv[4 + d]) / 3 - uv[2 * k + d];
}

/* A face that turns over within the model's tolerance of its boundary. A
 * curve lies on the faces it bounds only to the model's tolerance
 * (hoc_cad_tolerance), and where a trimmed face's untrimmed
 * parametrisation folds (phi_u x phi_v vanishes and reverses) or curls
 * over (turns its normal by more than 90 degrees) along that boundary, the
 * curve's point on the face can land on the far side, in a strip narrower
 * than the tolerance (repatch_hpdc: a fold 1.5e-4 inside, the tolerance
 * 0.01; the bottle's face 4: 140 degrees within 0.025 of its side, the
 * tolerance 0.013). The normal there points away from the face's. A curve
 * or vertex slot whose normal is opposite (beyond 90 degrees) to the
 * face's halfway to its elements' middle, where the point at which the
 * normal turns across (its component along the halfway one changes sign)
 * is within the tolerance of the node, takes the face's normal as far past
 * that point as the slot is before it. A wider fold stays: the measure
 * sees it. */
hoc_status hoc_mesh_turned_normal(const hoc_mesh *m, int f, const double *uv, const double *x,
                                  const double *to, double tol, double *normal) {
  double p[2], mid[3], c[3], y[3];
  for (int d = 0; d < 2; ++d) p[d] = uv[d] + 0.5 * to[d];
  HOC_TRY(face_direction(m, f, p, mid));
  if (hoc_dot3(mid, normal) >= 0) return HOC_OK; /* (singular halfway: 0, nothing known) */
  /* where the normal turns across, between the slot (t = 0) and halfway
   * (t = 1/2) */
  double lo = 0, hi = 0.5;
  for (int it = 0; it < FOLD_BISECTIONS; ++it) {
    double t = 0.5 * (lo + hi);
    for (int d = 0; d < 2; ++d) p[d] = uv[d] + t * to[d];
    HOC_TRY(face_direction(m, f, p, c));
    if (hoc_dot3(c, mid) > 0) hi = t;
    else lo = t;
  }
  /* that line's nearest point: the foot of the slot on the line through
   * the crossing across the gradient, in parameters, of the normal's
   * component along `mid` (central differences) */
  double cross[2] = {uv[0] + hi * to[0], uv[1] + hi * to[1]}, grad[2], g[2];
  double h = 1e-3 * hi * hypot(to[0], to[1]);
  for (int d = 0; d < 2; ++d) {
    for (int side = 0; side < 2; ++side) {
      memcpy(p, cross, sizeof p);
      p[d] += side ? h : -h;
      HOC_TRY(face_direction(m, f, p, c));
      g[side] = hoc_dot3(c, mid);
    }
    grad[d] = g[1] - g[0];
  }
  double gg = grad[0] * grad[0] + grad[1] * grad[1];
  if (!(gg > 0)) return HOC_OK;
  double along = ((cross[0] - uv[0]) * grad[0] + (cross[1] - uv[1]) * grad[1]) / gg;
  for (int d = 0; d < 2; ++d) p[d] = uv[d] + along * grad[d];
  HOC_TRY(hoc_cad_face_eval(m->model, f, 1, p, y, NULL, NULL));
  if (!(hoc_dist3(y, x) <= tol)) return HOC_OK;
  /* the normal past the line, or halfway where the face is singular there */
  for (int d = 0; d < 2; ++d) p[d] = uv[d] + fmin(2 * hi, 0.5) * to[d];
  HOC_TRY(face_direction(m, f, p, c));
  if (!(hoc_dot3(c, mid) > 0)) memcpy(c, mid, sizeof c);
  double inv = 1 / sqrt(hoc_dot3(c, c));
  for (int d = 0; d < 3; ++d) normal[d] = c[d] * inv;
  return HOC_OK;
}

/* A curve or vertex slot, not at a pole, flagged in which (all if NULL). */
static int boundary_slot(const hoc_mesh *m, const unsigned char *which, size_t s) {
  return (!which || which[s]) && !m->slot_pole[s] && m->dim[m->slot_node[s]] != HOC_ON_FACE;
}

/* hoc_mesh_turned_normal at the curve and vertex slots flagged in which
 * (all if NULL), each toward the mean of its elements' middles. */
static hoc_status boundary_fold_normals(const hoc_mesh *m, const unsigned char *which,
                                        double *normal) {
  double tol = 0;
  HOC_TRY(hoc_cad_tolerance(m->model, &tol));
  if (!(tol > 0)) return HOC_OK;
  size_t n = 0;
  for (size_t s = 0; s < m->n_slots; ++s) n += boundary_slot(m, which, s);
  if (!n) return HOC_OK;
  inward *in;
  HOC_ALLOC(in, n);
  n = 0;
  for (size_t s = 0; s < m->n_slots; ++s)
    if (boundary_slot(m, which, s)) in[n++] = (inward){.slot = s};
  size_t np = (size_t)m->np;
  for (size_t e = 0; e < m->n_elems; ++e) {
    for (size_t k = 0; k < np; ++k) {
      if (m->dim[m->conn[e * np + k]] == HOC_ON_FACE) continue;
      inward *w = bsearch(m->elem_slot + e * np + k, in, n, sizeof *in, inward_cmp);
      if (!w) continue;
      hoc_mesh_add_inward(m, e, k, w->to);
      w->count++;
    }
  }
  hoc_status status = HOC_OK;
  for (size_t j = 0; j < n && status == HOC_OK; ++j) {
    const inward *w = in + j;
    size_t s = w->slot;
    if (!w->count) continue;
    double to[2] = {w->to[0] / w->count, w->to[1] / w->count};
    status = hoc_mesh_turned_normal(m, m->slot_face[s], m->slot_uv + 2 * s,
                                    m->xyz + 3 * m->slot_node[s], to, tol, normal + 3 * s);
  }
  free(in);
  return status;
}

hoc_status hoc_mesh_slot_normals(const hoc_mesh *m, double *normal) {
  return hoc_mesh_slot_normals_of(m, NULL, normal);
}

hoc_status hoc_mesh_slot_normals_of(const hoc_mesh *m, const unsigned char *which,
                                    double *normal) {
  const hoc_model *model = m->model;
  int nf = model->n_faces;
  /* slots grouped per face */
  size_t *start, *order, *chunk = NULL, n_chunks = 0;
  HOC_ALLOC(start, (size_t)nf + 1);
  order = hoc_calloc(m->n_slots, sizeof *order);
  size_t *fill = hoc_calloc((size_t)nf + 1, sizeof *fill);
  hoc_status status = HOC_OK;
  hoc_par_error err = {0};
  if (!order || !fill) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (size_t s = 0; s < m->n_slots; ++s)
    if (!which || which[s]) start[m->slot_face[s] + 1]++;
  for (int f = 0; f < nf; ++f) start[f + 1] += start[f];
  memcpy(fill, start, ((size_t)nf + 1) * sizeof *fill);
  for (size_t s = 0; s < m->n_slots; ++s)
    if (!which || which[s]) order[fill[m->slot_face[s]]++] = s;
  HOC_TRY_GOTO(hoc_split_groups(start, nf, CHUNK, &chunk, &n_chunks), done);
#pragma omp parallel if (n_chunks > 1 && model->thread_safe)
  {
    double *uv = malloc(2 * CHUNK * sizeof *uv), *du = malloc(3 * CHUNK * sizeof *du),
           *dv = malloc(3 * CHUNK * sizeof *dv);
    if (!uv || !du || !dv) hoc_par_error_catch(&err, HOC_ERROR(HOC_ERR_MEMORY, "out of memory"));
#pragma omp for schedule(dynamic, 1)
    for (size_t c = 0; c < n_chunks; ++c) {
      if (!uv || !du || !dv) continue;
      int f = (int)chunk[2 * c];
      size_t a = chunk[2 * c + 1], n = start[f + 1] - a < CHUNK ? start[f + 1] - a : CHUNK;
      const hoc_cad_face *face = &model->faces[f];
      double sign = m->face_orient[f] < 0 ? -1.0 : 1.0;
      for (size_t k = 0; k < n; ++k) {
        size_t s = order[a + k];
        if (m->slot_pole[s])
          pole_inside(face, m->slot_uv + 2 * s, m->slot_pole[s], 1e-5, uv + 2 * k);
        else
          memcpy(uv + 2 * k, m->slot_uv + 2 * s, 2 * sizeof *uv);
      }
      hoc_status st = hoc_cad_face_eval(model, f, n, uv, NULL, du, dv);
      for (size_t k = 0; k < n && st == HOC_OK; ++k)
        st = slot_normal(model, f, uv + 2 * k, m->slot_uv + 2 * order[a + k],
                         m->slot_pole[order[a + k]], du + 3 * k, dv + 3 * k, sign,
                         normal + 3 * order[a + k]);
      hoc_par_error_catch(&err, st);
    }
    free(uv);
    free(du);
    free(dv);
  }
  status = hoc_par_error_raise(&err);
  if (status == HOC_OK) status = boundary_fold_normals(m, which, normal);
done:
  free(start);
  free(order);
  free(fill);
  free(chunk);
  return status;
}

/* Node builder ----------------------------------------------------------- */

hoc_status hoc_node_builder_reserve(hoc_node_builder *b, size_t n) {
  double *par = hoc_realloc(b->par, 2 * n, sizeof *par);
  if (par) b->par = par;
  signed char *d = hoc_realloc(b->dim, n, sizeof *d);
  if (d) b->dim = d;
  int *e = hoc_realloc(b->ent, n, sizeof *e);
  if (e) b->ent = e;
  HOC_CHECK(par && d && e, HOC_ERR_MEMORY, "out of memory for %zu nodes", n);
  if (n > b->cap) b->cap = n;
  return HOC_OK;
}

hoc_status hoc_node_builder_add(hoc_node_builder *b, int dim, int entity, double p0, double p1,
                                size_t *index) {
  if (b->n == b->cap) HOC_TRY(hoc_node_builder_reserve(b, b->cap ? 2 * b->cap : 1024));
  b->par[2 * b->n] = p0;
  b->par[2 * b->n + 1] = p1;
  b->dim[b->n] = (signed char)dim;
  b->ent[b->n] = entity;
  *index = b->n++;
  return HOC_OK;
}

void hoc_node_builder_free(hoc_node_builder *b) {
  free(b->par);
  free(b->dim);
  free(b->ent);
  *b = (hoc_node_builder){0};
}
