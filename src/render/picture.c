/* Public picture functions: meshes (with or without their CAD model) to the
 * renderer's arrays.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#include "basis/basis.h"
#include "core/cli_support.h"
#include "io/io.h"
#include "mesh/mesh.h"
#include "quality/quality.h"
#include "render/render.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

enum { MAX_VIEWS = 16 };

void hoc_picture_options_default(hoc_picture_options *options) {
  if (options) memset(options, 0, sizeof *options);
}

static void to_render_options(const hoc_picture_options *o, hoc_render_options *r) {
  memset(r, 0, sizeof *r);
  if (!o) return;
  r->width = o->width;
  r->height = o->height;
  memcpy(r->view, o->view, sizeof r->view);
  r->zoom_worst = o->zoom_worst;
  r->no_edges = o->no_edges;
  r->transparent = o->transparent;
}

typedef hoc_status (*draw_fn)(const char *, const hoc_render_mesh *, int,
                              const hoc_render_options *);

static hoc_status draw_meshes(draw_fn draw, const char *path, int n,
                              const hoc_mesh *const *meshes, const double *const *quality,
                              const char *const *titles, const hoc_picture_options *options) {
  HOC_CHECK(path && *path, HOC_ERR_ARGUMENT, "no picture file name given");
  HOC_CHECK(n >= 1 && n <= MAX_VIEWS, HOC_ERR_ARGUMENT, "%d meshes to draw (1..%d)", n, MAX_VIEWS);
  HOC_CHECK(meshes, HOC_ERR_ARGUMENT, "no meshes given");
  hoc_render_mesh views[MAX_VIEWS];
  double *rs[MAX_VIEWS] = {0};
  hoc_status status = HOC_OK;
  for (int k = 0; k < n && status == HOC_OK; ++k) {
    const hoc_mesh *m = meshes[k];
    if (!m) {
      status = HOC_ERROR(HOC_ERR_ARGUMENT, "mesh %d to draw is missing", k + 1);
      break;
    }
    rs[k] = malloc(2 * (size_t)m->np * sizeof *rs[k]);
    if (!rs[k]) {
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      break;
    }
    status = hoc_tri_nodes(m->order, m->nodeset, rs[k]);
    views[k] = (hoc_render_mesh){.order = m->order,
                                 .rs = rs[k],
                                 .n_nodes = m->n_nodes,
                                 .xyz = m->xyz,
                                 .n_elems = m->n_elems,
                                 .conn = m->conn,
                                 .q = quality ? quality[k] : NULL,
                                 .title = titles ? titles[k] : NULL};
  }
  hoc_render_options ro;
  to_render_options(options, &ro);
  if (ro.width == 0 && ro.height == 0 && n > 1) {
    /* side by side: panels about square rather than thin strips */
    ro.width = n * 900 > 3600 ? 3600 : n * 900;
    ro.height = 1000;
  }
  if (status == HOC_OK) status = draw(path, views, n, &ro);
  for (int k = 0; k < n; ++k) free(rs[k]);
  return status;
}

hoc_status hoc_picture_png(const char *path, int n, const hoc_mesh *const *meshes,
                           const double *const *quality, const char *const *titles,
                           const hoc_picture_options *options) {
  return draw_meshes(hoc_render_png, path, n, meshes, quality, titles, options);
}

hoc_status hoc_histogram_png(const char *path, int n, const hoc_mesh *const *meshes,
                             const double *const *quality, const char *const *titles,
                             const hoc_picture_options *options) {
  HOC_CHECK(quality, HOC_ERR_ARGUMENT, "a histogram needs the quality of each mesh");
  return draw_meshes(hoc_render_histogram_png, path, n, meshes, quality, titles, options);
}

/* q of every element of a raw mesh, each measured against the normal of the
 * plane through its corners (no CAD). */
static hoc_status measure_raw(const hoc_msh_raw *raw, hoc_measure measure, double *q) {
  const hoc_quality_tables *t;
  HOC_TRY(hoc_quality_tables_get(raw->order, HOC_NODES_EQUISPACED, &t));
  const int np = t->np;
  hoc_status status = HOC_OK;
#pragma omp parallel
  {
    double *x = malloc(6 * (size_t)np * sizeof *x), *nrm = x ? x + 3 * np : NULL;
    if (!x) {
#pragma omp critical(hoc_picture_status)
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    }
#pragma omp for schedule(dynamic, 256)
    for (size_t e = 0; e < raw->n_tris; ++e) {
      if (!x) continue;
      const size_t *cn = raw->tri_nodes + e * (size_t)np;
      for (int i = 0; i < np; ++i) memcpy(x + 3 * i, raw->xyz + 3 * cn[i], 3 * sizeof *x);
      double a[3], b[3], c[3];
      for (int d = 0; d < 3; ++d) a[d] = x[3 + d] - x[d], b[d] = x[6 + d] - x[d];
      c[0] = a[1] * b[2] - a[2] * b[1];
      c[1] = a[2] * b[0] - a[0] * b[2];
      c[2] = a[0] * b[1] - a[1] * b[0];
      double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
      if (!(len > 0)) { /* corners on a line: no plane to measure in */
        q[e] = 0;
        continue;
      }
      for (int i = 0; i < np; ++i)
        for (int d = 0; d < 3; ++d) nrm[3 * i + d] = c[d] / len;
      double eta, smin;
      q[e] = hoc_element_quality(t, measure, x, nrm, &eta, &smin);
    }
    free(x);
  }
  return status;
}

hoc_status hoc_picture_msh_file(const char *msh_path, hoc_measure measure, const char *png_path,
                                const char *histogram_path, const hoc_picture_options *options,
                                hoc_quality_stats *stats) {
  HOC_CHECK(msh_path && *msh_path, HOC_ERR_ARGUMENT, "no mesh file given");
  HOC_CHECK(png_path && *png_path, HOC_ERR_ARGUMENT, "no picture file name given");
  HOC_CHECK(measure == HOC_MEASURE_SHAPE || measure == HOC_MEASURE_ODDY, HOC_ERR_ARGUMENT,
            "unknown distortion measure %d", (int)measure);
  hoc_msh_raw raw;
  double *q = NULL, *rs = NULL;
  HOC_TRY(hoc_msh_read(msh_path, &raw));
  hoc_status status = HOC_OK;
  if (!raw.n_tris) {
    status = HOC_ERROR(HOC_ERR_FORMAT, "'%s' holds no surface triangles", msh_path);
    goto done;
  }
  size_t np = (size_t)(raw.order + 1) * (size_t)(raw.order + 2) / 2;
  q = malloc(raw.n_tris * sizeof *q);
  rs = malloc(2 * np * sizeof *rs);
  if (!q || !rs) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  HOC_TRY_GOTO(hoc_tri_nodes(raw.order, HOC_NODES_EQUISPACED, rs), done);
  HOC_TRY_GOTO(measure_raw(&raw, measure, q), done);
  const char *base = strrchr(msh_path, '/');
  hoc_render_mesh view = {.order = raw.order,
                          .rs = rs,
                          .n_nodes = raw.n_nodes,
                          .xyz = raw.xyz,
                          .n_elems = raw.n_tris,
                          .conn = raw.tri_nodes,
                          .q = q,
                          .title = base ? base + 1 : msh_path};
  hoc_render_options ro;
  to_render_options(options, &ro);
  HOC_TRY_GOTO(hoc_render_png(png_path, &view, 1, &ro), done);
  if (histogram_path) HOC_TRY_GOTO(hoc_render_histogram_png(histogram_path, &view, 1, &ro), done);
  if (stats) hoc_quality_stats_from(q, raw.n_tris, raw.order, stats);
done:
  free(q);
  free(rs);
  hoc_msh_raw_free(&raw);
  return status;
}
