/* The command line's value parsers and names (core/cli_support.h): what
 * `hocad` checks and derives that does not depend on how it prints.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "core/cli_support.h"
#include "core/error.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

hoc_status hoc_cli_parse_int(const char *opt, const char *s, int lo, int hi, int *out) {
  char *end;
  errno = 0;
  long v = s ? strtol(s, &end, 10) : 0;
  HOC_CHECK(s && *s && !*end && !errno && v >= lo && v <= hi, HOC_ERR_ARGUMENT,
            "%s expects an integer in %d..%d, got '%s'", opt, lo, hi, s ? s : "");
  *out = (int)v;
  return HOC_OK;
}

hoc_status hoc_cli_parse_positive(const char *opt, const char *s, double *out) {
  char *end;
  errno = 0;
  double v = s ? strtod(s, &end) : 0;
  HOC_CHECK(s && *s && !*end && !errno && isfinite(v) && v > 0, HOC_ERR_ARGUMENT,
            "%s expects a positive number, got '%s'", opt, s ? s : "");
  *out = v;
  return HOC_OK;
}

hoc_status hoc_cli_parse_view(const char *opt, const char *s, double view[3]) {
  static const struct {
    const char *name;
    double d[3];
  } named[] = {{"iso", {1, 1, 1}},   {"front", {0, -1, 0}},  {"back", {0, 1, 0}},
               {"top", {0, 0, 1}},   {"bottom", {0, 0, -1}}, {"side", {1, 0, 0}},
               {"left", {-1, 0, 0}}, {"right", {1, 0, 0}}};
  for (size_t k = 0; s && k < sizeof named / sizeof *named; ++k)
    if (!strcmp(s, named[k].name)) {
      memcpy(view, named[k].d, sizeof named[k].d);
      return HOC_OK;
    }
  const char *c = s;
  int ok = s != NULL;
  for (int d = 0; d < 3 && ok; ++d) {
    char *end;
    errno = 0;
    view[d] = strtod(c, &end);
    ok = end != c && !errno && isfinite(view[d]) && *end == (d < 2 ? ',' : '\0');
    c = end + 1;
  }
  HOC_CHECK(ok && view[0] * view[0] + view[1] * view[1] + view[2] * view[2] > 0, HOC_ERR_ARGUMENT,
            "%s expects iso, front, back, top, bottom, side, left, right or x,y,z (not all "
            "zero), got '%s'",
            opt, s ? s : "");
  return HOC_OK;
}

hoc_status hoc_cli_parse_picture_size(const char *opt, const char *s,
                                      hoc_picture_options *options) {
  char *end = NULL;
  errno = 0;
  long w = s ? strtol(s, &end, 10) : 0, h = 0;
  if (s && !errno && end != s && (*end == 'x' || *end == 'X')) {
    const char *c = end + 1;
    h = strtol(c, &end, 10);
    if (end == c) h = 0;
  }
  HOC_CHECK(s && !errno && !*end && w >= 64 && w <= 16384 && h >= 64 && h <= 16384,
            HOC_ERR_ARGUMENT, "%s expects WIDTHxHEIGHT in pixels, each 64..16384, got '%s'", opt,
            s ? s : "");
  options->width = (int)w;
  options->height = (int)h;
  return HOC_OK;
}

/* The index of s in names[n], or -1. */
static int name_index(const char *s, const char *const *names, int n) {
  for (int k = 0; s && k < n; ++k)
    if (!strcmp(s, names[k])) return k;
  return -1;
}

hoc_status hoc_cli_parse_measure(const char *opt, const char *s, hoc_measure *out) {
  static const char *const names[] = {"shape", "oddy"};
  static const hoc_measure values[] = {HOC_MEASURE_SHAPE, HOC_MEASURE_ODDY};
  int k = name_index(s, names, 2);
  HOC_CHECK(k >= 0, HOC_ERR_ARGUMENT, "%s expects shape or oddy, got '%s'", opt, s ? s : "");
  *out = values[k];
  return HOC_OK;
}

hoc_status hoc_cli_parse_nodeset(const char *opt, const char *s, hoc_nodeset *out) {
  static const char *const names[] = {"equispaced", "fekete", "warp-blend"};
  static const hoc_nodeset values[] = {HOC_NODES_EQUISPACED, HOC_NODES_FEKETE,
                                       HOC_NODES_WARP_BLEND};
  int k = name_index(s, names, 3);
  HOC_CHECK(k >= 0, HOC_ERR_ARGUMENT, "%s expects equispaced, fekete or warp-blend, got '%s'", opt,
            s ? s : "");
  *out = values[k];
  return HOC_OK;
}

hoc_status hoc_cli_parse_msh_version(const char *opt, const char *s, int *version) {
  static const char *const names[] = {"4.1", "4", "2.2", "2"};
  static const int values[] = {41, 41, 22, 22};
  int k = name_index(s, names, 4);
  HOC_CHECK(k >= 0, HOC_ERR_ARGUMENT, "%s expects 4.1 or 2.2, got '%s'", opt, s ? s : "");
  *version = values[k];
  return HOC_OK;
}

void hoc_cli_default_output(const char *model, int order, char *buf, size_t size) {
  const char *base = strrchr(model, '/');
  base = base ? base + 1 : model;
  const char *dot = strrchr(base, '.');
  int len = dot ? (int)(dot - base) : (int)strlen(base);
  snprintf(buf, size, "%.*s_p%d.%s", len, base, order, order <= 10 ? "msh" : "vtu");
}

hoc_status hoc_cli_cad_offset(const hoc_mesh *mesh, const hoc_model *model, double *offset,
                              double *relative) {
  double bb[6];
  *offset = *relative = 0;
  hoc_status status = hoc_mesh_max_cad_distance(mesh, offset);
  hoc_model_bbox(model, bb);
  double diag = sqrt((bb[3] - bb[0]) * (bb[3] - bb[0]) + (bb[4] - bb[1]) * (bb[4] - bb[1]) +
                     (bb[5] - bb[2]) * (bb[5] - bb[2]));
  *relative = diag > 0 ? *offset / diag : 0;
  return status;
}
