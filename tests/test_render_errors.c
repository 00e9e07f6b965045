/* The renderers reject invalid input with HOC_ERR_ARGUMENT and a one-line
 * message, and an unwritable output with HOC_ERR_IO, leaving no file.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "render/render.h"
#include "test_util.h"

#include <string.h>
#include <sys/stat.h>

/* One order-2 element: a curved triangle. */
static const double rs2[12] = {0, 0, 1, 0, 0, 1, 0.5, 0, 0.5, 0.5, 0, 0.5};
static double xyz[18] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0.5, -0.1, 0.1, 0.6, 0.6, 0, -0.1, 0.5, 0};
static const size_t conn[6] = {0, 1, 2, 3, 4, 5};
static double q[1] = {0.5};

static hoc_render_mesh good(void) {
  hoc_render_mesh m = {2, rs2, 6, xyz, 1, conn, q, "one element"};
  return m;
}

static int exists(const char *path) {
  struct stat st;
  return stat(path, &st) == 0;
}

/* Both renderers fail with `expected`, the message is one non-empty line and
 * no file is left behind. */
static void check_fails(const hoc_render_mesh *views, int n, const hoc_render_options *opt,
                        hoc_status expected, int histogram_too) {
  remove("bad.png");
  CHECK_STATUS(hoc_render_png("bad.png", views, n, opt), expected);
  CHECK(hoc_last_error()[0] != '\0' && !strchr(hoc_last_error(), '\n'));
  if (histogram_too) CHECK_STATUS(hoc_render_histogram_png("bad.png", views, n, opt), expected);
  CHECK(!exists("bad.png"));
}

int main(void) {
  hoc_render_options opt = {320, 240, {0, 0, 1}, 0, 0, 0};
  hoc_render_mesh m = good();
  CHECK_OK(hoc_render_png("good.png", &m, 1, &opt));
  CHECK_OK(hoc_render_histogram_png("good_hist.png", &m, 1, &opt));
  CHECK(exists("good.png") && exists("good_hist.png"));
  CHECK_OK(hoc_render_png("good_defaults.png", &m, 1, NULL)); /* NULL options: defaults */

  /* arguments */
  CHECK_STATUS(hoc_render_png(NULL, &m, 1, &opt), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_render_png("", &m, 1, &opt), HOC_ERR_ARGUMENT);
  check_fails(NULL, 1, &opt, HOC_ERR_ARGUMENT, 1);
  check_fails(&m, 0, &opt, HOC_ERR_ARGUMENT, 1);
  check_fails(&m, 17, &opt, HOC_ERR_ARGUMENT, 1);
  hoc_render_mesh v = good();
  v.order = 0;
  check_fails(&v, 1, &opt, HOC_ERR_ARGUMENT, 0);
  v.order = 16;
  check_fails(&v, 1, &opt, HOC_ERR_ARGUMENT, 0);
  v = good();
  v.rs = NULL;
  check_fails(&v, 1, &opt, HOC_ERR_ARGUMENT, 0);
  v = good();
  v.xyz = NULL;
  check_fails(&v, 1, &opt, HOC_ERR_ARGUMENT, 0);
  v = good();
  v.conn = NULL;
  check_fails(&v, 1, &opt, HOC_ERR_ARGUMENT, 0);
  v = good();
  v.n_nodes = 5; /* element uses node 5 */
  check_fails(&v, 1, &opt, HOC_ERR_ARGUMENT, 0);
  double bad_xyz[18];
  memcpy(bad_xyz, xyz, sizeof xyz);
  bad_xyz[7] = NAN;
  v = good();
  v.xyz = bad_xyz;
  check_fails(&v, 1, &opt, HOC_ERR_ARGUMENT, 0);
  bad_xyz[7] = INFINITY;
  check_fails(&v, 1, &opt, HOC_ERR_ARGUMENT, 0);
  /* reference nodes that are not unisolvent (all on a line) */
  double line_rs[12] = {0, 0, 1, 0, 0.2, 0, 0.4, 0, 0.6, 0, 0.8, 0};
  v = good();
  v.rs = line_rs;
  check_fails(&v, 1, &opt, HOC_ERR_ARGUMENT, 0);
  double bad_q[1] = {NAN};
  v = good();
  v.q = bad_q;
  check_fails(&v, 1, &opt, HOC_ERR_ARGUMENT, 1);
  bad_q[0] = 1.5;
  check_fails(&v, 1, &opt, HOC_ERR_ARGUMENT, 1);
  bad_q[0] = -0.1;
  check_fails(&v, 1, &opt, HOC_ERR_ARGUMENT, 1);
  /* the histogram needs q, the picture does not */
  v = good();
  v.q = NULL;
  CHECK_OK(hoc_render_png("good.png", &v, 1, &opt));
  CHECK_STATUS(hoc_render_histogram_png("bad.png", &v, 1, &opt), HOC_ERR_ARGUMENT);
  /* zoom on the worst needs q too */
  hoc_render_options zoom = opt;
  zoom.zoom_worst = 1;
  check_fails(&v, 1, &zoom, HOC_ERR_ARGUMENT, 0);

  /* sizes and view direction */
  const int sizes[][2] = {{16385, 100}, {100, 16385}, {-1, 100}, {10, 100}, {100, 20}};
  for (size_t i = 0; i < sizeof sizes / sizeof *sizes; ++i) {
    hoc_render_options o = opt;
    o.width = sizes[i][0];
    o.height = sizes[i][1];
    check_fails(&m, 1, &o, HOC_ERR_ARGUMENT, 1);
  }
  hoc_render_options o = opt;
  o.view[0] = NAN;
  check_fails(&m, 1, &o, HOC_ERR_ARGUMENT, 0);

  /* an unwritable place: no file, HOC_ERR_IO */
  CHECK_STATUS(hoc_render_png("no_such_dir/x.png", &m, 1, &opt), HOC_ERR_IO);
  CHECK(!exists("no_such_dir/x.png"));
  CHECK_STATUS(hoc_render_histogram_png("no_such_dir/x.png", &m, 1, &opt), HOC_ERR_IO);
  mkdir("render_ro", 0555);
  chmod("render_ro", 0555);
  FILE *probe = fopen("render_ro/probe", "w"); /* root writes anyway: skip then */
  if (probe) {
    fclose(probe);
    remove("render_ro/probe");
  } else {
    CHECK_STATUS(hoc_render_png("render_ro/x.png", &m, 1, &opt), HOC_ERR_IO);
    CHECK(!exists("render_ro/x.png"));
  }
  /* a failed render leaves an existing target as it was */
  FILE *f = fopen("keep.png", "w");
  fputs("old", f);
  fclose(f);
  v = good();
  v.order = 0;
  CHECK_STATUS(hoc_render_png("keep.png", &v, 1, &opt), HOC_ERR_ARGUMENT);
  f = fopen("keep.png", "r");
  char buf[8] = {0};
  CHECK(f && fread(buf, 1, sizeof buf, f) == 3 && !strcmp(buf, "old"));
  if (f) fclose(f);
  return test_report();
}
