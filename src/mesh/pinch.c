/* Pinches: iso-lines inside a face's (u, v) whose image is one point, and
 * the elements across them.
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * A B-spline patch whose control row collapses to a point inside it (a
 * bow tie, a spline surface of an IGES file pinched between two lobes)
 * maps a whole line u = c (or v = c) to that point. An element whose
 * (u, v) crosses the line is curved through the point: its Jacobian
 * vanishes along the line inside it, and the more nodes it has there, the
 * closer its q comes to 0. Only a mesh with nodes on the line avoids it. */
#include "core/geometry.h"
#include "mesh/mesh.h"

#include <math.h>
#include <stdlib.h>

/* Iso-lines probed across each direction, points along each, and golden
 * section steps that find the narrowest line near each probed minimum. */
enum { LINES = 64, ALONG = 17, REFINE = 40 };

/* The largest distance of the image of face f's iso-line (dir 0: u = c,
 * 1: v = c) from its first point, over the face's range of the other
 * parameter. */
static hoc_status spread(const hoc_model *model, int f, int dir, double c, double *s) {
  const hoc_cad_face *face = &model->faces[f];
  int o = 1 - dir;
  double uv[2 * ALONG], xyz[3 * ALONG];
  for (int k = 0; k < ALONG; ++k) {
    uv[2 * k + dir] = c;
    uv[2 * k + o] = face->lo[o] + (face->hi[o] - face->lo[o]) * k / (ALONG - 1);
  }
  HOC_TRY(hoc_cad_face_eval(model, f, ALONG, uv, xyz, NULL, NULL));
  *s = 0;
  for (int k = 1; k < ALONG; ++k)
    *s = fmax(*s, hoc_dist3(xyz + 3 * k, xyz));
  return HOC_OK;
}

hoc_status hoc_face_pinches(const hoc_model *model, int f, double share, hoc_pinch *pinch, int max,
                           int *n) {
  HOC_CHECK(model && pinch && n && f >= 0 && f < model->n_faces && max > 0 && share > 0,
            HOC_ERR_ARGUMENT, "pinch search: bad argument");
  *n = 0;
  const hoc_cad_face *face = &model->faces[f];
  double size = 0;
  for (int k = 0; k < 3; ++k)
    size = fmax(size, face->bbox[k + 3] - face->bbox[k]);
  double tol = share * size;
  for (int dir = 0; dir < 2; ++dir) {
    double lo = face->lo[dir], hi = face->hi[dir], h = (hi - lo) / LINES, s[LINES + 1];
    if (!(hi > lo)) continue;
    for (int i = 0; i <= LINES; ++i)
      HOC_TRY(spread(model, f, dir, lo + i * h, &s[i]));
    for (int i = 1; i < LINES && *n < max; ++i) {
      /* a minimum, not a plateau (a cylinder's lines all spread alike) */
      if (!(s[i] <= s[i - 1] && s[i] <= s[i + 1] && (s[i] < s[i - 1] || s[i] < s[i + 1])))
        continue;
      /* the narrowest line between the neighbouring probes */
      const double g = 0.5 * (sqrt(5.0) - 1);
      double a = lo + (i - 1) * h, b = lo + (i + 1) * h;
      double x1 = b - g * (b - a), x2 = a + g * (b - a), f1, f2;
      HOC_TRY(spread(model, f, dir, x1, &f1));
      HOC_TRY(spread(model, f, dir, x2, &f2));
      for (int k = 0; k < REFINE; ++k) {
        if (f1 <= f2) {
          b = x2, x2 = x1, f2 = f1, x1 = b - g * (b - a);
          HOC_TRY(spread(model, f, dir, x1, &f1));
        } else {
          a = x1, x1 = x2, f1 = f2, x2 = a + g * (b - a);
          HOC_TRY(spread(model, f, dir, x2, &f2));
        }
      }
      double c = f1 <= f2 ? x1 : x2, sc = fmin(f1, f2);
      /* inside the face: a collapsed side is a pole (hoc_cad_face.pole) */
      if (sc < tol && c > lo + 1e-9 * (hi - lo) && c < hi - 1e-9 * (hi - lo)) {
        pinch[*n].dir = dir;
        pinch[*n].c = c;
        ++*n;
      }
    }
  }
  return HOC_OK;
}

int hoc_mesh_element_crosses_pinch(const hoc_mesh *mesh, size_t e, const hoc_pinch *pinch,
                                   int n) {
  const hoc_cad_face *face = &mesh->model->faces[mesh->elem_face[e]];
  const double *uv = mesh->elem_uv + 2 * (size_t)mesh->np * e;
  for (int k = 0; k < n; ++k) {
    int d = pinch[k].dir;
    double eps = 1e-9 * (face->hi[d] - face->lo[d]);
    /* an element across a seam has its parameters unwrapped past it */
    for (int w = -1; w <= 1; ++w) {
      if (w && !(face->period[d] > 0)) continue;
      double c = pinch[k].c + w * face->period[d];
      int below = 0, above = 0;
      for (int i = 0; i < mesh->np; ++i) {
        below |= uv[2 * i + d] < c - eps;
        above |= uv[2 * i + d] > c + eps;
      }
      if (below && above) return 1;
    }
  }
  return 0;
}

hoc_status hoc_pinch_table_init(hoc_pinch_table *t, const hoc_model *model, double share,
                                int max) {
  HOC_CHECK(t && model && share > 0 && max > 0, HOC_ERR_ARGUMENT, "pinch table: bad argument");
  size_t nf = (size_t)model->n_faces;
  t->share = share;
  t->max = max;
  t->n = hoc_calloc(nf + 1, sizeof *t->n);
  t->line = hoc_calloc(nf * (size_t)max + 1, sizeof *t->line);
  if (!t->n || !t->line) {
    hoc_pinch_table_free(t);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  for (size_t f = 0; f < nf; ++f)
    t->n[f] = -1;
  return HOC_OK;
}

void hoc_pinch_table_free(hoc_pinch_table *t) {
  if (!t) return;
  free(t->n);
  free(t->line);
  t->n = NULL;
  t->line = NULL;
}

hoc_status hoc_mesh_element_across_pinch(const hoc_mesh *mesh, size_t e, hoc_pinch_table *t,
                                         int *across) {
  int f = mesh->elem_face[e];
  hoc_pinch *line = t->line + (size_t)f * (size_t)t->max;
  if (t->n[f] < 0) HOC_TRY(hoc_face_pinches(mesh->model, f, t->share, line, t->max, &t->n[f]));
  *across = hoc_mesh_element_crosses_pinch(mesh, e, line, t->n[f]);
  return HOC_OK;
}
