/* From a classified triangulation to a hoc_mesh: parameters of every node,
 * slots (node seen from a face), curve lines, face orientation; the
 * unwrapped element parameters and pole slots are in poles.c.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "core/geometry.h"
#include "core/hash.h"
#include "mesh/mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* How far a given mesh (read from a file) may lie from the model, in units
 * of the model's measured tolerance: the measure samples each curve at 33
 * points, which on the corpus fall at most 2.5 times short of a dense
 * measure; and at least a fraction of the diagonal, for positions a file's
 * writer rounded to about 7 significant digits. */
enum { GIVEN_TOLERANCES = 4 };
static const double GIVEN_ROUNDING = 1e-6;
/* A given mesh's high-order node inside a face may lie this share of the
 * diagonal off the surface: gmsh leaves such a node where its own
 * projection fails (seen at 7e-3 of the model's size); farther, the mesh
 * is not on this model. */
static const double GIVEN_FACE_NODE = 1e-2;

hoc_status hoc_mesh_given_limit(hoc_model *model, double *limit) {
  HOC_CHECK(model && limit, HOC_ERR_ARGUMENT, "NULL argument");
  double t;
  HOC_TRY(hoc_cad_tolerance(model, &t));
  *limit = fmax(GIVEN_TOLERANCES * t, GIVEN_ROUNDING * model->diagonal);
  return HOC_OK;
}

double hoc_mesh_face_gap(const hoc_mesh *mesh) { return mesh ? mesh->face_gap : 0.0; }

/* Index of the first node of local edge k (0..2) in gmsh ordering. */
static inline int edge_first_node(int p, int k) { return 3 + k * (p - 1); }

static size_t node_label(const hoc_mesh_source *src, size_t i) {
  return src->node_tag ? src->node_tag[i] : i + 1;
}

/* Validation ------------------------------------------------------------- */

static hoc_status validate(const hoc_model *model, const hoc_mesh_source *src) {
  HOC_CHECK(src->order >= 1 && src->order <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT,
            "element order %d out of range 1..%d", src->order, HOC_MAX_ORDER);
  HOC_CHECK(src->n_elems > 0, HOC_ERR_MESH, "the mesh has no triangles");
  HOC_CHECK(src->n_nodes > 0 && src->n_nodes < ((size_t)1 << 32), HOC_ERR_ARGUMENT,
            "node count %zu out of range", src->n_nodes);
  HOC_CHECK(src->dim && src->entity && src->conn && src->elem_face, HOC_ERR_ARGUMENT,
            "incomplete mesh source");
  for (size_t i = 0; i < src->n_nodes; ++i) {
    int d = src->dim[i], e = src->entity[i];
    int n_ent = d == 0 ? model->n_vertices : d == 1 ? model->n_curves : model->n_faces;
    HOC_CHECK(d >= 0 && d <= 2, HOC_ERR_MISMATCH, "node %zu is not on a CAD vertex, curve or face",
              node_label(src, i));
    HOC_CHECK(e >= 0 && e < n_ent, HOC_ERR_MISMATCH,
              "node %zu is on a CAD entity the model does not have", node_label(src, i));
    if (src->xyz)
      HOC_CHECK(isfinite(src->xyz[3 * i]) && isfinite(src->xyz[3 * i + 1]) &&
                    isfinite(src->xyz[3 * i + 2]),
                HOC_ERR_FORMAT, "node %zu has a non-finite coordinate", node_label(src, i));
    if (src->param && (!src->has_param || src->has_param[i]))
      HOC_CHECK(isfinite(src->param[2 * i]) && isfinite(src->param[2 * i + 1]), HOC_ERR_FORMAT,
                "node %zu has a non-finite parametric coordinate", node_label(src, i));
  }
  int np = (src->order + 1) * (src->order + 2) / 2;
  for (size_t e = 0; e < src->n_elems; ++e) {
    HOC_CHECK(src->elem_face[e] >= 0 && src->elem_face[e] < model->n_faces, HOC_ERR_MISMATCH,
              "triangle %zu is on a face the model does not have", e + 1);
    for (int k = 0; k < np; ++k) {
      size_t i = src->conn[e * (size_t)np + k];
      HOC_CHECK(i < src->n_nodes, HOC_ERR_ARGUMENT, "triangle %zu refers to a missing node", e + 1);
      if (src->dim[i] == HOC_ON_FACE)
        HOC_CHECK(src->entity[i] == src->elem_face[e], HOC_ERR_MISMATCH,
                  "triangle %zu on face %d uses node %zu of face %d", e + 1,
                  model->faces[src->elem_face[e]].tag, node_label(src, i),
                  model->faces[src->entity[i]].tag);
    }
    for (int a = 0; a < 3; ++a)
      for (int b = a + 1; b < 3; ++b)
        HOC_CHECK(src->conn[e * (size_t)np + a] != src->conn[e * (size_t)np + b],
                  HOC_ERR_MESH, "triangle %zu repeats a vertex", e + 1);
  }
  for (size_t l = 0; l < src->n_lines; ++l) {
    HOC_CHECK(src->line_curve[l] >= 0 && src->line_curve[l] < model->n_curves, HOC_ERR_MISMATCH,
              "line %zu is on a curve the model does not have", l + 1);
    for (int k = 0; k <= src->order; ++k)
      HOC_CHECK(src->line_conn[l * (size_t)(src->order + 1) + k] < src->n_nodes,
                HOC_ERR_ARGUMENT, "line %zu refers to a missing node", l + 1);
  }
  return HOC_OK;
}

/* Parameter of a vertex on one of its curves: lo at the start, hi at the end;
 * on a closed curve the one nearest `near` (NAN: lo). */
static double vertex_t_on_curve(const hoc_cad_curve *c, int vertex, double near, int *ok) {
  *ok = 1;
  int at0 = c->v0 == vertex, at1 = c->v1 == vertex;
  if (at0 && at1) {
    if (isnan(near)) return c->lo;
    return fabs(near - c->lo) <= fabs(near - c->hi) ? c->lo : c->hi;
  }
  if (at0) return c->lo;
  if (at1) return c->hi;
  *ok = 0;
  return NAN;
}

/* Locate a point on face f without a usable guess: the kernel's projection
 * (which may fail on hard B-splines), then Newton from a 5 x 5 grid of
 * starting points over the face's bounds; the best result wins. */
static hoc_status locate_on_face(const hoc_model *model, int f, const double *x, double *uv,
                                 double *dist) {
  const hoc_cad_face *face = &model->faces[f];
  double best = INFINITY, p[2], d;
  if (model->ops->face_project(model->ctx, face, 1, x, p) == HOC_OK && isfinite(p[0]) &&
      isfinite(p[1])) {
    HOC_TRY(hoc_cad_face_invert(model, f, x, p, &d));
    if (d < best) best = d, uv[0] = p[0], uv[1] = p[1];
  }
  hoc_error_clear();
  for (int i = 0; i < 5 && best > 1e-9 * model->diagonal; ++i)
    for (int j = 0; j < 5; ++j) {
      p[0] = face->lo[0] + (face->hi[0] - face->lo[0]) * (i + 0.5) / 5;
      p[1] = face->lo[1] + (face->hi[1] - face->lo[1]) * (j + 0.5) / 5;
      HOC_TRY(hoc_cad_face_invert(model, f, x, p, &d));
      if (d < best) best = d, uv[0] = p[0], uv[1] = p[1];
    }
  *dist = best;
  return HOC_OK;
}

/* Parameters of nodes the source gave none: curve nodes along lines and by
 * projection; face nodes from neighbours inside their elements. */
static hoc_status recover_params(hoc_mesh *m, const hoc_mesh_source *src,
                                 unsigned char *known) {
  const hoc_model *model = m->model;
  int p = m->order, np = m->np;
  /* curve nodes: guesses along the lines, repeated until no progress */
  int progress = 1;
  while (progress) {
    progress = 0;
    for (size_t l = 0; l < src->n_lines; ++l) {
      const size_t *ln = src->line_conn + l * (size_t)(p + 1);
      int c = src->line_curve[l];
      double guess = NAN;
      for (int k = 0; k <= p && isnan(guess); ++k) {
        size_t i = ln[k];
        if (m->dim[i] == HOC_ON_CURVE && m->entity[i] == c && known[i]) guess = m->param[2 * i];
        if (m->dim[i] == HOC_ON_VERTEX) {
          int ok;
          double t = vertex_t_on_curve(&model->curves[c], m->entity[i], NAN, &ok);
          if (ok) guess = t;
        }
      }
      if (isnan(guess)) continue;
      for (int k = 0; k <= p; ++k) {
        size_t i = ln[k];
        if (m->dim[i] != HOC_ON_CURVE || known[i] || m->entity[i] != c) continue;
        double t = guess, d;
        HOC_TRY(hoc_cad_curve_invert(model, c, src->xyz + 3 * i, &t, &d));
        /* only a converged Newton: one stuck (a start where the curve's
         * derivative vanishes, a local minimum) leaves the node to another
         * guess or to the projection below */
        if (d <= 1e-9 * model->diagonal) {
          m->param[2 * i] = t;
          known[i] = 1;
          progress = 1;
        }
      }
    }
  }
  for (size_t i = 0; i < m->n_nodes; ++i) {
    if (m->dim[i] != HOC_ON_CURVE || known[i]) continue;
    int c = m->entity[i];
    double t, d;
    HOC_TRY(model->ops->curve_project(model->ctx, &model->curves[c], 1, src->xyz + 3 * i, &t));
    HOC_TRY(hoc_cad_curve_invert(model, c, src->xyz + 3 * i, &t, &d));
    /* how far is judged once every node is placed (hoc_mesh_assemble), with
     * the model's tolerance in the message */
    HOC_CHECK(isfinite(d), HOC_ERR_MISMATCH,
              "node %zu cannot be located on curve %d: the mesh does not match this model",
              node_label(src, i), model->curves[c].tag);
    m->param[2 * i] = t;
    known[i] = 1;
  }
  /* face nodes: breadth-first through the elements; a node is located from
   * the parameters of a located node of the same element (an unwrapped
   * guess, so Newton converges in a few steps); where no element links a
   * located node to the rest, one node is projected (slow) as a start */
  size_t missing = 0;
  for (size_t i = 0; i < m->n_nodes; ++i) missing += m->dim[i] == HOC_ON_FACE && !known[i];
  if (!missing) return HOC_OK;
  size_t *first = NULL, *list = NULL, *queue = NULL;
  unsigned char *queued = NULL;
  hoc_status status = HOC_OK;
  first = hoc_calloc(m->n_nodes + 1, sizeof *first);
  list = hoc_calloc(m->n_elems * (size_t)np, sizeof *list);
  queue = hoc_calloc(m->n_elems, sizeof *queue);
  queued = hoc_calloc(m->n_elems, 1);
  if (!first || !list || !queue || !queued) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  /* node -> elements (CSR) */
  for (size_t e = 0; e < m->n_elems; ++e)
    for (int k = 0; k < np; ++k) first[src->conn[e * (size_t)np + k] + 1]++;
  for (size_t i = 0; i < m->n_nodes; ++i) first[i + 1] += first[i];
  for (size_t e = 0; e < m->n_elems; ++e)
    for (int k = 0; k < np; ++k) list[first[src->conn[e * (size_t)np + k]]++] = e;
  for (size_t i = m->n_nodes; i > 0; --i) first[i] = first[i - 1];
  first[0] = 0;
  size_t head = 0, tail = 0;
  for (size_t e = 0; e < m->n_elems; ++e)
    for (int k = 0; k < np && !queued[e]; ++k) {
      size_t i = src->conn[e * (size_t)np + k];
      if (m->dim[i] == HOC_ON_FACE && known[i]) {
        queued[e] = 1;
        queue[tail++] = e;
      }
    }
  size_t scan = 0; /* next node to consider to project as a start */
  while (missing) {
    if (head == tail) {
      while (!(m->dim[scan] == HOC_ON_FACE && !known[scan])) ++scan;
      size_t i = scan;
      int f = m->entity[i];
      double uv[2] = {0, 0}, d;
      HOC_TRY_GOTO(locate_on_face(model, f, src->xyz + 3 * i, uv, &d), done);
      if (!isfinite(d)) { /* how far is judged once every node is placed */
        status = HOC_ERROR(HOC_ERR_MISMATCH,
                           "node %zu cannot be located on face %d: the mesh does not match this "
                           "model",
                           node_label(src, i), model->faces[f].tag);
        goto done;
      }
      hoc_cad_face_wrap(&model->faces[f], uv);
      memcpy(m->param + 2 * i, uv, sizeof uv);
      known[i] = 1;
      --missing;
      for (size_t j = first[i]; j < first[i + 1]; ++j)
        if (!queued[list[j]]) {
          queued[list[j]] = 1;
          queue[tail++] = list[j];
        }
      continue;
    }
    size_t e = queue[head++];
    const size_t *cn = src->conn + e * (size_t)np;
    int f = src->elem_face[e];
    for (int k = 0; k < np; ++k) {
      size_t i = cn[k];
      if (m->dim[i] != HOC_ON_FACE || known[i]) continue;
      /* Newton from each located node of the element in turn, until one
       * converges to the node (a start may end in a local minimum, e.g. on
       * the domain's edge); the closest result otherwise */
      double uv[2] = {0, 0}, d = INFINITY, found = 1e-9 * model->diagonal;
      for (int g = 0; g < np && !(d <= found); ++g) {
        size_t j = cn[g];
        if (m->dim[j] != HOC_ON_FACE || !known[j] || m->entity[j] != f) continue;
        double t[2] = {m->param[2 * j], m->param[2 * j + 1]}, dt;
        HOC_TRY_GOTO(hoc_cad_face_invert(model, f, src->xyz + 3 * i, t, &dt), done);
        if (dt < d) d = dt, uv[0] = t[0], uv[1] = t[1];
      }
      /* not converged: another element may bring a better guess, else the
       * node is projected as a start */
      if (!(d <= found)) continue;
      hoc_cad_face_wrap(&model->faces[f], uv);
      memcpy(m->param + 2 * i, uv, sizeof uv);
      known[i] = 1;
      --missing;
      for (size_t j = first[i]; j < first[i + 1]; ++j)
        if (!queued[list[j]]) {
          queued[list[j]] = 1;
          queue[tail++] = list[j];
        }
    }
  }
done:
  free(first);
  free(list);
  free(queue);
  free(queued);
  return status;
}

/* Slots ------------------------------------------------------------------ */

/* Slots: one per (node, face) pair an element uses. A node's first pair is
 * found through first[] without hashing; only nodes on CAD curves and
 * vertices, which several faces share, need the hash for further faces. */
static hoc_status build_slots(hoc_mesh *m) {
  int np = m->np;
  hoc_hash h = {0};
  hoc_status status = HOC_OK;
  size_t cap = m->n_nodes + 16, n = 0;
  size_t *node = hoc_calloc(cap, sizeof *node);
  int *face = hoc_calloc(cap, sizeof *face);
  size_t *first = hoc_calloc(m->n_nodes, sizeof *first);
  if (!node || !face || !first) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto fail;
  }
  size_t shared = 0;
  for (size_t i = 0; i < m->n_nodes; ++i) {
    first[i] = SIZE_MAX;
    shared += m->dim[i] != HOC_ON_FACE;
  }
  HOC_TRY_GOTO(hoc_hash_init(&h, shared), fail);
  uint64_t nf = (uint64_t)m->model->n_faces;
  for (size_t e = 0; e < m->n_elems; ++e) {
    int f = m->elem_face[e];
    for (int k = 0; k < np; ++k) {
      size_t i = m->conn[e * (size_t)np + k], s;
      int found = 0;
      if (first[i] == SIZE_MAX) {
        s = n;
      } else if (face[first[i]] == f) {
        s = first[i];
        found = 1;
      } else {
        HOC_TRY_GOTO(hoc_hash_insert(&h, (uint64_t)i * nf + (uint64_t)f, n, &found, &s), fail);
      }
      if (!found) {
        if (n == cap) {
          cap *= 2;
          size_t *n2 = hoc_realloc(node, cap, sizeof *node);
          if (n2) node = n2;
          int *f2 = hoc_realloc(face, cap, sizeof *face);
          if (f2) face = f2;
          if (!n2 || !f2) {
            status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
            goto fail;
          }
        }
        if (first[i] == SIZE_MAX) first[i] = n;
        node[n] = i;
        face[n] = f;
        ++n;
      }
      m->elem_slot[e * (size_t)np + k] = s;
    }
  }
  hoc_hash_free(&h);
  free(first);
  m->n_slots = n;
  m->slot_node = node;
  m->slot_face = face;
  m->slot_uv = hoc_calloc(2 * n, sizeof *m->slot_uv);
  m->slot_pole = hoc_calloc(n, sizeof *m->slot_pole);
  HOC_CHECK(m->slot_uv && m->slot_pole, HOC_ERR_MEMORY, "out of memory");
  return HOC_OK;
fail:
  hoc_hash_free(&h);
  free(node);
  free(face);
  free(first);
  return status;
}

/* Parameters of every slot on its face (of the nodes flagged in which, if
 * not NULL: their pole flags are left, and *pole_moved set where one would
 * change): a curve node's is the face's pcurve at its parameter, a
 * vertex's the face's own point of it, the face's nearest point only where
 * those give none or leave the face's bounds. One rule for every mesh,
 * hocad's own and read from a file alike, so that a mesh measures the same
 * read back (tests/test_mesh_slots_read_back.c). Checked against the node
 * position: a slot farther than `refuse` fails (given meshes). */
static hoc_status slot_params(hoc_mesh *m, const hoc_mesh_source *src, double refuse,
                              const unsigned char *which, int *pole_moved) {
  const hoc_model *model = m->model;
  /* group the curve slots by (curve, face) for batched reparametrisation */
  size_t n = m->n_slots;
  size_t *order;
  HOC_ALLOC(order, n);
  size_t cnt = 0;
  for (size_t s = 0; s < n; ++s) {
    size_t i = m->slot_node[s];
    if (which && !which[i]) continue;
    if (m->dim[i] == HOC_ON_FACE) {
      memcpy(m->slot_uv + 2 * s, m->param + 2 * i, 2 * sizeof(double));
    } else if (m->dim[i] == HOC_ON_VERTEX) {
      hoc_status st = hoc_cad_vertex_to_face(model, m->entity[i], m->slot_face[s],
                                             m->slot_uv + 2 * s);
      if (st != HOC_OK) m->slot_uv[2 * s] = m->slot_uv[2 * s + 1] = NAN;
    } else {
      order[cnt++] = s;
    }
  }
  /* simple insertion-free grouping: sort curve slots by (curve, face) */
  int nfaces = model->n_faces;
  size_t *keys = hoc_calloc(cnt, sizeof *keys);
  double *t = hoc_calloc(cnt, sizeof *t), *uv = hoc_calloc(2 * cnt, sizeof *uv);
  hoc_status status = HOC_OK;
  if (!keys || !t || !uv) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (size_t k = 0; k < cnt; ++k) {
    size_t s = order[k];
    keys[k] = (size_t)m->entity[m->slot_node[s]] * (size_t)nfaces + (size_t)m->slot_face[s];
  }
  /* counting sort would need a table of curves x faces; a merge sort on keys */
  {
    size_t *tmp_o = hoc_calloc(cnt, sizeof *tmp_o), *tmp_k = hoc_calloc(cnt, sizeof *tmp_k);
    if (!tmp_o || !tmp_k) {
      free(tmp_o);
      free(tmp_k);
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      goto done;
    }
    for (size_t w = 1; w < cnt; w *= 2) {
      for (size_t lo = 0; lo < cnt; lo += 2 * w) {
        size_t mid = lo + w < cnt ? lo + w : cnt, hi = lo + 2 * w < cnt ? lo + 2 * w : cnt;
        size_t a = lo, b = mid, o = lo;
        while (a < mid || b < hi) {
          if (b >= hi || (a < mid && keys[a] <= keys[b])) {
            tmp_k[o] = keys[a];
            tmp_o[o++] = order[a++];
          } else {
            tmp_k[o] = keys[b];
            tmp_o[o++] = order[b++];
          }
        }
      }
      memcpy(keys, tmp_k, cnt * sizeof *keys);
      memcpy(order, tmp_o, cnt * sizeof *order);
    }
    free(tmp_o);
    free(tmp_k);
  }
  for (size_t a = 0; a < cnt;) {
    size_t b = a;
    while (b < cnt && keys[b] == keys[a]) ++b;
    int c = (int)(keys[a] / (size_t)nfaces), f = (int)(keys[a] % (size_t)nfaces);
    for (size_t k = a; k < b; ++k) t[k - a] = m->param[2 * m->slot_node[order[k]]];
    hoc_status st = hoc_cad_curve_to_face(model, c, f, b - a, t, uv);
    for (size_t k = a; k < b; ++k) {
      double *dst = m->slot_uv + 2 * order[k];
      if (st == HOC_OK) {
        dst[0] = uv[2 * (k - a)];
        dst[1] = uv[2 * (k - a) + 1];
      } else {
        dst[0] = dst[1] = NAN;
      }
    }
    a = b;
  }
  /* verify: phi_f(slot uv) must be the node; repair by local inversion or projection */
  for (size_t s = 0; s < n; ++s) {
    size_t i = m->slot_node[s];
    if (m->dim[i] == HOC_ON_FACE || (which && !which[i])) continue;
    int f = m->slot_face[s];
    const hoc_cad_face *face = &model->faces[f];
    double *p = m->slot_uv + 2 * s, x[3], d = INFINITY;
    /* a pcurve may give the other copy of a periodic surface's seam while
     * the face's own domain does not cross it (a piece of a periodic
     * surface): bring it back into the face's bounds */
    int outside = 0;
    for (int k = 0; k < 2 && isfinite(p[0]) && isfinite(p[1]); ++k) {
      double margin = 1e-6 * (face->hi[k] - face->lo[k]);
      if (!(face->period[k] > 0) && (p[k] < face->lo[k] - margin || p[k] > face->hi[k] + margin)) {
        p[k] = p[k] < face->lo[k] ? face->lo[k] : face->hi[k];
        outside = 1;
      }
    }
    if (outside) {
      HOC_TRY_GOTO(hoc_cad_face_invert(model, f, m->xyz + 3 * i, p, &d), done);
    } else if (isfinite(p[0]) && isfinite(p[1])) {
      HOC_TRY_GOTO(hoc_cad_face_eval(model, f, 1, p, x, NULL, NULL), done);
      d = hoc_dist3(x, m->xyz + 3 * i);
    }
    if (!(isfinite(p[0]) && isfinite(p[1]))) {
      HOC_TRY_GOTO(model->ops->face_project(model->ctx, &model->faces[f], 1, m->xyz + 3 * i, p),
                   done);
      HOC_TRY_GOTO(hoc_cad_face_invert(model, f, m->xyz + 3 * i, p, &d), done);
    }
    /* a curve and the faces it bounds agree only to the model's tolerance
     * (up to 3e-3 of its size in the corpus, 2e-2 seen in an IGES model):
     * the node stays on its curve, the slot is the pcurve's point, and
     * the distance is recorded; a given mesh's curve or vertex
     * node may lie off the face by twice its given limit (that far off
     * its curve, the curve as far off the face) */
    if (d > m->face_gap) m->face_gap = d;
    if (d > refuse) {
      status = HOC_ERROR(HOC_ERR_MISMATCH,
                         "node %zu is %.3g away from face %d it bounds, more than the %.3g "
                         "allowed (the model's own tolerance is %.3g): the mesh does not match "
                         "this model",
                         node_label(src, i), d, model->faces[f].tag, refuse, model->tolerance);
      goto done;
    }
  }
  /* poles: a coordinate is arbitrary where the node sits on a degenerate side */
  for (size_t s = 0; s < n; ++s) {
    if (which && !which[m->slot_node[s]]) continue;
    const hoc_cad_face *f = &model->faces[m->slot_face[s]];
    const double *p = m->slot_uv + 2 * s;
    unsigned char pole = 0;
    for (int side = 0; side < 4; ++side) {
      if (!f->pole[side]) continue;
      int d = side / 2;
      double at = side % 2 ? f->hi[d] : f->lo[d], range = f->hi[d] - f->lo[d];
      if (fabs(p[d] - at) <= 1e-9 * range + 1e-300) pole |= (unsigned char)(1 << (1 - d));
    }
    /* a curve node at a pinch of the face (a line of its (u, v) that maps
     * to one point, inside it: pinch.c cuts the mesh there) */
    if (!pole && m->dim[m->slot_node[s]] == HOC_ON_CURVE && hoc_face_may_pinch(f) &&
        isfinite(p[0]) && isfinite(p[1])) {
      double du[3], dv[3], spread;
      HOC_TRY_GOTO(hoc_cad_face_eval(model, m->slot_face[s], 1, p, NULL, du, dv), done);
      double a = sqrt(hoc_dot3(du, du)), b = sqrt(hoc_dot3(dv, dv));
      int stalled_v = b <= HOC_CAD_STALL * f->dv_scale;
      int stalled_u = a <= HOC_CAD_STALL * f->du_scale;
      for (int d = 0; d < 2; ++d) {
        /* d: the line's fixed coordinate, the other one stalls along it */
        if (!(d == 0 ? stalled_v && !stalled_u : stalled_u && !stalled_v)) continue;
        HOC_TRY_GOTO(hoc_face_line_spread(model, m->slot_face[s], d, p[d], &spread), done);
        if (spread <= hoc_mesh_collapse_distance(model)) pole |= (unsigned char)(1 << (1 - d));
      }
    }
    if (!which)
      m->slot_pole[s] |= pole;
    else if ((m->slot_pole[s] | pole) != m->slot_pole[s])
      *pole_moved = 1;
  }
done:
  free(order);
  free(keys);
  free(t);
  free(uv);
  return status;
}

/* Lines ------------------------------------------------------------------ */

/* Parameter of line end `i` on curve c, given the other end's parameter
 * (NAN if unknown). */
static int end_param(const hoc_mesh *m, size_t i, int c, double near, double *t) {
  if (m->dim[i] == HOC_ON_CURVE) {
    if (m->entity[i] == c) {
      *t = m->param[2 * i];
      return 1;
    }
    /* a node of another curve that passes through this one's point (a
     * pinch's point, on every curve that crosses the pinch: pinch.c) */
    const hoc_cad_curve *cv = &m->model->curves[c];
    double tol = hoc_mesh_collapse_distance(m->model);
    for (int guess = 0; guess < 2; ++guess) {
      double g = near, d = INFINITY;
      if (guess || !isfinite(g))
        if (m->model->ops->curve_project(m->model->ctx, cv, 1, m->xyz + 3 * i, &g) != HOC_OK)
          break;
      if (hoc_cad_curve_invert(m->model, c, m->xyz + 3 * i, &g, &d) != HOC_OK) break;
      if (d <= tol) {
        *t = g;
        return 1;
      }
    }
    hoc_error_clear();
    return 0;
  }
  if (m->dim[i] != HOC_ON_VERTEX) return 0;
  int ok;
  const hoc_cad_curve *cv = &m->model->curves[c];
  *t = vertex_t_on_curve(cv, m->entity[i], near, &ok);
  if (ok) return 1;
  /* a vertex that stands for another at its point (collapse.c): the
   * curve's end there */
  double ends[2] = {cv->lo, cv->hi}, x[6];
  if (hoc_cad_curve_eval(m->model, c, 2, ends, x, NULL) != HOC_OK) {
    hoc_error_clear();
    return 0;
  }
  const double *v = m->model->vertices[m->entity[i]].xyz;
  double d0 = hoc_dist3(x, v), d1 = hoc_dist3(x + 3, v), tol = hoc_mesh_collapse_distance(m->model);
  if (d0 <= tol && d1 <= tol && !isnan(near))
    *t = fabs(near - cv->lo) <= fabs(near - cv->hi) ? cv->lo : cv->hi;
  else if (d0 <= tol || d1 <= tol)
    *t = d0 <= d1 ? cv->lo : cv->hi;
  else
    return 0;
  return 1;
}

static hoc_status line_params(hoc_mesh *m, size_t l) {
  const hoc_model *model = m->model;
  int p = m->order, c = m->line_curve[l];
  const hoc_cad_curve *cv = &model->curves[c];
  const size_t *ln = m->line_conn + l * (size_t)(p + 1);
  double ta = NAN, tb = NAN;
  /* an interior node (p >= 2) or a curve-node end tells which copy to take */
  double hint = NAN;
  if (p >= 2 && m->dim[ln[2]] == HOC_ON_CURVE) hint = m->param[2 * ln[2]];
  int oka = m->dim[ln[0]] == HOC_ON_CURVE ? end_param(m, ln[0], c, NAN, &ta) : 0;
  int okb = m->dim[ln[1]] == HOC_ON_CURVE ? end_param(m, ln[1], c, NAN, &tb) : 0;
  if (!oka) oka = end_param(m, ln[0], c, okb ? tb : hint, &ta);
  if (!okb) okb = end_param(m, ln[1], c, oka ? (isnan(hint) ? ta : hint) : hint, &tb);
  HOC_CHECK(oka && okb, HOC_ERR_MISMATCH, "a mesh line on curve %d has an end off that curve",
            cv->tag);
  if (cv->period > 0) tb -= cv->period * floor((tb - ta) / cv->period + 0.5);
  if (cv->period > 0 && ta == tb) tb = ta + cv->period; /* a closed curve in one line */
  m->line_t[2 * l] = ta;
  m->line_t[2 * l + 1] = tb;
  return HOC_OK;
}

/* Lines from the element edges when the source has none: an edge is on a
 * curve when its interior nodes are (p >= 2), or for p = 1 when it joins two
 * nodes of one curve and bounds its face (one triangle of that face on it,
 * or triangles of two faces). */
static hoc_status infer_lines(hoc_mesh *m) {
  const hoc_model *model = m->model;
  int p = m->order, np = m->np;
  hoc_hash use;
  HOC_TRY(hoc_hash_init(&use, 3 * m->n_elems));
  hoc_status status = HOC_OK;
  /* for p = 1: count the triangles of each face on each edge: key edge, value
   * count * (n_faces + 1) + face (-1 if faces differ) */
  size_t *count = hoc_calloc(3 * m->n_elems, sizeof *count);
  int *eface = hoc_calloc(3 * m->n_elems, sizeof *eface);
  size_t n_edges = 0, cap = 64, n_lines = 0;
  size_t *lc = hoc_calloc(cap * (size_t)(p + 1), sizeof *lc);
  int *lcv = hoc_calloc(cap, sizeof *lcv);
  if (!count || !eface || !lc || !lcv) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (size_t e = 0; e < m->n_elems; ++e)
    for (int k = 0; k < 3; ++k) {
      size_t a = m->conn[e * (size_t)np + k], b = m->conn[e * (size_t)np + (k + 1) % 3], id;
      int found;
      HOC_TRY_GOTO(hoc_hash_insert(&use, hoc_pair_key(a, b), n_edges, &found, &id), done);
      if (!found) {
        eface[n_edges] = m->elem_face[e];
        ++n_edges;
      } else if (eface[id] != m->elem_face[e]) {
        eface[id] = -1;
      }
      count[id]++;
    }
  hoc_hash seen;
  HOC_TRY_GOTO(hoc_hash_init(&seen, 64), done);
  for (size_t e = 0; e < m->n_elems; ++e)
    for (int k = 0; k < 3; ++k) {
      const size_t *cn = m->conn + e * (size_t)np;
      size_t a = cn[k], b = cn[(k + 1) % 3];
      int c = -1, ok = 1;
      for (int j = 0; j < p - 1 && ok; ++j) {
        size_t i = cn[edge_first_node(p, k) + j];
        if (m->dim[i] != HOC_ON_CURVE || (c >= 0 && m->entity[i] != c)) ok = 0;
        else c = m->entity[i];
      }
      if (!ok) continue;
      if (p == 1) {
        size_t id = hoc_hash_get(&use, hoc_pair_key(a, b));
        if (!(count[id] == 1 || eface[id] < 0)) continue;
        if (m->dim[a] == HOC_ON_CURVE) c = m->entity[a];
        else if (m->dim[b] == HOC_ON_CURVE) c = m->entity[b];
        else if (m->dim[a] == HOC_ON_VERTEX && m->dim[b] == HOC_ON_VERTEX) {
          int va = m->entity[a], vb = m->entity[b], hits = 0;
          for (int ci = 0; ci < model->n_curves; ++ci) {
            const hoc_cad_curve *cv = &model->curves[ci];
            if ((cv->v0 == va && cv->v1 == vb) || (cv->v0 == vb && cv->v1 == va)) {
              c = ci;
              ++hits;
            }
          }
          if (hits != 1) continue; /* none or ambiguous: leave the edge straight in (u,v) */
        }
      }
      if (c < 0) continue;
      double t;
      if (!end_param(m, a, c, NAN, &t) || !end_param(m, b, c, NAN, &t)) continue;
      int found;
      HOC_TRY_GOTO(hoc_hash_insert(&seen, hoc_pair_key(a, b), n_lines, &found, NULL), done_seen);
      if (found) continue;
      if (n_lines == cap) {
        cap *= 2;
        size_t *l2 = hoc_realloc(lc, cap * (size_t)(p + 1), sizeof *lc);
        if (l2) lc = l2;
        int *c2 = hoc_realloc(lcv, cap, sizeof *lcv);
        if (c2) lcv = c2;
        if (!l2 || !c2) {
          status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
          goto done_seen;
        }
      }
      size_t *ln = lc + n_lines * (size_t)(p + 1);
      ln[0] = a;
      ln[1] = b;
      for (int j = 0; j < p - 1; ++j) ln[2 + j] = cn[edge_first_node(p, k) + j];
      lcv[n_lines++] = c;
    }
done_seen:
  hoc_hash_free(&seen);
  if (status == HOC_OK) {
    m->n_lines = n_lines;
    m->line_conn = lc;
    m->line_curve = lcv;
    lc = NULL;
    lcv = NULL;
  }
done:
  hoc_hash_free(&use);
  free(count);
  free(eface);
  free(lc);
  free(lcv);
  return status;
}

/* Face orientation ------------------------------------------------------- */

/* +1 if most elements of a face turn like phi_u x phi_v at their parametric
 * centroid, -1 if most turn the other way. */
static hoc_status orient_faces(hoc_mesh *m) {
  const hoc_model *model = m->model;
  int np = m->np, nf = model->n_faces;
  long *votes;
  HOC_ALLOC(votes, (size_t)nf);
  hoc_status status = HOC_OK;
  double *uv = hoc_calloc(2 * m->n_elems, sizeof *uv), *du = hoc_calloc(3 * m->n_elems, sizeof *du),
         *dv = hoc_calloc(3 * m->n_elems, sizeof *dv);
  size_t *idx = hoc_calloc(m->n_elems, sizeof *idx);
  if (!uv || !du || !dv || !idx) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  /* elements grouped by face: a counting sort */
  size_t *start = hoc_calloc((size_t)nf + 1, sizeof *start);
  if (!start) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (size_t e = 0; e < m->n_elems; ++e) start[m->elem_face[e] + 1]++;
  for (int f = 0; f < nf; ++f) start[f + 1] += start[f];
  for (size_t e = 0; e < m->n_elems; ++e) idx[start[m->elem_face[e]]++] = e;
  for (int f = nf; f > 0; --f) start[f] = start[f - 1];
  start[0] = 0;
  for (int f = 0; f < nf && status == HOC_OK; ++f) {
    size_t n = start[f + 1] - start[f];
    if (!n) continue;
    for (size_t k = 0; k < n; ++k) {
      const double *eu = m->elem_uv + 2 * idx[start[f] + k] * (size_t)np;
      uv[2 * k] = (eu[0] + eu[2] + eu[4]) / 3;
      uv[2 * k + 1] = (eu[1] + eu[3] + eu[5]) / 3;
    }
    status = hoc_cad_face_eval(model, f, n, uv, NULL, du, dv);
    for (size_t k = 0; k < n && status == HOC_OK; ++k) {
      const size_t *cn = m->conn + idx[start[f] + k] * (size_t)np;
      const double *x0 = m->xyz + 3 * cn[0], *x1 = m->xyz + 3 * cn[1], *x2 = m->xyz + 3 * cn[2];
      double a[3], b[3], c[3], nn[3];
      for (int d = 0; d < 3; ++d) a[d] = x1[d] - x0[d], b[d] = x2[d] - x0[d];
      c[0] = a[1] * b[2] - a[2] * b[1];
      c[1] = a[2] * b[0] - a[0] * b[2];
      c[2] = a[0] * b[1] - a[1] * b[0];
      const double *u = du + 3 * k, *v = dv + 3 * k;
      nn[0] = u[1] * v[2] - u[2] * v[1];
      nn[1] = u[2] * v[0] - u[0] * v[2];
      nn[2] = u[0] * v[1] - u[1] * v[0];
      double dot = c[0] * nn[0] + c[1] * nn[1] + c[2] * nn[2];
      votes[f] += dot > 0 ? 1 : dot < 0 ? -1 : 0;
    }
    m->face_orient[f] = votes[f] >= 0 ? 1 : -1;
  }
  free(start);
done:
  free(votes);
  free(uv);
  free(du);
  free(dv);
  free(idx);
  return status;
}

/* Assembly --------------------------------------------------------------- */

static hoc_status assemble(hoc_model *model, const hoc_mesh_source *src, hoc_mesh **out);

hoc_status hoc_mesh_assemble(hoc_model *model, const hoc_mesh_source *given, hoc_mesh **out) {
  HOC_CHECK(out, HOC_ERR_ARGUMENT, "mesh output is NULL");
  *out = NULL;
  HOC_CHECK(model && given, HOC_ERR_ARGUMENT, "NULL model or mesh source");
  HOC_TRY(validate(model, given));
  hoc_mesh_source src = *given;
  hoc_mesh_collapse collapse;
  HOC_TRY(hoc_mesh_collapse_sides(model, &src, &collapse));
  hoc_status status = assemble(model, &src, out);
  if (status == HOC_OK) (*out)->n_collapsed = collapse.n_dropped;
  hoc_mesh_collapse_free(&collapse);
  return status;
}

hoc_status hoc_mesh_move_nodes(hoc_mesh *m, const unsigned char *which, int *at_pole) {
  HOC_CHECK(m && which && at_pole, HOC_ERR_ARGUMENT, "no mesh or no nodes given");
  hoc_mesh_source none = {0};
  *at_pole = 0;
  HOC_TRY(hoc_mesh_update_xyz_of(m, which));
  HOC_TRY(slot_params(m, &none, INFINITY, which, at_pole));
  hoc_mesh_element_params(m);
  hoc_mesh_per_element_pole_params(m);
  return HOC_OK;
}

static hoc_status assemble(hoc_model *model, const hoc_mesh_source *src, hoc_mesh **out) {
  HOC_CHECK(src->xyz || src->param, HOC_ERR_ARGUMENT, "nodes have neither positions nor parameters");
  double tol = GIVEN_FACE_NODE * model->diagonal;
  /* a given mesh: corners, curve and vertex nodes within `limit` of the
   * model; high-order nodes inside faces within the larger `tol` */
  double limit = INFINITY;
  if (src->given) {
    HOC_TRY(hoc_mesh_given_limit(model, &limit));
    if (limit > tol) tol = limit;
  }
  hoc_mesh *m;
  HOC_TRY(hoc_mesh_alloc(model, src->order, src->n_nodes, src->n_elems, &m));
  hoc_status status = HOC_OK;
  unsigned char *known = hoc_calloc(src->n_nodes, 1), *corner = NULL;
  double *given = NULL;
  if (!known) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto fail;
  }
  m->nodeset = src->nodeset;
  for (size_t i = 0; i < src->n_nodes; ++i) {
    m->dim[i] = src->dim[i];
    m->entity[i] = src->entity[i];
    if (src->xyz) memcpy(m->xyz + 3 * i, src->xyz + 3 * i, 3 * sizeof(double));
    if (src->dim[i] == HOC_ON_VERTEX) {
      known[i] = 1;
    } else if (src->param && (!src->has_param || src->has_param[i])) {
      m->param[2 * i] = src->param[2 * i];
      m->param[2 * i + 1] = src->dim[i] == HOC_ON_FACE ? src->param[2 * i + 1] : 0.0;
      known[i] = 1;
    }
  }
  memcpy(m->conn, src->conn, src->n_elems * (size_t)m->np * sizeof *m->conn);
  memcpy(m->elem_face, src->elem_face, src->n_elems * sizeof *m->elem_face);

  size_t unknown = 0;
  for (size_t i = 0; i < src->n_nodes; ++i) unknown += !known[i];
  if (unknown) {
    HOC_CHECK(src->xyz, HOC_ERR_ARGUMENT, "nodes without parameters need positions");
    HOC_TRY_GOTO(recover_params(m, src, known), fail);
  }
  /* positions from parameters: every node exactly on the CAD */
  if (src->xyz) {
    given = hoc_calloc(3 * src->n_nodes, sizeof *given);
    if (!given) {
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      goto fail;
    }
    memcpy(given, src->xyz, 3 * src->n_nodes * sizeof *given);
  }
  HOC_TRY_GOTO(hoc_mesh_update_xyz(m), fail);
  if (given && src->given) {
    corner = hoc_calloc(src->n_nodes, 1);
    if (!corner) {
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      goto fail;
    }
    for (size_t e = 0; e < src->n_elems; ++e)
      for (int k = 0; k < 3; ++k) corner[src->conn[e * (size_t)m->np + k]] = 1;
  }
  if (given) {
    for (size_t i = 0; i < src->n_nodes; ++i) {
      double d = hoc_dist3(given + 3 * i, m->xyz + 3 * i);
      if (d > m->off_cad) m->off_cad = d;
      if (!src->given) continue; /* hocad's own: positions and parameters from one kernel */
      double allowed = m->dim[i] == HOC_ON_FACE && !corner[i] ? tol : limit;
      if (!(d <= allowed)) {
        const char *what = m->dim[i] == HOC_ON_FACE ? "face" : m->dim[i] == HOC_ON_CURVE ? "curve" : "vertex";
        int tag = m->dim[i] == HOC_ON_FACE     ? model->faces[m->entity[i]].tag
                  : m->dim[i] == HOC_ON_CURVE ? model->curves[m->entity[i]].tag
                                               : model->vertices[m->entity[i]].tag;
        status = HOC_ERROR(HOC_ERR_MISMATCH,
                           "node %zu is %.3g away from its %s %d, more than the %.3g allowed "
                           "(the model's own tolerance is %.3g): the mesh does not match this "
                           "model",
                           node_label(src, i), d, what, tag, allowed, model->tolerance);
        goto fail;
      }
    }
  }
  if (given && src->keep_xyz) memcpy(m->xyz, given, 3 * src->n_nodes * sizeof *given);
  HOC_TRY_GOTO(build_slots(m), fail);
  HOC_TRY_GOTO(slot_params(m, src, src->given ? 2 * limit : INFINITY, NULL, NULL), fail);
  HOC_TRY_GOTO(hoc_mesh_split_pole_slots(m), fail);
  hoc_mesh_element_params(m);
  hoc_mesh_per_element_pole_params(m);

  if (src->n_lines) {
    m->n_lines = src->n_lines;
    m->line_conn = hoc_calloc(src->n_lines * (size_t)(m->order + 1), sizeof *m->line_conn);
    m->line_curve = hoc_calloc(src->n_lines, sizeof *m->line_curve);
    if (!m->line_conn || !m->line_curve) {
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      goto fail;
    }
    memcpy(m->line_conn, src->line_conn,
           src->n_lines * (size_t)(m->order + 1) * sizeof *m->line_conn);
    memcpy(m->line_curve, src->line_curve, src->n_lines * sizeof *m->line_curve);
  } else {
    HOC_TRY_GOTO(infer_lines(m), fail);
  }
  m->line_t = hoc_calloc(2 * m->n_lines + 2, sizeof *m->line_t);
  if (!m->line_t) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto fail;
  }
  for (size_t l = 0; l < m->n_lines; ++l) HOC_TRY_GOTO(line_params(m, l), fail);
  if (src->face_orient)
    memcpy(m->face_orient, src->face_orient, (size_t)model->n_faces * sizeof *m->face_orient);
  else
    HOC_TRY_GOTO(orient_faces(m), fail);
  free(known);
  free(corner);
  free(given);
  *out = m;
  return HOC_OK;
fail:
  free(known);
  free(corner);
  free(given);
  hoc_mesh_destroy(&m);
  return status;
}
