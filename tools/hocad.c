/* hocad: the command-line tool. Options, progress, printing and exit codes
 * live here; the work is done by libhocad.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"
#include "core/cli_support.h"

#include <omp.h>
#include <signal.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

/* Exit codes (documented in README.md, docs/cli.md and --help). */
enum {
  EXIT_OK = 0,
  EXIT_USAGE = 1,    /* bad command line */
  EXIT_INPUT = 2,    /* model or mesh file missing, unreadable, corrupt or mismatched */
  EXIT_OUTPUT = 3,   /* an output file cannot be written */
  EXIT_PARTIAL = 4,  /* some faces could not be meshed; the rest was written */
  EXIT_TANGLED = 5,  /* tangled elements remain in the written mesh */
  EXIT_FAILURE_ = 6, /* meshing failed, out of memory, or an internal error */
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
  int threads, quiet, no_output;
  double size_factor; /* --size-factor: the default size (and size_min) times this (0: none) */
  hoc_mesh_options pipe; /* what the library's pipelines take (measure: every command's) */
  hoc_picture_options picture;
  hoc_msh_options msh; /* the .msh written */
} options;

/* A parser's verdict (core/cli_support.h): 1, or 0 after printing its error. */
static int parsed(hoc_status st) {
  if (st != HOC_OK) error_line("%s", hoc_last_error());
  return st == HOC_OK;
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

#define MSH_OPTIONS                                                                                \
  "  --msh-version V      4.1 (default) or 2.2, for readers that take only 2.2\n"                  \
  "                       (MFEM, older NekMesh and PyFR)\n"                                        \
  "  --msh-binary         write the .msh in binary (host byte order), not ASCII\n"                 \
  "  --msh-parametric     also write each node's parametric coordinates (t on a\n"                 \
  "                       curve, u v on a face), as gmsh's Mesh.SaveParametric;\n"                 \
  "                       hocad reads them back exactly, many readers refuse them\n"

#define OPTIMIZE_OPTIONS                                                                           \
  "  --fix-curves         keep nodes on CAD curves fixed (the paper's choice);\n"                  \
  "                       by default they slide along their curve\n"                               \
  "  --max-iterations N   optimizer sweeps (default 100); if elements are still\n"                 \
  "                       tangled then, a second attempt of up to N/2 more\n"                      \
  "  --check-gradient     compare the analytic gradient with finite differences\n"

#define PICTURE_OPTIONS(size_option)                                                               \
  "  --view V             iso | front | back | top | bottom | side | left | right |\n"             \
  "                       x,y,z (direction towards the eye; default iso)\n"                        \
  "  " size_option " WxH\n"                                                                        \
  "                       picture size in pixels (default 1600x1200; stages side\n"                \
  "                       by side 2700x1000)\n"                                                    \
  "  --zoom-worst         frame the worst elements instead of the whole model\n"                   \
  "  --no-edges           do not draw element edges\n"                                             \
  "  --transparent        transparent background instead of white\n"

static const char *usage_render =
    "usage: hocad render MESH.msh [--model MODEL] -o PICTURE.png [options]\n"
    "\n"
    "Draw a .msh surface mesh (any order up to 10) as curved elements coloured by\n"
    "q = 1/eta, with a colour bar; tangled elements in magenta. With --model, q is\n"
    "the paper's Definition 2 on the CAD (as 'hocad quality'); without it, each\n"
    "element is measured against the plane through its three corners.\n"
    "\n"
    "options:\n"
    "  -o, --output F.png   the picture\n"
    "  --model MODEL        the CAD model the mesh lies on\n"
    "  --histogram F.png    also a histogram of q\n" PICTURE_OPTIONS(
        "--size") "  --measure M          shape | oddy (default shape)\n"
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
    "raise them to order P (new nodes in each face's parameters, or at the feet of\n"
    "the straight elements' points on the surface where that does better; on CAD\n"
    "curves, on the curves), untangle and smooth them, and report the quality\n"
    "q = 1/eta of every stage (eta: the paper's Definition 2). Repair rules:\n"
    "docs/cli.md.\n"
    "\n"
    "options:\n"
    "  -p, --order P        element order, 1..15 (default 3)\n"
    "  --size H             maximum edge length of the linear mesh\n"
    "                       (default: bounding-box diagonal / 20)\n"
    "  --size-min H         minimum edge length (default: size / 10)\n"
    "  --size-factor F      the default --size and --size-min times F\n"
    "  --curvature N        elements per 2*pi of curvature radius (default 12 for\n"
    "                       order 1, 8 above: curved elements follow the surface)\n"
    "  --mesher-timeout S   seconds gmsh may take to mesh (default 300), then each\n"
    "                       face alone: the faces it does not finish are skipped\n"
    "  --no-grading         gmsh's mesh as is: not graded to short curves and thin\n"
    "                       faces, no edge swapped\n"
    "  --nodes SET          equispaced | fekete | warp-blend (default equispaced);\n"
    "                       files always hold equispaced nodes\n"
    "  --measure M          shape | oddy (default shape)\n"
    "  --linear M.msh       start from this linear mesh of MODEL instead of meshing\n"
    "  --no-optimize        stop after raising the order (at order 1, where\n"
    "                       triangles are inverted on the CAD, hocad untangles\n"
    "                       them unless this is given)\n"
    "  --refinements N      if elements stay tangled, split them as 'hocad optimize'\n"
    "                       does (below order 6, or at folds and cusps; kept if\n"
    "                       that leaves none tangled), else mesh their faces again\n"
    "                       with edges half as long (docs/cli.md) and start again,\n"
    "                       at most N times (default 2), then split, N times per\n"
    "                       chain (with --linear only the splits, default 3)\n"
    "  --repair-time S      seconds for those repairs (default: 4 x the time to the\n"
    "                       first optimised mesh + 60 s), then the best is kept\n" OPTIMIZE_OPTIONS
    "  -o, --output F.msh   gmsh MSH 4.1 output (default: MODEL-NAME_pP.msh here;\n"
    "                       orders above 10 have no MSH type: use --vtu)\n" MSH_OPTIONS
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
    "  --repair-time S      seconds the splits may take (default: 4 x the time to\n"
    "                       the first optimised mesh + 60 s; none: no limit); then\n"
    "                       the result with the fewest tangled elements is kept\n" MSH_OPTIONS
    "  --vtu F.vtu          also a VTU with q per element\n"
    "  --json F.json        the report as JSON\n"
    "  --measure M          shape | oddy (default shape)\n" OPTIMIZE_OPTIONS
    "  --threads N          threads (default: all cores)\n"
    "  -q, --quiet          print only errors\n";

static const char *usage_quality =
    "usage: hocad quality MODEL MESH.msh [options]\n"
    "\n"
    "Read a gmsh MSH 4.1 or 2.2 surface mesh of MODEL (any triangle order up to 10,\n"
    "e.g. written by hocad or by gmsh) and report q = 1/eta (the paper's\n"
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
      if (!parsed(hoc_cli_parse_measure("--measure", v, &o->pipe.measure))) return 0;
    } else if (VALUE("--threads")) {
      if (!parsed(hoc_cli_parse_int("--threads", v, 1, 1024, &o->threads))) return 0;
    } else if (!render && VALUE("--json")) {
      o->json = v;
    } else if (!render && VALUE("--vtu")) {
      o->vtu = v;
    } else if (render && (VALUE("--output") || VALUE("-o"))) {
      o->png = v;
    } else if (render && VALUE("--model")) {
      o->model = v;
    } else if (render && VALUE("--size")) {
      if (!parsed(hoc_cli_parse_picture_size("--size", v, &o->picture))) return 0;
    } else if (mesh && VALUE("--png-size")) {
      if (!parsed(hoc_cli_parse_picture_size("--png-size", v, &o->picture))) return 0;
    } else if (mesh && VALUE("--png")) {
      o->png = v;
    } else if (picture && VALUE("--histogram")) {
      o->histogram = v;
    } else if (picture && VALUE("--view")) {
      if (!parsed(hoc_cli_parse_view("--view", v, o->picture.view))) return 0;
    } else if (picture && !strcmp(a, "--zoom-worst")) {
      o->picture.zoom_worst = 1;
    } else if (picture && !strcmp(a, "--no-edges")) {
      o->picture.no_edges = 1;
    } else if (picture && !strcmp(a, "--transparent")) {
      o->picture.transparent = 1;
    } else if (cmd == CMD_OPTIMIZE && !strcmp(a, "--keep-nodes")) {
      o->pipe.keep_nodes = 1;
    } else if (opt && !strcmp(a, "--fix-curves")) {
      o->pipe.fix_curves = 1;
    } else if (opt && !strcmp(a, "--check-gradient")) {
      o->pipe.check_gradient = 1;
    } else if (opt && VALUE("--max-iterations")) {
      if (!parsed(hoc_cli_parse_int("--max-iterations", v, 1, 100000, &o->pipe.max_iterations)))
        return 0;
    } else if (opt && (VALUE("--output") || VALUE("-o"))) {
      o->out = v;
    } else if (opt && VALUE("--msh-version")) {
      if (!parsed(hoc_cli_parse_msh_version("--msh-version", v, &o->msh.version))) return 0;
    } else if (opt && !strcmp(a, "--msh-binary")) {
      o->msh.binary = 1;
    } else if (opt && !strcmp(a, "--msh-parametric")) {
      o->msh.parametric = 1;
    } else if (opt && VALUE("--refinements")) {
      if (!parsed(hoc_cli_parse_int("--refinements", v, 0, 10, &o->pipe.refinements))) return 0;
    } else if (opt && VALUE("--repair-time")) {
      if (!strcmp(v, "none"))
        o->pipe.repair_time = -1;
      else if (!parsed(hoc_cli_parse_positive("--repair-time", v, &o->pipe.repair_time)))
        return 0;
    } else if (mesh && (VALUE("--order") || VALUE("-p"))) {
      if (!parsed(hoc_cli_parse_int("--order", v, 1, HOC_MAX_ORDER, &o->pipe.order))) return 0;
    } else if (mesh && VALUE("--size-min")) {
      if (!parsed(hoc_cli_parse_positive("--size-min", v, &o->pipe.size_min))) return 0;
    } else if (mesh && VALUE("--size")) {
      if (!parsed(hoc_cli_parse_positive("--size", v, &o->pipe.size))) return 0;
    } else if (mesh && VALUE("--size-factor")) {
      if (!parsed(hoc_cli_parse_positive("--size-factor", v, &o->size_factor))) return 0;
    } else if (mesh && VALUE("--curvature")) {
      if (!parsed(hoc_cli_parse_positive("--curvature", v, &o->pipe.curvature))) return 0;
      if (o->pipe.curvature > 1000) {
        error_line("--curvature expects at most 1000 elements per 2*pi, got '%s'", v);
        return 0;
      }
    } else if (mesh && VALUE("--mesher-timeout")) {
      if (!parsed(hoc_cli_parse_positive("--mesher-timeout", v, &o->pipe.mesher_timeout)))
        return 0;
    } else if (mesh && VALUE("--nodes")) {
      if (!parsed(hoc_cli_parse_nodeset("--nodes", v, &o->pipe.nodeset))) return 0;
    } else if (mesh && VALUE("--linear")) {
      o->linear = v;
    } else if (mesh && !strcmp(a, "--no-optimize")) {
      o->pipe.optimize = 0;
    } else if (mesh && !strcmp(a, "--no-grading")) {
      o->pipe.grading = 0;
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

/* Printing ---------------------------------------------------------------- */

static void progress(const options *o, const char *fmt, ...) {
  if (o->quiet || !isatty(STDERR_FILENO)) return;
  va_list ap;
  va_start(ap, fmt);
  fprintf(stderr, "[hocad] ");
  vfprintf(stderr, fmt, ap);
  fputc('\n', stderr);
  va_end(ap);
}

/* A repair, note or warning from the library, on stderr. */
static void say(hoc_event_kind kind, const char *message) {
  fprintf(stderr, "%s: %s%s\n", program,
          kind == HOC_EVENT_NOTE      ? "note: "
          : kind == HOC_EVENT_WARNING ? "warning: "
                                      : "",
          message);
}

/* The pipelines' events: progress and sweeps on a terminal, repairs and
 * notes unless quiet, warnings always, the gradient check on stdout. */
static int on_event(void *user, const hoc_event *ev) {
  const options *o = user;
  if (ev->kind == HOC_EVENT_PROGRESS || ev->kind == HOC_EVENT_ITERATION)
    progress(o, "%s", ev->message);
  else if (ev->kind == HOC_EVENT_CHECK && !o->quiet)
    printf("%s\n", ev->message);
  else if (ev->kind == HOC_EVENT_WARNING ||
           (!o->quiet && ev->kind != HOC_EVENT_STAGE && ev->kind != HOC_EVENT_CHECK))
    say(ev->kind, ev->message);
  return 0;
}

static void print_table(const hoc_report *r) {
  printf("%-11s %5s %9s %7s %7s %7s %7s %8s %8s\n", "stage", "order", "elements", "min q", "max q",
         "mean q", "std q", "tangled", "seconds");
  size_t n = hoc_report_num_stages(r);
  for (size_t i = 0; i < n; ++i) {
    const hoc_stage *s = hoc_report_stage(r, i);
    printf("%-11s %5d %9zu %7.4f %7.4f %7.4f %7.4f %8zu %8.3f\n", s->name, s->stats.order,
           s->stats.elements, s->stats.min, s->stats.max, s->stats.mean, s->stats.std,
           s->stats.tangled, s->seconds);
  }
  for (size_t i = 0; i < n; ++i) {
    const hoc_stage *s = hoc_report_stage(r, i);
    const hoc_optimize_result *res = hoc_report_stage_result(r, i);
    if (!res) continue;
    printf("%s: %d iterations, objective %.6g -> %.6g%s", s->name, s->iterations,
           s->objective_initial, s->objective, s->converged ? ", converged" : ", not converged");
    if (res->diagnostics.polished)
      printf(", %zu untangled by the final polish", res->diagnostics.polished);
    printf("\n");
  }
  /* the time the table does not show: attempts not kept, measuring */
  if (n > 1) {
    double staged = 0;
    for (size_t i = 0; i < n; ++i)
      staged += hoc_report_stage(r, i)->seconds + hoc_report_stage(r, i)->stats.seconds;
    double total = hoc_report_seconds(r), rest = total > staged ? total - staged : 0;
    printf("total: %.3f s, %.3f s of them in attempts not kept and in measuring\n", total, rest);
  }
}

/* What the report finds about the result, on stderr, also when quiet. */
static void print_findings(const hoc_report *r) {
  for (size_t i = 0; i < hoc_report_num_findings(r); ++i) {
    hoc_event_kind kind;
    const char *text = hoc_report_finding(r, i, &kind);
    say(kind, text);
  }
}

/* Outputs ----------------------------------------------------------------- */

/* q of every element of `mesh` in a new array *q (freed by the caller, also
 * on failure), with its statistics if `stats` is not NULL. */
static int measure_all(const options *o, const hoc_mesh *mesh, double **q,
                       hoc_quality_stats *stats) {
  size_t ne = hoc_mesh_num_elements(mesh);
  if (!(*q = malloc((ne ? ne : 1) * sizeof **q))) {
    error_line("out of memory");
    return EXIT_FAILURE_;
  }
  hoc_status st = hoc_mesh_measure(mesh, o->pipe.measure, *q, NULL, stats);
  return st == HOC_OK ? EXIT_OK : fail(st, 0);
}

/* Write the requested files for `mesh` with per-element q. */
static int write_outputs(const options *o, const hoc_mesh *mesh, const double *q, const char *out) {
  const char *paths[2] = {out, o->vtu};
  for (int k = 0; k < 2; ++k) {
    if (!paths[k]) continue;
    progress(o, "writing %s", paths[k]);
    size_t len = strlen(paths[k]);
    int is_vtu = k || (len >= 4 && !strcasecmp(paths[k] + len - 4, ".vtu"));
    hoc_status st = is_vtu ? hoc_mesh_write_vtu(mesh, q, paths[k])
                           : hoc_mesh_write_msh_with(mesh, paths[k], &o->msh);
    if (st != HOC_OK) return fail(st, 0);
    if (!o->quiet) printf("wrote %s\n", paths[k]);
  }
  return EXIT_OK;
}

/* The report as JSON, if asked for; tell: print its name. */
static int write_json(const options *o, const hoc_report *r, double model_seconds,
                      double write_seconds, int tell) {
  if (!o->json) return EXIT_OK;
  hoc_report_files files = {o->model, o->mesh_in, model_seconds, write_seconds};
  hoc_status st = hoc_report_write_json(r, &files, o->json);
  if (st != HOC_OK) return fail(st, 0);
  if (!o->quiet && tell) printf("wrote %s\n", o->json);
  return EXIT_OK;
}

/* Pictures of n meshes side by side, and their histograms, with these
 * titles; q[k] of meshes[k], or NULL to measure it here. */
static int write_pictures(const options *o, int n, const hoc_mesh *const *meshes,
                          const double *const *given_q, const char *const *titles) {
  double *q[3] = {0};
  const double *qs[3];
  int code = EXIT_OK;
  for (int k = 0; k < n && !code; ++k)
    if (!(qs[k] = given_q[k]) && !(code = measure_all(o, meshes[k], &q[k], NULL))) qs[k] = q[k];
  const char *paths[2] = {o->png, o->histogram};
  for (int k = 0; k < 2 && !code; ++k) {
    if (!paths[k]) continue;
    progress(o, "drawing %s", paths[k]);
    hoc_status st = k ? hoc_histogram_png(paths[k], n, meshes, qs, titles, &o->picture)
                      : hoc_picture_png(paths[k], n, meshes, qs, titles, &o->picture);
    if (st != HOC_OK)
      code = fail(st, 0);
    else if (!o->quiet)
      printf("wrote %s\n", paths[k]);
  }
  for (int k = 0; k < n; ++k)
    free(q[k]);
  return code;
}

/* Commands ---------------------------------------------------------------- */

/* Parse a command's arguments into o: exactly n_pos positional ones into
 * pos, else the error `need`. Returns -1 to go on, else the exit code. */
static int start(int argc, char **argv, int cmd, options *o, const char **pos, int n_pos,
                 const char *usage, const char *need) {
  memset(o, 0, sizeof *o);
  hoc_mesh_options_default(&o->pipe);
  hoc_msh_options_default(&o->msh);
  o->pipe.event = on_event;
  o->pipe.event_user = o;
  int n, pr = parse(argc, argv, o, pos, n_pos, &n, cmd);
  if (pr < 0) {
    fputs(usage, stdout);
    return EXIT_OK;
  }
  if (!pr) return EXIT_USAGE;
  if (n != n_pos) {
    error_line("%s (see hocad %s --help)", need, command_name(cmd));
    return EXIT_USAGE;
  }
  if (o->threads) omp_set_num_threads(o->threads);
  return -1;
}

/* Open the model o->model and read the mesh o->mesh_in on it. Returns the
 * exit code of a failure, or EXIT_OK. */
static int open_inputs(const options *o, hoc_model **model, hoc_mesh **mesh) {
  hoc_status st = hoc_model_open(o->model, model);
  if (st == HOC_OK && (st = hoc_mesh_read_msh(*model, o->mesh_in, mesh)) != HOC_OK)
    hoc_model_destroy(model);
  return st == HOC_OK ? EXIT_OK : fail(st, 1);
}

static int cmd_mesh(int argc, char **argv) {
  options o;
  const char *pos[1];
  int code = start(argc, argv, CMD_MESH, &o, pos, 1, usage_mesh, "mesh needs one CAD model");
  if (code >= 0) return code;
  o.model = pos[0];
  const hoc_mesh_options *mo = &o.pipe;
  if (o.size_factor > 0 && mo->size > 0) {
    error_line("give --size or --size-factor, not both");
    return EXIT_USAGE;
  }
  if (mo->size_min > 0 && mo->size > 0 && mo->size_min > mo->size) {
    error_line("--size-min %g exceeds --size %g", mo->size_min, mo->size);
    return EXIT_USAGE;
  }
  char out_buf[1024];
  const char *out = o.out;
  if (!out && !o.no_output && !o.vtu) {
    hoc_cli_default_output(o.model, mo->order, out_buf, sizeof out_buf);
    out = out_buf;
  }
  if (o.no_output) out = NULL;
  if (out && mo->order > 10 && strlen(out) >= 4 && !strcasecmp(out + strlen(out) - 4, ".msh")) {
    error_line("gmsh's MSH format has no triangle of order %d (at most 10): use --vtu", mo->order);
    return EXIT_USAGE;
  }
  code = EXIT_OK;
  hoc_model *model = NULL;
  hoc_mesh *given = NULL, *final = NULL;
  hoc_report *r = NULL;
  progress(&o, "reading %s", o.model);
  double t0 = now();
  hoc_status st = hoc_model_open(o.model, &model);
  if (st != HOC_OK) return fail(st, 1);
  double model_seconds = now() - t0, bb[6];
  hoc_model_bbox(model, bb);
  if (o.size_factor > 0) {
    hoc_linear_options lo;
    hoc_linear_options_default(&lo);
    double size_max, size_min;
    hoc_linear_sizes(model, &lo, &size_max, &size_min);
    o.pipe.size = o.size_factor * size_max;
  }
  if (!o.quiet)
    printf("model %s: %d faces, %d curves, %d vertices, size %.4g x %.4g x %.4g (%.2f s)\n",
           o.model, hoc_model_num_faces(model), hoc_model_num_curves(model),
           hoc_model_num_vertices(model), bb[3] - bb[0], bb[4] - bb[1], bb[5] - bb[2], now() - t0);
  /* a given linear mesh (e.g. gmsh's, to compare elevation on one mesh) */
  if (o.linear) progress(&o, "reading %s", o.linear);
  if (o.linear && (st = hoc_mesh_read_msh(model, o.linear, &given)) != HOC_OK) {
    code = fail(st, 1);
    goto done;
  }
  o.pipe.linear = given;
  o.pipe.keep_stages = o.png || o.histogram;
  o.pipe.equispaced = out || o.vtu;
  if ((st = hoc_mesh_model(model, &o.pipe, &final, &r)) != HOC_OK) {
    code = fail(st, 0);
    goto done;
  }
  if (!o.quiet) print_table(r);
  const double *q = hoc_report_quality(r);
  t0 = now();
  if ((code = write_outputs(&o, final, q, out))) goto done;
  if ((code = write_json(&o, r, model_seconds, now() - t0, 1))) goto done;
  if (o.png || o.histogram) {
    /* the stages side by side: linear | raised | optimized (at order 1,
     * linear | optimized where the linear mesh was untangled) */
    const hoc_mesh *raised = hoc_report_raised(r);
    const hoc_mesh *meshes[3] = {hoc_report_linear(r), raised ? raised : final, final};
    const double *qs[3] = {NULL, raised ? NULL : q, q};
    int n = mo->order == 1 ? (hoc_report_num_stages(r) > 1 ? 2 : 1) : raised ? 3 : 2;
    const char *names[3] = {"linear", raised || !mo->optimize ? "raised" : "optimized",
                            "optimized"};
    char title[3][96];
    const char *titles[3] = {title[0], title[1], title[2]};
    for (int k = 0; k < 3; ++k)
      snprintf(title[k], sizeof title[k], "%s, order %d", names[k], hoc_mesh_order(meshes[k]));
    if ((code = write_pictures(&o, n, meshes, qs, titles))) goto done;
  }
  print_findings(r);
  if (hoc_report_tangled(r)) code = EXIT_TANGLED;
  if (!code && hoc_report_num_failed_faces(r)) code = EXIT_PARTIAL;
done:
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&final);
  hoc_mesh_destroy(&given);
  hoc_model_destroy(&model);
  return code;
}

/* hocad quality and hocad optimize: a mesh file measured, or repaired. */
static int cmd_mesh_file(int argc, char **argv, int cmd) {
  options o;
  const char *pos[2];
  int optimize = cmd == CMD_OPTIMIZE;
  int code = start(argc, argv, cmd, &o, pos, 2, optimize ? usage_optimize : usage_quality,
                   optimize ? "optimize needs a CAD model and a .msh mesh"
                            : "quality needs a CAD model and a .msh mesh");
  if (code >= 0) return code;
  if (optimize && !o.out && !o.vtu) {
    error_line("optimize needs an output: -o OUT.msh (the input is never overwritten in place)");
    return EXIT_USAGE;
  }
  o.model = pos[0];
  o.mesh_in = pos[1];
  hoc_model *model = NULL;
  hoc_mesh *mesh = NULL, *result = NULL;
  hoc_report *r = NULL;
  if ((code = open_inputs(&o, &model, &mesh))) return code;
  hoc_status st = optimize ? hoc_mesh_repair(mesh, &o.pipe, &result, &r)
                           : hoc_mesh_quality_report(mesh, o.pipe.measure, &r);
  if (st != HOC_OK) {
    code = fail(st, 0);
    goto done;
  }
  if (optimize) hoc_mesh_destroy(&mesh);
  const hoc_mesh *m = optimize ? result : mesh;
  if (!o.quiet && optimize) {
    printf("mesh %s on %s: %zu nodes\n", o.mesh_in, o.model, hoc_mesh_num_nodes(m));
  } else if (!o.quiet) {
    double off, rel;
    (void)hoc_cli_cad_offset(m, model, &off, &rel);
    printf("mesh %s on %s: %zu nodes, farthest node %.3g from the CAD (%.2g of the model's size)\n",
           o.mesh_in, o.model, hoc_mesh_num_nodes(m), off, rel);
  }
  if (!o.quiet) print_table(r);
  if ((code = write_outputs(&o, m, hoc_report_quality(r), o.out))) goto done;
  if ((code = write_json(&o, r, 0, 0, 0))) goto done;
  print_findings(r);
  if (hoc_report_tangled(r) && optimize) code = EXIT_TANGLED;
done:
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&result);
  hoc_mesh_destroy(&mesh);
  hoc_model_destroy(&model);
  return code;
}

static int cmd_render(int argc, char **argv) {
  options o;
  const char *pos[1];
  int code = start(argc, argv, CMD_RENDER, &o, pos, 1, usage_render, "render needs one .msh mesh");
  if (code >= 0) return code;
  if (!o.png) {
    error_line("render needs an output: -o PICTURE.png");
    return EXIT_USAGE;
  }
  o.mesh_in = pos[0];
  const char *base = strrchr(o.mesh_in, '/');
  base = base ? base + 1 : o.mesh_in;
  hoc_model *model = NULL;
  hoc_mesh *mesh = NULL;
  double *q = NULL;
  hoc_quality_stats s;
  if (!o.model) {
    hoc_status st =
        hoc_picture_msh_file(o.mesh_in, o.pipe.measure, o.png, o.histogram, &o.picture, &s);
    if (st != HOC_OK) return fail(st, st == HOC_ERR_IO && access(o.mesh_in, R_OK) != 0);
    if (!o.quiet)
      printf("%s: %zu elements of order %d, q min %.4f mean %.4f, %zu tangled (measured without "
             "CAD: against each element's corner plane)\nwrote %s\n%s%s%s",
             base, s.elements, s.order, s.min, s.mean, s.tangled, o.png,
             o.histogram ? "wrote " : "", o.histogram ? o.histogram : "", o.histogram ? "\n" : "");
    return EXIT_OK;
  }
  if (!(code = open_inputs(&o, &model, &mesh)) && !(code = measure_all(&o, mesh, &q, &s))) {
    if (!o.quiet)
      printf("%s: %zu elements of order %d, q min %.4f mean %.4f, %zu tangled\n", base, s.elements,
             s.order, s.min, s.mean, s.tangled);
    const hoc_mesh *views[1] = {mesh};
    const double *qs[1] = {q};
    code = write_pictures(&o, 1, views, qs, &base);
  }
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
  if (!strcmp(cmd, "quality")) return cmd_mesh_file(argc - 2, argv + 2, CMD_QUALITY);
  if (!strcmp(cmd, "optimize")) return cmd_mesh_file(argc - 2, argv + 2, CMD_OPTIMIZE);
  if (!strcmp(cmd, "render")) return cmd_render(argc - 2, argv + 2);
  error_line("unknown command '%s' (commands: mesh, optimize, quality, render; see hocad "
             "--help)",
             cmd);
  return EXIT_USAGE;
}
