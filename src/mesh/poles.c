/* Element parameters and pole slots of an assembled mesh: each element's
 * (u,v), unwrapped around a regular node of the element, and one slot per
 * element at each pole of its face, holding the element's own parameters.
 * Called by hoc_mesh_assemble (assemble.c) once the slots are built.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"

#include <stdlib.h>
#include <string.h>

/* A slot at a pole of its face whose node is shared with other faces (on a
 * CAD vertex or curve: a degenerate one, a vertex at an apex). */
static int pole_slot(const hoc_mesh *m, size_t s) {
  return m->slot_pole[s] && m->dim[m->slot_node[s]] != HOC_ON_FACE;
}

/* One slot per element at each pole: the first element using a pole slot
 * keeps it, every further one gets a copy (same node, face, parameters and
 * pole bits). At a pole phi_u x phi_v = 0 and the normal is the limit of
 * the surface's along the direction of approach: the same from every
 * direction where the surface is smooth there (a sphere's pole), but not
 * at the apex of a cone or any other point where the surface has no
 * tangent plane. Each element's slot then holds the element's own
 * direction (hoc_mesh_per_element_pole_params), so that whatever reads normals
 * through elem_slot (measuring, the optimiser, pictures) sees the normal
 * of the surface on that element's side of the pole. */
hoc_status hoc_mesh_split_pole_slots(hoc_mesh *m) {
  size_t n = m->n_slots, extra = 0, np = (size_t)m->np;
  unsigned char *claimed = hoc_calloc(n + 1, 1);
  HOC_CHECK(claimed, HOC_ERR_MEMORY, "out of memory");
  for (size_t x = 0; x < m->n_elems * np; ++x) {
    size_t s = m->elem_slot[x];
    if (!pole_slot(m, s)) continue;
    extra += claimed[s];
    claimed[s] = 1;
  }
  if (!extra) {
    free(claimed);
    return HOC_OK;
  }
  size_t total = n + extra;
  size_t *node = hoc_realloc(m->slot_node, total, sizeof *node);
  if (node) m->slot_node = node;
  int *face = hoc_realloc(m->slot_face, total, sizeof *face);
  if (face) m->slot_face = face;
  double *uv = hoc_realloc(m->slot_uv, 2 * total, sizeof *uv);
  if (uv) m->slot_uv = uv;
  unsigned char *pole = hoc_realloc(m->slot_pole, total, sizeof *pole);
  if (pole) m->slot_pole = pole;
  if (!node || !face || !uv || !pole) {
    free(claimed);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory for %zu slots", total);
  }
  memset(claimed, 0, n);
  for (size_t x = 0; x < m->n_elems * np; ++x) {
    size_t s = m->elem_slot[x];
    if (!pole_slot(m, s)) continue;
    if (!claimed[s]) {
      claimed[s] = 1;
      continue;
    }
    size_t c = m->n_slots++;
    node[c] = node[s];
    face[c] = face[s];
    uv[2 * c] = uv[2 * s];
    uv[2 * c + 1] = uv[2 * s + 1];
    pole[c] = pole[s];
    m->elem_slot[x] = c;
  }
  free(claimed);
  return HOC_OK;
}

/* The arbitrary coordinate of each element's pole slot: the element's own
 * (hoc_mesh_element_params), wrapped into the face's range. At a pole
 * inside the face's range (a pinch: pinch.c) the element lies on one side
 * of the pole's line: HOC_POLE_BELOW or HOC_POLE_ABOVE says which. */
void hoc_mesh_per_element_pole_params(hoc_mesh *m) {
  size_t np = (size_t)m->np;
  for (size_t x = 0; x < m->n_elems * np; ++x) {
    size_t s = m->elem_slot[x];
    if (!pole_slot(m, s)) continue;
    const hoc_cad_face *f = &m->model->faces[m->slot_face[s]];
    double uv[2] = {m->elem_uv[2 * x], m->elem_uv[2 * x + 1]};
    hoc_cad_face_wrap(f, uv);
    for (int d = 0; d < 2; ++d)
      if (m->slot_pole[s] & (1 << d)) m->slot_uv[2 * s + (size_t)d] = uv[d];
    for (int d = 0; d < 2; ++d) {
      /* d: the pole line's fixed coordinate */
      if (!(m->slot_pole[s] & (1 << (1 - d))) || (m->slot_pole[s] & (1 << d))) continue;
      double at = m->slot_uv[2 * s + (size_t)d], range = f->hi[d] - f->lo[d];
      if (!(at > f->lo[d] + 1e-9 * range && at < f->hi[d] - 1e-9 * range)) continue;
      size_t e = x / np;
      const double *euv = m->elem_uv + 2 * e * np;
      double mean = 0;
      for (int k = 0; k < 3; ++k) mean += euv[2 * k + d] / 3;
      m->slot_pole[s] &= (unsigned char)~((HOC_POLE_BELOW | HOC_POLE_ABOVE) << d);
      if (mean < at) m->slot_pole[s] |= (unsigned char)(HOC_POLE_BELOW << d);
      if (mean > at) m->slot_pole[s] |= (unsigned char)(HOC_POLE_ABOVE << d);
    }
  }
}

/* Each pole node of an element (slots sl, parameters uv) takes the mean of
 * the element's regular vertices in its arbitrary coordinate. */
static void pole_means(const hoc_mesh *m, const size_t *sl, double *uv) {
  for (int k = 0; k < m->np; ++k) {
    unsigned char pole = m->slot_pole[sl[k]];
    for (int d = 0; d < 2; ++d) {
      if (!(pole & (1 << d))) continue;
      double sum = 0;
      int cnt = 0;
      for (int j = 0; j < 3; ++j)
        if (j != k && !(m->slot_pole[sl[j]] & (1 << d))) {
          sum += uv[2 * j + d];
          ++cnt;
        }
      if (cnt) uv[2 * k + d] = sum / cnt;
    }
  }
}

void hoc_mesh_pole_params_follow(hoc_mesh *m) {
  size_t np = (size_t)m->np;
  for (size_t e = 0; e < m->n_elems; ++e)
    pole_means(m, m->elem_slot + e * np, m->elem_uv + 2 * e * np);
  hoc_mesh_per_element_pole_params(m);
}

/* Element parameters, unwrapped around a regular node of the element; pole
 * nodes take the mean of the element's regular vertices in the arbitrary
 * coordinate. */
void hoc_mesh_element_params(hoc_mesh *m) {
  const hoc_model *model = m->model;
  int np = m->np;
  for (size_t e = 0; e < m->n_elems; ++e) {
    const hoc_cad_face *f = &model->faces[m->elem_face[e]];
    const size_t *sl = m->elem_slot + e * (size_t)np;
    double *uv = m->elem_uv + 2 * e * (size_t)np;
    int anchor = -1;
    for (int k = 0; k < np && anchor < 0; ++k)
      if (m->dim[m->slot_node[sl[k]]] == HOC_ON_FACE) anchor = k;
    for (int k = 0; k < np && anchor < 0; ++k)
      if (!m->slot_pole[sl[k]]) anchor = k;
    if (anchor < 0) anchor = 0;
    const double *ref = m->slot_uv + 2 * sl[anchor];
    for (int k = 0; k < np; ++k) {
      uv[2 * k] = m->slot_uv[2 * sl[k]];
      uv[2 * k + 1] = m->slot_uv[2 * sl[k] + 1];
      hoc_cad_face_unwrap_near(f, ref, uv + 2 * k);
    }
    pole_means(m, sl, uv);
  }
}
