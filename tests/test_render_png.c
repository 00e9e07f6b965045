/* Pictures of curved meshes, read back with libpng's own reader (not our
 * writer): a sphere seen along +z is a disc of the radius the framing rule
 * gives, centred; a tangled element shows in the tangled colour and only
 * then; the picture does not depend on the thread count.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "render/render.h"
#include "test_util.h"
#define HOC_FIXTURES_PNG
#include "test_fixtures.h"

#include <png.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

/* A sphere of radius R: the octahedron with each face cut into L^2
 * triangles, every element's nodes (order p, equispaced) mapped radially
 * onto the sphere. Nodes are not shared (the renderer does not need it). */
typedef struct sphere {
  int order, np;
  double rs[2 * 136];
  size_t n_nodes, n_elems;
  double *xyz;
  size_t *conn;
} sphere;

static void sphere_build(sphere *s, int order, int L, double R) {
  s->order = order;
  s->np = hoc_tri_num_nodes(order);
  hoc_tri_nodes(order, HOC_NODES_EQUISPACED, s->rs);
  s->n_elems = 8 * (size_t)L * (size_t)L;
  s->n_nodes = s->n_elems * (size_t)s->np;
  s->xyz = malloc(3 * s->n_nodes * sizeof *s->xyz);
  s->conn = malloc(s->n_nodes * sizeof *s->conn);
  size_t e = 0;
  for (int face = 0; face < 8; ++face) {
    double sg[3] = {face & 1 ? -1 : 1, face & 2 ? -1 : 1, face & 4 ? -1 : 1};
    double A[3] = {sg[0], 0, 0}, B[3] = {0, sg[1], 0}, C[3] = {0, 0, sg[2]};
    for (int j = 0; j < L; ++j)
      for (int i = 0; i < L - j; ++i)
        for (int up = 0; up < 2; ++up) {
          if (!up && i == L - j - 1) continue;
          /* lattice corners (i, j) of the face: A + i/L (B - A) + j/L (C - A) */
          int c[3][2] = {{i, j}, {i + 1, j}, {i, j + 1}};
          if (!up) c[0][0] = i + 1, c[0][1] = j, c[1][0] = i + 1, c[1][1] = j + 1;
          double P[3][3];
          for (int k = 0; k < 3; ++k)
            for (int d = 0; d < 3; ++d)
              P[k][d] =
                  A[d] + (double)c[k][0] / L * (B[d] - A[d]) + (double)c[k][1] / L * (C[d] - A[d]);
          for (int a = 0; a < s->np; ++a) {
            double r = s->rs[2 * a], t = s->rs[2 * a + 1], x[3], n = 0;
            for (int d = 0; d < 3; ++d) {
              x[d] = P[0][d] + r * (P[1][d] - P[0][d]) + t * (P[2][d] - P[0][d]);
              n += x[d] * x[d];
            }
            size_t node = e * (size_t)s->np + (size_t)a;
            for (int d = 0; d < 3; ++d)
              s->xyz[3 * node + d] = R * x[d] / sqrt(n);
            s->conn[node] = node;
          }
          ++e;
        }
  }
}

static void sphere_free(sphere *s) {
  free(s->xyz);
  free(s->conn);
}

static hoc_render_mesh sphere_view(const sphere *s, const double *q, const char *title) {
  hoc_render_mesh m = {s->order, s->rs, s->n_nodes, s->xyz, s->n_elems, s->conn, q, title};
  return m;
}


/* Pixels of the tangled colour (magenta, shaded): red = blue, no green. */
static size_t count_tangled_pixels(const unsigned char *px, int w, int h) {
  size_t n = 0;
  for (size_t i = 0; i < (size_t)w * (size_t)h; ++i) {
    const unsigned char *p = px + 4 * i;
    if (p[3] > 200 && p[0] >= 100 && p[1] < 40 && abs(p[0] - p[2]) < 25) ++n;
  }
  return n;
}

/* Opaque-ish pixels darker than any shaded grey face (edges are). */
static size_t count_dark(const unsigned char *px, int w, int h) {
  size_t n = 0;
  for (size_t i = 0; i < (size_t)w * (size_t)h; ++i) {
    const unsigned char *p = px + 4 * i;
    if (p[3] > 128 && p[0] < 60 && p[1] < 60 && p[2] < 60) ++n;
  }
  return n;
}

/* The silhouette of a sphere filling the frame along +z. */
static void check_disc(const sphere *s, const char *path) {
  const int W = 400, H = 300;
  hoc_render_mesh v = sphere_view(s, NULL, NULL);
  hoc_render_options opt = {W, H, {0, 0, 1}, 0, 0, 1};
  CHECK_OK(hoc_render_png(path, &v, 1, &opt));
  int w = 0, h = 0;
  unsigned char *px = fixture_read_png(path, &w, &h);
  CHECK(px != NULL);
  if (!px) return;
  CHECK(w == W && h == H);
  /* without title, q or colour bar the panel is the whole picture and the
   * nodes' extent (2R both ways) fills 90% of its smaller side */
  const double radius = 0.9 * H / 2, cx = W / 2.0, cy = H / 2.0;
  double area = 0, mx = 0, my = 0;
  int inside_ok = 1, outside_ok = 1;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double a = px[4 * ((size_t)y * (size_t)w + (size_t)x) + 3] / 255.0;
      double d = hypot(x + 0.5 - cx, y + 0.5 - cy);
      area += a;
      mx += a * (x + 0.5);
      my += a * (y + 0.5);
      if (d < radius - 2 && a < 1) inside_ok = 0;
      if (d > radius + 2 && a > 0) outside_ok = 0;
    }
  const double pi = 3.14159265358979323846;
  CHECK(fabs(area / (pi * radius * radius) - 1) < 0.02);
  CHECK_NEAR(mx / area, cx, 0.5);
  CHECK_NEAR(my / area, cy, 0.5);
  CHECK(inside_ok);
  CHECK(outside_ok);
  /* element edges are dark lines; without them the grey shading stays light */
  CHECK(count_dark(px, w, h) > 100);
  free(px);
  opt.no_edges = 1;
  CHECK_OK(hoc_render_png(path, &v, 1, &opt));
  px = fixture_read_png(path, &w, &h);
  CHECK(px && count_dark(px, w, h) == 0);
  free(px);
}

int main(void) {
  sphere s1, s3;
  sphere_build(&s1, 1, 8, 2.5);
  sphere_build(&s3, 3, 4, 2.5);
  check_disc(&s1, "render_sphere_p1.png");
  check_disc(&s3, "render_sphere_p3.png");

  /* qualities in (0.3, 1], then one element facing the eye tangled */
  double *q = malloc(s3.n_elems * sizeof *q);
  size_t front = 0;
  double zmax = -1;
  for (size_t e = 0; e < s3.n_elems; ++e) {
    q[e] = 0.3 + 0.7 * (double)((e * 7) % s3.n_elems) / (double)s3.n_elems;
    double z = 0;
    for (int a = 0; a < 3; ++a)
      z += s3.xyz[3 * (e * (size_t)s3.np + (size_t)a) + 2];
    if (z > zmax) zmax = z, front = e;
  }
  hoc_render_options opt = {640, 480, {0.2, 0.1, 1}, 0, 0, 0};
  hoc_render_mesh v = sphere_view(&s3, q, "sphere, order 3");
  int w, h;
  CHECK_OK(hoc_render_png("render_untangled.png", &v, 1, &opt));
  unsigned char *px = fixture_read_png("render_untangled.png", &w, &h);
  CHECK(px && count_tangled_pixels(px, w, h) == 0);
  free(px);
  q[front] = 0;
  CHECK_OK(hoc_render_png("render_tangled.png", &v, 1, &opt));
  px = fixture_read_png("render_tangled.png", &w, &h);
  /* the element covers a few hundred pixels */
  CHECK(px && count_tangled_pixels(px, w, h) > 200);
  free(px);

  /* two views, zoom on the worst, every thread count gives the same bytes */
  hoc_render_mesh two[2] = {sphere_view(&s3, q, "tangled"), sphere_view(&s1, NULL, "linear")};
  hoc_render_options zoom = {800, 400, {0, 0, 0}, 1, 0, 0};
  zoom.view[2] = 1;
#ifdef _OPENMP
  int threads = omp_get_max_threads();
  omp_set_num_threads(1);
#endif
  CHECK_OK(hoc_render_png("render_threads1.png", two, 2, &zoom));
#ifdef _OPENMP
  omp_set_num_threads(3);
#endif
  CHECK_OK(hoc_render_png("render_threads3.png", two, 2, &zoom));
#ifdef _OPENMP
  omp_set_num_threads(threads);
#endif
  int w1, h1, w3, h3;
  unsigned char *p1 = fixture_read_png("render_threads1.png", &w1, &h1);
  unsigned char *p3 = fixture_read_png("render_threads3.png", &w3, &h3);
  CHECK(p1 && p3 && w1 == w3 && h1 == h3 && !memcmp(p1, p3, 4 * (size_t)w1 * (size_t)h1));
  /* zoomed on the tangled element: it fills a good part of the left panel */
  CHECK(p1 && count_tangled_pixels(p1, w1, h1) > 4000);
  free(p1);
  free(p3);

  free(q);
  sphere_free(&s1);
  sphere_free(&s3);
  return test_report();
}
