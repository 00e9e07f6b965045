/* Quality of a whole mesh: CAD normals at the nodes, the element kernel in
 * parallel, and the statistics of the paper's Table 2.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "mesh/mesh.h"
#include "quality/quality.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* q of the elements flagged in which[n_elems] (all if NULL), in parallel;
 * normals from the CAD at their slots only. */
static hoc_status measure_elements(const hoc_mesh *mesh, const hoc_quality_tables *t,
                                   hoc_measure measure, const unsigned char *which, double *q) {
  size_t ne = mesh->n_elems;
  int np = mesh->np;
  double *normal;
  HOC_ALLOC(normal, 3 * mesh->n_slots + 3);
  unsigned char *slots = NULL;
  hoc_status status = HOC_OK;
  if (which) {
    slots = hoc_calloc(mesh->n_slots + 1, 1);
    if (!slots) status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    for (size_t e = 0; e < ne && slots; ++e)
      for (int i = 0; i < np && which[e]; ++i) slots[mesh->elem_slot[e * (size_t)np + i]] = 1;
  }
  if (status == HOC_OK) status = hoc_mesh_slot_normals_of(mesh, slots, normal);
  int alloc_failed = 0;
  if (status == HOC_OK) {
#pragma omp parallel
    {
      double *x = malloc(6 * (size_t)np * sizeof *x);
      if (!x) {
#pragma omp atomic write
        alloc_failed = 1;
      }
      double *n = x ? x + 3 * np : NULL;
#pragma omp for schedule(dynamic, 64)
      for (size_t e = 0; e < ne; ++e) {
        if (!x || (which && !which[e])) continue;
        const size_t *cn = mesh->conn + e * (size_t)np;
        const size_t *sl = mesh->elem_slot + e * (size_t)np;
        for (int i = 0; i < np; ++i) {
          memcpy(x + 3 * i, mesh->xyz + 3 * cn[i], 3 * sizeof *x);
          memcpy(n + 3 * i, normal + 3 * sl[i], 3 * sizeof *n);
        }
        double eta;
        q[e] = hoc_element_quality(t, measure, x, n, &eta, NULL);
      }
      free(x);
    }
  }
  free(slots);
  free(normal);
  if (alloc_failed) return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  return status;
}

static hoc_status check_measure(hoc_measure measure) {
  HOC_CHECK(measure == HOC_MEASURE_SHAPE || measure == HOC_MEASURE_ODDY, HOC_ERR_ARGUMENT,
            "unknown distortion measure %d", (int)measure);
  return HOC_OK;
}

/* q of every element with tables t, in parallel; normals from the CAD. */
hoc_status hoc_mesh_measure_tables(const hoc_mesh *mesh, const hoc_quality_tables *t,
                                   hoc_measure measure, double *q) {
  HOC_CHECK(t->np == mesh->np, HOC_ERR_ARGUMENT, "tables of order %d for a mesh of order %d",
            t->p, mesh->order);
  return measure_elements(mesh, t, measure, NULL, q);
}

hoc_status hoc_mesh_measure_some(const hoc_mesh *mesh, hoc_measure measure,
                                 const unsigned char *elements, double *q) {
  HOC_CHECK(mesh && elements && q, HOC_ERR_ARGUMENT, "NULL argument");
  HOC_TRY(check_measure(measure));
  const hoc_quality_tables *t;
  HOC_TRY(hoc_quality_tables_get(mesh->order, mesh->nodeset, &t));
  return measure_elements(mesh, t, measure, elements, q);
}

void hoc_quality_stats_from(const double *q, size_t ne, int order, hoc_quality_stats *stats) {
  double mn = INFINITY, mx = -INFINITY, sum = 0, sum2 = 0;
  size_t nt = 0;
  for (size_t e = 0; e < ne; ++e) {
    mn = fmin(mn, q[e]);
    mx = fmax(mx, q[e]);
    sum += q[e];
    nt += q[e] == 0.0;
  }
  double mean = ne ? sum / (double)ne : 0;
  for (size_t e = 0; e < ne; ++e) sum2 += (q[e] - mean) * (q[e] - mean);
  stats->elements = ne;
  stats->order = order;
  stats->min = ne ? mn : 0;
  stats->max = ne ? mx : 0;
  stats->mean = mean;
  stats->std = ne ? sqrt(sum2 / (double)ne) : 0;
  stats->tangled = nt;
  stats->seconds = 0;
}

hoc_status hoc_mesh_measure(const hoc_mesh *mesh, hoc_measure measure, double *quality,
                            unsigned char *tangled, hoc_quality_stats *stats) {
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "no mesh given");
  HOC_TRY(check_measure(measure));
  double t0 = hoc_now();
  const hoc_quality_tables *t;
  HOC_TRY(hoc_quality_tables_get(mesh->order, mesh->nodeset, &t));
  size_t ne = mesh->n_elems;
  double *q = quality;
  if (!q) {
    q = hoc_calloc(ne, sizeof *q);
    HOC_CHECK(q, HOC_ERR_MEMORY, "out of memory");
  }
  hoc_status status = hoc_mesh_measure_tables(mesh, t, measure, q);
  if (status == HOC_OK && tangled)
    for (size_t e = 0; e < ne; ++e) tangled[e] = q[e] == 0.0;
  if (status == HOC_OK && stats) {
    hoc_quality_stats_from(q, ne, mesh->order, stats);
    stats->seconds = hoc_now() - t0;
  }
  if (q != quality) free(q);
  return status;
}
