/* Histogram of q, read back with libpng's reader: the tangled bar (and the
 * legend colour) shows exactly when some element is tangled; one panel per
 * view side by side; a view without q is refused.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "render/render.h"
#include "test_util.h"
#define HOC_FIXTURES_PNG
#include "test_fixtures.h"

#include <png.h>
#include <string.h>


/* Magenta pixels (the tangled colour) in columns [x0, x1). */
static size_t count_magenta(const unsigned char *px, int w, int h, int x0, int x1) {
  size_t n = 0;
  for (int y = 0; y < h; ++y)
    for (int x = x0; x < x1; ++x) {
      const unsigned char *p = px + 4 * ((size_t)y * (size_t)w + (size_t)x);
      if (p[0] > 200 && p[1] < 40 && p[2] > 200) ++n;
    }
  return n;
}

/* Non-white pixels in columns [x0, x1). */
static size_t count_ink(const unsigned char *px, int w, int h, int x0, int x1) {
  size_t n = 0;
  for (int y = 0; y < h; ++y)
    for (int x = x0; x < x1; ++x) {
      const unsigned char *p = px + 4 * ((size_t)y * (size_t)w + (size_t)x);
      if (p[0] < 250 || p[1] < 250 || p[2] < 250) ++n;
    }
  return n;
}

int main(void) {
  enum { N = 1000 };
  double q_good[N], q_bad[N];
  for (int e = 0; e < N; ++e)
    q_good[e] = q_bad[e] = 0.2 + 0.8 * e / (N - 1.0);
  q_bad[10] = q_bad[500] = 0;
  /* the histogram reads only q and the count */
  hoc_render_mesh views[2] = {{1, NULL, 0, NULL, N, NULL, q_good, "before"},
                              {1, NULL, 0, NULL, N, NULL, q_bad, "after"}};
  hoc_render_options opt = {800, 300, {0, 0, 0}, 0, 0, 0};
  int w, h;

  CHECK_OK(hoc_render_histogram_png("hist_good.png", views, 1, &opt));
  unsigned char *px = fixture_read_png("hist_good.png", &w, &h);
  CHECK(px && w == 800 && h == 300);
  if (px) CHECK(count_magenta(px, w, h, 0, w) == 0);
  free(px);

  CHECK_OK(hoc_render_histogram_png("hist_two.png", views, 2, &opt));
  px = fixture_read_png("hist_two.png", &w, &h);
  CHECK(px && w == 800 && h == 300);
  if (px) {
    /* the left panel has no tangled bar, the right one has */
    CHECK(count_magenta(px, w, h, 0, w / 2) == 0);
    CHECK(count_magenta(px, w, h, w / 2, w) > 50);
    /* both panels are drawn */
    CHECK(count_ink(px, w, h, 0, w / 2) > 5000);
    CHECK(count_ink(px, w, h, w / 2, w) > 5000);
  }
  free(px);

  /* transparent background: the corners are transparent */
  opt.transparent = 1;
  CHECK_OK(hoc_render_histogram_png("hist_alpha.png", views, 2, &opt));
  px = fixture_read_png("hist_alpha.png", &w, &h);
  CHECK(px && px[3] == 0 && px[4 * ((size_t)w * (size_t)h - 1) + 3] == 0);
  free(px);

  views[1].q = NULL;
  CHECK_STATUS(hoc_render_histogram_png("hist_bad.png", views, 2, &opt), HOC_ERR_ARGUMENT);
  return test_report();
}
