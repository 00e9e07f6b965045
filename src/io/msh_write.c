/* gmsh MSH writer, 4.1 and 2.2, ASCII and binary: nodes grouped by entity
 * (with their parametric coordinates if asked), curve lines and surface
 * triangles of order 1..10, and in 4.1 the entities, in 2.2 point elements.
 * The element type tables and the exact decimal conversion it shares with
 * the reader are in msh_numbers.c.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"
#include "io/msh_digits.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Buffered output ------------------------------------------------------------ */

enum { WBUF_SIZE = 1 << 18, WBUF_ITEM = 64 };

typedef struct wbuf {
  FILE *fp;
  char *buf;
  size_t len;
  int err;    /* errno of the first failed write, 0 if none */
  int binary; /* fields as raw bytes in the host's order instead of text */
  int fresh;  /* no field yet on this ASCII line */
} wbuf;

static void wb_flush(wbuf *w) {
  if (w->len && !w->err && fwrite(w->buf, 1, w->len, w->fp) != w->len) w->err = errno ? errno : EIO;
  w->len = 0;
}

/* Room for one item of at most WBUF_ITEM characters. */
static inline char *wb_room(wbuf *w) {
  if (WBUF_SIZE - w->len < WBUF_ITEM) wb_flush(w);
  return w->buf + w->len;
}

static void wb_str(wbuf *w, const char *s) {
  for (size_t n = strlen(s); n;) {
    size_t k = n < WBUF_ITEM ? n : WBUF_ITEM;
    memcpy(wb_room(w), s, k);
    w->len += k;
    s += k;
    n -= k;
  }
}

static inline void wb_char(wbuf *w, char c) {
  *wb_room(w) = c;
  ++w->len;
}

static inline void wb_bytes(wbuf *w, const void *p, size_t n) { /* n <= WBUF_ITEM */
  memcpy(wb_room(w), p, n);
  w->len += n;
}

static inline void wb_u64(wbuf *w, uint64_t x) {
  char *s = wb_room(w);
  w->len += format_u64(x, s);
}

static inline void wb_int(wbuf *w, int x) {
  char *s = wb_room(w);
  if (x < 0) {
    *s++ = '-';
    ++w->len;
  }
  w->len += format_u64(x < 0 ? (uint64_t)0 - (uint64_t)(int64_t)x : (uint64_t)x, s);
}

static inline void wb_double(wbuf *w, double x) {
  char *s = wb_room(w);
  w->len += hoc_io_format_double(x, s);
}

/* Fields of the file's records: in ASCII, separated by one space within a
 * line and ended by f_eol; in binary, their bytes (int: 4, size: 8, real:
 * 8) with nothing between them. */
static inline void f_sep(wbuf *w) {
  if (!w->fresh) wb_char(w, ' ');
  w->fresh = 0;
}

static inline void f_int(wbuf *w, int x) {
  if (w->binary) {
    int32_t v = x;
    wb_bytes(w, &v, sizeof v);
    return;
  }
  f_sep(w);
  wb_int(w, x);
}

static inline void f_size(wbuf *w, uint64_t x) {
  if (w->binary) {
    wb_bytes(w, &x, sizeof x);
    return;
  }
  f_sep(w);
  wb_u64(w, x);
}

static inline void f_real(wbuf *w, double x) {
  if (w->binary) {
    wb_bytes(w, &x, sizeof x);
    return;
  }
  f_sep(w);
  wb_double(w, x);
}

static inline void f_eol(wbuf *w) {
  if (!w->binary) wb_char(w, '\n');
  w->fresh = 1;
}

/* A section's first line, text in either mode; binary records start after it. */
static void section_begin(wbuf *w, const char *name) {
  wb_char(w, '$');
  wb_str(w, name);
  wb_char(w, '\n');
  w->fresh = 1;
}

/* "$EndName" on a line of its own (after the binary records' last byte). */
static void section_end(wbuf *w, const char *name) {
  if (w->binary) wb_char(w, '\n');
  wb_str(w, "$End");
  wb_str(w, name);
  wb_char(w, '\n');
  w->fresh = 1;
}

/* A count on a text line of its own (MSH 2.2 writes its counts so in binary
 * files too). */
static void text_count(wbuf *w, uint64_t n) {
  wb_u64(w, n);
  wb_char(w, '\n');
  w->fresh = 1;
}

/* Entities ------------------------------------------------------------------ */

/* The entities of one dimension sorted by tag: tag[k] is the k-th smallest,
 * index[k] its position in the caller's arrays. */
typedef struct entity_list {
  int n;
  int *tag;   /* [n] */
  int *index; /* [n] */
} entity_list;

static void entity_list_free(entity_list *l) {
  free(l->tag);
  free(l->index);
  memset(l, 0, sizeof *l);
}

static hoc_status entity_list_build(entity_list *l, int n, const int *tags, const char *what) {
  memset(l, 0, sizeof *l);
  HOC_CHECK(n >= 0, HOC_ERR_ARGUMENT, "negative number of %ss (%d)", what, n);
  HOC_CHECK(n == 0 || tags, HOC_ERR_ARGUMENT, "%s tags missing", what);
  l->n = n;
  l->tag = hoc_calloc((size_t)n + 1, sizeof *l->tag);
  l->index = hoc_calloc((size_t)n + 1, sizeof *l->index);
  int *tmp = hoc_calloc((size_t)n + 1, sizeof *tmp);
  if (!l->tag || !l->index || !tmp) {
    free(tmp);
    entity_list_free(l);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory for %d %ss", n, what);
  }
  /* bottom-up merge sort of the positions by tag */
  for (int k = 0; k < n; ++k)
    l->index[k] = k;
  for (int w = 1; w < n; w *= 2) {
    for (int lo = 0; lo < n; lo += 2 * w) {
      int mid = lo + w < n ? lo + w : n, hi = lo + 2 * w < n ? lo + 2 * w : n;
      int a = lo, b = mid, o = lo;
      while (a < mid && b < hi)
        tmp[o++] = tags[l->index[b]] < tags[l->index[a]] ? l->index[b++] : l->index[a++];
      while (a < mid)
        tmp[o++] = l->index[a++];
      while (b < hi)
        tmp[o++] = l->index[b++];
    }
    memcpy(l->index, tmp, (size_t)n * sizeof *tmp);
  }
  free(tmp);
  for (int k = 0; k < n; ++k)
    l->tag[k] = tags[l->index[k]];
  for (int k = 1; k < n; ++k)
    if (l->tag[k] == l->tag[k - 1]) {
      int dup = l->tag[k];
      entity_list_free(l);
      return HOC_ERROR(HOC_ERR_ARGUMENT, "%s %d is listed twice", what, dup);
    }
  return HOC_OK;
}

/* Rank of `tag` in the sorted list, -1 if absent. */
static int entity_rank(const entity_list *l, int tag) {
  int lo = 0, hi = l->n;
  while (lo < hi) {
    int mid = lo + (hi - lo) / 2;
    if (l->tag[mid] < tag)
      lo = mid + 1;
    else
      hi = mid;
  }
  return lo < l->n && l->tag[lo] == tag ? lo : -1;
}

static int all_finite(const double *x, size_t n) {
  for (size_t k = 0; k < n; ++k)
    if (!isfinite(x[k])) return 0;
  return 1;
}

/* Checks of the bounding boxes and boundaries of one dimension's entities. */
static hoc_status check_entities(int n, const int *tags, const double *bbox, const int *bnd_start,
                                 const int *bnd, const char *what) {
  if (!n) return HOC_OK;
  HOC_CHECK(bbox && bnd_start, HOC_ERR_ARGUMENT, "%s bounding boxes or boundaries missing", what);
  HOC_CHECK(bnd_start[0] >= 0, HOC_ERR_ARGUMENT, "%s boundary offsets start below 0", what);
  for (int k = 0; k < n; ++k) {
    HOC_CHECK(all_finite(bbox + 6 * (size_t)k, 6), HOC_ERR_ARGUMENT,
              "%s %d has a non-finite bounding box: nothing written", what, tags[k]);
    HOC_CHECK(bnd_start[k + 1] >= bnd_start[k], HOC_ERR_ARGUMENT,
              "%s %d: boundary offsets decrease", what, tags[k]);
  }
  HOC_CHECK(bnd || bnd_start[n] == bnd_start[0], HOC_ERR_ARGUMENT, "%s boundaries missing", what);
  return HOC_OK;
}

/* Node and element layout of the file --------------------------------------- */

/* Where everything goes: blocks are numbered points (by tag), then curves,
 * then surfaces, as in the file. */
typedef struct layout {
  entity_list ent[3];   /* points, curves, surfaces sorted by tag */
  int n_blocks;         /* n_points + n_curves + n_surfaces */
  size_t *node_order;   /* [n_nodes] caller's node index at each file position */
  size_t *node_tag;     /* [n_nodes] file tag (1-based position) of each caller node */
  size_t *block_start;  /* [n_blocks+1] first file position of each node block */
  size_t *line_order;   /* [n_lines] caller's line at each file position */
  size_t *tri_order;    /* [n_tris] */
  size_t *lblock_start; /* [n_curves+1] */
  size_t *tblock_start; /* [n_surfaces+1] */
} layout;

static void layout_free(layout *L) {
  for (int k = 0; k < 3; ++k)
    entity_list_free(&L->ent[k]);
  free(L->node_order);
  free(L->node_tag);
  free(L->block_start);
  free(L->line_order);
  free(L->tri_order);
  free(L->lblock_start);
  free(L->tblock_start);
  memset(L, 0, sizeof *L);
}

/* Stable counting sort of n items into nb buckets: start[nb+1] (zeroed on
 * entry) receives the bucket offsets and order[n] the items bucket by bucket. */
static void bucket_sort(size_t n, const int *bucket, int nb, size_t *start, size_t *order) {
  for (size_t i = 0; i < n; ++i)
    ++start[bucket[i] + 1];
  for (int b = 0; b < nb; ++b)
    start[b + 1] += start[b];
  for (size_t i = 0; i < n; ++i)
    order[start[bucket[i]]++] = i;
  for (int b = nb; b > 0; --b)
    start[b] = start[b - 1];
  start[0] = 0;
}

static hoc_status layout_build(layout *L, const hoc_msh_write_data *d) {
  static const char *dim_name[3] = {"point", "curve", "surface"};
  const int counts[3] = {d->n_points, d->n_curves, d->n_surfaces};
  const int *tags[3] = {d->point_tag, d->curve_tag, d->surface_tag};
  for (int k = 0; k < 3; ++k)
    HOC_TRY(entity_list_build(&L->ent[k], counts[k], tags[k], dim_name[k]));
  L->n_blocks = counts[0] + counts[1] + counts[2];
  const int base[3] = {0, counts[0], counts[0] + counts[1]};
  const int np = (d->order + 1) * (d->order + 2) / 2, nl = d->order + 1;
  size_t nn = d->n_nodes;
  int *bucket = NULL;
  hoc_status status = HOC_OK;
  size_t nmax = nn > d->n_tris ? nn : d->n_tris;
  if (d->n_lines > nmax) nmax = d->n_lines;
  HOC_ALLOC_GOTO(bucket, nmax + 1, done);
  /* nodes: the block of each, checking positions and parameters */
  for (size_t i = 0; i < nn; ++i) {
    int dim = d->node_dim[i];
    if (dim < 0 || dim > 2) {
      status =
          HOC_ERROR(HOC_ERR_ARGUMENT, "node %zu has dimension %d (0, 1 or 2 expected)", i, dim);
      goto done;
    }
    int r = entity_rank(&L->ent[dim], d->node_entity_tag[i]);
    if (r < 0) {
      status =
          HOC_ERROR(HOC_ERR_ARGUMENT, "node %zu lies on %s %d, which is not in the entity list", i,
                    dim_name[dim], d->node_entity_tag[i]);
      goto done;
    }
    if (!all_finite(d->xyz + 3 * i, 3) ||
        (d->param && !all_finite(d->param + 2 * i, (size_t)dim))) {
      status = HOC_ERROR(HOC_ERR_ARGUMENT,
                         "node %zu has a non-finite coordinate or parameter: nothing written", i);
      goto done;
    }
    bucket[i] = base[dim] + r;
  }
  HOC_ALLOC_GOTO(L->node_order, nn + 1, done);
  HOC_ALLOC_GOTO(L->node_tag, nn + 1, done);
  HOC_ALLOC_GOTO(L->block_start, (size_t)L->n_blocks + 1, done);
  bucket_sort(nn, bucket, L->n_blocks, L->block_start, L->node_order);
  for (size_t k = 0; k < nn; ++k)
    L->node_tag[L->node_order[k]] = k + 1;
  /* lines: one block per curve */
  for (size_t e = 0; e < d->n_lines; ++e) {
    int r = entity_rank(&L->ent[1], d->line_curve_tag[e]);
    if (r < 0) {
      status =
          HOC_ERROR(HOC_ERR_ARGUMENT, "line %zu lies on curve %d, which is not in the entity list",
                    e, d->line_curve_tag[e]);
      goto done;
    }
    for (int k = 0; k < nl; ++k)
      if (d->line_nodes[e * (size_t)nl + (size_t)k] >= nn) {
        status = HOC_ERROR(HOC_ERR_ARGUMENT, "line %zu uses node %zu of %zu", e,
                           d->line_nodes[e * (size_t)nl + (size_t)k], nn);
        goto done;
      }
    bucket[e] = r;
  }
  HOC_ALLOC_GOTO(L->line_order, d->n_lines + 1, done);
  HOC_ALLOC_GOTO(L->lblock_start, (size_t)counts[1] + 1, done);
  bucket_sort(d->n_lines, bucket, counts[1], L->lblock_start, L->line_order);
  /* triangles: one block per surface */
  for (size_t e = 0; e < d->n_tris; ++e) {
    int r = entity_rank(&L->ent[2], d->tri_surface_tag[e]);
    if (r < 0) {
      status = HOC_ERROR(HOC_ERR_ARGUMENT,
                         "triangle %zu lies on surface %d, which is not in the entity list", e,
                         d->tri_surface_tag[e]);
      goto done;
    }
    for (int k = 0; k < np; ++k)
      if (d->tri_nodes[e * (size_t)np + (size_t)k] >= nn) {
        status = HOC_ERROR(HOC_ERR_ARGUMENT, "triangle %zu uses node %zu of %zu", e,
                           d->tri_nodes[e * (size_t)np + (size_t)k], nn);
        goto done;
      }
    bucket[e] = r;
  }
  HOC_ALLOC_GOTO(L->tri_order, d->n_tris + 1, done);
  HOC_ALLOC_GOTO(L->tblock_start, (size_t)counts[2] + 1, done);
  bucket_sort(d->n_tris, bucket, counts[2], L->tblock_start, L->tri_order);
done:
  free(bucket);
  return status;
}

/* MSH 4.1 ------------------------------------------------------------------------ */

static void write_bbox_and_boundary(wbuf *w, const double *bbox, const int *bnd_start,
                                    const int *bnd, int k) {
  for (int c = 0; c < 6; ++c)
    f_real(w, bbox[6 * (size_t)k + (size_t)c]);
  f_size(w, 0); /* no physical tags */
  f_size(w, (uint64_t)(bnd_start[k + 1] - bnd_start[k]));
  for (int j = bnd_start[k]; j < bnd_start[k + 1]; ++j)
    f_int(w, bnd[j]);
  f_eol(w);
}

static void write_entities41(wbuf *w, const hoc_msh_write_data *d, const layout *L) {
  section_begin(w, "Entities");
  f_size(w, (uint64_t)d->n_points);
  f_size(w, (uint64_t)d->n_curves);
  f_size(w, (uint64_t)d->n_surfaces);
  f_size(w, 0);
  f_eol(w);
  for (int r = 0; r < d->n_points; ++r) { /* tag x y z 0 */
    int k = L->ent[0].index[r];
    f_int(w, d->point_tag[k]);
    for (int c = 0; c < 3; ++c)
      f_real(w, d->point_xyz[3 * (size_t)k + (size_t)c]);
    f_size(w, 0);
    f_eol(w);
  }
  for (int r = 0; r < d->n_curves; ++r) {
    int k = L->ent[1].index[r];
    f_int(w, d->curve_tag[k]);
    write_bbox_and_boundary(w, d->curve_bbox, d->curve_bnd_start, d->curve_bnd, k);
  }
  for (int r = 0; r < d->n_surfaces; ++r) {
    int k = L->ent[2].index[r];
    f_int(w, d->surface_tag[k]);
    write_bbox_and_boundary(w, d->surface_bbox, d->surface_bnd_start, d->surface_bnd, k);
  }
  section_end(w, "Entities");
}

static void write_nodes41(wbuf *w, const hoc_msh_write_data *d, const layout *L) {
  size_t nn = d->n_nodes;
  int used = 0;
  for (int b = 0; b < L->n_blocks; ++b)
    used += L->block_start[b + 1] > L->block_start[b];
  section_begin(w, "Nodes");
  f_size(w, (uint64_t)used);
  f_size(w, nn);
  f_size(w, nn ? 1 : 0);
  f_size(w, nn);
  f_eol(w);
  int b = 0;
  for (int dim = 0; dim < 3; ++dim)
    for (int r = 0; r < L->ent[dim].n; ++r, ++b) {
      size_t first = L->block_start[b], last = L->block_start[b + 1];
      if (first == last) continue;
      /* dim tag parametric count, then the tags, then x y z [t | u v] */
      f_int(w, dim);
      f_int(w, L->ent[dim].tag[r]);
      f_int(w, d->param ? 1 : 0);
      f_size(w, last - first);
      f_eol(w);
      for (size_t k = first; k < last; ++k) {
        f_size(w, k + 1);
        f_eol(w);
      }
      for (size_t k = first; k < last; ++k) {
        size_t i = L->node_order[k];
        const double *x = d->xyz + 3 * i; /* [3] */
        f_real(w, x[0]);
        f_real(w, x[1]);
        f_real(w, x[2]);
        if (d->param)
          for (int c = 0; c < dim; ++c)
            f_real(w, d->param[2 * i + (size_t)c]);
        f_eol(w);
      }
    }
  section_end(w, "Nodes");
}

/* One element block per entity: lines on curves, triangles on surfaces. */
static void write_element_blocks41(wbuf *w, const layout *L, const entity_list *ents, int dim,
                                   int type, const size_t *start, const size_t *order,
                                   const size_t *nodes, int nper, size_t *next_tag) {
  for (int r = 0; r < ents->n; ++r) {
    if (start[r + 1] == start[r]) continue;
    f_int(w, dim);
    f_int(w, ents->tag[r]);
    f_int(w, type);
    f_size(w, start[r + 1] - start[r]);
    f_eol(w);
    for (size_t k = start[r]; k < start[r + 1]; ++k) {
      const size_t *en = nodes + order[k] * (size_t)nper; /* [nper] caller's node indices */
      f_size(w, (*next_tag)++);
      for (int j = 0; j < nper; ++j)
        f_size(w, L->node_tag[en[j]]);
      f_eol(w);
    }
  }
}

static void write_elements41(wbuf *w, const hoc_msh_write_data *d, const layout *L) {
  int p = d->order, np = (p + 1) * (p + 2) / 2;
  size_t ne = d->n_lines + d->n_tris;
  int used = 0;
  for (int r = 0; r < d->n_curves; ++r)
    used += L->lblock_start[r + 1] > L->lblock_start[r];
  for (int r = 0; r < d->n_surfaces; ++r)
    used += L->tblock_start[r + 1] > L->tblock_start[r];
  section_begin(w, "Elements");
  f_size(w, (uint64_t)used);
  f_size(w, ne);
  f_size(w, ne ? 1 : 0);
  f_size(w, ne);
  f_eol(w);
  size_t next_tag = 1;
  write_element_blocks41(w, L, &L->ent[1], 1, hoc_msh_line_type(p), L->lblock_start,
                         L->line_order, d->line_nodes, p + 1, &next_tag);
  write_element_blocks41(w, L, &L->ent[2], 2, hoc_msh_triangle_type(p), L->tblock_start,
                         L->tri_order, d->tri_nodes, np, &next_tag);
  section_end(w, "Elements");
}

/* MSH 2.2 ------------------------------------------------------------------------ */

/* "tag x y z" or, parametric, "tag x y z dim entity [t | u v]", in file order
 * (the nodes of each entity together, as in 4.1). */
static void write_nodes22(wbuf *w, const hoc_msh_write_data *d, const layout *L) {
  const char *name = d->param ? "ParametricNodes" : "Nodes";
  section_begin(w, name);
  text_count(w, d->n_nodes);
  int b = 0;
  for (int dim = 0; dim < 3; ++dim)
    for (int r = 0; r < L->ent[dim].n; ++r, ++b)
      for (size_t k = L->block_start[b]; k < L->block_start[b + 1]; ++k) {
        size_t i = L->node_order[k];
        f_int(w, (int)(k + 1));
        for (int c = 0; c < 3; ++c)
          f_real(w, d->xyz[3 * i + (size_t)c]);
        if (d->param) {
          f_int(w, dim);
          f_int(w, L->ent[dim].tag[r]);
          for (int c = 0; c < dim; ++c)
            f_real(w, d->param[2 * i + (size_t)c]);
        }
        f_eol(w);
      }
  section_end(w, name);
}

/* Elements of `count` per entity (start[n_entities + 1] offsets): ASCII
 * "tag type 2 0 entity nodes...", binary one header (type, count, 2) per
 * entity then "tag 0 entity nodes..." as ints. node(item, j) is the file
 * tag of the j-th node of the item-th element in file order. */
typedef struct elements22 {
  int type, nper;
  const entity_list *ents;
  const size_t *start;   /* [ents->n + 1] */
  const size_t *order;   /* [count] caller's element at each file position, or NULL */
  const size_t *nodes;   /* [][nper] caller's node indices, or NULL: the item is a node */
} elements22;

static void write_elements22_kind(wbuf *w, const layout *L, const elements22 *k,
                                  size_t *next_tag) {
  for (int r = 0; r < k->ents->n; ++r) {
    size_t first = k->start[r], last = k->start[r + 1];
    if (first == last) continue;
    if (w->binary) {
      f_int(w, k->type);
      f_int(w, (int)(last - first));
      f_int(w, 2);
    }
    for (size_t q = first; q < last; ++q) {
      f_int(w, (int)(*next_tag)++);
      if (!w->binary) {
        f_int(w, k->type);
        f_int(w, 2);
      }
      f_int(w, 0); /* physical: none */
      f_int(w, k->ents->tag[r]);
      if (k->nodes) {
        const size_t *en = k->nodes + k->order[q] * (size_t)k->nper; /* [nper] */
        for (int j = 0; j < k->nper; ++j)
          f_int(w, (int)L->node_tag[en[j]]);
      } else {
        f_int(w, (int)(q + 1)); /* point element on the node of file tag q + 1 */
      }
      f_eol(w);
    }
  }
}

static void write_elements22(wbuf *w, const hoc_msh_write_data *d, const layout *L) {
  int p = d->order, np = (p + 1) * (p + 2) / 2;
  size_t n_points = L->block_start[L->ent[0].n];
  section_begin(w, "Elements");
  text_count(w, n_points + d->n_lines + d->n_tris);
  size_t next_tag = 1;
  /* the nodes of the point entities are the first n_points in file order */
  elements22 points = {15, 1, &L->ent[0], L->block_start, NULL, NULL};
  elements22 lines = {hoc_msh_line_type(p), p + 1, &L->ent[1], L->lblock_start, L->line_order,
                      d->line_nodes};
  elements22 tris = {hoc_msh_triangle_type(p), np, &L->ent[2], L->tblock_start, L->tri_order,
                     d->tri_nodes};
  write_elements22_kind(w, L, &points, &next_tag);
  write_elements22_kind(w, L, &lines, &next_tag);
  write_elements22_kind(w, L, &tris, &next_tag);
  section_end(w, "Elements");
}

/* The file ------------------------------------------------------------------------ */

void hoc_msh_options_default(hoc_msh_options *options) {
  if (!options) return;
  memset(options, 0, sizeof *options);
  options->version = 41;
}

hoc_status hoc_msh_write(const char *path, const hoc_msh_write_data *data,
                         const hoc_msh_options *options) {
  HOC_CHECK(path && path[0], HOC_ERR_ARGUMENT, "no output file name given");
  HOC_CHECK(data, HOC_ERR_ARGUMENT, "no mesh given to write '%s'", path);
  hoc_msh_options o;
  hoc_msh_options_default(&o);
  if (options) o = *options;
  HOC_CHECK(o.version == 41 || o.version == 22, HOC_ERR_ARGUMENT,
            "MSH version %d: 41 (4.1) or 22 (2.2) expected", o.version);
  HOC_CHECK(o.binary == 0 || o.binary == 1, HOC_ERR_ARGUMENT, "binary flag %d: 0 or 1 expected",
            o.binary);
  HOC_CHECK(o.parametric == 0 || o.parametric == 1, HOC_ERR_ARGUMENT,
            "parametric flag %d: 0 or 1 expected", o.parametric);
  HOC_CHECK(!o.parametric || !data->n_nodes || data->param, HOC_ERR_ARGUMENT,
            "parametric coordinates asked for '%s' but not given", path);
  hoc_msh_write_data dd = *data;
  const hoc_msh_write_data *d = &dd;
  if (!o.parametric) dd.param = NULL;
  HOC_CHECK(d->order >= 1, HOC_ERR_ARGUMENT, "order %d: at least 1 expected", d->order);
  HOC_CHECK(d->order <= 10, HOC_ERR_UNSUPPORTED,
            "cannot write '%s': gmsh's MSH format has no triangle of order %d (at most 10)", path,
            d->order);
  HOC_CHECK(!d->n_nodes || (d->xyz && d->node_dim && d->node_entity_tag), HOC_ERR_ARGUMENT,
            "node arrays missing");
  HOC_CHECK(!d->n_tris || (d->tri_nodes && d->tri_surface_tag), HOC_ERR_ARGUMENT,
            "triangle arrays missing");
  HOC_CHECK(!d->n_lines || (d->line_nodes && d->line_curve_tag), HOC_ERR_ARGUMENT,
            "line arrays missing");
  HOC_CHECK(!d->n_points || d->point_xyz, HOC_ERR_ARGUMENT, "point coordinates missing");
  for (int k = 0; k < d->n_points; ++k)
    HOC_CHECK(all_finite(d->point_xyz + 3 * (size_t)k, 3), HOC_ERR_ARGUMENT,
              "point %d has a non-finite coordinate: nothing written",
              d->point_tag ? d->point_tag[k] : k);
  HOC_TRY(check_entities(d->n_curves, d->curve_tag, d->curve_bbox, d->curve_bnd_start, d->curve_bnd,
                         "curve"));
  HOC_TRY(check_entities(d->n_surfaces, d->surface_tag, d->surface_bbox, d->surface_bnd_start,
                         d->surface_bnd, "surface"));
  layout L = {0};
  hoc_outfile out = {0};
  wbuf w = {0};
  hoc_status status = HOC_OK;
  /* 2.2 tags are int: every node, and every element (points included) */
  HOC_CHECK(o.version != 22 || d->n_nodes <= (size_t)INT32_MAX, HOC_ERR_UNSUPPORTED,
            "cannot write '%s' as MSH 2.2: %zu nodes, its int tags stop at %d (write MSH 4.1)",
            path, d->n_nodes, INT32_MAX);
  HOC_TRY_GOTO(layout_build(&L, d), done);
  size_t n_elems22 = L.block_start[L.ent[0].n] + d->n_lines + d->n_tris;
  if (o.version == 22 && n_elems22 > (size_t)INT32_MAX) {
    status = HOC_ERROR(HOC_ERR_UNSUPPORTED,
                       "cannot write '%s' as MSH 2.2: %zu elements, its int tags stop at %d "
                       "(write MSH 4.1)",
                       path, n_elems22, INT32_MAX);
    goto done;
  }
  HOC_ALLOC_GOTO(w.buf, WBUF_SIZE, done);
  HOC_TRY_GOTO(hoc_outfile_open(&out, path), done);
  w.fp = out.fp;
  wb_str(&w, o.version == 22 ? "$MeshFormat\n2.2 " : "$MeshFormat\n4.1 ");
  wb_str(&w, o.binary ? "1 8\n" : "0 8\n");
  if (o.binary) {
    const int32_t one = 1; /* tells the reader the byte order */
    wb_bytes(&w, &one, sizeof one);
    wb_char(&w, '\n');
  }
  wb_str(&w, "$EndMeshFormat\n");
  w.binary = o.binary;
  w.fresh = 1;
  if (o.version == 22) {
    write_nodes22(&w, d, &L);
    write_elements22(&w, d, &L);
  } else {
    write_entities41(&w, d, &L);
    write_nodes41(&w, d, &L);
    write_elements41(&w, d, &L);
  }
  wb_flush(&w);
  if (w.err) {
    status = HOC_ERROR(HOC_ERR_IO, "cannot write '%s': %s", path, strerror(w.err));
    goto done;
  }
  status = hoc_outfile_commit(&out);
done:
  hoc_outfile_abort(&out);
  free(w.buf);
  layout_free(&L);
  return status;
}
