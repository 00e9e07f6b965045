/* The gmsh CAD backend (OpenCASCADE inside): import, evaluation,
 * reparametrisation and projection through gmsh's C API.
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * gmsh keeps one global model; this backend owns it while a hoc_model from
 * it exists. gmsh and OpenCASCADE print on the process's stdout/stderr on
 * their own (General.Terminal only silences gmsh's logger): calls that may
 * print run with both descriptors redirected to a scratch file, whose first
 * error line goes into our message instead.
 *
 * Threads: OpenCASCADE evaluates its elementary and B-spline surfaces and
 * curves (Geom_*::D0/D1, called by gmsh's getValue/getDerivative) without
 * mutable state, so these evaluations run concurrently. Every other call
 * (other surface kinds, whose evaluators keep adaptor caches; projection;
 * reparametrisation) holds one lock.
 */
#include "cad/cad.h"
#include "cad/gmsh_util.h"

#include <gmshc.h>
#include <omp.h>

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <pthread.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

static int gmsh_initialized;
static int gmsh_model_in_use;
static pthread_mutex_t gmsh_lock = PTHREAD_MUTEX_INITIALIZER;

/* The calls held are short (a reparametrisation costs about 2 us): a
 * waiting thread first spins a while, as a thread put to sleep on the
 * mutex takes longer to wake (a virtual machine's wake-up interrupt) than
 * the holder takes to finish. */
static void serial_begin(int needed) {
  if (!needed) return;
  for (int i = 0; i < 2000; ++i) {
    if (pthread_mutex_trylock(&gmsh_lock) == 0) return;
#if defined(__x86_64__) || defined(__i386__)
    __builtin_ia32_pause();
#endif
  }
  pthread_mutex_lock(&gmsh_lock);
}
static void serial_end(int needed) {
  if (needed) pthread_mutex_unlock(&gmsh_lock);
}

/* Kinds OpenCASCADE evaluates without shared or cached state (gmsh's type names). */
static int concurrent_kind(int dim, const char *type) {
  static const char *const surfaces[] = {"Plane", "Cylinder",        "Cone",          "Sphere",
                                         "Torus", "BSpline surface", "Bezier surface"};
  static const char *const curves[] = {"Line",     "Circle",  "Ellipse", "Hyperbola",
                                       "Parabola", "BSpline", "Bezier"};
  const char *const *list = dim == 2 ? surfaces : curves;
  size_t n = dim == 2 ? sizeof surfaces / sizeof *surfaces : sizeof curves / sizeof *curves;
  for (size_t i = 0; i < n; ++i)
    if (!strcmp(type, list[i])) return 1;
  return 0;
}

hoc_status hoc_gmsh_error(const char *what) {
  char *msg = NULL;
  int ierr = 0;
  gmshLoggerGetLastError(&msg, &ierr);
  hoc_status st;
  if (!ierr && msg && msg[0])
    st = HOC_ERROR(HOC_ERR_CAD, "%s: %s", what, msg);
  else
    st = HOC_ERROR(HOC_ERR_CAD, "%s failed in gmsh", what);
  gmshFree(msg);
  return st;
}

hoc_status hoc_gmsh_start(void) {
  if (gmsh_initialized) return HOC_OK;
  int ierr = 0;
  /* gmsh sets OpenMP to its own General.NumThreads (1): keep the caller's */
  int threads = omp_get_max_threads();
  gmshInitialize(0, NULL, 0, &ierr);
  omp_set_num_threads(threads);
  HOC_CHECK(!ierr, HOC_ERR_CAD, "gmsh could not be initialised");
  gmshOptionSetNumber("General.Terminal", 0, &ierr);
  gmshOptionSetNumber("General.Verbosity", 1, &ierr);
  gmsh_initialized = 1;
  return HOC_OK;
}

/* A failed import leaves gmsh unable to read the next file (seen with 4.8:
 * every later gmshOpen yields an empty model); only a restart recovers. */
static void gmsh_restart_after_failure(void) {
  int ierr = 0;
  if (!gmsh_initialized) return;
  gmshFinalize(&ierr);
  gmsh_initialized = 0;
}

/* Redirection of stdout/stderr around chatty kernel calls. */
static FILE *child_sink; /* set in a child process (child.c) */

void hoc_quiet_in_child(FILE *sink) { child_sink = sink; }

hoc_status hoc_quiet_begin(hoc_quiet *q) {
  q->saved_out = q->saved_err = -1;
  if (child_sink) {
    q->sink = NULL;
    return HOC_OK;
  }
  q->sink = tmpfile();
  if (!q->sink) return HOC_OK; /* cannot redirect: the kernel may print, nothing worse */
  fflush(stdout);
  fflush(stderr);
  q->saved_out = dup(STDOUT_FILENO);
  q->saved_err = dup(STDERR_FILENO);
  int fd = fileno(q->sink);
  if (q->saved_out >= 0) dup2(fd, STDOUT_FILENO);
  if (q->saved_err >= 0) dup2(fd, STDERR_FILENO);
  return HOC_OK;
}

void hoc_quiet_end(hoc_quiet *q, char *first_error, size_t size) {
  if (first_error && size) first_error[0] = '\0';
  if (child_sink) {
    fflush(stdout);
    fflush(stderr);
    hoc_first_error_line(child_sink, first_error, size);
    return;
  }
  if (!q->sink) return;
  fflush(stdout);
  fflush(stderr);
  if (q->saved_out >= 0) {
    dup2(q->saved_out, STDOUT_FILENO);
    close(q->saved_out);
  }
  if (q->saved_err >= 0) {
    dup2(q->saved_err, STDERR_FILENO);
    close(q->saved_err);
  }
  hoc_first_error_line(q->sink, first_error, size);
  fclose(q->sink);
  q->sink = NULL;
}

/* Backend operations ----------------------------------------------------- */

/* Evaluation without the lock. A failure's message comes from gmsh's global
 * logger, read only when `message` (the caller then holds the lock). */
static hoc_status gmsh_face_eval_raw(const hoc_cad_face *f, size_t n, const double *uv, double *xyz,
                                     double *du, double *dv, int message) {
  int ierr = 0;
  if (xyz) {
    double *x = NULL;
    size_t nx = 0;
    gmshModelGetValue(2, f->tag, (double *)uv, 2 * n, &x, &nx, &ierr);
    if (ierr || nx != 3 * n) {
      gmshFree(x);
      return message ? hoc_gmsh_error("surface evaluation") : HOC_ERR_CAD;
    }
    memcpy(xyz, x, 3 * n * sizeof *x);
    gmshFree(x);
  }
  if (du || dv) {
    double *d = NULL;
    size_t nd = 0;
    gmshModelGetDerivative(2, f->tag, (double *)uv, 2 * n, &d, &nd, &ierr);
    if (ierr || nd != 6 * n) {
      gmshFree(d);
      return message ? hoc_gmsh_error("surface derivative") : HOC_ERR_CAD;
    }
    for (size_t i = 0; i < n; ++i)
      for (int k = 0; k < 3; ++k) {
        if (du) du[3 * i + k] = d[6 * i + k];
        if (dv) dv[3 * i + k] = d[6 * i + 3 + k];
      }
    gmshFree(d);
  }
  return HOC_OK;
}

static hoc_status gmsh_face_eval(void *ctx, const hoc_cad_face *f, size_t n, const double *uv,
                                 double *xyz, double *du, double *dv) {
  (void)ctx;
  if (!n) return HOC_OK;
  int lock = !f->concurrent;
  serial_begin(lock);
  hoc_status st = gmsh_face_eval_raw(f, n, uv, xyz, du, dv, lock);
  if (st != HOC_OK && !lock) { /* again under the lock, for the message */
    serial_begin(1);
    st = gmsh_face_eval_raw(f, n, uv, xyz, du, dv, 1);
    serial_end(1);
  }
  serial_end(lock);
  return st;
}

static hoc_status gmsh_curve_eval_raw(const hoc_cad_curve *c, size_t n, const double *t,
                                      double *xyz, double *dt, int message) {
  int ierr = 0;
  if (xyz) {
    double *x = NULL;
    size_t nx = 0;
    gmshModelGetValue(1, c->tag, (double *)t, n, &x, &nx, &ierr);
    if (ierr || nx != 3 * n) {
      gmshFree(x);
      return message ? hoc_gmsh_error("curve evaluation") : HOC_ERR_CAD;
    }
    memcpy(xyz, x, 3 * n * sizeof *x);
    gmshFree(x);
  }
  if (dt) {
    double *d = NULL;
    size_t nd = 0;
    gmshModelGetDerivative(1, c->tag, (double *)t, n, &d, &nd, &ierr);
    if (ierr || nd != 3 * n) {
      gmshFree(d);
      return message ? hoc_gmsh_error("curve derivative") : HOC_ERR_CAD;
    }
    memcpy(dt, d, 3 * n * sizeof *d);
    gmshFree(d);
  }
  return HOC_OK;
}

static hoc_status gmsh_curve_eval(void *ctx, const hoc_cad_curve *c, size_t n, const double *t,
                                  double *xyz, double *dt) {
  (void)ctx;
  if (!n) return HOC_OK;
  int lock = !c->concurrent;
  serial_begin(lock);
  hoc_status st = gmsh_curve_eval_raw(c, n, t, xyz, dt, lock);
  if (st != HOC_OK && !lock) { /* again under the lock, for the message */
    serial_begin(1);
    st = gmsh_curve_eval_raw(c, n, t, xyz, dt, 1);
    serial_end(1);
  }
  serial_end(lock);
  return st;
}

static hoc_status gmsh_curve_to_face_unlocked(void *ctx, const hoc_cad_curve *c,
                                              const hoc_cad_face *f, size_t n, const double *t,
                                              double *uv) {
  (void)ctx;
  if (!n) return HOC_OK;
  int ierr = 0;
  double *p = NULL;
  size_t np = 0;
  gmshModelReparametrizeOnSurface(1, c->tag, (double *)t, n, f->tag, &p, &np, 0, &ierr);
  if (ierr || np != 2 * n) {
    gmshFree(p);
    return hoc_gmsh_error("curve reparametrisation on a surface");
  }
  memcpy(uv, p, 2 * n * sizeof *p);
  gmshFree(p);
  return HOC_OK;
}

static hoc_status gmsh_vertex_to_face_unlocked(void *ctx, const hoc_cad_vertex *v,
                                               const hoc_cad_face *f, double *uv) {
  (void)ctx;
  int ierr = 0;
  double *p = NULL;
  size_t np = 0;
  gmshModelReparametrizeOnSurface(0, v->tag, NULL, 0, f->tag, &p, &np, 0, &ierr);
  if (ierr || np != 2) {
    gmshFree(p);
    return hoc_gmsh_error("vertex reparametrisation on a surface");
  }
  uv[0] = p[0];
  uv[1] = p[1];
  gmshFree(p);
  return HOC_OK;
}

static hoc_status gmsh_face_project_unlocked(void *ctx, const hoc_cad_face *f, size_t n,
                                             const double *xyz, double *uv) {
  (void)ctx;
  if (!n) return HOC_OK;
  int ierr = 0;
  double *p = NULL;
  size_t np = 0;
  gmshModelGetParametrization(2, f->tag, (double *)xyz, 3 * n, &p, &np, &ierr);
  if (ierr || np != 2 * n) {
    gmshFree(p);
    return hoc_gmsh_error("projection on a surface");
  }
  memcpy(uv, p, 2 * n * sizeof *p);
  gmshFree(p);
  return HOC_OK;
}

static hoc_status gmsh_curve_project_unlocked(void *ctx, const hoc_cad_curve *c, size_t n,
                                              const double *xyz, double *t) {
  (void)ctx;
  if (!n) return HOC_OK;
  int ierr = 0;
  double *p = NULL;
  size_t np = 0;
  gmshModelGetParametrization(1, c->tag, (double *)xyz, 3 * n, &p, &np, &ierr);
  if (ierr || np != n) {
    gmshFree(p);
    return hoc_gmsh_error("projection on a curve");
  }
  memcpy(t, p, n * sizeof *p);
  gmshFree(p);
  return HOC_OK;
}

/* reparametrisation and projection: one caller at a time */
static hoc_status gmsh_curve_to_face(void *ctx, const hoc_cad_curve *c, const hoc_cad_face *f,
                                     size_t n, const double *t, double *uv) {
  serial_begin(1);
  hoc_status st = gmsh_curve_to_face_unlocked(ctx, c, f, n, t, uv);
  serial_end(1);
  return st;
}

static hoc_status gmsh_vertex_to_face(void *ctx, const hoc_cad_vertex *v, const hoc_cad_face *f,
                                      double *uv) {
  serial_begin(1);
  hoc_status st = gmsh_vertex_to_face_unlocked(ctx, v, f, uv);
  serial_end(1);
  return st;
}

static hoc_status gmsh_face_project(void *ctx, const hoc_cad_face *f, size_t n, const double *xyz,
                                    double *uv) {
  serial_begin(1);
  hoc_status st = gmsh_face_project_unlocked(ctx, f, n, xyz, uv);
  serial_end(1);
  return st;
}

static hoc_status gmsh_curve_project(void *ctx, const hoc_cad_curve *c, size_t n, const double *xyz,
                                     double *t) {
  serial_begin(1);
  hoc_status st = gmsh_curve_project_unlocked(ctx, c, n, xyz, t);
  serial_end(1);
  return st;
}

static void gmsh_destroy(void *ctx) {
  (void)ctx;
  int ierr = 0;
  gmshClear(&ierr);
  gmsh_model_in_use = 0;
}

static const hoc_cad_ops gmsh_ops = {
    gmsh_face_eval,    gmsh_curve_eval,    gmsh_curve_to_face, gmsh_vertex_to_face,
    gmsh_face_project, gmsh_curve_project, gmsh_destroy,
};

/* Import ------------------------------------------------------------------ */

static int has_cad_extension(const char *path) {
  const char *dot = strrchr(path, '.');
  const char *slash = strrchr(path, '/');
  if (!dot || (slash && dot < slash)) return 0;
  static const char *const ext[] = {".step", ".stp", ".iges", ".igs", ".brep", ".brp"};
  for (size_t i = 0; i < sizeof ext / sizeof *ext; ++i)
    if (!strcasecmp(dot, ext[i])) return 1;
  return 0;
}

static hoc_status get_entities(int dim, int **tags, size_t *n) {
  int *dt = NULL, ierr = 0;
  size_t ndt = 0;
  gmshModelGetEntities(&dt, &ndt, dim, &ierr);
  if (ierr) {
    gmshFree(dt);
    return hoc_gmsh_error("listing the model's entities");
  }
  *n = ndt / 2;
  int *t = hoc_calloc(*n, sizeof *t);
  if (!t) {
    gmshFree(dt);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory for %zu entities", *n);
  }
  for (size_t i = 0; i < *n; ++i) t[i] = dt[2 * i + 1];
  gmshFree(dt);
  *tags = t;
  return HOC_OK;
}

static hoc_status get_bounds(int dim, int tag, double *lo, double *hi) {
  double *mn = NULL, *mx = NULL;
  size_t nmn = 0, nmx = 0;
  int ierr = 0;
  gmshModelGetParametrizationBounds(dim, tag, &mn, &nmn, &mx, &nmx, &ierr);
  if (ierr || nmn != (size_t)dim || nmx != (size_t)dim) {
    gmshFree(mn);
    gmshFree(mx);
    return hoc_gmsh_error("reading parametric bounds");
  }
  for (int k = 0; k < dim; ++k) {
    lo[k] = mn[k];
    hi[k] = mx[k];
  }
  gmshFree(mn);
  gmshFree(mx);
  return HOC_OK;
}

static hoc_status get_boundary(int dim, int tag, int **bnd, int *n) {
  int dimtag[2] = {dim, tag}, *out = NULL, ierr = 0;
  size_t nout = 0;
  gmshModelGetBoundary(dimtag, 2, &out, &nout, 0, 1, 0, &ierr);
  if (ierr) {
    gmshFree(out);
    return hoc_gmsh_error("reading an entity's boundary");
  }
  *n = (int)(nout / 2);
  int *b = hoc_calloc((size_t)*n, sizeof *b);
  if (!b) {
    gmshFree(out);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  for (int i = 0; i < *n; ++i) b[i] = out[2 * i + 1];
  gmshFree(out);
  *bnd = b;
  return HOC_OK;
}

static void get_bbox(int dim, int tag, double *bb) {
  int ierr = 0;
  gmshModelGetBoundingBox(dim, tag, bb, bb + 1, bb + 2, bb + 3, bb + 4, bb + 5, &ierr);
  if (ierr)
    for (int k = 0; k < 6; ++k) bb[k] = 0;
}

/* Widens box bb (lo, hi) to hold box add. */
static void add_box(double *bb, const double *add, int first) {
  for (int k = 0; k < 3; ++k) {
    bb[k] = first ? add[k] : fmin(bb[k], add[k]);
    bb[k + 3] = first ? add[k + 3] : fmax(bb[k + 3], add[k + 3]);
  }
}

/* bb: the box of m's faces, of the curves that bound them, of those
 * curves' vertices and of the volumes. */
static hoc_status faces_box(const hoc_model *m, double *bb) {
  int max_tag = 0;
  for (int c = 0; c < m->n_curves; ++c)
    if (m->curves[c].tag > max_tag) max_tag = m->curves[c].tag;
  unsigned char *used = hoc_calloc((size_t)max_tag + 1 + (size_t)m->n_vertices, 1);
  HOC_CHECK(used, HOC_ERR_MEMORY, "out of memory");
  unsigned char *vused = used + max_tag + 1; /* used[tag] for curves */
  for (int i = 0; i < m->n_faces; ++i) {
    const hoc_cad_face *f = &m->faces[i];
    add_box(bb, f->bbox, i == 0);
    for (int k = 0; k < f->n_curves; ++k)
      if (abs(f->curves[k]) <= max_tag) used[abs(f->curves[k])] = 1;
  }
  for (int c = 0; c < m->n_curves; ++c) {
    if (m->curves[c].tag < 0 || !used[m->curves[c].tag]) continue;
    add_box(bb, m->curves[c].bbox, 0);
    if (m->curves[c].v0 >= 0) vused[m->curves[c].v0] = 1;
    if (m->curves[c].v1 >= 0) vused[m->curves[c].v1] = 1;
  }
  for (int v = 0; v < m->n_vertices; ++v) {
    if (!vused[v]) continue;
    double vb[6];
    get_bbox(0, m->vertices[v].tag, vb);
    add_box(bb, vb, 0);
  }
  free(used);
  int *vol = NULL;
  size_t nvol = 0;
  HOC_TRY(get_entities(3, &vol, &nvol));
  for (size_t i = 0; i < nvol; ++i) {
    double vb[6];
    get_bbox(3, vol[i], vb);
    add_box(bb, vb, 0);
  }
  free(vol);
  return HOC_OK;
}

static hoc_status fill_model(hoc_model *m, const int *ftags, const int *ctags, const int *vtags) {
  int ierr = 0;
  for (int i = 0; i < m->n_vertices; ++i) {
    hoc_cad_vertex *v = &m->vertices[i];
    v->tag = vtags[i];
    double bb[6];
    get_bbox(0, v->tag, bb);
    for (int k = 0; k < 3; ++k) v->xyz[k] = 0.5 * (bb[k] + bb[k + 3]);
  }
  for (int i = 0; i < m->n_curves; ++i) {
    hoc_cad_curve *c = &m->curves[i];
    c->tag = ctags[i];
    HOC_TRY(get_bounds(1, c->tag, &c->lo, &c->hi));
    get_bbox(1, c->tag, c->bbox);
    char *type = NULL;
    gmshModelGetType(1, c->tag, &type, &ierr);
    c->concurrent = (unsigned char)(!ierr && type && concurrent_kind(1, type));
    gmshFree(type);
    int *b = NULL, nb = 0;
    HOC_TRY(get_boundary(1, c->tag, &b, &nb));
    /* gmsh lists a curve's start vertex first */
    c->v0 = c->v1 = -1;
    for (int k = 0; k < nb && k < 2; ++k) {
      int idx = -1;
      for (int j = 0; j < m->n_vertices; ++j)
        if (m->vertices[j].tag == abs(b[k])) idx = j;
      if (k == 0) c->v0 = idx;
      else c->v1 = idx;
    }
    if (nb == 1) c->v1 = c->v0; /* closed curve with one vertex */
    free(b);
  }
  for (int i = 0; i < m->n_faces; ++i) {
    hoc_cad_face *f = &m->faces[i];
    f->tag = ftags[i];
    HOC_TRY(get_bounds(2, f->tag, f->lo, f->hi));
    get_bbox(2, f->tag, f->bbox);
    HOC_TRY(get_boundary(2, f->tag, &f->curves, &f->n_curves));
    char *s = NULL;
    gmshModelGetType(2, f->tag, &s, &ierr);
    if (!ierr && s) snprintf(f->type, sizeof f->type, "%s", s);
    f->concurrent = (unsigned char)(!ierr && s && concurrent_kind(2, s));
    gmshFree(s);
    s = NULL;
    gmshModelGetEntityName(2, f->tag, &s, &ierr);
    if (!ierr && s) snprintf(f->name, sizeof f->name, "%s", s);
    gmshFree(s);
  }
  /* the box of the faces and of the curves and vertices around them (the
   * kernel's boxes, each widened by its entity's tolerance): a file may
   * keep vertices and curves that bound no face (construction points, the
   * sections of a loft, annotations) anywhere, and hocad meshes the faces
   * (a model without faces is refused later) */
  get_bbox(-1, -1, m->bbox);
  if (m->n_faces) HOC_TRY(faces_box(m, m->bbox));
  return HOC_OK;
}

static hoc_status open_here(const char *path, hoc_model **model);

/* The import first runs in a child process: gmsh's STEP reader crashes on
 * some malformed files (SIGSEGV after it reports an unresolved reference),
 * and a crash must end only the child. The child does all this process
 * then does (import, entity tables, the checks of hoc_cad_finish) and
 * reports its status and message; this process imports only after the
 * child succeeded, and reports the child's failure as its own otherwise
 * (its own gmsh stays untouched by a failed import). The cost is a second
 * import, twice the time: 0.07 to 0.64 s more on the largest models of
 * the corpus (docs/kernel.md). */
typedef struct import_job {
  const char *path;
} import_job;

static int import_child(void *arg, int fd) {
  const import_job *job = arg;
  omp_set_num_threads(1); /* see child.c on OpenMP after fork */
  hoc_model *m = NULL;
  hoc_status st = open_here(job->path, &m);
  hoc_model_destroy(&m); /* a leak checker looks at the child too */
  const char *msg = st == HOC_OK ? "" : hoc_last_error();
  uint32_t head[2] = {(uint32_t)st, (uint32_t)strlen(msg)};
  return hoc_child_write(fd, head, sizeof head) && hoc_child_write(fd, msg, head[1]) ? 0 : 1;
}

static hoc_status open_in_child(const char *path) {
  import_job job = {path};
  hoc_child c;
  HOC_TRY(hoc_child_start(&c, import_child, &job));
  uint32_t head[2] = {0, 0};
  char msg[1024] = ""; /* room for any message: they hold at most 511 bytes (core/error.c) */
  int got = hoc_child_read(&c, head, sizeof head) && head[1] < sizeof msg &&
            hoc_child_read(&c, msg, head[1]);
  hoc_child_end end;
  hoc_child_finish(&c, !got, &end);
  if (got) {
    msg[head[1]] = '\0';
    if (head[0] == HOC_OK) return HOC_OK;
    return HOC_ERROR((hoc_status)head[0], "%s", msg);
  }
  const char *sep = end.first_error[0] ? ": " : "";
  if (end.signal && hoc_signal_is_interrupt(end.signal))
    return HOC_ERROR(HOC_ERR_INTERRUPTED, "interrupted (%s) while reading '%s'",
                     hoc_signal_name(end.signal), path);
  if (end.signal == SIGKILL)
    return HOC_ERROR(HOC_ERR_CAD, "cannot read CAD file '%s': gmsh's importer was killed (SIGKILL)",
                     path);
  if (end.signal)
    return HOC_ERROR(HOC_ERR_FORMAT, "cannot read CAD file '%s': gmsh's importer crashed (%s)%s%s",
                     path, hoc_signal_name(end.signal), sep, end.first_error);
  return HOC_ERROR(HOC_ERR_CAD,
                   "cannot read CAD file '%s': gmsh's importer ended without a result (exit "
                   "status %d)%s%s",
                   path, end.exit_code, sep, end.first_error);
}

hoc_status hoc_cad_open_gmsh(const char *path, hoc_model **model) {
  HOC_CHECK(model, HOC_ERR_ARGUMENT, "model output is NULL");
  *model = NULL;
  HOC_CHECK(path && path[0], HOC_ERR_ARGUMENT, "no CAD file name given");
  HOC_CHECK(!gmsh_model_in_use, HOC_ERR_ARGUMENT,
            "another CAD model is open: gmsh holds one model at a time");
  struct stat sb;
  if (stat(path, &sb) != 0)
    return HOC_ERROR(HOC_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
  HOC_CHECK(!S_ISDIR(sb.st_mode), HOC_ERR_IO, "'%s' is a directory, not a CAD file", path);
  FILE *probe = fopen(path, "rb");
  if (!probe) return HOC_ERROR(HOC_ERR_IO, "cannot read '%s': %s", path, strerror(errno));
  fclose(probe);
  HOC_CHECK(has_cad_extension(path), HOC_ERR_FORMAT,
            "'%s' is not a CAD file: expected .step, .stp, .iges, .igs or .brep", path);
  HOC_CHECK(sb.st_size > 0, HOC_ERR_FORMAT, "'%s' is empty", path);
  HOC_TRY(hoc_gmsh_start());
  int ierr = 0;
  gmshClear(&ierr);
  HOC_TRY(open_in_child(path));
  return open_here(path, model);
}

/* Import and entity tables in this process (gmsh started, its model empty). */
static hoc_status open_here(const char *path, hoc_model **model) {
  int ierr = 0;
  hoc_quiet q;
  hoc_quiet_begin(&q);
  int threads = omp_get_max_threads();
  gmshOpen(path, &ierr);
  omp_set_num_threads(threads);
  char kernel_msg[256];
  hoc_quiet_end(&q, kernel_msg, sizeof kernel_msg);
  if (ierr) {
    /* what OpenCASCADE printed, else gmsh's own message ("OpenCASCADE
     * exception TopoDS::Face" for an IGES face it cannot build) */
    char *logged = NULL;
    int ierr2 = 0;
    if (!kernel_msg[0]) gmshLoggerGetLastError(&logged, &ierr2);
    if (!kernel_msg[0] && !ierr2 && logged)
      snprintf(kernel_msg, sizeof kernel_msg, "%s", logged);
    gmshFree(logged);
    gmsh_restart_after_failure();
    if (kernel_msg[0])
      return HOC_ERROR(HOC_ERR_FORMAT, "cannot read CAD file '%s': %s", path, kernel_msg);
    return HOC_ERROR(HOC_ERR_FORMAT, "cannot read CAD file '%s' (corrupt or unsupported)", path);
  }

  int *ftags = NULL, *ctags = NULL, *vtags = NULL;
  size_t nf = 0, nc = 0, nv = 0;
  hoc_model *m = NULL;
  hoc_status status = HOC_OK;
  HOC_TRY_GOTO(get_entities(2, &ftags, &nf), fail);
  HOC_TRY_GOTO(get_entities(1, &ctags, &nc), fail);
  HOC_TRY_GOTO(get_entities(0, &vtags, &nv), fail);
  if (nf == 0) {
    status = HOC_ERROR(HOC_ERR_CAD, "'%s' holds no surface (no CAD face to mesh)", path);
    goto fail;
  }
  HOC_TRY_GOTO(hoc_cad_create((int)nf, (int)nc, (int)nv, &m), fail);
  m->ops = &gmsh_ops;
  m->ctx = NULL;
  m->thread_safe = 1; /* see the lock at the top */
  m->is_gmsh = 1;
  gmsh_model_in_use = 1;
  HOC_TRY_GOTO(fill_model(m, ftags, ctags, vtags), fail);
  HOC_TRY_GOTO(hoc_cad_finish(m), fail);
  free(ftags);
  free(ctags);
  free(vtags);
  *model = m;
  return HOC_OK;
fail:
  free(ftags);
  free(ctags);
  free(vtags);
  hoc_model_destroy(&m);
  gmsh_model_in_use = 0;
  gmsh_restart_after_failure();
  return status;
}

hoc_status hoc_model_open(const char *path, hoc_model **model) {
  return hoc_cad_open_gmsh(path, model);
}
