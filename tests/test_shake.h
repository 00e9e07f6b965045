/* Random moves of a mesh's face nodes for the optimiser's tests: the same
 * moves on every machine (a fixed seed).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#ifndef HOC_TEST_SHAKE_H
#define HOC_TEST_SHAKE_H

#include "mesh/mesh.h"
#include "test_util.h"

#include <stdlib.h>
#include <string.h>

/* A 64-bit linear congruential generator: uniform in [0, 1). */
static inline double shake_uniform(unsigned long long *state) {
  *state = *state * 6364136223846793005ULL + 1442695040888963407ULL;
  return (double)(*state >> 11) / 9007199254740992.0;
}

/* Every face node of m moved by up to amp * (du, dv) in (u, v), in node
 * order (its element copies and its slot follow), then every position
 * evaluated from the parameters. */
static inline void shake(hoc_mesh *m, double amp, double du, double dv, unsigned long long seed) {
  size_t np = (size_t)m->np;
  double *d = calloc(2 * m->n_nodes + 2, sizeof *d);
  CHECK(d != NULL);
  if (!d) return;
  for (size_t i = 0; i < m->n_nodes; ++i) {
    if (m->dim[i] != HOC_ON_FACE) continue;
    d[2 * i] = amp * du * (2 * shake_uniform(&seed) - 1);
    d[2 * i + 1] = amp * dv * (2 * shake_uniform(&seed) - 1);
    m->param[2 * i] += d[2 * i];
    m->param[2 * i + 1] += d[2 * i + 1];
  }
  for (size_t e = 0; e < m->n_elems; ++e)
    for (size_t k = 0; k < np; ++k) {
      size_t i = m->conn[e * np + k];
      m->elem_uv[2 * (e * np + k)] += d[2 * i];
      m->elem_uv[2 * (e * np + k) + 1] += d[2 * i + 1];
      if (m->dim[i] == HOC_ON_FACE)
        memcpy(m->slot_uv + 2 * m->elem_slot[e * np + k], m->param + 2 * i, 2 * sizeof *d);
    }
  free(d);
  CHECK_OK(hoc_mesh_update_xyz(m));
}

#endif
