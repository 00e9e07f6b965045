/* File formats: gmsh MSH 4.1 (write, read), VTK .vtu (write), and atomic
 * output files. This module knows nothing of CAD: it moves arrays.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef HOC_IO_H
#define HOC_IO_H

#include "core/error.h"

#include <stdio.h>

/* Atomic output ----------------------------------------------------------- */

/** An output file written under a temporary name in the target's directory
 *  and renamed over the target only by hoc_outfile_commit. */
typedef struct hoc_outfile {
  FILE *fp;       /* write here */
  char *path;     /* final name */
  char *tmp_path; /* temporary name */
} hoc_outfile;

/** Create the temporary file. Fails with HOC_ERR_IO (message names the
 *  path and the reason) if the directory is not writable. */
hoc_status hoc_outfile_open(hoc_outfile *out, const char *path);
/** Flush, sync, close and rename onto the final name; on any failure the
 *  temporary file is removed and the target is left as it was. */
hoc_status hoc_outfile_commit(hoc_outfile *out);
/** Close and remove the temporary file (safe to call after a commit or on a
 *  zeroed struct). */
void hoc_outfile_abort(hoc_outfile *out);

/** Remove every temporary file still open (for a signal handler: only
 *  async-signal-safe calls). */
void hoc_outfile_abort_all_from_signal(void);

/* gmsh MSH 4.1 ------------------------------------------------------------ */

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
  const double *param;        /* [n_nodes][2]: u,v on a surface, t (first) on a curve */
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

/** Write an ASCII MSH 4.1 file with parametric nodes (atomically). Node
 *  tags are 1..n_nodes in output order; nodes are grouped in one block per
 *  entity, blocks sorted by (dim, tag). Numbers are written with 17
 *  significant digits. */
hoc_status hoc_msh_write(const char *path, const hoc_msh_write_data *data);

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
  int order;                  /* order of the triangles */
  size_t n_tris;
  size_t *tri_nodes;          /* [n_tris][np] 0-based indices into the node arrays */
  int *tri_surface_tag;       /* [n_tris] */
  size_t n_lines;
  size_t *line_nodes;         /* [n_lines][order+1] */
  int *line_curve_tag;        /* [n_lines] */
} hoc_msh_raw;

/** Read a MSH 4.1 (ASCII or binary) or MSH 2.2 (ASCII) file. Keeps the
 *  triangles (all of one order, else HOC_ERR_UNSUPPORTED) and the lines of
 *  the same order; ignores other elements and nodes no kept element uses.
 *  Malformed input fails with HOC_ERR_FORMAT and a message naming the line
 *  or section; never reads out of bounds. */
hoc_status hoc_msh_read(const char *path, hoc_msh_raw *raw);
/** Same from memory (for the fuzz target); `name` is used in messages. */
hoc_status hoc_msh_read_buffer(const char *data, size_t size, const char *name,
                               hoc_msh_raw *raw);
void hoc_msh_raw_free(hoc_msh_raw *raw);

/** gmsh element type of the triangle / line of order p (1..10), or 0. */
int hoc_msh_triangle_type(int p);
int hoc_msh_line_type(int p);

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
 *  cell data present. Atomic. */
hoc_status hoc_vtu_write(const char *path, const hoc_vtu_data *data);

#endif
