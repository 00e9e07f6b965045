/* gmsh MSH reader: 4.1 ASCII and binary, 2.2 ASCII. Keeps surface
 * triangles (one order) and the curve lines of that order; every count in
 * the file is checked against what the rest of the file can hold.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "core/hash.h"
#include "io/io.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* Nodes per element of gmsh's element types (0: unknown). */
static int type_nodes(int type) {
  static const int n[] = {
      0,  2,  3,  4,  4,  8,  6,  5,  3,  6,  9,  10, 27, 18, 14, 1,  8,  20, 15, 13,
      9,  10, 12, 15, 15, 21, 4,  5,  6,  20, 35, 56, 22, 28, 0,  0,  16, 25, 36, 12,
      16, 20, 28, 36, 45, 55, 66, 49, 64, 81, 100, 121, 18, 21, 24, 27, 30, 24, 28, 32,
      36, 40, 7,  8,  9,  10, 11};
  if (type >= 0 && type < (int)(sizeof n / sizeof *n)) return n[type];
  if (type >= 71 && type <= 75) { /* tetrahedra of order 6..10 */
    int p = type - 65;
    return (p + 1) * (p + 2) * (p + 3) / 6;
  }
  if (type >= 92 && type <= 98) { /* hexahedra of order 3..9 */
    int p = type - 89;
    return (p + 1) * (p + 1) * (p + 1);
  }
  return 0;
}

/* Triangle / line order of a type, 0 if the type is neither. */
static int triangle_order(int type) {
  for (int p = 1; p <= 10; ++p)
    if (hoc_msh_triangle_type(p) == type) return p;
  return 0;
}
static int line_order(int type) {
  for (int p = 1; p <= 10; ++p)
    if (hoc_msh_line_type(p) == type) return p;
  return 0;
}

typedef struct reader {
  const char *data, *end, *cur;
  const char *name;
  int binary, swap;
} reader;

#define FAIL(r, ...) return HOC_ERROR(HOC_ERR_FORMAT, __VA_ARGS__)

static void skip_space(reader *r) {
  while (r->cur < r->end && (*r->cur == ' ' || *r->cur == '\t' || *r->cur == '\r' || *r->cur == '\n'))
    ++r->cur;
}

/* Next whitespace-separated token into buf (NUL-terminated). */
static int next_token(reader *r, char *buf, size_t size) {
  skip_space(r);
  size_t n = 0;
  while (r->cur < r->end && !(*r->cur == ' ' || *r->cur == '\t' || *r->cur == '\r' || *r->cur == '\n')) {
    if (n + 1 < size) buf[n++] = *r->cur;
    ++r->cur;
  }
  buf[n] = '\0';
  return n > 0;
}

static hoc_status read_long(reader *r, long long *v, const char *what) {
  char tok[64], *e;
  if (!next_token(r, tok, sizeof tok)) FAIL(r, "'%s': file ends in %s", r->name, what);
  errno = 0;
  *v = strtoll(tok, &e, 10);
  if (*e || errno) FAIL(r, "'%s': expected an integer in %s, found '%.20s'", r->name, what, tok);
  return HOC_OK;
}

static hoc_status read_double(reader *r, double *v, const char *what) {
  char tok[128], *e;
  if (!next_token(r, tok, sizeof tok)) FAIL(r, "'%s': file ends in %s", r->name, what);
  *v = strtod(tok, &e);
  if (*e) FAIL(r, "'%s': expected a number in %s, found '%.20s'", r->name, what, tok);
  if (!isfinite(*v)) FAIL(r, "'%s': non-finite number in %s", r->name, what);
  return HOC_OK;
}

/* Binary fields, with byte swapping if the file's endianness differs. */
static hoc_status read_bytes(reader *r, void *dst, size_t size, const char *what) {
  if ((size_t)(r->end - r->cur) < size) FAIL(r, "'%s': file ends in %s", r->name, what);
  memcpy(dst, r->cur, size);
  if (r->swap) {
    unsigned char *b = dst;
    for (size_t i = 0; i < size / 2; ++i) {
      unsigned char t = b[i];
      b[i] = b[size - 1 - i];
      b[size - 1 - i] = t;
    }
  }
  r->cur += size;
  return HOC_OK;
}

static hoc_status read_int(reader *r, long long *v, const char *what) {
  if (!r->binary) return read_long(r, v, what);
  int32_t x = 0;
  HOC_TRY(read_bytes(r, &x, sizeof x, what));
  *v = x;
  return HOC_OK;
}

static hoc_status read_size(reader *r, long long *v, const char *what) {
  if (!r->binary) return read_long(r, v, what);
  uint64_t x = 0;
  HOC_TRY(read_bytes(r, &x, sizeof x, what));
  if (x > (uint64_t)INT64_MAX) FAIL(r, "'%s': absurd count in %s", r->name, what);
  *v = (long long)x;
  return HOC_OK;
}

static hoc_status read_real(reader *r, double *v, const char *what) {
  if (!r->binary) return read_double(r, v, what);
  HOC_TRY(read_bytes(r, v, sizeof *v, what));
  if (!isfinite(*v)) FAIL(r, "'%s': non-finite number in %s", r->name, what);
  return HOC_OK;
}

/* A count must be non-negative and fit in what remains of the file, at
 * `min_bytes` per item. */
static hoc_status check_count(reader *r, long long n, size_t min_bytes, const char *what) {
  if (n < 0) FAIL(r, "'%s': negative count in %s", r->name, what);
  if ((unsigned long long)n > (unsigned long long)(r->end - r->cur) / (min_bytes ? min_bytes : 1))
    FAIL(r, "'%s': %s announces %lld items, more than the file holds", r->name, what, n);
  return HOC_OK;
}

/* Move past the line "$EndName" (searched as text). */
static hoc_status skip_to_end(reader *r, const char *section) {
  char marker[80];
  snprintf(marker, sizeof marker, "$End%.60s", section);
  size_t m = strlen(marker);
  for (const char *p = r->cur; p + m <= r->end; ++p)
    if (*p == '$' && !memcmp(p, marker, m)) {
      r->cur = p + m;
      return HOC_OK;
    }
  FAIL(r, "'%s': section $%s has no %s", r->name, section, marker);
}

static hoc_status expect_end(reader *r, const char *section) {
  char tok[64], want[80];
  snprintf(want, sizeof want, "$End%.60s", section);
  if (!r->binary) {
    if (!next_token(r, tok, sizeof tok) || strcmp(tok, want))
      FAIL(r, "'%s': section $%s does not end with %s", r->name, section, want);
    return HOC_OK;
  }
  skip_space(r);
  size_t m = strlen(want);
  if ((size_t)(r->end - r->cur) < m || memcmp(r->cur, want, m))
    FAIL(r, "'%s': section $%s does not end with %s", r->name, section, want);
  r->cur += m;
  return HOC_OK;
}

/* The raw mesh being built: every node read, then compacted. */
typedef struct builder {
  hoc_hash index; /* node tag -> position */
  size_t n, cap;
  size_t *tag;
  double *xyz, *par;
  int *dim, *ent;
  unsigned char *has;
  /* elements kept */
  int order;  /* of the triangles */
  int lorder; /* of the lines (lines of another order are dropped) */
  size_t nt, tcap, nl, lcap;
  size_t *tri_tags, *line_tags; /* node tags, resolved at the end */
  int *tri_ent, *line_ent;
} builder;

static void builder_free(builder *b) {
  hoc_hash_free(&b->index);
  free(b->tag);
  free(b->xyz);
  free(b->par);
  free(b->dim);
  free(b->ent);
  free(b->has);
  free(b->tri_tags);
  free(b->line_tags);
  free(b->tri_ent);
  free(b->line_ent);
}

static hoc_status add_node(builder *b, reader *r, long long tag, const double *x, int dim, int ent,
                           const double *par, int npar) {
  if (tag < 1) FAIL(r, "'%s': node tag %lld is not positive", r->name, tag);
  if (b->n == b->cap) {
    size_t cap = b->cap ? 2 * b->cap : 1024;
    size_t *t = hoc_realloc(b->tag, cap, sizeof *t);
    if (t) b->tag = t;
    double *xx = hoc_realloc(b->xyz, 3 * cap, sizeof *xx);
    if (xx) b->xyz = xx;
    double *pp = hoc_realloc(b->par, 2 * cap, sizeof *pp);
    if (pp) b->par = pp;
    int *dd = hoc_realloc(b->dim, cap, sizeof *dd);
    if (dd) b->dim = dd;
    int *ee = hoc_realloc(b->ent, cap, sizeof *ee);
    if (ee) b->ent = ee;
    unsigned char *hh = hoc_realloc(b->has, cap, 1);
    if (hh) b->has = hh;
    HOC_CHECK(t && xx && pp && dd && ee && hh, HOC_ERR_MEMORY, "out of memory reading '%s'", r->name);
    b->cap = cap;
  }
  int found;
  HOC_TRY(hoc_hash_insert(&b->index, (uint64_t)tag, b->n, &found, NULL));
  if (found) FAIL(r, "'%s': node %lld appears twice", r->name, tag);
  size_t i = b->n++;
  b->tag[i] = (size_t)tag;
  memcpy(b->xyz + 3 * i, x, 3 * sizeof *x);
  b->dim[i] = dim;
  b->ent[i] = ent;
  b->par[2 * i] = npar > 0 ? par[0] : 0;
  b->par[2 * i + 1] = npar > 1 ? par[1] : 0;
  b->has[i] = (unsigned char)(npar > 0 && dim > 0);
  return HOC_OK;
}

/* Record an element of a kept type. */
static hoc_status add_element(builder *b, reader *r, int type, int ent, const long long *nodes) {
  int tp = triangle_order(type), lp = line_order(type);
  if (tp) {
    if (b->order && b->order != tp)
      return HOC_ERROR(HOC_ERR_UNSUPPORTED, "'%s' mixes triangles of orders %d and %d", r->name,
                       b->order, tp);
    b->order = tp;
  } else if (!lp) {
    return HOC_OK;
  } else {
    if (!b->lorder) b->lorder = lp;
    if (lp != b->lorder) return HOC_OK;
  }
  int nn = type_nodes(type);
  size_t **arr = tp ? &b->tri_tags : &b->line_tags;
  int **ents = tp ? &b->tri_ent : &b->line_ent;
  size_t *count = tp ? &b->nt : &b->nl, *cap = tp ? &b->tcap : &b->lcap;
  if (*count == *cap) {
    size_t c = *cap ? 2 * *cap : 1024;
    size_t *a = hoc_realloc(*arr, c * (size_t)nn, sizeof *a);
    if (a) *arr = a;
    int *e = hoc_realloc(*ents, c, sizeof *e);
    if (e) *ents = e;
    HOC_CHECK(a && e, HOC_ERR_MEMORY, "out of memory reading '%s'", r->name);
    *cap = c;
  }
  for (int k = 0; k < nn; ++k) {
    if (nodes[k] < 1) FAIL(r, "'%s': element refers to node tag %lld", r->name, nodes[k]);
    (*arr)[*count * (size_t)nn + (size_t)k] = (size_t)nodes[k];
  }
  (*ents)[*count] = ent;
  ++*count;
  return HOC_OK;
}

/* MSH 4.1 ---------------------------------------------------------------- */

static hoc_status read_nodes41(reader *r, builder *b) {
  long long nblocks, nnodes, mn, mx;
  HOC_TRY(read_size(r, &nblocks, "$Nodes"));
  HOC_TRY(read_size(r, &nnodes, "$Nodes"));
  HOC_TRY(read_size(r, &mn, "$Nodes"));
  HOC_TRY(read_size(r, &mx, "$Nodes"));
  HOC_TRY(check_count(r, nblocks, 4, "$Nodes blocks"));
  HOC_TRY(check_count(r, nnodes, 8, "$Nodes"));
  long long total = 0;
  for (long long blk = 0; blk < nblocks; ++blk) {
    long long dim, tag, par, n;
    HOC_TRY(read_int(r, &dim, "a $Nodes block"));
    HOC_TRY(read_int(r, &tag, "a $Nodes block"));
    HOC_TRY(read_int(r, &par, "a $Nodes block"));
    HOC_TRY(read_size(r, &n, "a $Nodes block"));
    if (dim < 0 || dim > 3) FAIL(r, "'%s': $Nodes block of dimension %lld", r->name, dim);
    if (par != 0 && par != 1) FAIL(r, "'%s': $Nodes block with parametric flag %lld", r->name, par);
    HOC_TRY(check_count(r, n, 8, "a $Nodes block"));
    total += n;
    if (total > nnodes) FAIL(r, "'%s': $Nodes blocks hold more nodes than announced", r->name);
    int npar = par ? (int)dim : 0;
    long long *tags = hoc_calloc((size_t)n + 1, sizeof *tags);
    HOC_CHECK(tags, HOC_ERR_MEMORY, "out of memory reading '%s'", r->name);
    hoc_status st = HOC_OK;
    for (long long k = 0; k < n && st == HOC_OK; ++k) st = read_size(r, &tags[k], "node tags");
    for (long long k = 0; k < n && st == HOC_OK; ++k) {
      double x[3], u[3] = {0, 0, 0};
      for (int c = 0; c < 3 && st == HOC_OK; ++c) st = read_real(r, &x[c], "node coordinates");
      for (int c = 0; c < npar && st == HOC_OK; ++c) st = read_real(r, &u[c], "node parameters");
      if (st == HOC_OK) st = add_node(b, r, tags[k], x, (int)dim, (int)tag, u, npar);
    }
    free(tags);
    HOC_TRY(st);
  }
  if (total != nnodes) FAIL(r, "'%s': $Nodes announces %lld nodes but holds %lld", r->name, nnodes, total);
  return expect_end(r, "Nodes");
}

static hoc_status read_elements41(reader *r, builder *b) {
  long long nblocks, nelem, mn, mx;
  HOC_TRY(read_size(r, &nblocks, "$Elements"));
  HOC_TRY(read_size(r, &nelem, "$Elements"));
  HOC_TRY(read_size(r, &mn, "$Elements"));
  HOC_TRY(read_size(r, &mx, "$Elements"));
  HOC_TRY(check_count(r, nblocks, 4, "$Elements blocks"));
  HOC_TRY(check_count(r, nelem, 4, "$Elements"));
  long long total = 0, nodes[1024];
  for (long long blk = 0; blk < nblocks; ++blk) {
    long long dim, tag, type, n;
    HOC_TRY(read_int(r, &dim, "an $Elements block"));
    HOC_TRY(read_int(r, &tag, "an $Elements block"));
    HOC_TRY(read_int(r, &type, "an $Elements block"));
    HOC_TRY(read_size(r, &n, "an $Elements block"));
    HOC_TRY(check_count(r, n, 4, "an $Elements block"));
    total += n;
    if (total > nelem) FAIL(r, "'%s': $Elements blocks hold more elements than announced", r->name);
    int nn = type_nodes((int)type);
    if (!nn && r->binary)
      return HOC_ERROR(HOC_ERR_UNSUPPORTED, "'%s': unknown element type %lld in a binary file",
                       r->name, type);
    for (long long k = 0; k < n; ++k) {
      long long etag;
      HOC_TRY(read_size(r, &etag, "an element"));
      if (!nn) { /* ASCII, unknown type: the rest of the line */
        while (r->cur < r->end && *r->cur != '\n') ++r->cur;
        continue;
      }
      for (int j = 0; j < nn; ++j) HOC_TRY(read_size(r, &nodes[j], "an element's nodes"));
      if (dim == 2 || dim == 1) HOC_TRY(add_element(b, r, (int)type, (int)tag, nodes));
    }
  }
  if (total != nelem)
    FAIL(r, "'%s': $Elements announces %lld elements but holds %lld", r->name, nelem, total);
  return expect_end(r, "Elements");
}

/* MSH 2.2 ---------------------------------------------------------------- */

static hoc_status read_nodes22(reader *r, builder *b) {
  long long n;
  HOC_TRY(read_long(r, &n, "$Nodes"));
  HOC_TRY(check_count(r, n, 8, "$Nodes"));
  for (long long k = 0; k < n; ++k) {
    long long tag;
    double x[3];
    HOC_TRY(read_long(r, &tag, "$Nodes"));
    for (int c = 0; c < 3; ++c) HOC_TRY(read_double(r, &x[c], "node coordinates"));
    HOC_TRY(add_node(b, r, tag, x, -1, 0, NULL, 0));
  }
  return expect_end(r, "Nodes");
}

static hoc_status read_elements22(reader *r, builder *b, size_t **points, size_t *n_points,
                                  int **point_ent) {
  long long n, nodes[1024];
  HOC_TRY(read_long(r, &n, "$Elements"));
  HOC_TRY(check_count(r, n, 8, "$Elements"));
  size_t cap = 0;
  for (long long k = 0; k < n; ++k) {
    long long tag, type, ntags, t = 0, ent = 0;
    HOC_TRY(read_long(r, &tag, "$Elements"));
    HOC_TRY(read_long(r, &type, "$Elements"));
    HOC_TRY(read_long(r, &ntags, "$Elements"));
    if (ntags < 0 || ntags > 64) FAIL(r, "'%s': element %lld has %lld tags", r->name, tag, ntags);
    for (long long j = 0; j < ntags; ++j) {
      HOC_TRY(read_long(r, &t, "element tags"));
      if (j == 1) ent = t; /* the elementary entity */
    }
    int nn = type_nodes((int)type);
    if (!nn) FAIL(r, "'%s': unknown element type %lld", r->name, type);
    for (int j = 0; j < nn; ++j) HOC_TRY(read_long(r, &nodes[j], "element nodes"));
    if (type == 15) {
      if (*n_points == cap) {
        cap = cap ? 2 * cap : 64;
        size_t *p = hoc_realloc(*points, cap, sizeof *p);
        if (p) *points = p;
        int *e = hoc_realloc(*point_ent, cap, sizeof *e);
        if (e) *point_ent = e;
        HOC_CHECK(p && e, HOC_ERR_MEMORY, "out of memory");
      }
      if (nodes[0] < 1) FAIL(r, "'%s': point element refers to node %lld", r->name, nodes[0]);
      (*points)[*n_points] = (size_t)nodes[0];
      (*point_ent)[(*n_points)++] = (int)ent;
    } else {
      HOC_TRY(add_element(b, r, (int)type, (int)ent, nodes));
    }
  }
  return expect_end(r, "Elements");
}

/* Driver ------------------------------------------------------------------- */

/* Keep the nodes the kept elements use; resolve tags to indices. */
static hoc_status finish(reader *r, builder *b, hoc_msh_raw *raw) {
  int p = b->order;
  if (!b->nt) FAIL(r, "'%s' holds no triangles", r->name);
  int np = (p + 1) * (p + 2) / 2;
  size_t *newi = hoc_calloc(b->n + 1, sizeof *newi);
  HOC_CHECK(newi, HOC_ERR_MEMORY, "out of memory");
  for (size_t i = 0; i < b->n; ++i) newi[i] = SIZE_MAX;
  size_t count = 0;
  hoc_status status = HOC_OK;
  /* lines of another order than the triangles are dropped */
  size_t keep_lines = b->lorder == p ? b->nl : 0;
  raw->order = p;
  raw->n_tris = b->nt;
  raw->tri_nodes = hoc_calloc(b->nt * (size_t)np, sizeof *raw->tri_nodes);
  raw->tri_surface_tag = hoc_calloc(b->nt, sizeof *raw->tri_surface_tag);
  raw->line_nodes = hoc_calloc(keep_lines * (size_t)(p + 1) + 1, sizeof *raw->line_nodes);
  raw->line_curve_tag = hoc_calloc(keep_lines + 1, sizeof *raw->line_curve_tag);
  if (!raw->tri_nodes || !raw->tri_surface_tag || !raw->line_nodes || !raw->line_curve_tag) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (size_t e = 0; e < b->nt; ++e) {
    raw->tri_surface_tag[e] = b->tri_ent[e];
    for (int k = 0; k < np; ++k) {
      size_t i = hoc_hash_get(&b->index, b->tri_tags[e * (size_t)np + (size_t)k]);
      if (i == SIZE_MAX) {
        status = HOC_ERROR(HOC_ERR_FORMAT, "'%s': a triangle uses node %zu, which is not in $Nodes",
                           r->name, b->tri_tags[e * (size_t)np + (size_t)k]);
        goto done;
      }
      if (newi[i] == SIZE_MAX) newi[i] = count++;
      raw->tri_nodes[e * (size_t)np + (size_t)k] = newi[i];
    }
  }
  /* lines: b->line_tags holds lines of any order; keep those of order p */
  size_t nl = 0;
  for (size_t l = 0; l < keep_lines; ++l) {
    size_t base = l * (size_t)(p + 1);
    int ok = 1;
    size_t idx[11];
    for (int k = 0; k <= p && ok; ++k) {
      size_t i = hoc_hash_get(&b->index, b->line_tags[base + (size_t)k]);
      if (i == SIZE_MAX) ok = 0;
      else idx[k] = i;
    }
    if (!ok) continue;
    for (int k = 0; k <= p; ++k) {
      if (newi[idx[k]] == SIZE_MAX) newi[idx[k]] = count++;
      raw->line_nodes[nl * (size_t)(p + 1) + (size_t)k] = newi[idx[k]];
    }
    raw->line_curve_tag[nl++] = b->line_ent[l];
  }
  raw->n_lines = nl;
  raw->n_nodes = count;
  raw->node_tag = hoc_calloc(count + 1, sizeof *raw->node_tag);
  raw->xyz = hoc_calloc(3 * count + 1, sizeof *raw->xyz);
  raw->param = hoc_calloc(2 * count + 1, sizeof *raw->param);
  raw->node_dim = hoc_calloc(count + 1, sizeof *raw->node_dim);
  raw->node_entity_tag = hoc_calloc(count + 1, sizeof *raw->node_entity_tag);
  raw->has_param = hoc_calloc(count + 1, 1);
  if (!raw->node_tag || !raw->xyz || !raw->param || !raw->node_dim || !raw->node_entity_tag ||
      !raw->has_param) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
    goto done;
  }
  for (size_t i = 0; i < b->n; ++i) {
    size_t j = newi[i];
    if (j == SIZE_MAX) continue;
    raw->node_tag[j] = b->tag[i];
    memcpy(raw->xyz + 3 * j, b->xyz + 3 * i, 3 * sizeof(double));
    memcpy(raw->param + 2 * j, b->par + 2 * i, 2 * sizeof(double));
    raw->node_dim[j] = b->dim[i];
    raw->node_entity_tag[j] = b->ent[i];
    raw->has_param[j] = b->has[i];
  }
done:
  free(newi);
  return status;
}

/* MSH 2.2: a node's entity is the lowest-dimensional kept element using it. */
static void classify22(hoc_msh_raw *raw, const builder *b, const size_t *points, size_t n_points,
                       const int *point_ent) {
  int p = raw->order, np = (p + 1) * (p + 2) / 2;
  for (size_t i = 0; i < raw->n_nodes; ++i) raw->node_dim[i] = -1;
  for (size_t e = 0; e < raw->n_tris; ++e)
    for (int k = 0; k < np; ++k) {
      size_t i = raw->tri_nodes[e * (size_t)np + (size_t)k];
      if (raw->node_dim[i] < 0) raw->node_dim[i] = 2, raw->node_entity_tag[i] = raw->tri_surface_tag[e];
    }
  for (size_t l = 0; l < raw->n_lines; ++l)
    for (int k = 0; k <= p; ++k) {
      size_t i = raw->line_nodes[l * (size_t)(p + 1) + (size_t)k];
      if (raw->node_dim[i] < 0 || raw->node_dim[i] > 1)
        raw->node_dim[i] = 1, raw->node_entity_tag[i] = raw->line_curve_tag[l];
    }
  /* points: map their node tags through the raw node tags */
  hoc_hash h;
  if (hoc_hash_init(&h, raw->n_nodes) != HOC_OK) return;
  for (size_t i = 0; i < raw->n_nodes; ++i) hoc_hash_insert(&h, raw->node_tag[i], i, NULL, NULL);
  for (size_t k = 0; k < n_points; ++k) {
    size_t i = hoc_hash_get(&h, points[k]);
    if (i != SIZE_MAX) raw->node_dim[i] = 0, raw->node_entity_tag[i] = point_ent[k];
  }
  hoc_hash_free(&h);
  (void)b;
}

hoc_status hoc_msh_read_buffer(const char *data, size_t size, const char *name, hoc_msh_raw *raw) {
  HOC_CHECK(raw, HOC_ERR_ARGUMENT, "NULL output");
  memset(raw, 0, sizeof *raw);
  HOC_CHECK(data || !size, HOC_ERR_ARGUMENT, "NULL data");
  reader r = {data, data + size, data, name ? name : "mesh", 0, 0};
  char tok[64];
  if (!next_token(&r, tok, sizeof tok) || strcmp(tok, "$MeshFormat"))
    FAIL(&r, "'%s' is not a gmsh .msh file", r.name);
  double version;
  long long ftype, dsize;
  HOC_TRY(read_double(&r, &version, "$MeshFormat"));
  HOC_TRY(read_long(&r, &ftype, "$MeshFormat"));
  HOC_TRY(read_long(&r, &dsize, "$MeshFormat"));
  int v41 = version >= 4.1 && version < 5, v22 = version >= 2 && version < 3;
  if (!v41 && !v22)
    return HOC_ERROR(HOC_ERR_UNSUPPORTED, "'%s': MSH version %g is not supported (4.1 or 2.2)",
                     r.name, version);
  if (ftype != 0 && ftype != 1) FAIL(&r, "'%s': file type %lld in $MeshFormat", r.name, ftype);
  if (ftype == 1 && v22)
    return HOC_ERROR(HOC_ERR_UNSUPPORTED, "'%s': binary MSH 2.2 is not supported", r.name);
  if (dsize != 8) FAIL(&r, "'%s': data size %lld (8 expected)", r.name, dsize);
  if (ftype == 1) {
    /* one int 1 right after the newline tells the endianness */
    while (r.cur < r.end && *r.cur != '\n') ++r.cur;
    if (r.cur < r.end) ++r.cur;
    int32_t one;
    if ((size_t)(r.end - r.cur) < sizeof one) FAIL(&r, "'%s': truncated $MeshFormat", r.name);
    memcpy(&one, r.cur, sizeof one);
    r.cur += sizeof one;
    if (one == 1) r.swap = 0;
    else if (one == 0x01000000) r.swap = 1;
    else FAIL(&r, "'%s': unreadable binary header", r.name);
    r.binary = 1;
  }
  HOC_TRY(expect_end(&r, "MeshFormat"));
  builder b = {0};
  size_t *points = NULL, n_points = 0;
  int *point_ent = NULL;
  hoc_status status = HOC_OK;
  int have_nodes = 0, have_elements = 0;
  HOC_TRY_GOTO(hoc_hash_init(&b.index, 1024), done);
  for (;;) {
    skip_space(&r);
    if (r.cur >= r.end) break;
    if (!next_token(&r, tok, sizeof tok)) break;
    if (tok[0] != '$') {
      status = HOC_ERROR(HOC_ERR_FORMAT, "'%s': expected a section, found '%.20s'", r.name, tok);
      goto done;
    }
    if (r.binary) { /* past the newline that ends the section name */
      while (r.cur < r.end && *r.cur != '\n') ++r.cur;
      if (r.cur < r.end) ++r.cur;
    }
    if (!strcmp(tok, "$Nodes")) {
      if (have_nodes) {
        status = HOC_ERROR(HOC_ERR_FORMAT, "'%s': two $Nodes sections", r.name);
        goto done;
      }
      have_nodes = 1;
      HOC_TRY_GOTO(v41 ? read_nodes41(&r, &b) : read_nodes22(&r, &b), done);
    } else if (!strcmp(tok, "$Elements")) {
      if (have_elements) {
        status = HOC_ERROR(HOC_ERR_FORMAT, "'%s': two $Elements sections", r.name);
        goto done;
      }
      have_elements = 1;
      HOC_TRY_GOTO(v41 ? read_elements41(&r, &b) : read_elements22(&r, &b, &points, &n_points, &point_ent),
                   done);
    } else {
      HOC_TRY_GOTO(skip_to_end(&r, tok + 1), done);
    }
  }
  if (!have_nodes || !have_elements) {
    status = HOC_ERROR(HOC_ERR_FORMAT, "'%s' has no %s section", r.name, have_nodes ? "$Elements" : "$Nodes");
    goto done;
  }
  HOC_TRY_GOTO(finish(&r, &b, raw), done);
  if (v22) classify22(raw, &b, points, n_points, point_ent);
done:
  builder_free(&b);
  free(points);
  free(point_ent);
  if (status != HOC_OK) hoc_msh_raw_free(raw);
  return status;
}

hoc_status hoc_msh_read(const char *path, hoc_msh_raw *raw) {
  HOC_CHECK(raw, HOC_ERR_ARGUMENT, "NULL output");
  memset(raw, 0, sizeof *raw);
  HOC_CHECK(path && path[0], HOC_ERR_ARGUMENT, "no mesh file name given");
  FILE *f = fopen(path, "rb");
  if (!f) return HOC_ERROR(HOC_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
  if (fseek(f, 0, SEEK_END) != 0) {
    fclose(f);
    return HOC_ERROR(HOC_ERR_IO, "cannot read '%s'", path);
  }
  long size = ftell(f);
  rewind(f);
  if (size < 0) {
    fclose(f);
    return HOC_ERROR(HOC_ERR_IO, "cannot read '%s' (not a regular file?)", path);
  }
  char *data = hoc_calloc((size_t)size + 1, 1);
  if (!data) {
    fclose(f);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory for '%s' (%ld bytes)", path, size);
  }
  size_t got = fread(data, 1, (size_t)size, f);
  int err = ferror(f);
  fclose(f);
  if (err || got != (size_t)size) {
    free(data);
    return HOC_ERROR(HOC_ERR_IO, "cannot read '%s'", path);
  }
  hoc_status st = hoc_msh_read_buffer(data, got, path, raw);
  free(data);
  return st;
}

void hoc_msh_raw_free(hoc_msh_raw *raw) {
  if (!raw) return;
  free(raw->node_tag);
  free(raw->xyz);
  free(raw->node_dim);
  free(raw->node_entity_tag);
  free(raw->param);
  free(raw->has_param);
  free(raw->tri_nodes);
  free(raw->tri_surface_tag);
  free(raw->line_nodes);
  free(raw->line_curve_tag);
  memset(raw, 0, sizeof *raw);
}
