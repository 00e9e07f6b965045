/* Linear surface mesh of the CAD model through gmsh, with every node's
 * classification and parameters.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "cad/gmsh_util.h"
#include "core/geometry.h"
#include "core/hash.h"
#include "mesh/mesh.h"

#include <gmshc.h>
#include <omp.h>

#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void hoc_linear_options_default(hoc_linear_options *o) {
  if (!o) return;
  memset(o, 0, sizeof *o);
  o->order = 1;
  o->grading = 1;
}

void hoc_linear_sizes(const hoc_model *model, const hoc_linear_options *o, double *size_max,
                      double *size_min) {
  *size_max = o && o->size_max > 0 ? o->size_max : model->diagonal / 20;
  *size_min = o && o->size_min > 0 ? o->size_min : *size_max / 10;
}

/* Default elements per 2 pi of curvature radius: enough that the linear
 * mesh follows curved faces and the curved elements of order p stay valid. */
static double default_curvature(int order) {
  /* a linear mesh must follow curved faces with its own chords; curved
   * elements of order >= 2 follow them exactly and need fewer */
  return order <= 1 ? 12 : 8;
}

typedef struct growable {
  size_t n, cap;
  double *xyz, *par;
  signed char *dim;
  int *ent;
  size_t *tag;
} growable;

static hoc_status reserve(growable *g, size_t more) {
  if (g->n + more <= g->cap) return HOC_OK;
  size_t cap = g->cap ? g->cap : 1024;
  while (cap < g->n + more) cap *= 2;
  double *x = hoc_realloc(g->xyz, 3 * cap, sizeof *x);
  if (x) g->xyz = x;
  double *p = hoc_realloc(g->par, 2 * cap, sizeof *p);
  if (p) g->par = p;
  signed char *d = hoc_realloc(g->dim, cap, sizeof *d);
  if (d) g->dim = d;
  int *e = hoc_realloc(g->ent, cap, sizeof *e);
  if (e) g->ent = e;
  size_t *t = hoc_realloc(g->tag, cap, sizeof *t);
  if (t) g->tag = t;
  HOC_CHECK(x && p && d && e && t, HOC_ERR_MEMORY, "out of memory for %zu nodes", cap);
  g->cap = cap;
  return HOC_OK;
}

static void growable_free(growable *g) {
  free(g->xyz);
  free(g->par);
  free(g->dim);
  free(g->ent);
  free(g->tag);
}

/* gmsh's mesher runs in a child process (cad/child.c): it aborts the
 * process on some models (an uncaught exception after "Unable to recover
 * the edge"), which must end only the child. The child meshes, then sends
 * the classified mesh through a pipe as gmsh's API returns it; this
 * process reads it in the order an in-process run asks gmsh for it, so the
 * mesh is the one an in-process run makes, bit for bit.
 *
 * When the child crashed, a second child finds the faces that crash gmsh
 * and meshes the others: it meshes the curves, then tries each face alone
 * in a child of its own (which inherits the curves' mesh, so a face costs
 * only its own meshing), then meshes the faces that survived. The faces
 * left out count as failed faces, like faces gmsh leaves empty.
 *
 * The stream (every count a uint64_t, arrays as gmsh returns them):
 *   when finding crashing faces, for each face: 0 if meshing it alone
 *     succeeded (or failed without a crash), else the signal that ended it
 *     (255: it ended without a result otherwise);
 *   status 0 (meshed), or 1 then a message (gmsh reported an error);
 *   for each vertex, curve, face (model order), the nodes classified on it:
 *     n, tags[n] (size_t), coordinates[3 n], m, parameters[m];
 *   for each face its triangles, for each curve its lines:
 *     n, node tags[n];
 *   a failed gmsh call in the child sends UINT64_MAX and a message instead
 *   of a count.
 * A message is its length (uint64_t) and its bytes. */

enum { MESSAGE_MAX = 512 };

typedef struct mesh_job {
  const hoc_model *model;
  const int *algorithm; /* NULL, or [n_faces] gmsh's 2D algorithm per face (0: its default) */
  int isolate; /* find the faces that crash gmsh first, and leave them out */
  int face;    /* a probe of one face (index): does meshing it alone crash? */
  double timeout; /* > 0: seconds a face probe may take (then it counts as failed) */
  const unsigned char *skip; /* NULL, or [n_faces]: nonzero for the faces known to fail
                                (left out unprobed; a probe reports the value) */
} mesh_job;

/* A face probe's report of a face gmsh did not finish meshing in time
 * (other nonzero reports are the signal that ended the probe, or 255). */
enum { FACE_TIMED_OUT = HOC_MESHER_TIMED_OUT };

/* While the faces are probed one by one, the parent waits for each face's
 * report up to PROBE_SLACK times the probe's limit plus PROBE_SLACK_SECONDS
 * (the child meshes the curves before the first probe, and forks each). */
#define PROBE_SLACK 2.0
#define PROBE_SLACK_SECONDS 10.0

static int send_u64(int fd, uint64_t v) { return hoc_child_write(fd, &v, sizeof v); }

static int send_message(int fd, const char *msg) {
  size_t n = strlen(msg);
  return send_u64(fd, n) && hoc_child_write(fd, msg, n);
}

/* gmsh's last error, prefixed by `what` */
static int send_gmsh_error(int fd, const char *what) {
  char *logged = NULL, msg[MESSAGE_MAX];
  int ierr = 0;
  gmshLoggerGetLastError(&logged, &ierr);
  if (!ierr && logged && logged[0]) snprintf(msg, sizeof msg, "%s: %s", what, logged);
  else snprintf(msg, sizeof msg, "%s failed in gmsh", what);
  gmshFree(logged);
  return send_message(fd, msg);
}

static int send_array(int fd, const void *data, size_t n, size_t size) {
  return send_u64(fd, n) && hoc_child_write(fd, data, n * size);
}

static int send_entity_nodes(int fd, int dim, int tag) {
  size_t *tags = NULL, nt = 0, nc = 0, npar = 0;
  double *coord = NULL, *par = NULL;
  int ierr = 0, ok;
  gmshModelMeshGetNodes(&tags, &nt, &coord, &nc, &par, &npar, dim, tag, 0, dim > 0, &ierr);
  if (ierr || nc != 3 * nt)
    ok = send_u64(fd, UINT64_MAX) && send_gmsh_error(fd, "reading mesh nodes");
  else
    ok = send_u64(fd, nt) && hoc_child_write(fd, tags, nt * sizeof *tags) &&
         hoc_child_write(fd, coord, nc * sizeof *coord) && send_array(fd, par, npar, sizeof *par);
  gmshFree(tags);
  gmshFree(coord);
  gmshFree(par);
  return ok;
}

static int send_entity_elements(int fd, int type, int tag) {
  size_t *etags = NULL, net = 0, *ntags = NULL, nnt = 0;
  int ierr = 0, ok;
  gmshModelMeshGetElementsByType(type, &etags, &net, &ntags, &nnt, tag, 0, 1, &ierr);
  int nodes_per = type == 2 ? 3 : 2;
  if (ierr || nnt != net * (size_t)nodes_per)
    ok = send_u64(fd, UINT64_MAX) && send_gmsh_error(fd, "reading mesh elements");
  else
    ok = send_array(fd, ntags, nnt, sizeof *ntags);
  gmshFree(etags);
  gmshFree(ntags);
  return ok;
}

/* The next generate meshes only the faces with keep[f] set. */
static void mesh_only(const hoc_model *model, const unsigned char *keep) {
  int ierr = 0;
  gmshOptionSetNumber("Mesh.MeshOnlyVisible", 1, &ierr);
  for (int f = 0; f < model->n_faces; ++f) {
    int dimtag[2] = {2, model->faces[f].tag};
    gmshModelSetVisibility(dimtag, 2, keep[f], 0, &ierr);
  }
}

/* In a grandchild: mesh face job->face alone (the curves are meshed). */
static int face_probe(void *arg, int fd) {
  const mesh_job *job = arg;
  const hoc_model *model = job->model;
  unsigned char *keep = hoc_calloc((size_t)model->n_faces, 1);
  if (!keep) return 1;
  keep[job->face] = 1;
  mesh_only(model, keep);
  free(keep);
  int ierr = 0;
  gmshModelMeshGenerate(2, &ierr);
  return send_u64(fd, 0) ? 0 : 1;
}

/* In the child: mesh and send the result. */
static int mesh_child(void *arg, int fd) {
  const mesh_job *job = arg;
  const hoc_model *model = job->model;
  int ierr = 0;
  omp_set_num_threads(1); /* one thread: the same mesh every time (and see child.c) */
  /* gmsh's errors (its verbosity is errors only) go to the child's
   * output, so that the cause of a crash is there after it */
  gmshOptionSetNumber("General.Terminal", 1, &ierr);
  /* the faces meshed with another algorithm (set here: the parent's gmsh
   * keeps its defaults); a face probe, forked from here, inherits them */
  for (int f = 0; job->algorithm && f < model->n_faces; ++f) {
    if (job->algorithm[f] <= 0) continue;
    gmshModelMeshSetAlgorithm(2, model->faces[f].tag, job->algorithm[f], &ierr);
    if (!ierr) continue;
    for (int k = 0; job->isolate && k < model->n_faces; ++k) /* no face tried */
      if (!send_u64(fd, 0)) return 1;
    return send_u64(fd, 1) && send_gmsh_error(fd, "choosing a face's algorithm") ? 0 : 1;
  }
  if (job->isolate) {
    gmshModelMeshGenerate(1, &ierr);
    if (ierr) { /* no face tried, then gmsh's error */
      for (int f = 0; f < model->n_faces; ++f)
        if (!send_u64(fd, 0)) return 1;
      return send_u64(fd, 1) && send_gmsh_error(fd, "meshing the curves") ? 0 : 1;
    }
    unsigned char *keep = hoc_calloc((size_t)model->n_faces, 1);
    if (!keep) return 1;
    int sent = 1;
    for (int f = 0; f < model->n_faces && sent; ++f) {
      if (job->skip && job->skip[f]) {
        sent = send_u64(fd, job->skip[f]);
        continue;
      }
      mesh_job probe = {model, job->algorithm, 0, f, 0, NULL};
      hoc_child c;
      hoc_child_end end;
      uint64_t ok = 1;
      if (hoc_child_start(&c, face_probe, &probe) != HOC_OK) {
        sent = 0;
        break;
      }
      c.idle_limit = job->timeout;
      int got = hoc_child_read(&c, &ok, sizeof ok);
      hoc_child_finish(&c, 0, &end);
      keep[f] = got && ok == 0;
      uint64_t why = end.timed_out ? FACE_TIMED_OUT : end.signal > 0 ? (uint64_t)end.signal : 255;
      sent = send_u64(fd, keep[f] ? 0 : why);
    }
    if (sent) mesh_only(model, keep);
    free(keep); /* a leak checker looks at the child too */
    if (!sent) return 1;
  } else if (job->skip) {
    unsigned char *keep = hoc_calloc((size_t)model->n_faces, 1);
    if (!keep) return 1;
    for (int f = 0; f < model->n_faces; ++f) keep[f] = !job->skip[f];
    mesh_only(model, keep);
    free(keep);
  }
  gmshModelMeshGenerate(2, &ierr);
  if (ierr) return send_u64(fd, 1) && send_gmsh_error(fd, "meshing") ? 0 : 1;
  if (!send_u64(fd, 0)) return 1;
  for (int v = 0; v < model->n_vertices; ++v)
    if (!send_entity_nodes(fd, 0, model->vertices[v].tag)) return 1;
  for (int c = 0; c < model->n_curves; ++c)
    if (!send_entity_nodes(fd, 1, model->curves[c].tag)) return 1;
  for (int f = 0; f < model->n_faces; ++f)
    if (!send_entity_nodes(fd, 2, model->faces[f].tag)) return 1;
  for (int f = 0; f < model->n_faces; ++f)
    if (!send_entity_elements(fd, 2, model->faces[f].tag)) return 1;
  for (int c = 0; c < model->n_curves; ++c)
    if (!send_entity_elements(fd, 1, model->curves[c].tag)) return 1;
  return 0;
}

/* In this process: reading the child's stream. `ended` is set when the
 * stream stops short (the child died: its exit status tells why). */
typedef struct reader {
  hoc_child *child;
  int ended;
} reader;

static hoc_status read_u64(reader *r, uint64_t *v) {
  if (hoc_child_read(r->child, v, sizeof *v)) return HOC_OK;
  r->ended = 1;
  return HOC_ERR_MESH;
}

static hoc_status read_bytes(reader *r, void *dst, size_t n) {
  if (hoc_child_read(r->child, dst, n)) return HOC_OK;
  r->ended = 1;
  return HOC_ERR_MESH;
}

/* A message from the child into this thread's error, as HOC_ERR_CAD. */
static hoc_status read_message(reader *r) {
  uint64_t n;
  char msg[MESSAGE_MAX];
  HOC_TRY(read_u64(r, &n));
  if (n >= sizeof msg) {
    r->ended = 1;
    return HOC_ERR_MESH;
  }
  HOC_TRY(read_bytes(r, msg, (size_t)n));
  msg[n] = '\0';
  return HOC_ERROR(HOC_ERR_CAD, "%s", msg);
}

/* A count, or the child's message if it sent one instead. */
static hoc_status read_count(reader *r, size_t limit, size_t *n) {
  uint64_t v;
  HOC_TRY(read_u64(r, &v));
  if (v == UINT64_MAX) return read_message(r);
  HOC_CHECK(v <= limit, HOC_ERR_INTERNAL, "gmsh's mesher sent a count of %llu",
            (unsigned long long)v);
  *n = (size_t)v;
  return HOC_OK;
}

/* Read an array of n items of `size` bytes into a new allocation. */
static hoc_status read_alloc(reader *r, size_t n, size_t size, void **out) {
  *out = hoc_calloc(n, size);
  HOC_CHECK(*out, HOC_ERR_MEMORY, "out of memory for %zu mesh items", n);
  return read_bytes(r, *out, n * size);
}

/* Append the nodes classified on one entity (not its boundary). */
static hoc_status add_entity_nodes(reader *r, growable *g, hoc_hash *index, int dim, int entity) {
  size_t *tags = NULL, nt = 0, npar = 0;
  double *coord = NULL, *par = NULL;
  hoc_status status = HOC_OK;
  const size_t limit = SIZE_MAX / 64;
  HOC_TRY_GOTO(read_count(r, limit, &nt), done);
  HOC_TRY_GOTO(read_alloc(r, nt, sizeof *tags, (void **)&tags), done);
  HOC_TRY_GOTO(read_alloc(r, 3 * nt, sizeof *coord, (void **)&coord), done);
  HOC_TRY_GOTO(read_count(r, limit, &npar), done);
  HOC_TRY_GOTO(read_alloc(r, npar, sizeof *par, (void **)&par), done);
  if (dim > 0 && npar != (size_t)dim * nt) {
    status = HOC_ERROR(HOC_ERR_CAD, "reading mesh nodes: gmsh gave %zu parameters for %zu nodes",
                       npar, nt);
    goto done;
  }
  HOC_TRY_GOTO(reserve(g, nt), done);
  for (size_t k = 0; k < nt; ++k) {
    size_t i = g->n;
    int found;
    HOC_TRY_GOTO(hoc_hash_insert(index, (uint64_t)tags[k], i, &found, NULL), done);
    if (found) continue; /* a node listed twice: keep its first classification */
    memcpy(g->xyz + 3 * i, coord + 3 * k, 3 * sizeof(double));
    g->par[2 * i] = dim > 0 ? par[(size_t)dim * k] : 0.0;
    g->par[2 * i + 1] = dim > 1 ? par[(size_t)dim * k + 1] : 0.0;
    g->dim[i] = (signed char)dim;
    g->ent[i] = entity;
    g->tag[i] = tags[k];
    g->n++;
  }
done:
  free(tags);
  free(coord);
  free(par);
  return status;
}

/* Append the elements of one entity as node indices. */
static hoc_status add_entity_elements(reader *r, int nodes_per, const hoc_hash *index,
                                      size_t **conn, size_t *n, size_t *cap, int **owner,
                                      int owner_value) {
  size_t *ntags = NULL, nnt = 0;
  hoc_status status = HOC_OK;
  HOC_TRY_GOTO(read_count(r, SIZE_MAX / 64, &nnt), done);
  HOC_TRY_GOTO(read_alloc(r, nnt, sizeof *ntags, (void **)&ntags), done);
  if (nnt % (size_t)nodes_per) {
    status = HOC_ERROR(HOC_ERR_INTERNAL, "gmsh's mesher sent %zu node tags for elements of %d",
                       nnt, nodes_per);
    goto done;
  }
  size_t net = nnt / (size_t)nodes_per;
  if (*n + net > *cap) {
    size_t c = *cap ? *cap : 1024;
    while (c < *n + net) c *= 2;
    size_t *c2 = hoc_realloc(*conn, c * (size_t)nodes_per, sizeof *c2);
    if (c2) *conn = c2;
    int *o2 = hoc_realloc(*owner, c, sizeof *o2);
    if (o2) *owner = o2;
    if (!c2 || !o2) {
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory for %zu elements", c);
      goto done;
    }
    *cap = c;
  }
  for (size_t e = 0; e < net; ++e) {
    for (int k = 0; k < nodes_per; ++k) {
      size_t i = hoc_hash_get(index, (uint64_t)ntags[e * (size_t)nodes_per + k]);
      if (i == SIZE_MAX) {
        status = HOC_ERROR(HOC_ERR_MESH, "gmsh element uses an unclassified node %zu",
                           ntags[e * (size_t)nodes_per + k]);
        goto done;
      }
      (*conn)[(*n + e) * (size_t)nodes_per + k] = i;
    }
    (*owner)[*n + e] = owner_value;
  }
  *n += net;
done:
  free(ntags);
  return status;
}

/* The classified linear mesh as the child sent it. */
typedef struct linear_parts {
  growable g;
  hoc_hash index;
  size_t *tri, n_tri, cap_tri, *lines, n_lines, cap_lines;
  int *tri_face, *line_curve, *failed, n_failed;
} linear_parts;

static void linear_parts_free(linear_parts *p) {
  growable_free(&p->g);
  hoc_hash_free(&p->index);
  free(p->tri);
  free(p->tri_face);
  free(p->lines);
  free(p->line_curve);
  free(p->failed);
  memset(p, 0, sizeof *p);
}

static hoc_status read_parts(reader *r, const hoc_model *model, linear_parts *p) {
  HOC_TRY(hoc_hash_init(&p->index, 4096));
  for (int v = 0; v < model->n_vertices; ++v)
    HOC_TRY(add_entity_nodes(r, &p->g, &p->index, 0, v));
  for (int c = 0; c < model->n_curves; ++c)
    HOC_TRY(add_entity_nodes(r, &p->g, &p->index, 1, c));
  for (int f = 0; f < model->n_faces; ++f)
    HOC_TRY(add_entity_nodes(r, &p->g, &p->index, 2, f));
  p->failed = hoc_calloc((size_t)model->n_faces, sizeof *p->failed);
  HOC_CHECK(p->failed, HOC_ERR_MEMORY, "out of memory");
  for (int f = 0; f < model->n_faces; ++f) {
    size_t before = p->n_tri;
    HOC_TRY(add_entity_elements(r, 3, &p->index, &p->tri, &p->n_tri, &p->cap_tri, &p->tri_face,
                                f));
    if (p->n_tri == before) p->failed[p->n_failed++] = f;
  }
  for (int c = 0; c < model->n_curves; ++c)
    HOC_TRY(add_entity_elements(r, 2, &p->index, &p->lines, &p->n_lines, &p->cap_lines,
                                &p->line_curve, c));
  return HOC_OK;
}

/* How a run of the mesher ended. */
typedef enum run_outcome {
  RUN_MESHED,     /* the mesh was read */
  RUN_GMSH_ERROR, /* gmsh reported an error: this thread's error holds it */
  RUN_CRASHED,    /* the child died of a signal (end->signal) */
  RUN_FAILED      /* anything else: this thread's error holds it */
} run_outcome;

/* One run of gmsh's mesher in a child. With `crashed` ([n_faces]), the
 * child first finds the faces that crash gmsh: crashed[f] receives the
 * signal that ended face f's probe (0: none), *probed how many faces it
 * reported before it ended. The faces flagged in skip (NULL: none) are left
 * out unprobed, their flag reported as their probe's. A run that did not
 * finish in time ends with end->signal FACE_TIMED_OUT. */
static run_outcome run_mesher(const hoc_model *model, const int *algorithm, double timeout,
                              const unsigned char *skip, unsigned char *crashed, int *probed,
                              linear_parts *parts, hoc_status *error, hoc_child_end *end) {
  mesh_job job = {model, algorithm, crashed != NULL, -1, timeout, skip};
  hoc_child child;
  *error = hoc_child_start(&child, mesh_child, &job);
  if (*error != HOC_OK) return RUN_FAILED;
  /* the whole mesh within timeout; each face probe within it (the child
   * ends the probe), then the faces that passed without a limit */
  if (timeout > 0)
    child.idle_limit = crashed ? PROBE_SLACK * timeout + PROBE_SLACK_SECONDS : timeout;
  reader r = {&child, 0};
  hoc_status st = HOC_OK;
  for (int f = 0; crashed && f < model->n_faces && st == HOC_OK; ++f) {
    uint64_t sig = 0;
    st = read_u64(&r, &sig);
    if (st == HOC_OK) {
      crashed[f] = (unsigned char)(sig < 256 ? sig : 255);
      *probed = f + 1;
    }
  }
  if (crashed) child.idle_limit = 0;
  uint64_t head = 0;
  if (st == HOC_OK) st = read_u64(&r, &head);
  int gmsh_error = st == HOC_OK && head == 1;
  if (st == HOC_OK && head > 1) st = HOC_ERROR(HOC_ERR_INTERNAL, "gmsh's mesher sent no status");
  if (gmsh_error) st = read_message(&r);
  else if (st == HOC_OK) st = read_parts(&r, model, parts);
  hoc_child_finish(&child, st != HOC_OK && !r.ended && !gmsh_error, end);
  if (r.ended) {
    if (end->signal && end->timed_out) end->signal = FACE_TIMED_OUT;
    if (end->signal) return RUN_CRASHED;
    *error = HOC_ERROR(HOC_ERR_MESH,
                       "gmsh's mesher ended without a result (exit status %d)%s%s",
                       end->exit_code, end->first_error[0] ? ": " : "", end->first_error);
    return RUN_FAILED;
  }
  *error = st;
  if (gmsh_error) return RUN_GMSH_ERROR;
  return st == HOC_OK ? RUN_MESHED : RUN_FAILED;
}

/* Error of a run that a signal ended, with what it was doing. */
static hoc_status crash_error(int sig, const char *first_error, const char *doing,
                              double timeout) {
  if (sig == FACE_TIMED_OUT)
    return HOC_ERROR(HOC_ERR_MESH, "gmsh's mesher did not finish in %g s (--mesher-timeout) %s",
                     timeout, doing);
  if (hoc_signal_is_interrupt(sig))
    return HOC_ERROR(HOC_ERR_INTERRUPTED, "interrupted (%s) while meshing", hoc_signal_name(sig));
  return HOC_ERROR(HOC_ERR_MESH, "gmsh's mesher %s (%s) %s%s%s",
                   sig == SIGKILL ? "was killed" : "crashed", hoc_signal_name(sig), doing,
                   first_error[0] ? ": " : "", first_error);
}

/* The faces gmsh's mesher failed on alone in an earlier meshing of the
 * model, to leave out now (*skip: NULL if none, else [n_faces] their
 * probes' reports): each crash, and each time-out within a limit no
 * shorter than timeout (0: none). A face that breaks the mesher costs a
 * whole run and its probe once per model, not again at each meshing of
 * the run (the grading's, the other algorithms', the remeshings). */
static hoc_status known_failures(const hoc_model *model, double timeout, unsigned char **skip,
                                 int *n_skipped) {
  *skip = NULL;
  *n_skipped = 0;
  if (!model->mesher_failed) return HOC_OK;
  unsigned char *s;
  HOC_ALLOC(s, (size_t)model->n_faces);
  for (int f = 0; f < model->n_faces; ++f) {
    unsigned char why = model->mesher_failed[f];
    int timed_out = why == FACE_TIMED_OUT;
    s[f] = why && (!timed_out || (timeout > 0 && timeout <= model->mesher_limit[f])) ? why : 0;
    *n_skipped += s[f] != 0;
  }
  if (*n_skipped) *skip = s;
  else free(s);
  return HOC_OK;
}

/* Record in the model the faces the probes found failing (crashed[f] for
 * f < probed, interruptions apart, and not those skipped: their record
 * stays) and the limit they had. */
static hoc_status remember_failures(hoc_model *model, const unsigned char *skip,
                                    const unsigned char *crashed, int probed, double timeout) {
  for (int f = 0; f < probed; ++f) {
    if (!crashed[f] || hoc_signal_is_interrupt(crashed[f]) || (skip && skip[f])) continue;
    if (!model->mesher_failed) {
      unsigned char *why = hoc_calloc((size_t)model->n_faces, 1);
      double *limit = hoc_calloc((size_t)model->n_faces, sizeof *limit);
      if (!why || !limit) {
        free(why);
        free(limit);
        return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      }
      model->mesher_failed = why;
      model->mesher_limit = limit;
    }
    model->mesher_failed[f] = crashed[f];
    model->mesher_limit[f] = timeout;
  }
  return HOC_OK;
}

/* One linear mesh with gmsh's current size settings and the faces'
 * algorithms (NULL: gmsh's default everywhere); model and mesh checked by
 * the caller. A graded meshing (grading not NULL) has budget seconds at
 * most (within the mesher's limit), and a crash or a time-out in it fails
 * at once (*timed_out: whether it ran out of time), no face probed or
 * remembered: a face that fails with the graded sizes alone is not one
 * gmsh cannot mesh. */
static hoc_status generate_once(hoc_model *model, const hoc_linear_options *options,
                                const int *algorithm, int extend,
                                const hoc_linear_grading *grading,
                                double budget, int *timed_out, hoc_mesh **mesh) {
  hoc_linear_options o;
  hoc_linear_options_default(&o);
  if (options) o = *options;
  HOC_CHECK(isfinite(o.size_max) && o.size_max >= 0, HOC_ERR_ARGUMENT,
            "mesh size must be a positive number");
  HOC_CHECK(isfinite(o.size_min) && o.size_min >= 0, HOC_ERR_ARGUMENT,
            "minimum mesh size must be a positive number");
  HOC_CHECK(!isnan(o.mesher_timeout), HOC_ERR_ARGUMENT, "mesher timeout must be a number");
  HOC_CHECK(isfinite(o.curvature) && o.curvature >= 0 && o.curvature <= 1000, HOC_ERR_ARGUMENT,
            "curvature elements per 2 pi must be in 0..1000");
  HOC_CHECK(o.order >= 1 && o.order <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT,
            "order %d out of range 1..%d", o.order, HOC_MAX_ORDER);
  double hmax, hmin;
  hoc_linear_sizes(model, &o, &hmax, &hmin);
  HOC_CHECK(hmin <= hmax, HOC_ERR_ARGUMENT, "minimum size %g exceeds maximum size %g", hmin, hmax);
  HOC_CHECK(hmax >= 1e-6 * model->diagonal, HOC_ERR_ARGUMENT,
            "mesh size %g is too small for a model of size %g (at most 10^6 edges across)", hmax,
            model->diagonal);
  double curv = o.curvature > 0 ? o.curvature : default_curvature(o.order);
  if (grading) {
    /* the first mesh's sizes carry the curvature's; the minimum under the
     * shortest curve's length */
    curv = 0;
    hmin = fmin(hmin, 0.5 * hoc_linear_grading_min_size(grading));
  }

  int ierr = 0;
  gmshModelMeshClear(NULL, 0, &ierr);
  gmshOptionSetNumber("Mesh.MeshSizeMax", hmax, &ierr);
  gmshOptionSetNumber("Mesh.MeshSizeMin", hmin, &ierr);
  gmshOptionSetNumber("Mesh.MeshSizeFromCurvature", curv, &ierr);
  /* graded: no extension of the curves' sizes into the faces (the field
   * has the first mesh's sizes: node_sizes in grading.c), and the field
   * jumps where the first mesh's nearest node changes, which gmsh's
   * integration of 1 / size along the curves resolves to its precision:
   * at its default 1e-9 the graded meshing of nist_ctc_01 takes 26 s, at
   * 1e-5 1.3 s (0.02% more triangles) */
  gmshOptionSetNumber("Mesh.MeshSizeExtendFromBoundary", grading || !extend ? 0 : 1, &ierr);
  gmshOptionSetNumber("Mesh.LcIntegrationPrecision", grading ? 1e-5 : 1e-9, &ierr);
  gmshOptionSetNumber("Mesh.ElementOrder", 1, &ierr);
  if (o.progress && o.progress(o.progress_user, "linear mesh", 0.0))
    return HOC_ERROR(HOC_ERR_INTERRUPTED, "interrupted");

  linear_parts p = {0};
  hoc_status status = HOC_OK, err;
  hoc_child_end end;
  unsigned char *crashed = NULL;
  int n_timed_out = 0;
  double timeout = o.mesher_timeout < 0 ? 0 : o.mesher_timeout > 0 ? o.mesher_timeout
                                                                   : HOC_MESHER_TIMEOUT;
  if (grading && budget > 0 && (timeout <= 0 || budget < timeout)) timeout = budget;
  /* under the model's mesher deadline (a remeshing's), a time-out fails
   * the meshing: no face is probed or remembered */
  int by_deadline = model->mesher_deadline > 0;
  if (by_deadline) {
    double left = model->mesher_deadline - hoc_now();
    HOC_CHECK(left > 0, HOC_ERR_MESH, "no time left for gmsh's mesher (a remeshing's time is "
                                      "spent)");
    if (timeout <= 0 || left < timeout) timeout = left;
  }
  unsigned char *skip = NULL;
  int n_skipped = 0;
  HOC_TRY_GOTO(known_failures(model, timeout, &skip, &n_skipped), done);
  if (n_skipped == model->n_faces) {
    status = crash_error(skip[0], "", "on every face (in an earlier meshing)", timeout);
    goto done;
  }
  run_outcome run = run_mesher(model, algorithm, timeout, skip, NULL, NULL, &p, &err, &end);
  if (grading && run == RUN_CRASHED && timed_out) *timed_out = end.signal == FACE_TIMED_OUT;
  if (by_deadline && run == RUN_CRASHED && end.signal == FACE_TIMED_OUT) {
    status = HOC_ERROR(HOC_ERR_MESH, "gmsh's mesher did not finish in the %.3g s left to a "
                                     "remeshing",
                       timeout);
    goto done;
  }
  if (!grading && run == RUN_CRASHED && !hoc_signal_is_interrupt(end.signal) &&
      model->n_faces > 1) {
    /* mesh the faces that neither crash gmsh nor keep it from finishing
     * in time; the others count as failed */
    hoc_child_end first = end;
    int probed = 0, n_crashed = 0;
    linear_parts_free(&p);
    crashed = hoc_calloc((size_t)model->n_faces, 1);
    if (!crashed) {
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      goto done;
    }
    run = run_mesher(model, algorithm, timeout, skip, crashed, &probed, &p, &err, &end);
    for (int f = 0; f < probed; ++f) {
      if (crashed[f] && hoc_signal_is_interrupt(crashed[f])) {
        status = crash_error(crashed[f], "", "", timeout);
        goto done;
      }
      n_crashed += crashed[f] != 0;
    }
    HOC_TRY_GOTO(remember_failures(model, skip, crashed, probed, timeout), done);
    if (run == RUN_CRASHED && probed == 0) {
      status = crash_error(end.signal, end.first_error, "meshing the curves", timeout);
      goto done;
    }
    if (probed == model->n_faces && n_crashed == model->n_faces) {
      status = crash_error(first.signal, first.first_error, "on every face", timeout);
      goto done;
    }
    if (run == RUN_CRASHED) {
      status = crash_error(end.signal, end.first_error,
                           probed < model->n_faces ? "while trying the faces one by one"
                                                   : "without the faces that crash it alone",
                           timeout);
      goto done;
    }
  }
  switch (run) {
  case RUN_MESHED: break;
  case RUN_GMSH_ERROR:
    status = HOC_ERROR(HOC_ERR_MESH, "gmsh could not mesh the surfaces: %s",
                       end.first_error[0] ? end.first_error : hoc_last_error());
    goto done;
  case RUN_CRASHED:
    status = crash_error(end.signal, end.first_error, "meshing the surfaces", timeout);
    goto done;
  case RUN_FAILED: status = err; goto done;
  }
  if (o.progress && o.progress(o.progress_user, "linear mesh", 0.9)) {
    status = HOC_ERROR(HOC_ERR_INTERRUPTED, "interrupted");
    goto done;
  }
  if (!p.n_tri) {
    status = HOC_ERROR(HOC_ERR_MESH, "gmsh produced no triangle on any of the %d faces%s%s",
                       model->n_faces, end.first_error[0] ? ": " : "", end.first_error);
    goto done;
  }
  hoc_mesh_source src = {0};
  src.order = 1;
  src.nodeset = HOC_NODES_EQUISPACED;
  src.n_nodes = p.g.n;
  src.xyz = p.g.xyz;
  src.param = p.g.par;
  src.dim = p.g.dim;
  src.entity = p.g.ent;
  src.n_elems = p.n_tri;
  src.conn = p.tri;
  src.elem_face = p.tri_face;
  src.n_lines = p.n_lines;
  src.line_conn = p.lines;
  src.line_curve = p.line_curve;
  src.node_tag = p.g.tag;
  HOC_TRY_GOTO(hoc_mesh_assemble(model, &src, mesh), done);
  (*mesh)->n_failed_faces = p.n_failed;
  (*mesh)->failed_faces = p.failed;
  for (int f = 0; f < model->n_faces; ++f)
    n_timed_out += (crashed ? crashed[f] : skip ? skip[f] : 0) == FACE_TIMED_OUT;
  (*mesh)->timed_out_faces = n_timed_out;
  (*mesh)->known_failed_faces = n_skipped;
  (*mesh)->mesher_timeout = timeout;
  p.failed = NULL;
done:
  linear_parts_free(&p);
  free(crashed);
  free(skip);
  return status;
}

/* Mesh sizes of the refined entities for gmsh's size callback (gmsh 4.8
 * takes the smaller of the callback's size and its own). */
typedef struct sizing {
  int max_face_tag, max_curve_tag;
  double *face_size, *curve_size; /* [max tag + 1]; 0: no bound */
} sizing;

static double size_at(int dim, int tag, double x, double y, double z, void *data) {
  (void)x, (void)y, (void)z;
  const sizing *s = data;
  double h = 0;
  if (dim == 2 && tag >= 0 && tag <= s->max_face_tag) h = s->face_size[tag];
  if (dim == 1 && tag >= 0 && tag <= s->max_curve_tag) h = s->curve_size[tag];
  return h > 0 ? h : 1e22;
}

/* The mesh with the options' sizes (and face_size's bounds). */
static hoc_status generate_sized(hoc_model *model, const hoc_linear_options *options,
                                 const int *algorithm, int extend, hoc_mesh **mesh) {
  HOC_CHECK(mesh, HOC_ERR_ARGUMENT, "mesh output is NULL");
  *mesh = NULL;
  HOC_CHECK(model && model->is_gmsh, HOC_ERR_ARGUMENT,
            "linear meshing needs a model opened from a CAD file");
  for (int f = 0; algorithm && f < model->n_faces; ++f)
    HOC_CHECK(algorithm[f] >= 0 && algorithm[f] <= HOC_GMSH_ALGORITHM_MAX, HOC_ERR_ARGUMENT,
              "meshing algorithm %d of face %d is not one of gmsh's (0..%d)", algorithm[f],
              model->faces[f].tag, HOC_GMSH_ALGORITHM_MAX);
  if (!options || !options->face_size)
    return generate_once(model, options, algorithm, extend, NULL, 0, NULL, mesh);
  /* faces meshed finer: the bound on the face and on its boundary curves */
  sizing s = {0};
  for (int f = 0; f < model->n_faces; ++f) {
    double h = options->face_size[f];
    HOC_CHECK(isfinite(h) && h >= 0, HOC_ERR_ARGUMENT,
              "size bound of face %d must be a finite number >= 0", model->faces[f].tag);
    if (model->faces[f].tag > s.max_face_tag) s.max_face_tag = model->faces[f].tag;
  }
  for (int c = 0; c < model->n_curves; ++c)
    if (model->curves[c].tag > s.max_curve_tag) s.max_curve_tag = model->curves[c].tag;
  s.face_size = hoc_calloc((size_t)s.max_face_tag + 1, sizeof *s.face_size);
  s.curve_size = hoc_calloc((size_t)s.max_curve_tag + 1, sizeof *s.curve_size);
  hoc_status status = HOC_OK;
  if (!s.face_size || !s.curve_size) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (int f = 0; f < model->n_faces; ++f) {
    double h = options->face_size[f];
    if (!(h > 0)) continue;
    s.face_size[model->faces[f].tag] = h;
    for (int k = 0; k < model->faces[f].n_curves; ++k) {
      int t = abs(model->faces[f].curves[k]);
      if (t <= s.max_curve_tag && (!(s.curve_size[t] > 0) || h < s.curve_size[t]))
        s.curve_size[t] = h;
    }
  }
  int ierr = 0;
  gmshModelMeshSetSizeCallback(size_at, &s, &ierr);
  status = ierr ? HOC_ERROR(HOC_ERR_MESH, "gmsh refused the mesh size callback")
                : generate_once(model, options, algorithm, extend, NULL, 0, NULL, mesh);
  gmshModelMeshRemoveSizeCallback(&ierr);
done:
  free(s.face_size);
  free(s.curve_size);
  return status;
}

static double graded_size(int dim, int tag, double x, double y, double z, void *data) {
  (void)dim, (void)tag;
  double p[3] = {x, y, z};
  return hoc_linear_grading_size(data, p);
}

/* The inverted triangles of m, its smallest q away from poles (q is 0 at
 * a corner where phi_u x phi_v vanishes, in every mesh of the face) and
 * its smallest q (*all). */
static hoc_status linear_quality(const hoc_mesh *m, size_t *tangled, double *qmin, double *all) {
  size_t ne = m->n_elems;
  double *q = hoc_calloc(ne + 1, sizeof *q);
  HOC_CHECK(q, HOC_ERR_MEMORY, "out of memory");
  hoc_quality_stats st;
  hoc_status status = hoc_mesh_measure(m, HOC_MEASURE_SHAPE, q, NULL, &st);
  if (status != HOC_OK) {
    free(q);
    return status;
  }
  *tangled = st.tangled;
  *all = st.min;
  *qmin = INFINITY;
  for (size_t e = 0; e < ne; ++e) {
    int at_pole = 0;
    for (size_t k = 0; k < 3; ++k)
      at_pole |= m->slot_pole[m->elem_slot[3 * e + k]] != 0;
    if (!at_pole && q[e] < *qmin) *qmin = q[e];
  }
  if (!isfinite(*qmin)) *qmin = st.min;
  free(q);
  return HOC_OK;
}

/* Whether mesh a is the better linear mesh: fewer faces failed, then fewer
 * inverted triangles, then a higher smallest q away from poles; *b_min:
 * b's smallest q. */
static hoc_status better(const hoc_mesh *a, const hoc_mesh *b, int *yes, double *b_min) {
  size_t ta, tb;
  double qa, qb, a_min;
  HOC_TRY(linear_quality(a, &ta, &qa, &a_min));
  HOC_TRY(linear_quality(b, &tb, &qb, b_min));
  if (a->n_failed_faces != b->n_failed_faces) *yes = a->n_failed_faces < b->n_failed_faces;
  else if (ta != tb) *yes = ta < tb;
  else *yes = qa > qb;
  return HOC_OK;
}

hoc_status hoc_mesh_generate_linear_ungraded(hoc_model *model, const hoc_linear_options *options,
                                             hoc_mesh **mesh) {
  return generate_sized(model, options, NULL, 1, mesh);
}

hoc_status hoc_mesh_grade(hoc_model *model, const hoc_linear_options *options,
                          const int *algorithm, double budget, hoc_mesh **mesh) {
  /* curves far shorter than the mesh around them, faces narrower: the mesh
   * made again with sizes graded down to them (HOC_LINEAR_SHORT_RATIO) */
  hoc_linear_grading *g = NULL;
  hoc_mesh *graded = NULL;
  hoc_linear_options o;
  hoc_linear_options_default(&o);
  if (options) o = *options;
  double hmax, hmin;
  hoc_linear_sizes(model, &o, &hmax, &hmin);
  double ncurv = o.curvature > 0 ? o.curvature : default_curvature(o.order);
  hoc_status status = hoc_linear_grading_make(*mesh, HOC_LINEAR_SHORT_RATIO, hmin, hmax, ncurv,
                                              o.face_size, &g);
  if (status != HOC_OK || !g) goto done;
  int ierr = 0, keep = 0;
  gmshModelMeshSetSizeCallback(graded_size, g, &ierr);
  if (ierr) {
    status = HOC_ERROR(HOC_ERR_MESH, "gmsh refused the mesh size callback");
    goto done;
  }
  int timed_out = 0;
  status = generate_once(model, options, algorithm, 0, g, budget, &timed_out, &graded);
  if (timed_out) (*mesh)->graded_budget = budget;
  gmshModelMeshRemoveSizeCallback(&ierr);
  if (status == HOC_ERR_INTERRUPTED || status == HOC_ERR_MEMORY) goto done;
  /* (a graded mesh gmsh fails on leaves the first) */
  status = HOC_OK;
  double first_q = 0;
  if (graded && graded->n_elems <= HOC_LINEAR_GRADED_GROWTH * (*mesh)->n_elems)
    HOC_TRY_GOTO(better(graded, *mesh, &keep, &first_q), done);
  if (keep) {
    graded->graded_curves = hoc_linear_grading_curves(g);
    graded->graded_faces = hoc_linear_grading_faces(g);
    graded->ungraded_elements = (*mesh)->n_elems;
    graded->ungraded_min_q = first_q;
    graded->small_faces = (*mesh)->small_faces;
    graded->small_min = (*mesh)->small_min;
    graded->unextended_elements = (*mesh)->unextended_elements;
    hoc_mesh_destroy(mesh);
    *mesh = graded;
    graded = NULL;
  }
done:
  hoc_linear_grading_free(&g);
  hoc_mesh_destroy(&graded);
  if (status != HOC_OK) hoc_mesh_destroy(mesh);
  return status;
}

/* Faces gmsh leaves without triangles because they are smaller than the
 * default minimum size (HOC_LINEAR_SMALL_FACE_EDGES): *mesh made again with the
 * minimum lowered for them, and o->size_min set to it if that is kept. */
static hoc_status fit_small_faces(hoc_model *model, hoc_linear_options *o, const int *algorithm,
                                  hoc_mesh **mesh) {
  const hoc_mesh *m = *mesh;
  if (!m->n_failed_faces || o->size_min > 0) return HOC_OK;
  double hmax, hmin, need = HUGE_VAL;
  hoc_linear_sizes(model, o, &hmax, &hmin);
  unsigned char *record = model->mesher_failed, *kept = NULL;
  for (int k = 0; k < m->n_failed_faces; ++k) {
    int f = m->failed_faces[k];
    if (record && record[f] == FACE_TIMED_OUT) continue;
    const double *b = model->faces[f].bbox;
    double across = fmax(b[3] - b[0], fmax(b[4] - b[1], b[5] - b[2]));
    need = fmin(need, across / HOC_LINEAR_SMALL_FACE_EDGES);
  }
  if (!(need < hmin) || !(need >= 1e-6 * model->diagonal)) return HOC_OK;
  /* a face whose curves had too few segments may also have crashed the
   * mesher (a torus's): tried again, its record set aside meanwhile */
  size_t nf = (size_t)model->n_faces;
  if (record) {
    HOC_ALLOC(kept, nf);
    memcpy(kept, record, nf);
    for (int k = 0; k < m->n_failed_faces; ++k)
      if (record[m->failed_faces[k]] != FACE_TIMED_OUT) record[m->failed_faces[k]] = 0;
  }
  hoc_linear_options lowered = *o;
  lowered.size_min = need;
  hoc_mesh *trial = NULL;
  hoc_status status = generate_sized(model, &lowered, algorithm, 1, &trial);
  int keep = status == HOC_OK && trial->n_failed_faces < m->n_failed_faces &&
             trial->n_elems <= HOC_LINEAR_GRADED_GROWTH * m->n_elems;
  if (keep) {
    trial->small_faces = m->n_failed_faces - trial->n_failed_faces;
    trial->small_min = need;
    hoc_mesh_destroy(mesh);
    *mesh = trial;
    *o = lowered;
  } else {
    hoc_mesh_destroy(&trial);
    if (record) memcpy(record, kept, nf);
  }
  free(kept);
  return status == HOC_ERR_INTERRUPTED || status == HOC_ERR_MEMORY ? status : HOC_OK;
}

/* A mesh with more than HOC_LINEAR_UNEXTENDED x the triangles its faces
 * hold at the minimum size: *mesh made again without gmsh's extension of
 * the curves' sizes into the faces, kept if it has fewer triangles and no
 * more failed faces. */
static hoc_status unextend(hoc_model *model, const hoc_linear_options *o, const int *algorithm,
                           hoc_mesh **mesh) {
  const hoc_mesh *m = *mesh;
  double hmax, hmin, area = 0;
  hoc_linear_sizes(model, o, &hmax, &hmin);
  for (size_t e = 0; e < m->n_elems; ++e) {
    const size_t *c = m->conn + e * (size_t)m->np;
    const double *x0 = m->xyz + 3 * c[0], *x1 = m->xyz + 3 * c[1], *x2 = m->xyz + 3 * c[2];
    double a[3], b[3], n[3];
    for (int k = 0; k < 3; ++k)
      a[k] = x1[k] - x0[k], b[k] = x2[k] - x0[k];
    hoc_cross3(a, b, n);
    area += 0.5 * sqrt(hoc_dot3(n, n));
  }
  /* and the triangles along the faces' sides: a strip narrower than the
   * minimum has them all there */
  double sides = 0;
  for (size_t l = 0; l < m->n_lines; ++l)
    sides += 2 * hoc_dist3(m->xyz + 3 * m->line_conn[2 * l], m->xyz + 3 * m->line_conn[2 * l + 1]);
  double most =
      HOC_LINEAR_UNEXTENDED * (area / (0.25 * sqrt(3.0) * hmin * hmin) + sides / hmin);
  if (!((double)m->n_elems > most)) return HOC_OK;
  hoc_mesh *trial = NULL;
  hoc_status status = generate_sized(model, o, algorithm, 0, &trial);
  if (status == HOC_OK && trial->n_elems < m->n_elems &&
      trial->n_failed_faces <= m->n_failed_faces) {
    trial->unextended_elements = m->n_elems;
    trial->small_faces = m->small_faces;
    trial->small_min = m->small_min;
    hoc_mesh_destroy(mesh);
    *mesh = trial;
  } else {
    hoc_mesh_destroy(&trial);
  }
  return status == HOC_ERR_INTERRUPTED || status == HOC_ERR_MEMORY ? status : HOC_OK;
}

hoc_status hoc_mesh_generate_linear_with(hoc_model *model, const hoc_linear_options *options,
                                         const int *algorithm, hoc_mesh **mesh) {
  double t0 = hoc_now();
  HOC_TRY(generate_sized(model, options, algorithm, 1, mesh));
  hoc_linear_options o;
  hoc_linear_options_default(&o);
  if (options) o = *options;
  hoc_status status = fit_small_faces(model, &o, algorithm, mesh);
  if (status == HOC_OK) status = unextend(model, &o, algorithm, mesh);
  if (status != HOC_OK) {
    hoc_mesh_destroy(mesh);
    return status;
  }
  if (o.grading) {
    double budget = HOC_LINEAR_GRADED_GROWTH * (hoc_now() - t0) + HOC_LINEAR_GRADED_SECONDS;
    HOC_TRY(hoc_mesh_grade(model, &o, algorithm, budget, mesh));
    /* slivers on the surface that a swap of their edge removes */
    status = hoc_mesh_swap_edges(*mesh, &(*mesh)->swapped_edges, (*mesh)->swap_min_q);
  }
  /* no triangle across a line of a face that maps to one point */
  hoc_mesh *cut = NULL;
  int n_cut = 0;
  if (status == HOC_OK && !o.keep_pinches) status = hoc_mesh_cut_pinches(*mesh, &cut, &n_cut);
  if (status == HOC_OK && cut) {
    cut->cut_pinches = n_cut;
    hoc_mesh_destroy(mesh);
    *mesh = cut;
  }
  if (status != HOC_OK) hoc_mesh_destroy(mesh);
  return status;
}

hoc_status hoc_mesh_generate_linear_gmsh(hoc_model *model, const hoc_linear_options *options,
                                         hoc_mesh **mesh) {
  return hoc_mesh_generate_linear_with(model, options, NULL, mesh);
}

hoc_status hoc_mesh_generate_linear(hoc_model *model, const hoc_linear_options *options,
                                    hoc_mesh **mesh) {
  return hoc_mesh_generate_linear_with(model, options, NULL, mesh);
}
