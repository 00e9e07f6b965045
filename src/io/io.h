/* File formats: gmsh MSH 4.1 and 2.2 (write, read), VTK .vtu (write), and atomic
 * output files. This module knows nothing of CAD: it moves arrays.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef HOC_IO_H
#define HOC_IO_H

#include "core/error.h"

#include <stdint.h>
#include <stdio.h>

/* Atomic output ----------------------------------------------------------- */

/** An output file written under a temporary name in the target's directory
 *  and renamed over the target only by hoc_outfile_commit. */
typedef struct hoc_outfile {
  FILE *fp;       /* write here */
  char *path;     /* final name */
  char *tmp_path; /* temporary name */
} hoc_outfile;

/** Create the temporary file ".NAME.tmp-XXXXXX" beside `path`. Fails with
 *  HOC_ERR_IO (message names the path and the reason) if the directory is
 *  missing or not writable, or `path` is a directory or not a regular file.
 *  A symbolic link is followed: the file it points to is replaced and the
 *  link kept. The new file gets the permissions of the file it replaces, or
 *  0666 less the umask.
 *  @param[out] out  zeroed, then filled; on failure left zeroed */
hoc_status hoc_outfile_open(hoc_outfile *out, const char *path);
/** Check for write errors, flush, fsync, close and rename onto the final
 *  name; on any failure the temporary file is removed and the target is
 *  left as it was. `out` is zeroed either way. */
hoc_status hoc_outfile_commit(hoc_outfile *out);
/** Close and remove the temporary file (safe to call after a commit or on a
 *  zeroed struct). */
void hoc_outfile_abort(hoc_outfile *out);

/** Remove every temporary file still open (for a signal handler: only
 *  async-signal-safe calls; up to 32 files open at once are tracked). */
void hoc_outfile_abort_all_from_signal(void);

/* gmsh MSH 4.1 and 2.2 ---------------------------------------------------- */

/** What hoc_msh_write writes. Arrays are borrowed. */
typedef struct hoc_msh_write_data {
  /* $Entities: the model's entities with their kernel tags */
  int n_points;
  const int *point_tag;       /* [n_points] */
  const double *point_xyz;    /* [n_points][3] */
  int n_curves;
  const int *curve_tag;       /* [n_curves] */
  const double *curve_bbox;   /* [n_curves][6] xmin ymin zmin xmax ymax zmax */
  const int *curve_bnd_start; /* [n_curves+1] offsets into curve_bnd */
  const int *curve_bnd;       /* signed point tags bounding each curve */
  int n_surfaces;
  const int *surface_tag;
  const double *surface_bbox;
  const int *surface_bnd_start;
  const int *surface_bnd;     /* signed curve tags bounding each surface */
  /* $Nodes: every node on an entity listed above */
  size_t n_nodes;
  const double *xyz;          /* [n_nodes][3] */
  const double *param;        /* [n_nodes][2]: u,v on a surface, t (first) on a curve;
                                 may be NULL if options->parametric is 0 */
  const int *node_dim;        /* [n_nodes] 0, 1, 2 */
  const int *node_entity_tag; /* [n_nodes] kernel tag of the node's entity */
  /* $Elements: triangles of order p on surfaces, lines of order p on curves */
  int order;                  /* 1..10 */
  size_t n_tris;
  const size_t *tri_nodes;    /* [n_tris][np] 0-based node indices, gmsh ordering */
  const int *tri_surface_tag; /* [n_tris] */
  size_t n_lines;
  const size_t *line_nodes;   /* [n_lines][p+1] gmsh line ordering: end0, end1, interior */
  const int *line_curve_tag;  /* [n_lines] */
} hoc_msh_write_data;

/** Write an MSH file (atomically) as `options` say (NULL: MSH 4.1 ASCII
 *  without parameters). Node tags are 1..n_nodes in output order; nodes are
 *  grouped in one block per entity, blocks sorted by (dim, tag), in the
 *  caller's order inside a block; elements likewise (lines, then
 *  triangles), tags 1..n. ASCII numbers are written as printf "%.17g"
 *  writes them, binary ones as they are, so they read back bit for bit.
 *  MSH 4.1: $Entities (no physical tags), node blocks parametric only if
 *  options->parametric. MSH 2.2: no $Entities; $Nodes, or $ParametricNodes
 *  ("tag x y z dim entity [t | u v]") if options->parametric; elements
 *  "tag type 2 0 entity nodes..." (physical 0, elementary the entity), a
 *  point element (type 15) on each node of a point entity first, then the
 *  lines and triangles; binary 2.2 elements in one block (type, count, 2)
 *  per entity.
 *  Everything is checked before the file is created: HOC_ERR_ARGUMENT for an
 *  option out of range, parameters asked for without `param`, a non-finite
 *  coordinate, parameter or bounding box, a node or element on an entity not
 *  listed, a node index out of range, a tag listed twice;
 *  HOC_ERR_UNSUPPORTED for an order above 10, or a 2.2 file whose node or
 *  element tags would not fit an int. */
hoc_status hoc_msh_write(const char *path, const hoc_msh_write_data *data,
                         const hoc_msh_options *options);

/** A mesh as read from an MSH file: surface triangles and curve lines, the
 *  nodes they use, and each node's classification. */
typedef struct hoc_msh_raw {
  size_t n_nodes;
  size_t *node_tag;           /* [n_nodes] tag in the file */
  double *xyz;                /* [n_nodes][3] */
  int *node_dim;              /* [n_nodes] dimension of the node's entity, -1 if unknown */
  int *node_entity_tag;       /* [n_nodes] */
  double *param;              /* [n_nodes][2] parametric coordinates if present */
  unsigned char *has_param;   /* [n_nodes] 1 if param holds file values */
  int order;                  /* order of the triangles, 0 if there are none */
  size_t n_tris;
  size_t *tri_nodes;          /* [n_tris][np] 0-based indices into the node arrays */
  int *tri_surface_tag;       /* [n_tris] */
  size_t n_lines;
  size_t *line_nodes;         /* [n_lines][order+1] */
  int *line_curve_tag;        /* [n_lines] */
} hoc_msh_raw;

/** Read a MSH 4.1 or MSH 2.x file (ASCII or binary, either byte order;
 *  binary 2.x: its int tags, as gmsh writes them). Keeps the complete
 *  triangles (all of one order, else
 *  HOC_ERR_UNSUPPORTED; incomplete ones are HOC_ERR_UNSUPPORTED too) and
 *  the lines of the same order; skips every other element and section, and
 *  drops the nodes no kept element uses. Nodes keep their file order.
 *  Classification: in 4.1 from the node's entity block (parameters if the
 *  block is parametric); in 2.x from $ParametricNodes if present, else the
 *  lowest (dim, entity) of the kept elements and point elements using the
 *  node. A file without triangles reads as an empty mesh (order 0).
 *  Malformed input (truncated, inconsistent counts, unknown node tags,
 *  non-finite numbers, counts larger than the file could hold...) fails
 *  with HOC_ERR_FORMAT and one line naming the line (or byte) and section;
 *  a missing or unreadable file with HOC_ERR_IO. Never reads out of bounds;
 *  memory stays proportional to the file size.
 *  @param[out] raw  zeroed, then filled; free with hoc_msh_raw_free */
hoc_status hoc_msh_read(const char *path, hoc_msh_raw *raw);
/** Same from memory (for the fuzz target); `name` is used in messages. */
hoc_status hoc_msh_read_buffer(const char *data, size_t size, const char *name,
                               hoc_msh_raw *raw);
/** Free every array and zero the struct (NULL or zeroed: no-op). */
void hoc_msh_raw_free(hoc_msh_raw *raw);

/** gmsh element type of the triangle / line of order p (1..10), or 0. */
int hoc_msh_triangle_type(int p);
int hoc_msh_line_type(int p);

/* Helpers shared by the MSH writer and reader (not part of the public API;
 * exported for the tests). ------------------------------------------------- */

/** Number of nodes of a gmsh element type (as gmsh 4.8 reports it), or 0
 *  for an unknown type or one of variable size (polygons). */
int hoc_msh_element_nodes(int type);

/** Order p of a complete triangle type (2, 9, 21, ...), 0 if `type` is not
 *  one; -p for an incomplete (serendipity) triangle of order p. */
int hoc_msh_triangle_order(int type);
/** Order p of a line type (1, 8, 26, ...), 0 if `type` is not one. */
int hoc_msh_line_order(int type);

/** 10^q as a truncated 128-bit mantissa: 10^q ~= (hi 2^64 + lo) 2^b with the
 *  top bit of hi set and (hi 2^64 + lo) 2^b <= 10^q < (hi 2^64 + lo + 1) 2^b.
 *  Returns 0 if q is outside [-350, 350]. Thread-safe (table built once). */
int hoc_io_pow10(int q, uint64_t *hi, uint64_t *lo, int *b);

/** Write v exactly as printf("%.17g", v) does (same characters), with a
 *  NUL; returns the length (at most 24). `out` holds at least 32 chars. */
size_t hoc_io_format_double(double v, char *out);

/** Parse the decimal number s[0..n) (no NUL needed) to the same double as
 *  strtod (correctly rounded; hexadecimal floats are refused). Returns 1 if
 *  the whole of s[0..n) is one number, 0 otherwise. "inf" and "nan" are
 *  returned as parsed: callers check finiteness. */
int hoc_io_parse_double(const char *s, size_t n, double *v);

/* VTK XML unstructured grid ---------------------------------------------- */

typedef struct hoc_vtu_data {
  int order;                   /* 1..HOC_MAX_ORDER */
  size_t n_points;
  const double *xyz;           /* [n_points][3] */
  size_t n_cells;
  const size_t *cells;         /* [n_cells][np] 0-based point indices, gmsh ordering */
  const double *quality;       /* [n_cells] or NULL */
  const unsigned char *tangled;/* [n_cells] or NULL */
  const int *face_tag;         /* [n_cells] or NULL */
} hoc_vtu_data;

/** Write VTK Lagrange triangles (cell type 69; type 5 for order 1) with the
 *  cell data present ("quality" Float64, "tangled" UInt8, "face" Int32), as
 *  an XML UnstructuredGrid (version 1.0, UInt64 headers, raw appended
 *  binary data in the host's byte order). VTK's point order in a Lagrange
 *  triangle is gmsh's, so cells are written as given (evidence in
 *  vtu_write.c). Atomic; HOC_ERR_ARGUMENT (nothing created) for an order
 *  outside 1..HOC_MAX_ORDER, a non-finite coordinate or a point index out of
 *  range. */
hoc_status hoc_vtu_write(const char *path, const hoc_vtu_data *data);

#endif
