/* gmsh MSH 4.1 ASCII writer: entities, parametric nodes grouped by entity,
 * lines and high-order triangles.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

int hoc_msh_triangle_type(int p) {
  static const int types[11] = {0, 2, 9, 21, 23, 25, 42, 43, 44, 45, 46};
  return p >= 1 && p <= 10 ? types[p] : 0;
}

int hoc_msh_line_type(int p) {
  static const int types[11] = {0, 1, 8, 26, 27, 28, 62, 63, 64, 65, 66};
  return p >= 1 && p <= 10 ? types[p] : 0;
}

static void put_bbox(FILE *fp, const double *bb) {
  fprintf(fp, "%.17g %.17g %.17g %.17g %.17g %.17g", bb[0], bb[1], bb[2], bb[3], bb[4], bb[5]);
}

/* Stable order of the items by (key1, key2) with a merge sort. */
static void sort_by_keys(size_t n, const int *k1, const int *k2, size_t *order, size_t *tmp) {
  for (size_t i = 0; i < n; ++i) order[i] = i;
  for (size_t w = 1; w < n; w *= 2) {
    for (size_t lo = 0; lo < n; lo += 2 * w) {
      size_t mid = lo + w < n ? lo + w : n, hi = lo + 2 * w < n ? lo + 2 * w : n;
      size_t a = lo, b = mid, o = lo;
      while (a < mid || b < hi) {
        int take_a = b >= hi;
        if (!take_a && a < mid) {
          size_t x = order[a], y = order[b];
          take_a = k1[x] < k1[y] || (k1[x] == k1[y] && k2[x] <= k2[y]);
        }
        tmp[o++] = take_a ? order[a++] : order[b++];
      }
    }
    memcpy(order, tmp, n * sizeof *order);
  }
}

hoc_status hoc_msh_write(const char *path, const hoc_msh_write_data *d) {
  HOC_CHECK(d && path, HOC_ERR_ARGUMENT, "NULL argument");
  int p = d->order, np = (p + 1) * (p + 2) / 2;
  HOC_CHECK(hoc_msh_triangle_type(p), HOC_ERR_UNSUPPORTED,
            "gmsh's MSH format has no triangle of order %d (at most 10)", p);
  for (size_t i = 0; i < d->n_nodes; ++i)
    HOC_CHECK(isfinite(d->xyz[3 * i]) && isfinite(d->xyz[3 * i + 1]) && isfinite(d->xyz[3 * i + 2]) &&
                  isfinite(d->param[2 * i]) && isfinite(d->param[2 * i + 1]),
              HOC_ERR_ARGUMENT, "node %zu has a non-finite coordinate: nothing written", i + 1);
  size_t nn = d->n_nodes;
  size_t *order = hoc_calloc(nn + 1, sizeof *order), *tmp = hoc_calloc(nn + 1, sizeof *tmp);
  size_t *tag = hoc_calloc(nn + 1, sizeof *tag);
  size_t ne = d->n_tris + d->n_lines;
  size_t *eorder = hoc_calloc(ne + 1, sizeof *eorder), *etmp = hoc_calloc(ne + 1, sizeof *etmp);
  int *ek1 = hoc_calloc(ne + 1, sizeof *ek1), *ek2 = hoc_calloc(ne + 1, sizeof *ek2);
  hoc_outfile out = {0};
  hoc_status status = HOC_OK;
  if (!order || !tmp || !tag || !eorder || !etmp || !ek1 || !ek2) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory writing '%s'", path);
    goto done;
  }
  sort_by_keys(nn, d->node_dim, d->node_entity_tag, order, tmp);
  for (size_t k = 0; k < nn; ++k) tag[order[k]] = k + 1;
  /* elements: lines (dim 1) then triangles (dim 2), by entity */
  for (size_t e = 0; e < d->n_lines; ++e) ek1[e] = 1, ek2[e] = d->line_curve_tag[e];
  for (size_t e = 0; e < d->n_tris; ++e) ek1[d->n_lines + e] = 2, ek2[d->n_lines + e] = d->tri_surface_tag[e];
  sort_by_keys(ne, ek1, ek2, eorder, etmp);

  HOC_TRY_GOTO(hoc_outfile_open(&out, path), done);
  FILE *fp = out.fp;
  fprintf(fp, "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Entities\n%d %d %d 0\n", d->n_points,
          d->n_curves, d->n_surfaces);
  for (int i = 0; i < d->n_points; ++i)
    fprintf(fp, "%d %.17g %.17g %.17g 0\n", d->point_tag[i], d->point_xyz[3 * i],
            d->point_xyz[3 * i + 1], d->point_xyz[3 * i + 2]);
  for (int i = 0; i < d->n_curves; ++i) {
    fprintf(fp, "%d ", d->curve_tag[i]);
    put_bbox(fp, d->curve_bbox + 6 * i);
    int a = d->curve_bnd_start[i], b = d->curve_bnd_start[i + 1];
    fprintf(fp, " 0 %d", b - a);
    for (int k = a; k < b; ++k) fprintf(fp, " %d", d->curve_bnd[k]);
    fputc('\n', fp);
  }
  for (int i = 0; i < d->n_surfaces; ++i) {
    fprintf(fp, "%d ", d->surface_tag[i]);
    put_bbox(fp, d->surface_bbox + 6 * i);
    int a = d->surface_bnd_start[i], b = d->surface_bnd_start[i + 1];
    fprintf(fp, " 0 %d", b - a);
    for (int k = a; k < b; ++k) fprintf(fp, " %d", d->surface_bnd[k]);
    fputc('\n', fp);
  }
  fprintf(fp, "$EndEntities\n$Nodes\n");
  size_t nblocks = 0;
  for (size_t k = 0; k < nn; ++k)
    if (k == 0 || d->node_dim[order[k]] != d->node_dim[order[k - 1]] ||
        d->node_entity_tag[order[k]] != d->node_entity_tag[order[k - 1]])
      ++nblocks;
  fprintf(fp, "%zu %zu %zu %zu\n", nblocks, nn, nn ? (size_t)1 : 0, nn);
  for (size_t a = 0; a < nn;) {
    size_t b = a;
    int dim = d->node_dim[order[a]], etag = d->node_entity_tag[order[a]];
    while (b < nn && d->node_dim[order[b]] == dim && d->node_entity_tag[order[b]] == etag) ++b;
    fprintf(fp, "%d %d %d %zu\n", dim, etag, dim > 0, b - a);
    for (size_t k = a; k < b; ++k) fprintf(fp, "%zu\n", k + 1);
    for (size_t k = a; k < b; ++k) {
      size_t i = order[k];
      const double *x = d->xyz + 3 * i, *u = d->param + 2 * i;
      if (dim == 2) fprintf(fp, "%.17g %.17g %.17g %.17g %.17g\n", x[0], x[1], x[2], u[0], u[1]);
      else if (dim == 1) fprintf(fp, "%.17g %.17g %.17g %.17g\n", x[0], x[1], x[2], u[0]);
      else fprintf(fp, "%.17g %.17g %.17g\n", x[0], x[1], x[2]);
    }
    a = b;
  }
  fprintf(fp, "$EndNodes\n$Elements\n");
  size_t eblocks = 0;
  for (size_t k = 0; k < ne; ++k)
    if (k == 0 || ek1[eorder[k]] != ek1[eorder[k - 1]] || ek2[eorder[k]] != ek2[eorder[k - 1]]) ++eblocks;
  fprintf(fp, "%zu %zu %zu %zu\n", eblocks, ne, ne ? (size_t)1 : 0, ne);
  for (size_t a = 0; a < ne;) {
    size_t b = a;
    int dim = ek1[eorder[a]], etag = ek2[eorder[a]];
    while (b < ne && ek1[eorder[b]] == dim && ek2[eorder[b]] == etag) ++b;
    fprintf(fp, "%d %d %d %zu\n", dim, etag, dim == 2 ? hoc_msh_triangle_type(p) : hoc_msh_line_type(p),
            b - a);
    for (size_t k = a; k < b; ++k) {
      size_t e = eorder[k];
      const size_t *cn = dim == 2 ? d->tri_nodes + (e - d->n_lines) * (size_t)np
                                  : d->line_nodes + e * (size_t)(p + 1);
      int cnt = dim == 2 ? np : p + 1;
      fprintf(fp, "%zu", k + 1);
      for (int j = 0; j < cnt; ++j) fprintf(fp, " %zu", tag[cn[j]]);
      fputc('\n', fp);
    }
    a = b;
  }
  fprintf(fp, "$EndElements\n");
  status = hoc_outfile_commit(&out);
done:
  hoc_outfile_abort(&out);
  free(order);
  free(tmp);
  free(tag);
  free(eorder);
  free(etmp);
  free(ek1);
  free(ek2);
  return status;
}
