/* gmsh MSH reader: 4.1 and 2.2, ASCII and binary. Keeps the surface
 * triangles (of one order) and the curve lines of that order, and the nodes
 * they use with their classification. Every count in the file is checked
 * against what the rest of the file can hold before anything is allocated
 * from it, and every read is bounds-checked: malformed input fails with
 * HOC_ERR_FORMAT and one line naming the place. Loading the file into
 * memory is in msh_load.c, decimal numbers in msh_numbers.c.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"

#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

/* Scanning ------------------------------------------------------------------- */

typedef struct scan {
  const char *begin, *p, *end;
  const char *name;    /* for messages */
  const char *section; /* the section being read, for messages */
  int binary, swap;    /* binary file; its byte order differs from ours */
  int dsize;           /* bytes of a size_t field in a binary file (4 or 8) */
} scan;

/* Record a failure with the place: "'NAME' line L ($Section): ...". */
#if defined(__GNUC__)
__attribute__((format(printf, 5, 6)))
#endif
static hoc_status
fail_at(const scan *s, hoc_status status, int line, const char *func, const char *fmt, ...) {
  char msg[320], where[96];
  va_list ap;
  va_start(ap, fmt);
  vsnprintf(msg, sizeof msg, fmt, ap);
  va_end(ap);
  const char *at = s->p < s->end ? s->p : s->end;
  if (s->binary) {
    snprintf(where, sizeof where, "byte %zu", (size_t)(at - s->begin));
  } else {
    size_t ln = 1;
    for (const char *c = s->begin; c < at; ++c)
      ln += *c == '\n';
    snprintf(where, sizeof where, "line %zu", ln);
  }
  if (s->section)
    return hoc_error_set(status, __FILE__, line, func, "'%s' %s (%s): %s", s->name, where,
                         s->section, msg);
  return hoc_error_set(status, __FILE__, line, func, "'%s' %s: %s", s->name, where, msg);
}
#define FAIL(s, ...) return fail_at((s), HOC_ERR_FORMAT, __LINE__, __func__, __VA_ARGS__)
#define FAIL_UNSUPPORTED(s, ...)                                                                   \
  return fail_at((s), HOC_ERR_UNSUPPORTED, __LINE__, __func__, __VA_ARGS__)

static inline int is_space(char c) {
  return c == ' ' || c == '\n' || c == '\r' || c == '\t' || c == '\v' || c == '\f';
}

static inline void skip_space(scan *s) {
  while (s->p < s->end && is_space(*s->p))
    ++s->p;
}

/* The next whitespace-delimited token [*t, *t + *n); 0 at the end. */
static inline int next_token(scan *s, const char **t, size_t *n) {
  skip_space(s);
  const char *b = s->p;
  while (s->p < s->end && !is_space(*s->p))
    ++s->p;
  *t = b;
  *n = (size_t)(s->p - b);
  return *n > 0;
}

/* Past the end of the current line. */
static void skip_line(scan *s) {
  while (s->p < s->end && *s->p != '\n')
    ++s->p;
  if (s->p < s->end) ++s->p;
}

/* A quoted excerpt of a token for messages. */
static const char *excerpt(const char *t, size_t n, char *buf, size_t size) {
  size_t k = 0;
  for (; k < n && k + 1 < size && k < 24; ++k)
    buf[k] = (t[k] >= 32 && t[k] < 127) ? t[k] : '?';
  buf[k] = '\0';
  return buf;
}

static hoc_status ascii_i64(scan *s, int64_t *v, const char *what) {
  const char *t;
  size_t n;
  if (!next_token(s, &t, &n)) FAIL(s, "the file ends in %s", what);
  size_t k = 0;
  int neg = 0;
  if (t[0] == '-' || t[0] == '+') neg = t[k++] == '-';
  if (k == n) FAIL(s, "%s: '%c' is not an integer", what, t[0]);
  uint64_t x = 0;
  for (; k < n; ++k) {
    if (t[k] < '0' || t[k] > '9') {
      char b[32];
      FAIL(s, "%s: '%s' is not an integer", what, excerpt(t, n, b, sizeof b));
    }
    x = 10 * x + (uint64_t)(t[k] - '0');
    if (x > (uint64_t)INT64_MAX) FAIL(s, "%s: integer too large", what);
  }
  *v = neg ? -(int64_t)x : (int64_t)x;
  return HOC_OK;
}

static hoc_status binary_bytes(scan *s, void *dst, size_t size, const char *what) {
  if ((size_t)(s->end - s->p) < size) FAIL(s, "the file ends in %s", what);
  memcpy(dst, s->p, size);
  if (s->swap) {
    unsigned char *b = dst;
    for (size_t i = 0; i < size / 2; ++i) {
      unsigned char t = b[i];
      b[i] = b[size - 1 - i];
      b[size - 1 - i] = t;
    }
  }
  s->p += size;
  return HOC_OK;
}

/* An int field (4 bytes in binary files). */
static hoc_status get_int(scan *s, int *v, const char *what) {
  if (s->binary) {
    int32_t x = 0;
    HOC_TRY(binary_bytes(s, &x, sizeof x, what));
    *v = x;
    return HOC_OK;
  }
  int64_t x = 0;
  HOC_TRY(ascii_i64(s, &x, what));
  if (x < INT32_MIN || x > INT32_MAX) FAIL(s, "%s: %lld is out of range", what, (long long)x);
  *v = (int)x;
  return HOC_OK;
}

/* A size_t field (dsize bytes in binary files): a count or a tag, >= 0. */
static hoc_status get_size(scan *s, uint64_t *v, const char *what) {
  if (s->binary) {
    if (s->dsize == 4) {
      uint32_t x = 0;
      HOC_TRY(binary_bytes(s, &x, sizeof x, what));
      *v = x;
    } else {
      HOC_TRY(binary_bytes(s, v, sizeof *v, what));
    }
    if (*v > (uint64_t)INT64_MAX) FAIL(s, "%s: absurd value %llu", what, (unsigned long long)*v);
    return HOC_OK;
  }
  int64_t x = 0;
  HOC_TRY(ascii_i64(s, &x, what));
  if (x < 0) FAIL(s, "%s: negative value %lld", what, (long long)x);
  *v = (uint64_t)x;
  return HOC_OK;
}

/* A double, which must be finite. */
static hoc_status get_real(scan *s, double *v, const char *what) {
  if (s->binary) {
    HOC_TRY(binary_bytes(s, v, sizeof *v, what));
  } else {
    const char *t;
    size_t n;
    if (!next_token(s, &t, &n)) FAIL(s, "the file ends in %s", what);
    if (!hoc_io_parse_double(t, n, v)) {
      char b[32];
      FAIL(s, "%s: '%s' is not a number", what, excerpt(t, n, b, sizeof b));
    }
  }
  if (!isfinite(*v)) FAIL(s, "%s: non-finite number", what);
  return HOC_OK;
}

/* `count` items of at least `min_bytes` each must fit in the rest. */
static hoc_status check_count(scan *s, uint64_t count, size_t min_bytes, const char *what) {
  if (count > (uint64_t)(s->end - s->p) / (min_bytes ? min_bytes : 1))
    FAIL(s, "%s is %llu, more than the rest of the file can hold", what, (unsigned long long)count);
  return HOC_OK;
}

/* Minimum bytes of n fields in this file: ASCII tokens take at least two
 * bytes (a digit and a separator), binary ones their size. */
static size_t min_bytes(const scan *s, size_t ints, size_t sizes, size_t reals) {
  if (!s->binary) return 2 * (ints + sizes + reals);
  return 4 * ints + (size_t)s->dsize * sizes + 8 * reals;
}

/* The line "$EndName" (after optional whitespace). */
static hoc_status expect_end(scan *s, const char *name) {
  char want[80];
  snprintf(want, sizeof want, "$End%s", name);
  size_t m = strlen(want);
  skip_space(s);
  if ((size_t)(s->end - s->p) < m || memcmp(s->p, want, m) ||
      (s->p + m < s->end && !is_space(s->p[m])))
    FAIL(s, "%s expected", want);
  s->p += m;
  return HOC_OK;
}

/* Skip a section we do not read: up to and past its "$EndName". */
static hoc_status skip_section(scan *s, const char *name) {
  char want[80];
  snprintf(want, sizeof want, "$End%s", name);
  size_t m = strlen(want);
  for (const char *c = s->p; (size_t)(s->end - c) >= m; ++c)
    if (*c == '$' && !memcmp(c, want, m) && (c + m == s->end || is_space(c[m]))) {
      s->p = c + m;
      return HOC_OK;
    }
  FAIL(s, "no %s", want);
}

/* Node tags -> positions ----------------------------------------------------- */

typedef struct tag_pair {
  uint64_t tag;
  size_t index;
} tag_pair;

typedef struct tag_map {
  uint64_t min;   /* smallest tag */
  size_t range;   /* direct table size, 0 if sorted */
  size_t *direct; /* [range] position of tag min + k, SIZE_MAX if none */
  size_t n;
  tag_pair *sorted; /* [n] by tag, when the tags are too sparse for a table */
} tag_map;

static int compare_pairs(const void *a, const void *b) {
  uint64_t x = ((const tag_pair *)a)->tag, y = ((const tag_pair *)b)->tag;
  return (x > y) - (x < y);
}

static void tag_map_free(tag_map *m) {
  free(m->direct);
  free(m->sorted);
  memset(m, 0, sizeof *m);
}

/* Dense tags (the usual case) get a direct table of at most 2n + 1024
 * entries; sparse ones a sorted array searched by bisection. */
static hoc_status tag_map_build(tag_map *m, scan *s, const uint64_t *tags, size_t n) {
  memset(m, 0, sizeof *m);
  m->n = n;
  if (!n) return HOC_OK;
  uint64_t lo = tags[0], hi = tags[0];
  for (size_t i = 1; i < n; ++i) {
    if (tags[i] < lo) lo = tags[i];
    if (tags[i] > hi) hi = tags[i];
  }
  m->min = lo;
  if (hi - lo < 2 * (uint64_t)n + 1024) {
    m->range = (size_t)(hi - lo) + 1;
    HOC_ALLOC(m->direct, m->range);
    for (size_t k = 0; k < m->range; ++k)
      m->direct[k] = SIZE_MAX;
    for (size_t i = 0; i < n; ++i) {
      size_t *slot = &m->direct[tags[i] - lo];
      if (*slot != SIZE_MAX) FAIL(s, "node %llu appears twice", (unsigned long long)tags[i]);
      *slot = i;
    }
    return HOC_OK;
  }
  HOC_ALLOC(m->sorted, n);
  for (size_t i = 0; i < n; ++i)
    m->sorted[i] = (tag_pair){tags[i], i};
  qsort(m->sorted, n, sizeof *m->sorted, compare_pairs);
  for (size_t i = 1; i < n; ++i)
    if (m->sorted[i].tag == m->sorted[i - 1].tag)
      FAIL(s, "node %llu appears twice", (unsigned long long)m->sorted[i].tag);
  return HOC_OK;
}

static inline size_t tag_map_get(const tag_map *m, uint64_t tag) {
  if (m->direct)
    return tag >= m->min && tag - m->min < m->range ? m->direct[tag - m->min] : SIZE_MAX;
  size_t lo = 0, hi = m->n;
  while (lo < hi) {
    size_t mid = lo + (hi - lo) / 2;
    if (m->sorted[mid].tag < tag)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < m->n && m->sorted[lo].tag == tag ? m->sorted[lo].index : SIZE_MAX;
}

/* What the file holds ---------------------------------------------------------- */

typedef struct mesh_in {
  int v2;         /* MSH 2.x */
  int classified; /* nodes came with their entity (4.1, 2.x $ParametricNodes) */
  /* every node of the file, in file order */
  size_t n_nodes;
  uint64_t *tag;      /* [n_nodes] */
  double *xyz;        /* [n_nodes][3] */
  double *param;      /* [n_nodes][2] */
  signed char *dim;   /* [n_nodes] */
  int *ent;           /* [n_nodes] */
  unsigned char *has; /* [n_nodes] */
  tag_map map;
  /* triangles of one order, as node positions */
  int order;
  size_t n_tris, cap_tri, cap_tri_ent;
  size_t *tri;  /* [n_tris][np] */
  int *tri_ent; /* [n_tris] */
  /* lines of every order (the triangles' order is known only at the end) */
  size_t n_lines, n_line_nodes, cap_line_start, cap_line_order, cap_line_ent, cap_line_node;
  size_t *line_start;        /* [n_lines] offset into line_node */
  unsigned char *line_order; /* [n_lines] */
  int *line_ent;             /* [n_lines] */
  size_t *line_node;         /* node positions of every line, end0 end1 interior */
  /* MSH 2.x point elements, to classify nodes */
  size_t n_pts, cap_pt_node, cap_pt_ent;
  size_t *pt_node; /* [n_pts] */
  int *pt_ent;     /* [n_pts] */
} mesh_in;

static void mesh_in_free(mesh_in *m) {
  free(m->tag);
  free(m->xyz);
  free(m->param);
  free(m->dim);
  free(m->ent);
  free(m->has);
  tag_map_free(&m->map);
  free(m->tri);
  free(m->tri_ent);
  free(m->line_start);
  free(m->line_order);
  free(m->line_ent);
  free(m->line_node);
  free(m->pt_node);
  free(m->pt_ent);
  memset(m, 0, sizeof *m);
}

static hoc_status alloc_nodes(mesh_in *m, size_t n) {
  m->n_nodes = n;
  HOC_ALLOC(m->tag, n + 1);
  HOC_ALLOC(m->xyz, 3 * n + 1);
  HOC_ALLOC(m->param, 2 * n + 1);
  HOC_ALLOC(m->dim, n + 1);
  HOC_ALLOC(m->ent, n + 1);
  HOC_ALLOC(m->has, n + 1);
  return HOC_OK;
}

/* An array of *cap elements of `size` bytes grown to hold `need`; NULL if
 * out of memory (the old array is then still valid). */
static void *grow(void *ptr, size_t *cap, size_t need, size_t size) {
  if (need <= *cap) return ptr;
  size_t c = *cap ? *cap : 256;
  while (c < need)
    c = c > SIZE_MAX / 4 ? need : 2 * c;
  void *q = hoc_realloc(ptr, c, size);
  if (q) *cap = c;
  return q;
}
#define RESERVE(m, field, need)                                                                    \
  do {                                                                                             \
    void *q_ = grow((m)->field, &(m)->cap_##field, (need), sizeof *(m)->field);                    \
    if (!q_) return HOC_ERROR(HOC_ERR_MEMORY, "out of memory for %zu elements", (size_t)(need));   \
    (m)->field = q_;                                                                               \
  } while (0)

/* Room for `count` more elements of a type whose nodes are `nn`. */
static hoc_status reserve_block(mesh_in *m, int type, size_t count, int nn) {
  if (hoc_msh_triangle_order(type) > 0) {
    RESERVE(m, tri, (m->n_tris + count) * (size_t)nn);
    RESERVE(m, tri_ent, m->n_tris + count);
  } else if (hoc_msh_line_order(type) > 0) {
    RESERVE(m, line_start, m->n_lines + count);
    RESERVE(m, line_order, m->n_lines + count);
    RESERVE(m, line_ent, m->n_lines + count);
    RESERVE(m, line_node, m->n_line_nodes + count * (size_t)nn);
  } else if (type == 15 && m->v2) {
    RESERVE(m, pt_node, m->n_pts + count);
    RESERVE(m, pt_ent, m->n_pts + count);
  }
  return HOC_OK;
}

/* The node positions of an element, from its tags. */
static hoc_status element_nodes(scan *s, const mesh_in *m, const uint64_t *tags, int nn,
                                size_t *out) {
  for (int k = 0; k < nn; ++k) {
    size_t i = tag_map_get(&m->map, tags[k]);
    if (i == SIZE_MAX)
      FAIL(s, "an element uses node %llu, which is not in the nodes section",
           (unsigned long long)tags[k]);
    out[k] = i;
  }
  return HOC_OK;
}

/* Check whether an element type is kept (and its order), before its block. */
static hoc_status check_kept_type(scan *s, mesh_in *m, int type, int dim) {
  int tp = hoc_msh_triangle_order(type), lp = hoc_msh_line_order(type);
  if (tp < 0)
    FAIL_UNSUPPORTED(s,
                     "incomplete (serendipity) triangles of order %d (element type %d) are not "
                     "supported",
                     -tp, type);
  if (tp > 0) {
    if (dim >= 0 && dim != 2) FAIL(s, "triangles in an entity block of dimension %d", dim);
    if (m->order && m->order != tp)
      FAIL_UNSUPPORTED(s, "triangles of orders %d and %d in one mesh are not supported", m->order,
                       tp);
    m->order = tp;
  }
  if (lp > 0 && dim >= 0 && dim != 1) FAIL(s, "lines in an entity block of dimension %d", dim);
  return HOC_OK;
}

/* Keep an element (`nodes` are positions); room was reserved. */
static void keep_element(mesh_in *m, int type, int ent, const size_t *nodes) {
  int tp = hoc_msh_triangle_order(type);
  if (tp > 0) {
    int np = (tp + 1) * (tp + 2) / 2;
    memcpy(m->tri + m->n_tris * (size_t)np, nodes, (size_t)np * sizeof *nodes);
    m->tri_ent[m->n_tris++] = ent;
    return;
  }
  int lp = hoc_msh_line_order(type);
  if (lp > 0) {
    memcpy(m->line_node + m->n_line_nodes, nodes, (size_t)(lp + 1) * sizeof *nodes);
    m->line_start[m->n_lines] = m->n_line_nodes;
    m->line_order[m->n_lines] = (unsigned char)lp;
    m->line_ent[m->n_lines++] = ent;
    m->n_line_nodes += (size_t)lp + 1;
    return;
  }
  if (type == 15 && m->v2) {
    m->pt_node[m->n_pts] = nodes[0];
    m->pt_ent[m->n_pts++] = ent;
  }
}

static int is_kept_type(const mesh_in *m, int type) {
  return hoc_msh_triangle_order(type) > 0 || hoc_msh_line_order(type) > 0 || (type == 15 && m->v2);
}

/* MSH 4.1 ---------------------------------------------------------------------- */

static hoc_status read_nodes41(scan *s, mesh_in *m) {
  uint64_t n_blocks = 0, n_nodes = 0, tag_min = 0, tag_max = 0;
  HOC_TRY(get_size(s, &n_blocks, "the number of node blocks"));
  HOC_TRY(get_size(s, &n_nodes, "the number of nodes"));
  HOC_TRY(get_size(s, &tag_min, "the smallest node tag"));
  HOC_TRY(get_size(s, &tag_max, "the largest node tag"));
  HOC_TRY(check_count(s, n_blocks, min_bytes(s, 3, 1, 0), "the number of node blocks"));
  HOC_TRY(check_count(s, n_nodes, min_bytes(s, 0, 1, 3), "the number of nodes"));
  HOC_TRY(alloc_nodes(m, (size_t)n_nodes));
  size_t done = 0;
  for (uint64_t b = 0; b < n_blocks; ++b) {
    int dim, ent, parametric;
    uint64_t count = 0;
    HOC_TRY(get_int(s, &dim, "a node block's dimension"));
    HOC_TRY(get_int(s, &ent, "a node block's entity"));
    HOC_TRY(get_int(s, &parametric, "a node block's parametric flag"));
    HOC_TRY(get_size(s, &count, "a node block's size"));
    if (dim < 0 || dim > 3) FAIL(s, "node block of dimension %d", dim);
    if (parametric != 0 && parametric != 1)
      FAIL(s, "node block with parametric flag %d", parametric);
    if (count > n_nodes - done)
      FAIL(s, "the node blocks hold more nodes than the %llu announced",
           (unsigned long long)n_nodes);
    int npar = parametric ? dim : 0;
    HOC_TRY(
        check_count(s, count, min_bytes(s, 0, 1, 3 + (size_t)npar), "the size of a node block"));
    for (size_t k = done; k < done + count; ++k) {
      HOC_TRY(get_size(s, &m->tag[k], "a node tag"));
      if (!m->tag[k]) FAIL(s, "node tag 0");
    }
    for (size_t k = done; k < done + count; ++k) {
      double *x = m->xyz + 3 * k, u[3] = {0, 0, 0}; /* x: [3], u: up to 3 parameters */
      for (int c = 0; c < 3; ++c)
        HOC_TRY(get_real(s, &x[c], "node coordinates"));
      for (int c = 0; c < npar; ++c)
        HOC_TRY(get_real(s, &u[c], "node parameters"));
      m->param[2 * k] = u[0];
      m->param[2 * k + 1] = u[1];
      m->dim[k] = (signed char)dim;
      m->ent[k] = ent;
      m->has[k] = (unsigned char)(parametric && (dim == 1 || dim == 2));
    }
    done += (size_t)count;
  }
  if (done != n_nodes)
    FAIL(s, "the node blocks hold %zu nodes, %llu announced", done, (unsigned long long)n_nodes);
  HOC_TRY(tag_map_build(&m->map, s, m->tag, m->n_nodes));
  m->classified = 1;
  return expect_end(s, "Nodes");
}

enum { MAX_ELEMENT_NODES = 1024 };

static hoc_status read_elements41(scan *s, mesh_in *m) {
  uint64_t n_blocks = 0, n_elems = 0, tag_min = 0, tag_max = 0;
  HOC_TRY(get_size(s, &n_blocks, "the number of element blocks"));
  HOC_TRY(get_size(s, &n_elems, "the number of elements"));
  HOC_TRY(get_size(s, &tag_min, "the smallest element tag"));
  HOC_TRY(get_size(s, &tag_max, "the largest element tag"));
  HOC_TRY(check_count(s, n_blocks, min_bytes(s, 3, 1, 0), "the number of element blocks"));
  HOC_TRY(check_count(s, n_elems, min_bytes(s, 0, 2, 0), "the number of elements"));
  uint64_t done = 0, tags[MAX_ELEMENT_NODES];
  size_t pos[MAX_ELEMENT_NODES];
  for (uint64_t b = 0; b < n_blocks; ++b) {
    int dim, ent, type;
    uint64_t count = 0;
    HOC_TRY(get_int(s, &dim, "an element block's dimension"));
    HOC_TRY(get_int(s, &ent, "an element block's entity"));
    HOC_TRY(get_int(s, &type, "an element block's type"));
    HOC_TRY(get_size(s, &count, "an element block's size"));
    if (dim < 0 || dim > 3) FAIL(s, "element block of dimension %d", dim);
    if (count > n_elems - done)
      FAIL(s, "the element blocks hold more elements than the %llu announced",
           (unsigned long long)n_elems);
    done += count;
    int nn = hoc_msh_element_nodes(type);
    if (!nn) { /* unknown size: ASCII elements are one per line */
      if (s->binary)
        FAIL_UNSUPPORTED(s, "element type %d (of unknown size) in a binary file", type);
      HOC_TRY(check_count(s, count, 2, "the size of an element block"));
      for (uint64_t k = 0; k < count; ++k) {
        skip_space(s);
        if (s->p >= s->end) FAIL(s, "the file ends in an element block");
        skip_line(s);
      }
      continue;
    }
    HOC_TRY(check_kept_type(s, m, type, dim));
    HOC_TRY(
        check_count(s, count, min_bytes(s, 0, 1 + (size_t)nn, 0), "the size of an element block"));
    int kept = is_kept_type(m, type);
    if (kept) HOC_TRY(reserve_block(m, type, (size_t)count, nn));
    for (uint64_t k = 0; k < count; ++k) {
      uint64_t etag;
      HOC_TRY(get_size(s, &etag, "an element tag"));
      for (int j = 0; j < nn; ++j)
        HOC_TRY(get_size(s, &tags[j], "an element's nodes"));
      if (!kept) continue;
      HOC_TRY(element_nodes(s, m, tags, nn, pos));
      keep_element(m, type, ent, pos);
    }
  }
  if (done != n_elems)
    FAIL(s, "the element blocks hold %llu elements, %llu announced", (unsigned long long)done,
         (unsigned long long)n_elems);
  return expect_end(s, "Elements");
}

/* MSH 2.x ---------------------------------------------------------------------- */

/* A count on a text line of its own: MSH 2.x writes the counts of its
 * sections so in binary files too, the binary records starting on the next
 * line. */
static hoc_status text_count(scan *s, uint64_t *n, const char *what) {
  int binary = s->binary;
  s->binary = 0;
  hoc_status st = get_size(s, n, what);
  s->binary = binary;
  if (st == HOC_OK && binary) skip_line(s);
  return st;
}

/* A node tag of a 2.x file (an int in binary files), > 0. */
static hoc_status tag2(scan *s, uint64_t *tag, const char *what) {
  if (s->binary) {
    int t;
    HOC_TRY(get_int(s, &t, what));
    if (t <= 0) FAIL(s, "%s %d (positive expected)", what, t);
    *tag = (uint64_t)t;
    return HOC_OK;
  }
  HOC_TRY(get_size(s, tag, what));
  if (!*tag) FAIL(s, "%s 0", what);
  return HOC_OK;
}

/* $Nodes (tag x y z) or $ParametricNodes (tag x y z dim entity [u [v]]). */
static hoc_status read_nodes2(scan *s, mesh_in *m, int parametric) {
  uint64_t n = 0;
  HOC_TRY(text_count(s, &n, "the number of nodes"));
  size_t ints = (s->binary ? 1 : 0) + (parametric ? 2 : 0), sizes = s->binary ? 0 : 1;
  HOC_TRY(check_count(s, n, min_bytes(s, ints, sizes, 3), "the number of nodes"));
  HOC_TRY(alloc_nodes(m, (size_t)n));
  for (size_t k = 0; k < n; ++k) {
    HOC_TRY(tag2(s, &m->tag[k], "node tag"));
    for (int c = 0; c < 3; ++c)
      HOC_TRY(get_real(s, &m->xyz[3 * k + (size_t)c], "node coordinates"));
    m->dim[k] = -1;
    if (!parametric) continue;
    int dim, ent;
    HOC_TRY(get_int(s, &dim, "a node's dimension"));
    HOC_TRY(get_int(s, &ent, "a node's entity"));
    if (dim < 0 || dim > 3) FAIL(s, "node of dimension %d", dim);
    int npar = dim == 1 || dim == 2 ? dim : 0;
    for (int c = 0; c < npar; ++c)
      HOC_TRY(get_real(s, &m->param[2 * k + (size_t)c], "node parameters"));
    m->dim[k] = (signed char)dim;
    m->ent[k] = ent;
    m->has[k] = (unsigned char)(npar > 0);
  }
  HOC_TRY(tag_map_build(&m->map, s, m->tag, m->n_nodes));
  m->classified = parametric;
  return expect_end(s, parametric ? "ParametricNodes" : "Nodes");
}

/* One element of a 2.x file after its type: tags (physical, elementary
 * entity, partitions...) then nn node tags, kept if its type is. */
static hoc_status read_element2(scan *s, mesh_in *m, int type, int ntags, int nn, int kept,
                                uint64_t *tags, size_t *pos) {
  int ent = 0;
  for (int j = 0; j < ntags; ++j) {
    int t = 0;
    HOC_TRY(get_int(s, &t, "an element's tags"));
    if (j == 1) ent = t;
  }
  for (int j = 0; j < nn; ++j)
    HOC_TRY(tag2(s, &tags[j], "an element's node"));
  if (!kept) return HOC_OK;
  HOC_TRY(element_nodes(s, m, tags, nn, pos));
  keep_element(m, type, ent, pos);
  return HOC_OK;
}

/* ASCII: "tag type ntags tags... nodes..." per line. Binary: blocks of a
 * header (type, count, ntags) and count records "tag tags... nodes...",
 * all int. */
static hoc_status read_elements2(scan *s, mesh_in *m) {
  uint64_t n = 0, done = 0, tags[MAX_ELEMENT_NODES];
  size_t pos[MAX_ELEMENT_NODES];
  HOC_TRY(text_count(s, &n, "the number of elements"));
  /* at least "tag type ntags node" in ASCII, a tag and a node in binary */
  HOC_TRY(check_count(s, n, s->binary ? 8 : min_bytes(s, 2, 2, 0), "the number of elements"));
  while (done < n) {
    int type, ntags, count = 1;
    if (s->binary) {
      HOC_TRY(get_int(s, &type, "an element block's type"));
      HOC_TRY(get_int(s, &count, "an element block's size"));
      HOC_TRY(get_int(s, &ntags, "an element block's number of tags"));
      if (count <= 0 || (uint64_t)count > n - done)
        FAIL(s, "an element block of %d elements (1 to the %llu left expected)", count,
             (unsigned long long)(n - done));
    } else {
      uint64_t etag;
      HOC_TRY(get_size(s, &etag, "an element tag"));
      HOC_TRY(get_int(s, &type, "an element's type"));
      HOC_TRY(get_int(s, &ntags, "an element's number of tags"));
    }
    if (ntags < 0) FAIL(s, "elements with %d tags", ntags);
    HOC_TRY(check_count(s, (uint64_t)ntags, min_bytes(s, 1, 0, 0), "an element's number of tags"));
    int nn = hoc_msh_element_nodes(type);
    if (!nn) { /* unknown size: the rest of an ASCII line */
      if (s->binary)
        FAIL_UNSUPPORTED(s, "element type %d (of unknown size) in a binary file", type);
      for (int j = 0; j < ntags; ++j) {
        int t;
        HOC_TRY(get_int(s, &t, "an element's tags"));
      }
      skip_line(s);
      ++done;
      continue;
    }
    HOC_TRY(check_kept_type(s, m, type, -1));
    int kept = is_kept_type(m, type);
    if (s->binary) {
      size_t rec = min_bytes(s, 1 + (size_t)ntags + (size_t)nn, 0, 0);
      HOC_TRY(check_count(s, (uint64_t)count, rec, "the size of an element block"));
      if (kept) HOC_TRY(reserve_block(m, type, (size_t)count, nn));
      for (int k = 0; k < count; ++k) {
        int t;
        HOC_TRY(get_int(s, &t, "an element tag"));
        HOC_TRY(read_element2(s, m, type, ntags, nn, kept, tags, pos));
      }
    } else {
      if (kept) HOC_TRY(reserve_block(m, type, 1, nn));
      HOC_TRY(read_element2(s, m, type, ntags, nn, kept, tags, pos));
    }
    done += (uint64_t)count;
  }
  return expect_end(s, "Elements");
}

/* The result -------------------------------------------------------------------- */

/* Give node j the entity (d, t) if it is lexicographically smaller. */
static void classify_node(hoc_msh_raw *raw, size_t j, int d, int t) {
  if (d < raw->node_dim[j] || (d == raw->node_dim[j] && t < raw->node_entity_tag[j])) {
    raw->node_dim[j] = d;
    raw->node_entity_tag[j] = t;
  }
}

/* Keep the nodes the kept elements use, in file order; for files without
 * classification, give each node the lowest (dim, entity) of the elements
 * using it. */
static hoc_status finish(const mesh_in *m, hoc_msh_raw *raw) {
  int p = m->order, np = p ? (p + 1) * (p + 2) / 2 : 0;
  size_t n = m->n_nodes, n_tris = p ? m->n_tris : 0, n_lines = 0;
  for (size_t l = 0; l < m->n_lines; ++l)
    n_lines += p && m->line_order[l] == p;
  size_t *newi;
  HOC_ALLOC(newi, n + 1);
  for (size_t i = 0; i < n; ++i)
    newi[i] = SIZE_MAX;
  for (size_t k = 0; k < n_tris * (size_t)np; ++k)
    newi[m->tri[k]] = 0;
  for (size_t l = 0; l < m->n_lines; ++l)
    if (p && m->line_order[l] == p)
      for (int k = 0; k <= p; ++k)
        newi[m->line_node[m->line_start[l] + (size_t)k]] = 0;
  size_t used = 0;
  for (size_t i = 0; i < n; ++i)
    if (newi[i] != SIZE_MAX) newi[i] = used++;
  hoc_status status = HOC_OK;
  raw->order = p;
  raw->n_nodes = used;
  raw->n_tris = n_tris;
  raw->n_lines = n_lines;
  HOC_ALLOC_GOTO(raw->node_tag, used + 1, done);
  HOC_ALLOC_GOTO(raw->xyz, 3 * used + 1, done);
  HOC_ALLOC_GOTO(raw->node_dim, used + 1, done);
  HOC_ALLOC_GOTO(raw->node_entity_tag, used + 1, done);
  HOC_ALLOC_GOTO(raw->param, 2 * used + 1, done);
  HOC_ALLOC_GOTO(raw->has_param, used + 1, done);
  HOC_ALLOC_GOTO(raw->tri_nodes, n_tris * (size_t)np + 1, done);
  HOC_ALLOC_GOTO(raw->tri_surface_tag, n_tris + 1, done);
  HOC_ALLOC_GOTO(raw->line_nodes, n_lines * (size_t)(p + 1) + 1, done);
  HOC_ALLOC_GOTO(raw->line_curve_tag, n_lines + 1, done);
  for (size_t i = 0; i < n; ++i) {
    size_t j = newi[i];
    if (j == SIZE_MAX) continue;
    raw->node_tag[j] = (size_t)m->tag[i];
    memcpy(raw->xyz + 3 * j, m->xyz + 3 * i, 3 * sizeof *raw->xyz);
    memcpy(raw->param + 2 * j, m->param + 2 * i, 2 * sizeof *raw->param);
    raw->node_dim[j] = m->classified ? m->dim[i] : -1;
    raw->node_entity_tag[j] = m->classified ? m->ent[i] : 0;
    raw->has_param[j] = m->has[i];
  }
  for (size_t e = 0; e < n_tris; ++e) {
    raw->tri_surface_tag[e] = m->tri_ent[e];
    for (int k = 0; k < np; ++k)
      raw->tri_nodes[e * (size_t)np + (size_t)k] = newi[m->tri[e * (size_t)np + (size_t)k]];
  }
  size_t nl = 0;
  for (size_t l = 0; l < m->n_lines; ++l) {
    if (!p || m->line_order[l] != p) continue;
    raw->line_curve_tag[nl] = m->line_ent[l];
    for (int k = 0; k <= p; ++k)
      raw->line_nodes[nl * (size_t)(p + 1) + (size_t)k] =
          newi[m->line_node[m->line_start[l] + (size_t)k]];
    ++nl;
  }
  if (!m->classified) {
    /* lexicographically smallest (dim, entity): points, then lines, then triangles */
    const int none = 127;
    for (size_t j = 0; j < used; ++j)
      raw->node_dim[j] = none;
    for (size_t k = 0; k < m->n_pts; ++k)
      if (newi[m->pt_node[k]] != SIZE_MAX) classify_node(raw, newi[m->pt_node[k]], 0, m->pt_ent[k]);
    for (size_t l = 0; l < n_lines; ++l)
      for (int k = 0; k <= p; ++k)
        classify_node(raw, raw->line_nodes[l * (size_t)(p + 1) + (size_t)k], 1,
                      raw->line_curve_tag[l]);
    for (size_t e = 0; e < n_tris; ++e)
      for (int k = 0; k < np; ++k)
        classify_node(raw, raw->tri_nodes[e * (size_t)np + (size_t)k], 2, raw->tri_surface_tag[e]);
    for (size_t j = 0; j < used; ++j)
      if (raw->node_dim[j] == none) raw->node_dim[j] = -1, raw->node_entity_tag[j] = 0;
  }
done:
  free(newi);
  return status;
}

/* The file -------------------------------------------------------------------------- */

static hoc_status read_header(scan *s, mesh_in *m) {
  const char *t;
  size_t n;
  if (!next_token(s, &t, &n) || n != 11 || memcmp(t, "$MeshFormat", 11))
    return HOC_ERROR(HOC_ERR_FORMAT, "'%s' is not a gmsh .msh file", s->name);
  s->section = "$MeshFormat";
  if (!next_token(s, &t, &n)) FAIL(s, "the file ends before the version");
  double version;
  char b[32];
  if (!hoc_io_parse_double(t, n, &version) || !isfinite(version))
    FAIL(s, "'%s' is not a version number", excerpt(t, n, b, sizeof b));
  int file_type, data_size;
  HOC_TRY(get_int(s, &file_type, "the file type"));
  HOC_TRY(get_int(s, &data_size, "the data size"));
  if (version >= 2 && version < 3) {
    m->v2 = 1;
  } else if (fabs(version - 4.1) > 1e-9) {
    FAIL_UNSUPPORTED(s,
                     "MSH version %s is not supported (4.1 or 2.2; gmsh can re-save it: "
                     "gmsh FILE -save -format msh41)",
                     excerpt(t, n, b, sizeof b));
  }
  if (file_type != 0 && file_type != 1) FAIL(s, "file type %d (0 or 1 expected)", file_type);
  if (data_size != 4 && data_size != 8) FAIL(s, "data size %d (8 expected)", data_size);
  if (file_type == 1) {
    if (m->v2 && data_size != 8)
      FAIL_UNSUPPORTED(s, "binary MSH 2 file of %d-byte reals (8 expected)", data_size);
    skip_line(s);
    uint32_t one;
    if ((size_t)(s->end - s->p) < sizeof one) FAIL(s, "the file ends in the binary header");
    memcpy(&one, s->p, sizeof one);
    s->p += sizeof one;
    if (one == 1)
      s->swap = 0;
    else if (one == UINT32_C(0x01000000))
      s->swap = 1;
    else
      FAIL(s, "unreadable binary byte-order mark");
    s->binary = 1;
    s->dsize = data_size;
  }
  return expect_end(s, "MeshFormat");
}

static hoc_status read_sections(scan *s, mesh_in *m) {
  int have_nodes = 0, have_elements = 0;
  char name[72];
  for (;;) {
    s->section = NULL;
    skip_space(s);
    if (s->p >= s->end) break;
    const char *t;
    size_t n;
    next_token(s, &t, &n);
    char b[32];
    if (t[0] != '$' || n < 2)
      FAIL(s, "a section ($Name) expected, found '%s'", excerpt(t, n, b, sizeof b));
    if (n >= sizeof name) FAIL(s, "section name '%s...' too long", excerpt(t, n, b, sizeof b));
    memcpy(name, t, n);
    name[n] = '\0';
    s->section = name;
    if (s->binary) skip_line(s); /* binary data starts on the next line */
    int is_nodes = !strcmp(name, "$Nodes") || (m->v2 && !strcmp(name, "$ParametricNodes"));
    if (is_nodes) {
      if (have_nodes) FAIL(s, "a second nodes section");
      have_nodes = 1;
      if (m->v2)
        HOC_TRY(read_nodes2(s, m, name[1] == 'P'));
      else
        HOC_TRY(read_nodes41(s, m));
    } else if (!strcmp(name, "$Elements")) {
      if (have_elements) FAIL(s, "a second $Elements section");
      if (!have_nodes) FAIL(s, "$Elements comes before the nodes");
      have_elements = 1;
      if (m->v2)
        HOC_TRY(read_elements2(s, m));
      else
        HOC_TRY(read_elements41(s, m));
    } else {
      HOC_TRY(skip_section(s, name + 1));
    }
  }
  s->section = NULL;
  if (!have_nodes) FAIL(s, "no $Nodes section");
  if (!have_elements) FAIL(s, "no $Elements section");
  return HOC_OK;
}

hoc_status hoc_msh_read_buffer(const char *data, size_t size, const char *name, hoc_msh_raw *raw) {
  HOC_CHECK(raw, HOC_ERR_ARGUMENT, "no output given");
  memset(raw, 0, sizeof *raw);
  HOC_CHECK(data || !size, HOC_ERR_ARGUMENT, "no data given");
  scan s = {data, data, data + size, name ? name : "mesh", NULL, 0, 0, 8};
  if (!data) s.begin = s.p = s.end = "";
  mesh_in m = {0};
  hoc_status status = read_header(&s, &m);
  if (status == HOC_OK) status = read_sections(&s, &m);
  if (status == HOC_OK) status = finish(&m, raw);
  mesh_in_free(&m);
  if (status != HOC_OK) hoc_msh_raw_free(raw);
  return status;
}
