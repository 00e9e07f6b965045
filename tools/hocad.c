/* hocad: the command-line tool. Options, progress, printing and exit codes
 * live here; the work is done by libhocad.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"

#include <errno.h>
#include <math.h>
#include <omp.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

/* Exit codes (documented in README.md and --help). */
enum {
  EXIT_OK = 0,
  EXIT_USAGE = 1,       /* bad command line */
  EXIT_INPUT = 2,       /* model or mesh file missing, unreadable, corrupt or mismatched */
  EXIT_OUTPUT = 3,      /* an output file cannot be written */
  EXIT_PARTIAL = 4,     /* some faces could not be meshed; the rest was written */
  EXIT_TANGLED = 5,     /* tangled elements remain in the written mesh */
  EXIT_FAILURE_ = 6,    /* meshing failed, out of memory, or an internal error */
  EXIT_INTERRUPTED = 130
};

static const char *program = "hocad";

static void error_line(const char *fmt, ...) {
  va_list ap;
  va_start(ap, fmt);
  fprintf(stderr, "%s: error: ", program);
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
}

/* Exit code of a failed library call, by what it was doing. */
static int fail(hoc_status st, int input_stage) {
  error_line("%s", hoc_last_error()[0] ? hoc_last_error() : hoc_status_string(st));
  switch (st) {
  case HOC_ERR_ARGUMENT: return EXIT_USAGE;
  case HOC_ERR_IO: return input_stage ? EXIT_INPUT : EXIT_OUTPUT;
  case HOC_ERR_FORMAT:
  case HOC_ERR_CAD:
  case HOC_ERR_MISMATCH: return EXIT_INPUT;
  case HOC_ERR_UNSUPPORTED: return input_stage ? EXIT_INPUT : EXIT_OUTPUT;
  case HOC_ERR_INTERRUPTED: return EXIT_INTERRUPTED;
  default: return EXIT_FAILURE_;
  }
}

static void on_signal(int sig) {
  hoc_abort_outputs_from_signal();
  static const char msg[] = "\nhocad: interrupted; no output was written\n";
  ssize_t w = write(STDERR_FILENO, msg, sizeof msg - 1);
  (void)w;
  _exit(sig == SIGINT ? EXIT_INTERRUPTED : 128 + sig);
}

static double now(void) {
  struct timespec ts;
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Options ----------------------------------------------------------------- */

typedef struct options {
  const char *model, *mesh_in, *out, *vtu, *json, *linear, *png, *histogram;
  int order, threads, quiet, no_output, optimize, have_order, fix_curves, max_iterations,
      check_gradient, keep_nodes, refinements;
  hoc_picture_options picture;
  double size, size_min, curvature;
  hoc_nodeset nodes;
  hoc_measure measure;
} options;

static int parse_int(const char *opt, const char *s, int lo, int hi, int *out) {
  char *end;
  errno = 0;
  long v = s ? strtol(s, &end, 10) : 0;
  if (!s || !*s || *end || errno || v < lo || v > hi) {
    error_line("%s expects an integer in %d..%d, got '%s'", opt, lo, hi, s ? s : "");
    return 0;
  }
  *out = (int)v;
  return 1;
}

static int parse_positive(const char *opt, const char *s, double *out) {
  char *end;
  errno = 0;
  double v = s ? strtod(s, &end) : 0;
  if (!s || !*s || *end || errno || !isfinite(v) || !(v > 0)) {
    error_line("%s expects a positive number, got '%s'", opt, s ? s : "");
    return 0;
  }
  *out = v;
  return 1;
}

/* --view iso|front|top|side|back|bottom|x,y,z: direction towards the eye. */
static int parse_view(const char *s, double view[3]) {
  static const struct {
    const char *name;
    double d[3];
  } named[] = {{"iso", {1, 1, 1}},   {"front", {0, -1, 0}}, {"back", {0, 1, 0}},
               {"top", {0, 0, 1}},   {"bottom", {0, 0, -1}}, {"side", {1, 0, 0}},
               {"left", {-1, 0, 0}}, {"right", {1, 0, 0}}};
  for (size_t k = 0; k < sizeof named / sizeof *named; ++k)
    if (!strcmp(s, named[k].name)) {
      memcpy(view, named[k].d, sizeof named[k].d);
      return 1;
    }
  char *end;
  const char *c = s;
  for (int d = 0; d < 3; ++d) {
    errno = 0;
    view[d] = strtod(c, &end);
    if (end == c || errno || !isfinite(view[d]) || *end != (d < 2 ? ',' : '\0')) goto bad;
    c = end + 1;
  }
  if (view[0] * view[0] + view[1] * view[1] + view[2] * view[2] > 0) return 1;
bad:
  error_line("--view expects iso, front, back, top, bottom, side, left, right or x,y,z (not all "
             "zero), got '%s'",
             s);
  return 0;
}

/* --size WxH of a picture, 64..16384 pixels a side. */
static int parse_picture_size(const char *opt, const char *s, hoc_picture_options *p) {
  char *end;
  errno = 0;
  long w = strtol(s, &end, 10), h = 0;
  if (!errno && end != s && (*end == 'x' || *end == 'X')) {
    const char *c = end + 1;
    h = strtol(c, &end, 10);
    if (end == c) h = 0;
  }
  if (errno || *end || w < 64 || w > 16384 || h < 64 || h > 16384) {
    error_line("%s expects WIDTHxHEIGHT in pixels, each 64..16384, got '%s'", opt, s);
    return 0;
  }
  p->width = (int)w;
  p->height = (int)h;
  return 1;
}

/* --name value or --name=value: returns the value or NULL if this argument
 * is not `name`. *i advances past a separate value. */
static const char *opt_value(int argc, char **argv, int *i, const char *name, int *missing) {
  const char *a = argv[*i];
  size_t n = strlen(name);
  if (strncmp(a, name, n)) return NULL;
  if (a[n] == '=') return a + n + 1;
  if (a[n]) return NULL;
  if (*i + 1 >= argc) {
    *missing = 1;
    return NULL;
  }
  return argv[++*i];
}

#define OPTIMIZE_OPTIONS                                                                           \
  "  --fix-curves         keep nodes on CAD curves fixed (the seed's choice);\n"                   \
  "                       by default they slide along their curve\n"                               \
  "  --max-iterations N   optimizer sweeps (default 100); if elements are still\n"                 \
  "                       tangled then, a second attempt of up to N/2 more\n"                      \
  "  --check-gradient     compare the analytic gradient with finite differences\n"

#define PICTURE_OPTIONS(size_option)                                                      \
  "  --view V             iso | front | back | top | bottom | side | left | right |\n"         \
  "                       x,y,z (direction towards the eye; default iso)\n"                   \
  "  " size_option " WxH\n"                                                                 \
  "                       picture size in pixels (default 1600x1200; stages side\n"          \
  "                       by side 2700x1000)\n"                                              \
  "  --zoom-worst         frame the worst elements instead of the whole model\n"             \
  "  --no-edges           do not draw element edges\n"                                        \
  "  --transparent        transparent background instead of white\n"

static const char *usage_render =
    "usage: hocad render MESH.msh [--model MODEL] -o PICTURE.png [options]\n"
    "\n"
    "Draw a .msh surface mesh (any order up to 10) as curved elements coloured by\n"
    "q = 1/eta, with a colour bar; tangled elements in magenta. With --model, q is\n"
    "the seed's Definition 2 on the CAD (as 'hocad quality'); without it, each\n"
    "element is measured against the plane through its three corners.\n"
    "\n"
    "options:\n"
    "  -o, --output F.png   the picture\n"
    "  --model MODEL        the CAD model the mesh lies on\n"
    "  --histogram F.png    also a histogram of q\n"
    PICTURE_OPTIONS("--size")
    "  --measure M          shape | oddy (default shape)\n"
    "  --threads N          threads (default: all cores)\n"
    "  -q, --quiet          print only errors\n";

static const char *usage_main =
    "usage: hocad <command> [options]\n"
    "\n"
    "Valid high-order (curved) triangle surface meshes on CAD models (STEP, IGES,\n"
    "BREP), every node on the CAD surface.\n"
    "\n"
    "commands:\n"
    "  mesh MODEL      linear mesh, raise to order P, untangle and smooth, measure\n"
    "  optimize MODEL IN.msh -o OUT.msh\n"
    "                  untangle and smooth any high-order .msh surface mesh of MODEL\n"
    "  quality MODEL MESH.msh\n"
    "                  measure a gmsh .msh surface mesh of MODEL\n"
    "  render MESH.msh -o PICTURE.png\n"
    "                  picture of a mesh coloured by quality (headless PNG)\n"
    "\n"
    "  hocad COMMAND --help   options of a command\n"
    "  hocad --version        version\n"
    "\n"
    "exit codes: 0 ok, 1 bad command line, 2 bad input file (missing, unreadable,\n"
    "corrupt, not CAD, mesh not on the model), 3 cannot write an output,\n"
    "4 some faces could not be meshed (the rest was written), 5 tangled\n"
    "elements remain, 6 meshing failed or internal error, 130 interrupted.\n";

static const char *usage_mesh =
    "usage: hocad mesh MODEL [options]\n"
    "\n"
    "Mesh every face of MODEL (.step .stp .iges .igs .brep) with linear triangles,\n"
    "raise them to order P (new nodes placed in each face's parametric space and\n"
    "mapped onto the surface; nodes on CAD curves placed on the curves), and\n"
    "report the quality q = 1/eta of every stage (eta: the seed's Definition 2).\n"
    "Elements an untangled result has below 0.9 x the linear mesh's min q are\n"
    "optimised once more with two rings around them (a 'smoothed' stage).\n"
    "\n"
    "options:\n"
    "  -p, --order P        element order, 1..15 (default 3)\n"
    "  --size H             maximum edge length of the linear mesh\n"
    "                       (default: bounding-box diagonal / 20)\n"
    "  --size-min H         minimum edge length (default: size / 10)\n"
    "  --curvature N        elements per 2*pi of curvature radius (default 12 for\n"
    "                       order 1, 8 above: curved elements follow the surface)\n"
    "  --nodes SET          equispaced | fekete | warp-blend (default equispaced);\n"
    "                       files always hold equispaced nodes\n"
    "  --measure M          shape | oddy (default shape)\n"
    "  --linear M.msh       start from this linear mesh of MODEL instead of meshing\n"
    "  --no-optimize        stop after raising the order\n"
    "  --refinements N      if elements stay tangled, split them as 'hocad optimize'\n"
    "                       does (kept if that leaves none tangled), else mesh\n"
    "                       their faces again with edges half as long (and,\n"
    "                       without --size-min, a minimum size ten times smaller\n"
    "                       unless that more than quadruples the mesh) and\n"
    "                       start again, at most N times (default 2), then\n"
    "                       split, N times per chain (with --linear only the\n"
    "                       splits, default 3)\n" OPTIMIZE_OPTIONS
    "  -o, --output F.msh   gmsh MSH 4.1 output (default: MODEL-NAME_pP.msh here;\n"
    "                       orders above 10 have no MSH type: use --vtu)\n"
    "  --vtu F.vtu          VTK Lagrange triangles with q per element\n"
    "  --json F.json        the report as JSON\n"
    "  --png F.png          picture of the stages side by side (linear | raised |\n"
    "                       optimized), coloured by q\n"
    "  --histogram F.png    histogram of q per stage\n" PICTURE_OPTIONS(
        "--png-size") "  --no-output          write no mesh file\n"
                      "  --threads N          threads (default: all cores)\n"
                      "  -q, --quiet          print only errors\n";

static const char *usage_optimize =
    "usage: hocad optimize MODEL IN.msh -o OUT.msh [options]\n"
    "\n"
    "Untangle and smooth a high-order surface mesh of MODEL (e.g. gmsh's own\n"
    "'gmsh MODEL -2 -order 3'): minimise the sum over elements of the integral of\n"
    "(eta - 1)^2 over the parametric coordinates of the nodes, so every node stays\n"
    "on the CAD. Reports the input and optimized stages.\n"
    "\n"
    "Where the input has tangled elements, the optimizer first starts from its\n"
    "corners with the high-order nodes placed afresh as 'hocad mesh' places them\n"
    "(straight in each face's parameters, along the curves; a 're-placed' stage in\n"
    "the report) unless that tangles over 10% more elements than the input; if\n"
    "elements stay tangled, it also starts from the input's own nodes and keeps\n"
    "the result with fewer tangled elements. Elements still tangled then are\n"
    "split (a 'split' stage; see --refinements): the new elements' nodes are\n"
    "placed straight between their corners, every other node stays. Two chains\n"
    "of splits are made in turn, one red-green from the unsplit result, one at\n"
    "longest edges (which cuts slivers across) from the mesh that result was\n"
    "optimised from, until a result has no tangled element; the result with the\n"
    "fewest tangled elements is kept.\n"
    "\n"
    "options:\n"
    "  -o, --output F.msh   optimized mesh (MSH 4.1), or F.vtu\n"
    "  --keep-nodes         always start from the input's own high-order nodes\n"
    "  --refinements N      if elements stay tangled, split them in four (their\n"
    "                       neighbours in two to four) and optimise again, at most\n"
    "                       N times in each chain (default 6; 0 keeps the input's\n"
    "                       elements)\n"
    "  --vtu F.vtu          also a VTU with q per element\n"
    "  --json F.json        the report as JSON\n"
    "  --measure M          shape | oddy (default shape)\n" OPTIMIZE_OPTIONS
    "  --threads N          threads (default: all cores)\n"
    "  -q, --quiet          print only errors\n";

static const char *usage_quality =
    "usage: hocad quality MODEL MESH.msh [options]\n"
    "\n"
    "Read a gmsh MSH 4.1 or 2.2 surface mesh of MODEL (any triangle order up to 10,\n"
    "e.g. written by hocad or by gmsh) and report q = 1/eta (the seed's\n"
    "Definition 2). Nodes without parametric coordinates are located on their\n"
    "CAD entities.\n"
    "\n"
    "options:\n"
    "  --measure M          shape | oddy (default shape)\n"
    "  --vtu F.vtu          write the mesh with q per element\n"
    "  --json F.json        the report as JSON\n"
    "  --threads N          threads (default: all cores)\n"
    "  -q, --quiet          print only errors\n";

enum { CMD_MESH = 1, CMD_OPTIMIZE = 2, CMD_QUALITY = 4, CMD_RENDER = 8 };

static const char *command_name(int cmd) {
  return cmd == CMD_MESH       ? "mesh"
         : cmd == CMD_OPTIMIZE ? "optimize"
         : cmd == CMD_RENDER   ? "render"
                               : "quality";
}

/* Parse the options of a command; positional arguments go to pos[].
 * Returns 1 on success, 0 after printing an error, -1 for --help. */
static int parse(int argc, char **argv, options *o, const char **pos, int max_pos, int *n_pos,
                 int cmd) {
  const int mesh = cmd == CMD_MESH, opt = cmd & (CMD_MESH | CMD_OPTIMIZE),
            render = cmd == CMD_RENDER, picture = cmd & (CMD_MESH | CMD_RENDER);
  *n_pos = 0;
  for (int i = 0; i < argc; ++i) {
    const char *a = argv[i], *v;
    int missing = 0;
#define VALUE(name) (!missing && (v = opt_value(argc, argv, &i, name, &missing)))
    if (!strcmp(a, "-h") || !strcmp(a, "--help")) return -1;
    if (!strcmp(a, "-q") || !strcmp(a, "--quiet")) {
      o->quiet = 1;
    } else if (VALUE("--measure")) {
      if (!strcmp(v, "shape")) o->measure = HOC_MEASURE_SHAPE;
      else if (!strcmp(v, "oddy")) o->measure = HOC_MEASURE_ODDY;
      else {
        error_line("--measure expects shape or oddy, got '%s'", v);
        return 0;
      }
    } else if (VALUE("--threads")) {
      if (!parse_int("--threads", v, 1, 1024, &o->threads)) return 0;
    } else if (!render && VALUE("--json")) {
      o->json = v;
    } else if (!render && VALUE("--vtu")) {
      o->vtu = v;
    } else if (render && (VALUE("--output") || VALUE("-o"))) {
      o->png = v;
    } else if (render && VALUE("--model")) {
      o->model = v;
    } else if (render && VALUE("--size")) {
      if (!parse_picture_size("--size", v, &o->picture)) return 0;
    } else if (mesh && VALUE("--png-size")) {
      if (!parse_picture_size("--png-size", v, &o->picture)) return 0;
    } else if (mesh && VALUE("--png")) {
      o->png = v;
    } else if (picture && VALUE("--histogram")) {
      o->histogram = v;
    } else if (picture && VALUE("--view")) {
      if (!parse_view(v, o->picture.view)) return 0;
    } else if (picture && !strcmp(a, "--zoom-worst")) {
      o->picture.zoom_worst = 1;
    } else if (picture && !strcmp(a, "--no-edges")) {
      o->picture.no_edges = 1;
    } else if (picture && !strcmp(a, "--transparent")) {
      o->picture.transparent = 1;
    } else if (cmd == CMD_OPTIMIZE && !strcmp(a, "--keep-nodes")) {
      o->keep_nodes = 1;
    } else if (opt && !strcmp(a, "--fix-curves")) {
      o->fix_curves = 1;
    } else if (opt && !strcmp(a, "--check-gradient")) {
      o->check_gradient = 1;
    } else if (opt && VALUE("--max-iterations")) {
      if (!parse_int("--max-iterations", v, 1, 100000, &o->max_iterations)) return 0;
    } else if (opt && (VALUE("--output") || VALUE("-o"))) {
      o->out = v;
    } else if (opt && VALUE("--refinements")) {
      if (!parse_int("--refinements", v, 0, 10, &o->refinements)) return 0;
    } else if (mesh && (VALUE("--order") || VALUE("-p"))) {
      if (!parse_int("--order", v, 1, HOC_MAX_ORDER, &o->order)) return 0;
      o->have_order = 1;
    } else if (mesh && VALUE("--size-min")) {
      if (!parse_positive("--size-min", v, &o->size_min)) return 0;
    } else if (mesh && VALUE("--size")) {
      if (!parse_positive("--size", v, &o->size)) return 0;
    } else if (mesh && VALUE("--curvature")) {
      if (!parse_positive("--curvature", v, &o->curvature)) return 0;
      if (o->curvature > 1000) {
        error_line("--curvature expects at most 1000 elements per 2*pi, got '%s'", v);
        return 0;
      }
    } else if (mesh && VALUE("--nodes")) {
      if (!strcmp(v, "equispaced")) o->nodes = HOC_NODES_EQUISPACED;
      else if (!strcmp(v, "fekete")) o->nodes = HOC_NODES_FEKETE;
      else if (!strcmp(v, "warp-blend")) o->nodes = HOC_NODES_WARP_BLEND;
      else {
        error_line("--nodes expects equispaced, fekete or warp-blend, got '%s'", v);
        return 0;
      }
    } else if (mesh && VALUE("--linear")) {
      o->linear = v;
    } else if (mesh && !strcmp(a, "--no-optimize")) {
      o->optimize = 0;
    } else if (mesh && !strcmp(a, "--no-output")) {
      o->no_output = 1;
    } else if (missing) {
      error_line("option %s needs a value", a);
      return 0;
    } else if (a[0] == '-' && a[1]) {
      error_line("unknown option '%s' (see hocad %s --help)", a, command_name(cmd));
      return 0;
    } else {
      if (*n_pos >= max_pos) {
        error_line("unexpected argument '%s' (see hocad %s --help)", a, command_name(cmd));
        return 0;
      }
      pos[(*n_pos)++] = a;
    }
#undef VALUE
    if (missing) {
      error_line("option %s needs a value", a);
      return 0;
    }
  }
  return 1;
}

/* Report ------------------------------------------------------------------ */

typedef struct stage {
  const char *name;
  hoc_quality_stats stats;
  double seconds; /* to produce the stage */
  int optimized;  /* the fields below are set */
  int iterations, converged;
  int stopped_at_limit; /* the optimiser ran out of sweeps with elements tangled */
  int best_iteration;   /* when the returned mesh's tangled count was first reached */
  int second_attempt;   /* first sweep of the optimiser's second attempt, or 0 */
  int exact_phase;      /* first sweep of its exact phase, or 0 */
  int protected_run;    /* first sweep of the kept protected run, or 0 */
  size_t polished;      /* elements the optimiser's final polish untangled */
  size_t fragile;       /* elements it guarded as fragile */
  double objective_initial, objective;
} stage;

typedef struct report {
  stage stages[6];
  int n;
  double write_seconds; /* writing the mesh files */
  double model_seconds; /* reading the CAD model */
  size_t nodes;         /* of the final mesh */
  int refinements;      /* times tangled elements were meshed again finer (mesh: their
                           faces, or split; optimize and mesh --linear: split) */
  int remeshings;       /* of those, mesh's remeshings of faces */
} report;

static void print_table(const report *r) {
  printf("%-11s %5s %9s %7s %7s %7s %7s %8s %8s\n", "stage", "order", "elements", "min q",
         "max q", "mean q", "std q", "tangled", "seconds");
  for (int i = 0; i < r->n; ++i) {
    const stage *s = &r->stages[i];
    printf("%-11s %5d %9zu %7.4f %7.4f %7.4f %7.4f %8zu %8.3f\n", s->name, s->stats.order,
           s->stats.elements, s->stats.min, s->stats.max, s->stats.mean, s->stats.std,
           s->stats.tangled, s->seconds);
  }
  for (int i = 0; i < r->n; ++i) {
    const stage *s = &r->stages[i];
    if (!s->optimized) continue;
    printf("%s: %d iterations, objective %.6g -> %.6g%s", s->name, s->iterations,
           s->objective_initial, s->objective, s->converged ? ", converged" : ", not converged");
    if (s->polished) printf(", %zu untangled by the final polish", s->polished);
    printf("\n");
  }
}

/* A growing text buffer for the JSON report. */
typedef struct text {
  char *s;
  size_t n, cap;
  int failed;
} text;

static void text_add(text *t, const char *fmt, ...) {
  if (t->failed) return;
  for (;;) {
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(t->s ? t->s + t->n : NULL, t->s ? t->cap - t->n : 0, fmt, ap);
    va_end(ap);
    if (k < 0) {
      t->failed = 1;
      return;
    }
    if (t->s && t->n + (size_t)k < t->cap) {
      t->n += (size_t)k;
      return;
    }
    size_t cap = t->cap ? 2 * t->cap : 1024;
    while (cap < t->n + (size_t)k + 1) cap *= 2;
    char *s = realloc(t->s, cap);
    if (!s) {
      t->failed = 1;
      return;
    }
    t->s = s;
    t->cap = cap;
  }
}

static void json_string(text *t, const char *s) {
  text_add(t, "\"");
  for (; s && *s; ++s) {
    unsigned char c = (unsigned char)*s;
    if (c == '"' || c == '\\') text_add(t, "\\%c", c);
    else if (c < 0x20) text_add(t, "\\u%04x", c);
    else text_add(t, "%c", c);
  }
  text_add(t, "\"");
}

static int write_json(const char *path, const options *o, const report *r, const char *command) {
  text t = {0};
  text_add(&t, "{\n  \"command\": ");
  json_string(&t, command);
  text_add(&t, ",\n  \"model\": ");
  json_string(&t, o->model);
  if (o->mesh_in) {
    text_add(&t, ",\n  \"mesh\": ");
    json_string(&t, o->mesh_in);
  }
  text_add(&t, ",\n  \"measure\": \"%s\",\n  \"version\": \"%s\",\n  \"stages\": [",
           o->measure == HOC_MEASURE_ODDY ? "oddy" : "shape", hoc_version());
  for (int i = 0; i < r->n; ++i) {
    const stage *s = &r->stages[i];
    text_add(&t,
             "%s\n    {\"name\": \"%s\", \"order\": %d, \"elements\": %zu, \"min\": %.17g, "
             "\"max\": %.17g, \"mean\": %.17g, \"std\": %.17g, \"tangled\": %zu, "
             "\"seconds\": %.6f, \"measure_seconds\": %.6f",
             i ? "," : "", s->name, s->stats.order, s->stats.elements, s->stats.min, s->stats.max,
             s->stats.mean, s->stats.std, s->stats.tangled, s->seconds, s->stats.seconds);
    if (s->optimized)
      text_add(&t,
               ", \"iterations\": %d, \"converged\": %s, \"best_iteration\": %d, "
               "\"second_attempt\": %d, \"exact_phase\": %d, \"protected_run\": %d, "
               "\"polished\": %zu, \"fragile\": %zu, \"objective_initial\": %.17g, "
               "\"objective\": %.17g",
               s->iterations, s->converged ? "true" : "false", s->best_iteration, s->second_attempt,
               s->exact_phase, s->protected_run, s->polished, s->fragile, s->objective_initial,
               s->objective);
    text_add(&t, "}");
  }
  text_add(&t,
           "\n  ],\n  \"refinements\": %d,\n  \"remeshings\": %d,\n  \"nodes\": %zu,\n  "
           "\"model_seconds\": %.6f,\n  \"write_seconds\": %.6f\n}\n",
           r->refinements, r->remeshings, r->nodes, r->model_seconds, r->write_seconds);
  if (t.failed) {
    free(t.s);
    error_line("out of memory writing the report");
    return EXIT_FAILURE_;
  }
  hoc_status st = hoc_write_file_atomic(path, t.s, t.n);
  free(t.s);
  return st == HOC_OK ? EXIT_OK : fail(st, 0);
}

static void progress(const options *o, const char *fmt, ...) {
  if (o->quiet || !isatty(STDERR_FILENO)) return;
  va_list ap;
  va_start(ap, fmt);
  fprintf(stderr, "[hocad] ");
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
}

static int measure_stage(const options *o, report *r, const char *name, const hoc_mesh *mesh,
                         double seconds, double *q) {
  stage *s = &r->stages[r->n];
  *s = (stage){0}; /* a slot reused after a refinement keeps nothing */
  s->name = name;
  s->seconds = seconds;
  hoc_status st = hoc_mesh_measure(mesh, o->measure, q, NULL, &s->stats);
  if (st != HOC_OK) return fail(st, 0);
  r->n++;
  return EXIT_OK;
}

/* q of every element of `mesh` in a new array *q (freed by the caller, also
 * on failure), with its statistics if `stats` is not NULL. */
static int measure_all(const options *o, const hoc_mesh *mesh, double **q,
                       hoc_quality_stats *stats) {
  size_t ne = hoc_mesh_num_elements(mesh);
  if (!(*q = malloc((ne ? ne : 1) * sizeof **q))) {
    error_line("out of memory");
    return EXIT_FAILURE_;
  }
  hoc_status st = hoc_mesh_measure(mesh, o->measure, *q, NULL, stats);
  return st == HOC_OK ? EXIT_OK : fail(st, 0);
}

/* Default output name: the model's base name without extension, _pP.msh, in
 * the current directory. */
static void default_output(const char *model, int order, char *buf, size_t size) {
  const char *base = strrchr(model, '/');
  base = base ? base + 1 : model;
  const char *dot = strrchr(base, '.');
  int len = dot ? (int)(dot - base) : (int)strlen(base);
  snprintf(buf, size, "%.*s_p%d.%s", len, base, order, order <= 10 ? "msh" : "vtu");
}

/* Optimisation stage, shared by mesh and optimize. */
static int iteration_line(void *user, const hoc_optimize_iteration *it) {
  const options *o = user;
  if (!o->quiet && isatty(STDERR_FILENO))
    fprintf(stderr,
            "[hocad] iteration %3d: objective %.6g, min q %.4f, %zu tangled, %zu nodes moved "
            "(%.1f s)%s\n",
            it->iteration, it->objective, it->min_q, it->tangled, it->moved, it->seconds,
            it->attempt == 2 ? ", second attempt" : "");
  return 0;
}

/* From this order on, a split of an optimised mesh is optimised locally:
 * only the nodes of the split's children and of LOCAL_RINGS rings of
 * elements around them move (the rest of the mesh is where the first
 * optimisation left it). Below it the whole mesh is optimised again, which
 * costs little there (orders 2, 3, 5 and gmsh's order-3 meshes were
 * measured so); at order 10 that took as long as the first optimisation,
 * each split. */
#define LOCAL_MIN_ORDER 6
#define LOCAL_RINGS 2

/* free: NULL, or the elements whose nodes (and those of LOCAL_RINGS rings
 * around them) alone may move. */
static int optimize_stage(const options *o, report *r, hoc_mesh *mesh,
                          const unsigned char *free) {
  if (o->check_gradient) {
    double err;
    hoc_status st = hoc_mesh_check_gradient(mesh, o->measure, o->fix_curves, 200, &err);
    if (st != HOC_OK) return fail(st, 0);
    if (!o->quiet)
      printf("gradient check: largest relative difference to central differences %.2e (%s)\n", err,
             err < 1e-4 ? "ok" : "MISMATCH");
  }
  hoc_optimize_options oo;
  hoc_optimize_options_default(&oo);
  oo.measure = o->measure;
  oo.fix_curves = o->fix_curves;
  if (o->max_iterations) oo.max_iterations = o->max_iterations;
  oo.progress = iteration_line;
  oo.progress_user = (void *)o;
  oo.free_elements = free;
  oo.free_rings = LOCAL_RINGS;
  progress(o, "optimizing %zu elements", hoc_mesh_num_elements(mesh));
  hoc_optimize_result res;
  double t0 = now();
  hoc_status st = hoc_mesh_optimize(mesh, &oo, &res);
  if (st != HOC_OK) return fail(st, 0);
  if (res.diagnostics.polished && !o->quiet)
    fprintf(stderr, "%s: note: the final polish untangled %zu element(s) the sweeps left\n",
            program, res.diagnostics.polished);
  int code = measure_stage(o, r, "optimized", mesh, now() - t0, NULL);
  if (code) return code;
  stage *s = &r->stages[r->n - 1];
  s->optimized = 1;
  s->iterations = res.iterations;
  s->converged = res.converged;
  s->stopped_at_limit = res.stopped_at_limit;
  s->best_iteration = res.best_iteration;
  s->second_attempt = res.diagnostics.second_attempt;
  s->exact_phase = res.diagnostics.exact_phase;
  s->protected_run = res.diagnostics.protected_run;
  s->polished = res.diagnostics.polished;
  s->fragile = res.diagnostics.fragile;
  s->objective_initial = res.objective_initial;
  s->objective = res.objective_final;
  return EXIT_OK;
}

/* The optimised stage of a report, or NULL. */
static const stage *optimized_stage(const report *r) {
  for (int i = 0; i < r->n; ++i)
    if (r->stages[i].optimized) return &r->stages[i];
  return NULL;
}

/* Where tangled elements remain: say which, and why (on stderr). `opt` is
 * the optimised stage, or NULL if the mesh was not optimised. */
static void report_tangled(const hoc_mesh *mesh, const double *q, const stage *opt, int from_cad) {
  /* `hocad mesh` can make a finer linear mesh; `optimize` keeps its input's */
  const char *advice = from_cad
                           ? "try a smaller --size-min or --size, or a larger --curvature"
                           : "not with the input's elements: a finer input mesh there may help";
  size_t ne = hoc_mesh_num_elements(mesh), shown = 0, total = 0;
  for (size_t e = 0; e < ne; ++e) total += q[e] == 0.0;
  if (!total) return;
  if (opt && !opt->converged && opt->stopped_at_limit && opt->iterations >= 10 &&
      2 * opt->best_iteration <= opt->iterations)
    fprintf(stderr,
            "%s: warning: %zu element(s) could not be untangled with this linear mesh (the fewest "
            "tangled since iteration %d of %d; %s):",
            program, total, opt->best_iteration, opt->iterations, advice);
  else if (opt && !opt->converged && opt->stopped_at_limit)
    fprintf(stderr,
            "%s: warning: %zu element(s) still tangled after %d iteration(s) (the limit, with a "
            "second attempt: raise --max-iterations):",
            program, total, opt->iterations);
  else if (opt)
    fprintf(stderr,
            "%s: warning: %zu element(s) could not be untangled with this linear mesh "
            "(%s):",
            program, total, advice);
  else
    fprintf(stderr, "%s: warning: %zu tangled element(s) (not optimized):", program, total);
  for (size_t e = 0; e < ne && shown < 20; ++e)
    if (q[e] == 0.0) {
      fprintf(stderr, " %zu (face %d)", e + 1, hoc_mesh_element_face_tag(mesh, e));
      ++shown;
    }
  fprintf(stderr, "%s\n", total > shown ? " ..." : "");
}

/* Elements that end below 0.9 x the linear mesh's worst and have a corner at
 * a cusp of the CAD: say so, and what the rest of the mesh reaches (see
 * hoc_cusp: a cusp element's curved corner closes where its straight one
 * does not; raising grades its edges against that, which can still fall
 * short, e.g. on a mesh read from a file). */
static void report_cusps(const report *r, const hoc_mesh *mesh, const double *q) {
  double bound = 0.9 * r->stages[0].stats.min, rest = 1; /* q <= 1 */
  size_t ne = hoc_mesh_num_elements(mesh), low = 0, at_cusp = 0;
  char list[512] = "";
  size_t len = 0;
  const stage *opt = optimized_stage(r);
  if (!opt || !opt->converged) return; /* a low q may still be the optimiser's */
  if (r->n < 2 || !(r->stages[r->n - 1].stats.min < bound)) return; /* none below */
  for (size_t e = 0; e < ne; ++e) {
    if (q[e] == 0.0 || (q[e] >= bound && q[e] >= rest)) continue; /* changes nothing below */
    hoc_cusp c;
    int found = 0;
    if (hoc_mesh_element_cusp(mesh, e, 2.0, &c, &found) != HOC_OK) found = 0;
    if (!found) {
      if (q[e] < rest) rest = q[e];
      low += q[e] < bound;
      continue;
    }
    if (!(q[e] < bound)) continue;
    ++low;
    if (++at_cusp <= 3 && len < sizeof list)
      len += (size_t)snprintf(list + len, sizeof list - len,
                              "%selement %zu at vertex %d (curves %d and %d, %.2g degrees)",
                              at_cusp > 1 ? "; " : "", e + 1, c.vertex_tag, c.curve_tags[0],
                              c.curve_tags[1], c.angle_degrees);
  }
  if (!at_cusp) return;
  fprintf(stderr,
          "%s: note: %zu of the %zu element(s) below 0.9 x the linear mesh's min q (%.4f) have a "
          "corner at a cusp of the CAD, where two of its curves meet at under 2 degrees (%s%s): "
          "following both curves, such an element closes there as the order grows; the "
          "elements at no cusp have min q %.4f\n",
          program, at_cusp, low, r->stages[0].stats.min, list, at_cusp > 3 ? "; ..." : "", rest);
}

/* Write the requested files for `mesh` with per-element q. */
static int write_outputs(const options *o, const hoc_mesh *mesh, const double *q, const char *out) {
  hoc_status st;
  if (out) {
    progress(o, "writing %s", out);
    size_t len = strlen(out);
    int is_vtu = len >= 4 && !strcasecmp(out + len - 4, ".vtu");
    st = is_vtu ? hoc_mesh_write_vtu(mesh, q, out) : hoc_mesh_write_msh(mesh, out);
    if (st != HOC_OK) return fail(st, 0);
    if (!o->quiet) printf("wrote %s\n", out);
  }
  if (o->vtu) {
    st = hoc_mesh_write_vtu(mesh, q, o->vtu);
    if (st != HOC_OK) return fail(st, 0);
    if (!o->quiet) printf("wrote %s\n", o->vtu);
  }
  return EXIT_OK;
}

/* Pictures of the stages side by side (and their histograms): titles say
 * the stage, its order and its q; `final_q` is the last stage's q. */
static int write_pictures(const options *o, int n, const hoc_mesh *const *meshes,
                          const hoc_mesh *final, const double *final_q) {
  static const char *names[3] = {"linear", "raised", "optimized"};
  double *q[3] = {0};
  char title[3][96];
  const char *titles[3];
  int code = EXIT_OK;
  for (int k = 0; k < n && !code; ++k) {
    if (meshes[k] == final) q[k] = (double *)final_q;
    else code = measure_all(o, meshes[k], &q[k], NULL);
    const char *name = n == 2 && k == 1 ? (o->optimize ? "optimized" : "raised") : names[k];
    snprintf(title[k], sizeof title[k], "%s, order %d", name, hoc_mesh_order(meshes[k]));
    titles[k] = title[k];
  }
  if (!code && o->png) {
    progress(o, "drawing %s", o->png);
    hoc_status st = hoc_picture_png(o->png, n, meshes, (const double *const *)q, titles,
                                    &o->picture);
    if (st != HOC_OK) code = fail(st, 0);
    else if (!o->quiet) printf("wrote %s\n", o->png);
  }
  if (!code && o->histogram) {
    hoc_status st = hoc_histogram_png(o->histogram, n, meshes, (const double *const *)q, titles,
                                      &o->picture);
    if (st != HOC_OK) code = fail(st, 0);
    else if (!o->quiet) printf("wrote %s\n", o->histogram);
  }
  for (int k = 0; k < n; ++k)
    if (meshes[k] != final) free(q[k]);
  return code;
}

/* Commands ---------------------------------------------------------------- */

/* After an optimised stage that left elements tangled: bound the edge
 * length on their faces by half their longest edge (*face_size, allocated
 * on first use), say so, and start the report again. */
/* The CAD tags of the faces holding flagged elements, each once, in element
 * order (at most 20), then a newline; on stderr. */
static void print_faces(const hoc_mesh *mesh, const unsigned char *flag) {
  size_t ne = hoc_mesh_num_elements(mesh);
  int shown[20], n_shown = 0, more = 0;
  for (size_t e = 0; e < ne; ++e) {
    if (!flag[e]) continue;
    int tag = hoc_mesh_element_face_tag(mesh, e), seen = 0;
    for (int k = 0; k < n_shown && !seen; ++k)
      seen = shown[k] == tag;
    if (seen) continue;
    if (n_shown == 20) {
      more = 1;
      break;
    }
    shown[n_shown++] = tag;
    fprintf(stderr, " %d", tag);
  }
  fprintf(stderr, "%s\n", more ? " ..." : "");
}

/* Where `optimize` leaves tangled elements of *mesh: split them in four
 * (their neighbours as `kind` says, to keep the mesh conforming; children
 * placed straight between their corners) and optimise again: *fine, with
 * the report r (its first n_keep stages kept, then "split" and
 * "optimized"). The mesh split is `base` (the same elements as mesh, e.g.
 * the start mesh was optimised from), or mesh itself if base is NULL; if
 * fine_start is not NULL, it receives a copy of the split mesh before its
 * optimisation. */
static int split_tangled(const options *o, report *r, int n_keep, hoc_split_kind kind,
                         const hoc_mesh *mesh, const hoc_mesh *base, hoc_mesh **fine,
                         hoc_mesh **fine_start) {
  size_t ne = hoc_mesh_num_elements(mesh), total = 0;
  unsigned char *tangled = calloc(ne ? ne : 1, 1);
  if (!tangled) {
    error_line("out of memory");
    return EXIT_FAILURE_;
  }
  double t0 = now();
  /* from LOCAL_MIN_ORDER on, a split of the optimised mesh is optimised
   * locally: its children and LOCAL_RINGS rings around them */
  int local = !base && hoc_mesh_order(mesh) >= LOCAL_MIN_ORDER;
  unsigned char *pieces = local ? calloc(ne ? ne : 1, 1) : NULL, *children = NULL;
  hoc_status st = local && !pieces ? HOC_ERR_MEMORY : HOC_OK;
  if (st == HOC_OK) st = hoc_mesh_measure(mesh, o->measure, NULL, tangled, NULL);
  if (st == HOC_OK) st = hoc_mesh_split(base ? base : mesh, tangled, kind, fine, pieces);
  if (st == HOC_OK && local) {
    size_t nf = hoc_mesh_num_elements(*fine), j = 0;
    if (!(children = calloc(nf ? nf : 1, 1))) st = HOC_ERR_MEMORY;
    for (size_t e = 0; e < ne && children; j += pieces[e++])
      for (size_t c = j; c < j + pieces[e] && c < nf; ++c) children[c] = pieces[e] > 1;
  }
  free(pieces);
  if (st != HOC_OK) {
    free(tangled);
    free(children);
    hoc_mesh_destroy(fine);
    if (st == HOC_ERR_MEMORY) {
      error_line("out of memory");
      return EXIT_FAILURE_;
    }
    return fail(st, 0);
  }
  for (size_t e = 0; e < ne; ++e)
    total += tangled[e];
  r->refinements++;
  if (!o->quiet) {
    fprintf(stderr,
            "%s: %zu element(s) still tangled; splitting them and their neighbours %s (%zu -> "
            "%zu elements) and optimising %s again (refinement %d): faces",
            program, total, kind == HOC_SPLIT_RED_GREEN ? "red-green" : "at their longest edges",
            ne, hoc_mesh_num_elements(*fine),
            local ? "the new elements and two rings around them" : "the mesh", r->refinements);
    print_faces(mesh, tangled);
  }
  free(tangled);
  r->n = n_keep; /* the stages before the optimisation stay */
  int code = measure_stage(o, r, "split", *fine, now() - t0, NULL);
  if (!code && fine_start && (st = hoc_mesh_copy(*fine, fine_start)) != HOC_OK) code = fail(st, 0);
  if (!code) code = optimize_stage(o, r, *fine, children);
  free(children);
  if (code) {
    hoc_mesh_destroy(fine);
    if (fine_start) hoc_mesh_destroy(fine_start);
  }
  return code;
}

/* Destroy *m unless it is one of keep[n]. */
static void drop_mesh(hoc_mesh **m, hoc_mesh *const *keep, int n) {
  for (int i = 0; i < n; ++i)
    if (*m == keep[i]) {
      *m = NULL;
      return;
    }
  hoc_mesh_destroy(m);
}

/* Two chains of splits from the optimised mesh *mesh, taken in turn: one
 * red-green (keeps shapes, but its two-way cuts make slivers thinner), one
 * at longest edges (cuts slivers across), each at most o->refinements
 * splits and each going on from its own latest result. Stops once a result
 * has no tangled element. Given `start`, the mesh *mesh was optimised from
 * (the same elements), the longest-edge chain splits that and then each of
 * its own split meshes as they were before their optimisation (the
 * elements that stay tangled flagged by the optimised ones): corners an
 * optimisation moved into a sliver that folds in (u, v) give children
 * folded the same way, split straight between them (gmsh's aircraft,
 * face 69: from the optimised meshes 4, 4, 8 tangled in three splits, from
 * the starts 6, 8, 4, 0 in four; gmsh 4.8's 6, 6, 5, 1, 1, 0 in six, hence
 * optimize's default of 6). *mesh and *r become the result with the
 * fewest tangled elements (the earlier on a tie); r->refinements goes on
 * counting with every split made; the split results' reports keep r's
 * first n_keep stages. A trial prints no closing note (its caller decides
 * what it keeps). */
static int refine_tangled(const options *o, report *r, int n_keep, hoc_mesh **mesh,
                          const hoc_mesh *start, int trial) {
  static const hoc_split_kind kinds[2] = {HOC_SPLIT_RED_GREEN, HOC_SPLIT_LONGEST_EDGE};
  hoc_mesh *base = *mesh, *best = base, *cur[2] = {base, base};
  hoc_mesh *own_start = NULL; /* the longest-edge chain's latest split mesh, unoptimised */
  report best_r = *r, chain_r[2] = {*r, *r};
  int code = EXIT_OK, made = r->refinements;
  for (int level = 0; level < o->refinements && !code; ++level)
    for (int k = 0; k < 2 && !code && best_r.stages[best_r.n - 1].stats.tangled; ++k) {
      hoc_mesh *fine = NULL, *fine_start = NULL;
      int from_start = k == 1 && start;
      chain_r[k].refinements = made;
      /* the last level's split mesh is never split again: no copy of it */
      int more = level + 1 < o->refinements;
      code = split_tangled(o, &chain_r[k], n_keep, kinds[k], cur[k], from_start ? start : NULL,
                           &fine, from_start && more ? &fine_start : NULL);
      made = chain_r[k].refinements;
      if (code) break;
      if (from_start) {
        hoc_mesh_destroy(&own_start);
        start = own_start = fine_start;
      }
      hoc_mesh *keep[4] = {base, best, cur[1 - k], fine};
      drop_mesh(&cur[k], keep, 4);
      cur[k] = fine;
      if (chain_r[k].stages[chain_r[k].n - 1].stats.tangled <
          best_r.stages[best_r.n - 1].stats.tangled) {
        hoc_mesh *keep2[3] = {base, cur[0], cur[1]};
        drop_mesh(&best, keep2, 3);
        best = fine;
        best_r = chain_r[k];
      }
    }
  hoc_mesh_destroy(&own_start);
  int improved = best != base;
  for (int k = 0; k < 2; ++k) {
    hoc_mesh *keep[3] = {base, best, k ? cur[0] : NULL};
    drop_mesh(&cur[k], keep, 3);
  }
  if (improved) hoc_mesh_destroy(&base);
  *mesh = best;
  *r = best_r;
  r->refinements = made;
  if (!code && !o->quiet && !trial && improved)
    fprintf(stderr,
            "%s: note: kept the mesh of refinement %d of %d, which has the fewest tangled "
            "elements\n",
            program, best_r.refinements, made);
  else if (!code && !o->quiet && !trial)
    fprintf(stderr, "%s: note: splitting left no fewer tangled elements: kept the mesh before it\n",
            program);
  return code;
}

/* refine_tangled on a copy of *ho: if that leaves no element tangled, *ho
 * and *r become its result and *done is 1; otherwise both stay as they
 * were. */
static int try_split_first(const options *o, report *r, hoc_mesh **ho, int *done) {
  *done = 0;
  hoc_mesh *copy = NULL;
  hoc_status st = hoc_mesh_copy(*ho, &copy);
  if (st != HOC_OK) return fail(st, 0);
  report trial = *r;
  if (!o->quiet)
    fprintf(stderr, "%s: splitting the tangled elements first (kept if that leaves none tangled)\n",
            program);
  int code = refine_tangled(o, &trial, 2, &copy, NULL, 1);
  size_t left = code ? 0 : trial.stages[trial.n - 1].stats.tangled;
  if (!code && !left) {
    if (!o->quiet)
      fprintf(stderr, "%s: note: kept the mesh of refinement %d, which has no tangled element\n",
              program, trial.refinements);
    hoc_mesh_destroy(ho);
    *ho = copy;
    *r = trial;
    *done = 1;
    return EXIT_OK;
  }
  hoc_mesh_destroy(&copy);
  r->refinements = trial.refinements; /* made, though not kept */
  if (!code && !o->quiet)
    fprintf(stderr,
            "%s: note: splitting left %zu tangled at best: meshing the faces again instead\n",
            program, left);
  return code;
}

static int refine_faces(const options *o, report *r, const hoc_model *model, const hoc_mesh *lin,
                        const hoc_mesh *ho, double **face_size) {
  size_t ne = hoc_mesh_num_elements(ho);
  unsigned char *tangled = calloc(ne ? ne : 1, 1);
  if (!*face_size) *face_size = calloc((size_t)hoc_model_num_faces(model) + 1, sizeof **face_size);
  if (!tangled || !*face_size) {
    free(tangled);
    error_line("out of memory");
    return EXIT_FAILURE_;
  }
  hoc_status st = hoc_mesh_measure(ho, o->measure, NULL, tangled, NULL);
  if (st == HOC_OK) st = hoc_mesh_refine_bounds(lin, tangled, 0.5, *face_size);
  if (st != HOC_OK) {
    free(tangled);
    return fail(st, 0);
  }
  r->refinements++;
  r->remeshings++;
  if (!o->quiet) {
    size_t total = 0;
    for (size_t e = 0; e < ne; ++e)
      total += tangled[e];
    fprintf(stderr,
            "%s: %zu element(s) still tangled; meshing their faces again with edges half "
            "as long (remeshing %d of at most %d, refinement %d): faces",
            program, total, r->remeshings, o->refinements, r->refinements);
    print_faces(ho, tangled);
  }
  free(tangled);
  r->n = 0;
  return EXIT_OK;
}

/* Elements an untangled optimised mesh *mesh has below 0.9 x the linear
 * mesh's min q (the bound hocad aims at): their nodes and those of
 * LOCAL_RINGS rings around them optimised once more, alone (a stage
 * "smoothed"). Kept only if that raises the min q: the objective is a sum
 * over the elements, not their minimum. (The aircraft at order 10: its
 * splits next to a CAD curve 0.002 long, at the wing root, left 0.00197
 * against a linear 0.00230; this gives 0.00219 in 7 s.) */
static int smooth_low(const options *o, report *r, hoc_mesh **mesh) {
  const stage *last = &r->stages[r->n - 1];
  double bound = 0.9 * r->stages[0].stats.min;
  if (!last->optimized || last->stats.tangled || !(last->stats.min < bound)) return EXIT_OK;
  size_t ne = hoc_mesh_num_elements(*mesh), n_low = 0;
  double *q = NULL;
  unsigned char *low = calloc(ne ? ne : 1, 1);
  hoc_mesh *copy = NULL;
  int code = low ? measure_all(o, *mesh, &q, NULL) : (error_line("out of memory"), EXIT_FAILURE_);
  hoc_status st = code ? HOC_OK : hoc_mesh_copy(*mesh, &copy);
  if (!code && st != HOC_OK) code = fail(st, 0);
  for (size_t e = 0; !code && e < ne; ++e) {
    low[e] = q[e] < bound;
    n_low += low[e];
  }
  report trial = *r;
  if (!code && !o->quiet)
    fprintf(stderr,
            "%s: %zu element(s) below 0.9 x the linear mesh's min q (%.4f); optimising them "
            "and two rings around them once more\n",
            program, n_low, r->stages[0].stats.min);
  if (!code) code = optimize_stage(o, &trial, copy, low);
  if (!code) {
    stage *sm = &trial.stages[trial.n - 1];
    sm->name = "smoothed";
    if (!sm->stats.tangled && sm->stats.min > last->stats.min) {
      hoc_mesh_destroy(mesh);
      *mesh = copy;
      copy = NULL;
      *r = trial;
    } else if (!o->quiet) {
      fprintf(stderr, "%s: note: that did not raise the min q (%.4f): kept the mesh before\n",
              program, sm->stats.min);
    }
  }
  hoc_mesh_destroy(&copy);
  free(q);
  free(low);
  return code;
}

/* Free the meshes *to[0..2] and move *from[0..2] into them (leaving NULL). */
static void move_meshes(hoc_mesh **to[3], hoc_mesh **from[3]) {
  for (int i = 0; i < 3; ++i) {
    hoc_mesh_destroy(to[i]);
    *to[i] = *from[i];
    *from[i] = NULL;
  }
}

static int cmd_mesh(int argc, char **argv) {
  options o = {0};
  o.order = 3;
  o.optimize = 1;
  o.refinements = -1; /* default below: 2, or 3 splits per chain with --linear */
  const char *pos[1];
  int n_pos, pr = parse(argc, argv, &o, pos, 1, &n_pos, CMD_MESH);
  if (pr < 0) {
    fputs(usage_mesh, stdout);
    return EXIT_OK;
  }
  if (!pr) return EXIT_USAGE;
  if (n_pos != 1) {
    error_line("mesh needs one CAD model (see hocad mesh --help)");
    return EXIT_USAGE;
  }
  o.model = pos[0];
  if (o.refinements < 0) o.refinements = o.linear ? 3 : 2;
  if (o.size_min > 0 && o.size > 0 && o.size_min > o.size) {
    error_line("--size-min %g exceeds --size %g", o.size_min, o.size);
    return EXIT_USAGE;
  }
  char out_buf[1024];
  const char *out = o.out;
  if (!out && !o.no_output && !o.vtu) {
    default_output(o.model, o.order, out_buf, sizeof out_buf);
    out = out_buf;
  }
  if (o.no_output) out = NULL;
  if (out && o.order > 10 && strlen(out) >= 4 && !strcasecmp(out + strlen(out) - 4, ".msh")) {
    error_line("gmsh's MSH format has no triangle of order %d (at most 10): use --vtu", o.order);
    return EXIT_USAGE;
  }
  if (o.threads) omp_set_num_threads(o.threads);

  int code = EXIT_OK;
  hoc_model *model = NULL;
  hoc_mesh *lin = NULL, *ho = NULL, *written = NULL, *raised = NULL;
  /* the remeshing attempt with the fewest tangled elements so far (the
   * earlier on a tie), while another is tried */
  hoc_mesh *kept_lin = NULL, *kept_ho = NULL, *kept_raised = NULL;
  hoc_mesh **attempt[3] = {&lin, &ho, &raised}, **kept[3] = {&kept_lin, &kept_ho, &kept_raised};
  report kept_r = {0};
  double *q = NULL, *face_size = NULL;
  report r = {0};
  progress(&o, "reading %s", o.model);
  double t0 = now();
  hoc_status st = hoc_model_open(o.model, &model);
  if (st != HOC_OK) return fail(st, 1);
  r.model_seconds = now() - t0;
  double bb[6];
  hoc_model_bbox(model, bb);
  if (!o.quiet)
    printf("model %s: %d faces, %d curves, %d vertices, size %.4g x %.4g x %.4g (%.2f s)\n",
           o.model, hoc_model_num_faces(model), hoc_model_num_curves(model),
           hoc_model_num_vertices(model), bb[3] - bb[0], bb[4] - bb[1], bb[5] - bb[2],
           now() - t0);

  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.size_max = o.size;
  lo.size_min = o.size_min;
  lo.curvature = o.curvature;
  lo.order = o.order;
  const hoc_mesh *final = NULL;
  /* the minimum size before a remeshing lowered it, and the elements of
   * the linear mesh before that remeshing */
  double unlowered_min = lo.size_min;
  size_t prev_elements = 0;
  for (;;) {
    lo.face_size = face_size;
    t0 = now();
    if (o.linear) {
      /* a given linear mesh (e.g. gmsh's, to compare elevation on one mesh) */
      progress(&o, "reading %s", o.linear);
      hoc_mesh *given = NULL;
      st = hoc_mesh_read_msh(model, o.linear, &given);
      if (st == HOC_OK && hoc_mesh_order(given) != 1) {
        st = hoc_mesh_elevate(given, 1, HOC_NODES_EQUISPACED, &lin);
        hoc_mesh_destroy(&given);
      } else {
        lin = given;
      }
    } else {
      progress(&o, "meshing %d faces", hoc_model_num_faces(model));
      st = hoc_mesh_generate_linear(model, &lo, &lin);
      /* the lowered minimum lets the curvature sizing go finer on every
       * face, not only on those meshed again (the aircraft at order 7:
       * 192 990 elements from 7 818); halving the edges of every face
       * would at most quadruple the mesh, so beyond that it is undone */
      if (st == HOC_OK && lo.size_min < unlowered_min &&
          hoc_mesh_num_elements(lin) > 4 * prev_elements) {
        if (!o.quiet)
          fprintf(stderr,
                  "%s: note: with the minimum size %g the faces made %zu elements, more than "
                  "four times the %zu before: meshing them again with the minimum size %g\n",
                  program, lo.size_min, hoc_mesh_num_elements(lin), prev_elements,
                  unlowered_min);
        hoc_mesh_destroy(&lin);
        lo.size_min = unlowered_min;
        st = hoc_mesh_generate_linear(model, &lo, &lin);
      }
    }
    if (st != HOC_OK) {
      code = fail(st, 1);
      goto done;
    }
    double t_lin = now() - t0;
    if (hoc_mesh_num_failed_faces(lin)) {
      int nfail = hoc_mesh_num_failed_faces(lin);
      fprintf(stderr, "%s: warning: %d face(s) could not be meshed (the rest is processed): faces",
              program, nfail);
      for (int i = 0; i < nfail && i < 30; ++i)
        fprintf(stderr, " %d", hoc_mesh_failed_face_tag(lin, i));
      fprintf(stderr, "%s\n", nfail > 30 ? " ..." : "");
    }
    if ((code = measure_stage(&o, &r, "linear", lin, t_lin, NULL))) goto done;
    final = lin;
    if (o.order > 1) {
      progress(&o, "raising %zu elements to order %d", hoc_mesh_num_elements(lin), o.order);
      t0 = now();
      st = hoc_mesh_elevate(lin, o.order, o.nodes, &ho);
      if (st != HOC_OK) {
        code = fail(st, 0);
        goto done;
      }
      if ((code = measure_stage(&o, &r, "high-order", ho, now() - t0, NULL))) goto done;
      final = ho;
    }
    if (o.optimize && o.order > 1) {
      /* the raised mesh before optimisation, for the pictures */
      if ((o.png || o.histogram) && (st = hoc_mesh_elevate(lin, o.order, o.nodes, &raised))) {
        code = fail(st, 0);
        goto done;
      }
      if ((code = optimize_stage(&o, &r, ho, NULL))) goto done;
    }
    /* elements left tangled: their faces meshed again finer, from the
     * start; in a given linear mesh, or once the remeshing is spent, the
     * elements split as `optimize` splits them */
    if (!o.optimize || o.order < 2 || !r.stages[r.n - 1].stats.tangled || o.refinements < 1) break;
    if (o.linear || r.remeshings >= o.refinements) {
      size_t now_tangled = r.stages[r.n - 1].stats.tangled;
      if (kept_ho && kept_r.stages[kept_r.n - 1].stats.tangled < now_tangled) {
        int made = r.refinements, remade = r.remeshings;
        if (!o.quiet)
          fprintf(stderr,
                  "%s: note: the last mesh has more tangled elements (%zu) than the one after "
                  "%d remeshing(s) (%zu): going on from that one\n",
                  program, now_tangled, kept_r.remeshings,
                  kept_r.stages[kept_r.n - 1].stats.tangled);
        move_meshes(attempt, kept);
        r = kept_r;
        r.refinements = made;
        r.remeshings = remade;
      }
      if ((code = refine_tangled(&o, &r, 2, &ho, NULL, 0))) goto done;
      final = ho;
      break;
    }
    /* first the local repair, on a copy: splitting the tangled elements
     * (as below, once remeshing is spent) keeps the rest of the mesh; it
     * is kept if it leaves none tangled (the bottle at order 2: two
     * elements at its thread's end, which two remeshings only make worse) */
    int split_code = 0;
    if ((code = try_split_first(&o, &r, &ho, &split_code))) goto done;
    if (split_code) {
      final = ho;
      break;
    }
    report attempt_r = r;
    if ((code = refine_faces(&o, &r, model, lin, ho, &face_size))) goto done;
    /* and unless --size-min was given, let the curvature sizing go ten
     * times finer (the bottle's thread curls through 130 degrees within
     * 0.03 at its end, where the default minimum of 0.4 kept it coarse) */
    prev_elements = hoc_mesh_num_elements(lin);
    if (!(o.size_min > 0)) {
      double size_max, size_min;
      hoc_linear_sizes(model, &lo, &size_max, &size_min);
      unlowered_min = size_min;
      lo.size_min = size_min / 10;
    }
    if (!kept_ho || attempt_r.stages[attempt_r.n - 1].stats.tangled <
                        kept_r.stages[kept_r.n - 1].stats.tangled) {
      move_meshes(kept, attempt);
      kept_r = attempt_r;
    } else {
      hoc_mesh_destroy(&raised);
      hoc_mesh_destroy(&ho);
      hoc_mesh_destroy(&lin);
    }
  }
  if (final == ho && o.optimize && o.order > 1) {
    if ((code = smooth_low(&o, &r, &ho))) goto done;
    final = ho;
  }
  /* files hold equispaced nodes: measure what is written */
  if (o.nodes != HOC_NODES_EQUISPACED && o.order >= 3 && (out || o.vtu)) {
    t0 = now();
    st = hoc_mesh_convert(final, HOC_NODES_EQUISPACED, &written);
    if (st != HOC_OK) {
      code = fail(st, 0);
      goto done;
    }
    if ((code = measure_stage(&o, &r, "written", written, now() - t0, NULL))) goto done;
    final = written;
  }
  if (!o.quiet) print_table(&r);
  if ((code = measure_all(&o, final, &q, NULL))) goto done;
  t0 = now();
  if ((code = write_outputs(&o, final, q, out))) goto done;
  r.write_seconds = now() - t0;
  r.nodes = hoc_mesh_num_nodes(final);
  if (o.json) {
    if ((code = write_json(o.json, &o, &r, "mesh"))) goto done;
    if (!o.quiet) printf("wrote %s\n", o.json);
  }
  if (o.png || o.histogram) {
    const hoc_mesh *stages[3] = {lin, raised ? raised : final, final};
    int n = o.order == 1 ? 1 : raised ? 3 : 2;
    if ((code = write_pictures(&o, n, stages, final, q))) goto done;
  }
  report_tangled(final, q, optimized_stage(&r), 1);
  if (o.optimize && o.order > 1) report_cusps(&r, final, q);
  if (r.stages[r.n - 1].stats.tangled) code = EXIT_TANGLED;
  if (!code && hoc_mesh_num_failed_faces(lin)) code = EXIT_PARTIAL;
done:
  free(q);
  free(face_size);
  hoc_mesh_destroy(&raised);
  hoc_mesh_destroy(&written);
  hoc_mesh_destroy(&ho);
  hoc_mesh_destroy(&lin);
  hoc_mesh_destroy(&kept_raised);
  hoc_mesh_destroy(&kept_ho);
  hoc_mesh_destroy(&kept_lin);
  hoc_model_destroy(&model);
  return code;
}

static int cmd_quality(int argc, char **argv) {
  options o = {0};
  const char *pos[2];
  int n_pos, pr = parse(argc, argv, &o, pos, 2, &n_pos, CMD_QUALITY);
  if (pr < 0) {
    fputs(usage_quality, stdout);
    return EXIT_OK;
  }
  if (!pr) return EXIT_USAGE;
  if (n_pos != 2) {
    error_line("quality needs a CAD model and a .msh mesh (see hocad quality --help)");
    return EXIT_USAGE;
  }
  o.model = pos[0];
  o.mesh_in = pos[1];
  if (o.threads) omp_set_num_threads(o.threads);
  int code = EXIT_OK;
  hoc_model *model = NULL;
  hoc_mesh *mesh = NULL;
  double *q = NULL;
  report r = {0};
  hoc_status st = hoc_model_open(o.model, &model);
  if (st != HOC_OK) return fail(st, 1);
  double t0 = now();
  st = hoc_mesh_read_msh(model, o.mesh_in, &mesh);
  if (st != HOC_OK) {
    code = fail(st, 1);
    goto done;
  }
  size_t ne = hoc_mesh_num_elements(mesh);
  q = calloc(ne ? ne : 1, sizeof *q);
  if (!q) {
    error_line("out of memory");
    code = EXIT_FAILURE_;
    goto done;
  }
  if ((code = measure_stage(&o, &r, "input", mesh, now() - t0, q))) goto done;
  if (!o.quiet) {
    double off = 0, bb[6];
    hoc_mesh_max_cad_distance(mesh, &off);
    hoc_model_bbox(model, bb);
    double diag = sqrt((bb[3] - bb[0]) * (bb[3] - bb[0]) + (bb[4] - bb[1]) * (bb[4] - bb[1]) +
                       (bb[5] - bb[2]) * (bb[5] - bb[2]));
    printf("mesh %s on %s: %zu nodes, farthest node %.3g from the CAD (%.2g of the model's size)\n",
           o.mesh_in, o.model, hoc_mesh_num_nodes(mesh), off, diag > 0 ? off / diag : 0);
    print_table(&r);
  }
  if (o.vtu) {
    st = hoc_mesh_write_vtu(mesh, q, o.vtu);
    if (st != HOC_OK) {
      code = fail(st, 0);
      goto done;
    }
  }
  r.nodes = hoc_mesh_num_nodes(mesh);
  if (o.json) code = write_json(o.json, &o, &r, "quality");
done:
  free(q);
  hoc_mesh_destroy(&mesh);
  hoc_model_destroy(&model);
  return code;
}

/* The input's high-order nodes placed afresh from its corners, as `mesh`
 * places them (straight in each face's parameters, along the curves), in
 * *alt with a "re-placed" stage, unless that tangles clearly more elements
 * (over 10% more) than the input (then *alt stays NULL). Other meshers'
 * placement (gmsh's SetOrder projects each node on the CAD) can leave
 * folds the optimiser does not undo from there, and the other way round:
 * cmd_optimize tries both. */
static int replace_nodes(const options *o, report *r, const hoc_mesh *mesh, hoc_mesh **alt) {
  double t0 = now();
  hoc_mesh *lin = NULL;
  hoc_status s = hoc_mesh_elevate(mesh, 1, HOC_NODES_EQUISPACED, &lin);
  if (s == HOC_OK) s = hoc_mesh_elevate(lin, hoc_mesh_order(mesh), hoc_mesh_nodeset(mesh), alt);
  hoc_mesh_destroy(&lin);
  int code = s == HOC_OK ? measure_stage(o, r, "re-placed", *alt, now() - t0, NULL) : fail(s, 0);
  if (code) {
    hoc_mesh_destroy(alt);
    return code;
  }
  size_t in = r->stages[0].stats.tangled;
  if (r->stages[r->n - 1].stats.tangled > in + in / 10) { /* clearly worse: not used */
    r->n--;
    hoc_mesh_destroy(alt);
  }
  return EXIT_OK;
}

/* optimize_stage on mesh, a copy of it before kept in *start (if that is
 * not NULL): the start the result came from. */
static int optimize_keep_start(const options *o, report *r, hoc_mesh *mesh, hoc_mesh **start) {
  hoc_status st;
  if (start && (st = hoc_mesh_copy(mesh, start)) != HOC_OK) return fail(st, 0);
  int code = optimize_stage(o, r, mesh, NULL);
  if (code && start) hoc_mesh_destroy(start);
  return code;
}

/* Optimise *mesh, or where a re-placed start exists, that first and, if it
 * stays tangled, the input's own nodes too: the result with fewer tangled
 * elements (then the lower objective) is kept in *mesh, and, if start is
 * not NULL, the mesh it was optimised from in *start (for refine_tangled). */
static int optimize_starts(const options *o, report *r, hoc_mesh **mesh, hoc_mesh **start) {
  hoc_mesh *alt = NULL, *alt_start = NULL;
  int code = EXIT_OK;
  if (!o->keep_nodes && r->stages[0].stats.tangled && hoc_mesh_order(*mesh) > 1 &&
      (code = replace_nodes(o, r, *mesh, &alt)))
    return code;
  if (!alt) return optimize_keep_start(o, r, *mesh, start);
  if ((code = optimize_keep_start(o, r, alt, start)) || !r->stages[r->n - 1].stats.tangled) {
    hoc_mesh_destroy(mesh);
    *mesh = alt;
    return code;
  }
  if (start) { /* the re-placed start, until the input's own wins */
    alt_start = *start;
    *start = NULL;
  }
  stage from_alt = r->stages[--r->n];
  if ((code = optimize_keep_start(o, r, *mesh, start))) {
    hoc_mesh_destroy(&alt);
    hoc_mesh_destroy(&alt_start);
    return code;
  }
  const stage *own = &r->stages[r->n - 1];
  int alt_wins = from_alt.stats.tangled < own->stats.tangled ||
                 (from_alt.stats.tangled == own->stats.tangled && from_alt.objective < own->objective);
  if (!o->quiet)
    fprintf(stderr,
            "%s: note: optimised from the re-placed nodes (%zu tangled left) and from the "
            "input's own (%zu): kept the %s\n",
            program, from_alt.stats.tangled, own->stats.tangled,
            alt_wins ? "re-placed start's result" : "input's");
  if (alt_wins) {
    r->stages[r->n - 1] = from_alt;
    hoc_mesh_destroy(mesh);
    *mesh = alt;
    if (start) {
      hoc_mesh_destroy(start);
      *start = alt_start;
    }
  } else {
    hoc_mesh_destroy(&alt);
    hoc_mesh_destroy(&alt_start);
    r->stages[r->n - 2] = r->stages[r->n - 1]; /* the re-placed start was not used */
    r->n--;
  }
  return EXIT_OK;
}

static int cmd_optimize(int argc, char **argv) {
  options o = {0};
  o.refinements = 6;
  const char *pos[2];
  int n_pos, pr = parse(argc, argv, &o, pos, 2, &n_pos, CMD_OPTIMIZE);
  if (pr < 0) {
    fputs(usage_optimize, stdout);
    return EXIT_OK;
  }
  if (!pr) return EXIT_USAGE;
  if (n_pos != 2) {
    error_line("optimize needs a CAD model and a .msh mesh (see hocad optimize --help)");
    return EXIT_USAGE;
  }
  if (!o.out && !o.vtu) {
    error_line("optimize needs an output: -o OUT.msh (the input is never overwritten in place)");
    return EXIT_USAGE;
  }
  o.model = pos[0];
  o.mesh_in = pos[1];
  if (o.threads) omp_set_num_threads(o.threads);
  int code = EXIT_OK;
  hoc_model *model = NULL;
  hoc_mesh *mesh = NULL, *start = NULL;
  double *q = NULL;
  report r = {0};
  hoc_status st = hoc_model_open(o.model, &model);
  if (st != HOC_OK) return fail(st, 1);
  double t0 = now();
  st = hoc_mesh_read_msh(model, o.mesh_in, &mesh);
  if (st != HOC_OK) {
    code = fail(st, 1);
    goto done;
  }
  if ((code = measure_stage(&o, &r, "input", mesh, now() - t0, NULL))) goto done;
  if ((code = optimize_starts(&o, &r, &mesh, o.refinements > 0 ? &start : NULL))) goto done;
  if (r.stages[r.n - 1].stats.tangled && o.refinements > 0 &&
      (code = refine_tangled(&o, &r, 1, &mesh, start, 0)))
    goto done;
  hoc_mesh_destroy(&start);
  if (!o.quiet) {
    printf("mesh %s on %s: %zu nodes\n", o.mesh_in, o.model, hoc_mesh_num_nodes(mesh));
    print_table(&r);
  }
  if ((code = measure_all(&o, mesh, &q, NULL))) goto done;
  if ((code = write_outputs(&o, mesh, q, o.out))) goto done;
  r.nodes = hoc_mesh_num_nodes(mesh);
  if (o.json && (code = write_json(o.json, &o, &r, "optimize"))) goto done;
  report_tangled(mesh, q, optimized_stage(&r), 0);
  if (r.stages[r.n - 1].stats.tangled) code = EXIT_TANGLED;
done:
  free(q);
  hoc_mesh_destroy(&start);
  hoc_mesh_destroy(&mesh);
  hoc_model_destroy(&model);
  return code;
}

static int cmd_render(int argc, char **argv) {
  options o = {0};
  const char *pos[1];
  int n_pos, pr = parse(argc, argv, &o, pos, 1, &n_pos, CMD_RENDER);
  if (pr < 0) {
    fputs(usage_render, stdout);
    return EXIT_OK;
  }
  if (!pr) return EXIT_USAGE;
  if (n_pos != 1) {
    error_line("render needs one .msh mesh (see hocad render --help)");
    return EXIT_USAGE;
  }
  if (!o.png) {
    error_line("render needs an output: -o PICTURE.png");
    return EXIT_USAGE;
  }
  o.mesh_in = pos[0];
  if (o.threads) omp_set_num_threads(o.threads);
  const char *base = strrchr(o.mesh_in, '/');
  base = base ? base + 1 : o.mesh_in;
  if (!o.model) {
    hoc_quality_stats s;
    hoc_status st =
        hoc_picture_msh_file(o.mesh_in, o.measure, o.png, o.histogram, &o.picture, &s);
    if (st != HOC_OK) return fail(st, st == HOC_ERR_IO && access(o.mesh_in, R_OK) != 0);
    if (!o.quiet) {
      printf("%s: %zu elements of order %d, q min %.4f mean %.4f, %zu tangled (measured "
             "without CAD: against each element's corner plane)\n",
             base, s.elements, s.order, s.min, s.mean, s.tangled);
      printf("wrote %s\n", o.png);
      if (o.histogram) printf("wrote %s\n", o.histogram);
    }
    return EXIT_OK;
  }
  int code = EXIT_OK;
  hoc_model *model = NULL;
  hoc_mesh *mesh = NULL;
  double *q = NULL;
  hoc_quality_stats s;
  hoc_status st = hoc_model_open(o.model, &model);
  if (st != HOC_OK) return fail(st, 1);
  if ((st = hoc_mesh_read_msh(model, o.mesh_in, &mesh)) != HOC_OK) {
    code = fail(st, 1);
    goto done;
  }
  if ((code = measure_all(&o, mesh, &q, &s))) goto done;
  const hoc_mesh *views[1] = {mesh};
  const double *qs[1] = {q};
  const char *titles[1] = {base};
  if ((st = hoc_picture_png(o.png, 1, views, qs, titles, &o.picture)) != HOC_OK) {
    code = fail(st, 0);
    goto done;
  }
  if (o.histogram &&
      (st = hoc_histogram_png(o.histogram, 1, views, qs, titles, &o.picture)) != HOC_OK) {
    code = fail(st, 0);
    goto done;
  }
  if (!o.quiet) {
    printf("%s: %zu elements of order %d, q min %.4f mean %.4f, %zu tangled\n", base,
           s.elements, s.order, s.min, s.mean, s.tangled);
    printf("wrote %s\n", o.png);
    if (o.histogram) printf("wrote %s\n", o.histogram);
  }
done:
  free(q);
  hoc_mesh_destroy(&mesh);
  hoc_model_destroy(&model);
  return code;
}

int main(int argc, char **argv) {
  signal(SIGINT, on_signal);
  signal(SIGTERM, on_signal);
  if (argc < 2) {
    fputs(usage_main, stderr);
    return EXIT_USAGE;
  }
  const char *cmd = argv[1];
  if (!strcmp(cmd, "-h") || !strcmp(cmd, "--help") || !strcmp(cmd, "help")) {
    fputs(usage_main, stdout);
    return EXIT_OK;
  }
  if (!strcmp(cmd, "--version") || !strcmp(cmd, "-V")) {
    printf("hocad %s\n", hoc_version());
    return EXIT_OK;
  }
  if (!strcmp(cmd, "mesh")) return cmd_mesh(argc - 2, argv + 2);
  if (!strcmp(cmd, "quality")) return cmd_quality(argc - 2, argv + 2);
  if (!strcmp(cmd, "optimize")) return cmd_optimize(argc - 2, argv + 2);
  if (!strcmp(cmd, "render")) return cmd_render(argc - 2, argv + 2);
  error_line("unknown command '%s' (commands: mesh, optimize, quality, render; see hocad "
             "--help)",
             cmd);
  return EXIT_USAGE;
}
