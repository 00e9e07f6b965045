/* Helpers several tests share, independent of the library's own code:
 * the gmsh node lattice of a triangle and a PNG decoder (libpng's).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#ifndef HOC_TEST_FIXTURES_H
#define HOC_TEST_FIXTURES_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Whole file in memory, NUL-terminated (*n bytes before the NUL); NULL if
 * it cannot be opened or memory runs out. */
static inline char *fixture_slurp(const char *path, size_t *n) {
  *n = 0;
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long s = ftell(f);
  rewind(f);
  char *d = s >= 0 ? malloc((size_t)s + 1) : NULL;
  if (d) {
    *n = fread(d, 1, (size_t)s, f);
    d[*n] = '\0';
  }
  fclose(f);
  return d;
}

/* Node lattice (i, j) of an order-p triangle in gmsh order (vertices, edges
 * 0-1, 1-2, 2-0, interior recursively), of size p at corner (i0, j0);
 * returns the number of nodes written. */
static inline int fixture_lattice(int p, int i0, int j0, int *ij) {
  if (p < 0) return 0;
  if (p == 0) {
    ij[0] = i0, ij[1] = j0;
    return 1;
  }
  int v[3][2] = {{i0, j0}, {i0 + p, j0}, {i0, j0 + p}}, n = 0;
  for (int k = 0; k < 3; ++k)
    ij[2 * n] = v[k][0], ij[2 * n + 1] = v[k][1], ++n;
  for (int e = 0; e < 3; ++e)
    for (int k = 1; k < p; ++k) {
      const int *a = v[e], *b = v[(e + 1) % 3];
      ij[2 * n] = a[0] + (b[0] - a[0]) * k / p;
      ij[2 * n + 1] = a[1] + (b[1] - a[1]) * k / p;
      ++n;
    }
  return n + fixture_lattice(p - 3, i0 + 1, j0 + 1, ij + 2 * n);
}

#ifdef HOC_FIXTURES_PNG
#include <png.h>
/* Decode with libpng's simplified reader into RGBA; NULL on failure. */
static inline unsigned char *fixture_read_png(const char *path, int *w, int *h) {
  png_image img;
  memset(&img, 0, sizeof img);
  img.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&img, path)) return NULL;
  img.format = PNG_FORMAT_RGBA;
  unsigned char *buf = malloc(PNG_IMAGE_SIZE(img));
  if (!buf || !png_image_finish_read(&img, NULL, buf, 0, NULL)) {
    free(buf);
    png_image_free(&img);
    return NULL;
  }
  *w = (int)img.width;
  *h = (int)img.height;
  return buf;
}
#endif

#endif
