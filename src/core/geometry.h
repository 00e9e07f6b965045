/* Small geometric helpers shared by the mesh, the CAD layer and the
 * optimiser.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#ifndef HOC_CORE_GEOMETRY_H
#define HOC_CORE_GEOMETRY_H

#include <math.h>

/* Euclidean distance between points a[3] and b[3]. */
static inline double hoc_dist3(const double *a, const double *b) {
  double dx = a[0] - b[0], dy = a[1] - b[1], dz = a[2] - b[2];
  return sqrt(dx * dx + dy * dy + dz * dz);
}

/* Dot product of a[3] and b[3]. */
static inline double hoc_dot3(const double *a, const double *b) {
  return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Cross product c[3] = a[3] x b[3] (c may not alias a or b). */
static inline void hoc_cross3(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

#endif
