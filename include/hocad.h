/* hocad: valid high-order triangle surface meshes on CAD models.
 *
 * Copyright (C) 2026 the hocad developers.
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * The method is the one of "the paper": A. Gargallo-Peiro, X. Roca,
 * J. Peraire, J. Sarrate, High-order mesh generation on CAD geometries
 * (definitions, tables and sections named below are that paper's).
 *
 * The public interface. Every function that can fail returns a hoc_status;
 * on failure a one-line message is available from hoc_last_error() (it is
 * per thread and valid until the next failing call on that thread). The
 * library never prints, never exits and never aborts.
 *
 * Objects are opaque handles with explicit create/destroy. Destroy functions
 * accept NULL and clear the caller's pointer. A hoc_mesh borrows its
 * hoc_model: destroy every mesh before its model.
 *
 * The CAD kernel (gmsh) has one global model: only one hoc_model opened from
 * a file may exist at a time.
 */
#ifndef HOC_HOCAD_H
#define HOC_HOCAD_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define HOC_VERSION_MAJOR 0
#define HOC_VERSION_MINOR 1
#define HOC_VERSION_PATCH 0

/** Highest element order the library builds and measures. */
#define HOC_MAX_ORDER 15

typedef enum hoc_status {
  HOC_OK = 0,
  HOC_ERR_ARGUMENT = 1,    /**< an argument is out of range, NaN, or NULL */
  HOC_ERR_IO = 2,          /**< a file cannot be opened, read or written */
  HOC_ERR_FORMAT = 3,      /**< a file's content is malformed or not the expected format */
  HOC_ERR_CAD = 4,         /**< the CAD kernel failed, or the model is unusable (e.g. no faces) */
  HOC_ERR_MESH = 5,        /**< linear meshing failed */
  HOC_ERR_MISMATCH = 6,    /**< a mesh does not match the model */
  HOC_ERR_MEMORY = 7,      /**< out of memory */
  HOC_ERR_INTERRUPTED = 8, /**< cancelled through the progress callback */
  HOC_ERR_UNSUPPORTED = 9, /**< a valid request the library cannot do (e.g. MSH order > 10) */
  HOC_ERR_INTERNAL = 10    /**< a bug: please report it */
} hoc_status;

/** Message of the last failure on the calling thread ("" if none). */
const char *hoc_last_error(void);

/** Short name of a status ("ok", "invalid argument", ...). */
const char *hoc_status_string(hoc_status status);

/** Library version, "MAJOR.MINOR.PATCH". */
const char *hoc_version(void);

/** Reference node distribution inside each element. */
typedef enum hoc_nodeset {
  HOC_NODES_EQUISPACED = 0, /**< equispaced lattice, gmsh's and VTK's own */
  HOC_NODES_FEKETE = 1,     /**< Fekete points (maximal Vandermonde determinant) */
  HOC_NODES_WARP_BLEND = 2  /**< Warburton's warp & blend points */
} hoc_nodeset;

/** Jacobian-based distortion measure eta of the paper's Table 1 (d = 2). */
typedef enum hoc_measure {
  HOC_MEASURE_SHAPE = 0, /**< eta = |S|^2 / (2 sigma) */
  HOC_MEASURE_ODDY = 1   /**< eta = (3/2) sigma^-2 (|S^T S|^2 - |S|^4 / 3) */
} hoc_measure;

/** Progress report: stage name and fraction in [0, 1]. Return nonzero to
 *  cancel the running operation, which then fails with HOC_ERR_INTERRUPTED
 *  and leaves no partial output behind. */
typedef int (*hoc_progress_fn)(void *user, const char *stage, double fraction);

/* ------------------------------------------------------------------------ */
/* CAD models                                                               */

typedef struct hoc_model hoc_model;

/** Open a CAD model (STEP .step/.stp, IGES .igs/.iges, OpenCASCADE .brep).
 *  @param[in]  path   file name; the format is chosen by its extension
 *  @param[out] model  new model on success, NULL on failure
 *  Fails with HOC_ERR_IO if the file cannot be read, HOC_ERR_FORMAT if the
 *  kernel cannot read it (also when its importer crashes: the import runs
 *  first in a child process, docs/kernel.md), HOC_ERR_CAD if it holds no
 *  usable face. */
hoc_status hoc_model_open(const char *path, hoc_model **model);

/** Destroy a model (NULL allowed); clears *model. */
void hoc_model_destroy(hoc_model **model);

/** Number of CAD faces, curves and vertices. */
int hoc_model_num_faces(const hoc_model *model);
int hoc_model_num_curves(const hoc_model *model);
int hoc_model_num_vertices(const hoc_model *model);

/** Axis-aligned bounding box [xmin, ymin, zmin, xmax, ymax, zmax] of the
 *  faces, their curves and vertices, and the volumes (the kernel's boxes,
 *  widened by tolerances): vertices and curves that bound no face do not
 *  count. Its diagonal is the model's length scale (default sizes,
 *  tolerances). */
void hoc_model_bbox(const hoc_model *model, double bbox[6]);

/** The model's own tolerance, measured: the largest distance between a
 *  curve and a face it bounds (the curve against the kernel's curve on
 *  that face, at 33 points of each curve) or between a vertex and its
 *  curves and faces. STEP and IGES models agree only to such a tolerance.
 *  A mesh read from a file must lie on the model within 4 times it (at
 *  least 1e-6 of the bounding-box diagonal): see hoc_mesh_read_msh.
 *  Measured on the first call (at most 0.05 s on large models), then kept;
 *  not thread-safe on the first call.
 *  @param[out] tolerance  a length in the model's units */
hoc_status hoc_model_tolerance(hoc_model *model, double *tolerance);

/* ------------------------------------------------------------------------ */
/* Meshes                                                                   */

typedef struct hoc_mesh hoc_mesh;

/** Options of the linear surface mesher. Zero means "choose". */
typedef struct hoc_linear_options {
  double size_max;  /**< maximum edge length (0: bounding-box diagonal / 20) */
  double size_min;  /**< minimum edge length (0: size_max / 10) */
  double curvature; /**< elements per 2 pi of curvature radius (0: 12 for order 1, 8 above) */
  int order;        /**< order the mesh will be raised to, used for the default curvature */
  const double *face_size; /**< NULL, or [faces] (index order) an upper bound on the edge
                                length on each face and its boundary curves (0: none) */
  hoc_progress_fn progress;
  void *progress_user;
  double mesher_timeout; /**< seconds gmsh's mesher may take (0: 300; < 0: no limit): if the
                              whole mesh takes longer, each face is meshed alone within it
                              and the faces that do not finish count as failed (the mesh's
                              failed faces), as faces that crash gmsh do */
  int grading; /**< 1 (default): a second meshing graded down to short curves and thin
                    faces where gmsh's has them (within 4 x the first's time + 10 s),
                    and edges swapped where that raises the
                    smaller q of their triangles (hoc_mesh_generate_linear); 0: gmsh's mesh */
  int keep_pinches; /**< 0 (default): the mesh is cut along its faces' pinches (lines of a
                         face's (u, v) that the CAD maps to one point: no triangle across
                         one, its point a node); 1: left as meshed (comparisons) */
} hoc_linear_options;

/** Fill options with defaults (all "choose", order 1, no progress, grading). */
void hoc_linear_options_default(hoc_linear_options *options);

/** The edge lengths the linear mesher uses for these options on this model:
 *  size_max, or the bounding-box diagonal / 20 if 0; size_min, or a tenth
 *  of that if 0 (options NULL: both 0). */
void hoc_linear_sizes(const hoc_model *model, const hoc_linear_options *options, double *size_max,
                      double *size_min);

/** Mesh every face of the model with linear triangles. gmsh's mesher runs
 *  in a child process (docs/kernel.md). Where CAD curves are shorter than
 *  a tenth of the edges at their ends, or faces narrower than a tenth of
 *  their edges, gmsh meshes the model a second time with sizes graded down
 *  to them, and that mesh is kept if it is better (docs/cli.md, `hocad
 *  mesh` rule 10); then edges are swapped where that raises the smaller q
 *  of their two triangles, straight and curved, or removes a triangle
 *  with its corners on one curve (rule 11). A face under the default
 *  minimum size that gmsh leaves empty has the mesh made again with the
 *  minimum lowered for it (rule 12). The mesh is cut along lines of a
 *  face's (u, v) that map to one point (rule 13; unless
 *  options->keep_pinches). Faces the kernel cannot mesh, or
 *  on which its mesher crashes, are skipped and counted in
 *  hoc_mesh_num_failed_faces(); HOC_ERR_MESH if it crashes on the curves
 *  or on every face, HOC_ERR_INTERRUPTED if the child is interrupted
 *  (SIGINT, SIGTERM). The model remembers the faces that crash the mesher
 *  or do not finish within the limit, and later meshings of it leave them
 *  out at once (a face that did not finish: while the limit is no longer);
 *  open the model again to try them afresh.
 *  @param[in]  model    the CAD model; it must outlive the mesh
 *  @param[in]  options  NULL for defaults
 *  @param[out] mesh     new order-1 mesh */
hoc_status hoc_mesh_generate_linear(hoc_model *model, const hoc_linear_options *options,
                                    hoc_mesh **mesh);

/** Raise (or lower) a mesh to order p (1..HOC_MAX_ORDER): the new nodes of
 *  each element are placed in the face's parametric space by evaluating the
 *  element's parametric map at the reference nodes of the requested
 *  distribution, and mapped onto the surface; nodes on CAD curves are placed
 *  in the curve's parameter. From a linear mesh this is the paper's step 2
 *  (elements straight in (u,v), curve edges following the curves), with
 *  one exception: at a cusp corner (a CAD vertex where the element's two
 *  edges follow curves whose angle is under half the straight element's
 *  angle there), both edges' nodes sit at sqrt(s) of the way from the
 *  vertex instead of s, and the interior nodes are graded alike, so that
 *  the curved element opens at that corner (see hoc_cusp).
 *  @param[in]  mesh     any mesh on the model
 *  @param[in]  order    target order p
 *  @param[in]  nodeset  reference node distribution
 *  @param[out] out      new mesh of order p */
hoc_status hoc_mesh_elevate(const hoc_mesh *mesh, int order, hoc_nodeset nodeset,
                            hoc_mesh **out);

/** The same elements with the nodes of another reference distribution
 *  (e.g. Fekete to equispaced, what MSH and VTU files mean): each element's
 *  parametric map evaluated at the new reference nodes, mapped onto the CAD.
 *  @param[out] out  new mesh of the same order */
hoc_status hoc_mesh_convert(const hoc_mesh *mesh, hoc_nodeset nodeset, hoc_mesh **out);

/** An exact copy of a mesh (same nodes, parameters and elements, bit for
 *  bit), on the same model.
 *  @param[out] out  the copy (destroy it with hoc_mesh_destroy) */
hoc_status hoc_mesh_copy(const hoc_mesh *mesh, hoc_mesh **out);

/** Read a gmsh MSH mesh of the model's surfaces: MSH 4.1 (ASCII or
 *  binary) or MSH 2.2 (ASCII or binary), e.g. one written by gmsh or by
 *  hoc_mesh_write_msh. Triangles of any order up to 10 are read; other
 *  elements are ignored. Nodes keep the positions the file gives. Nodes
 *  with parametric coordinates in the file keep them; the others are
 *  located on their CAD entity, by Newton's method from a located
 *  neighbour in the same element (a projection only where no neighbour
 *  leads to the node), a few microseconds per node. The
 *  entity of a node is the file's (4.1 node blocks, 2.2 $ParametricNodes),
 *  else, in a 2.2 file, that of the lowest-dimensional element using it
 *  (point, then line, then triangle; ties to the lowest tag).
 *  @param[in]  model  the model the mesh was made on
 *  @param[in]  path   .msh file
 *  @param[out] mesh   new mesh (equispaced node set)
 *  Fails with HOC_ERR_MISMATCH if the mesh does not lie on the model: a
 *  node on a CAD vertex or curve, or a triangle's corner, farther from its
 *  entity than 4 times the model's tolerance (hoc_model_tolerance; at
 *  least 1e-6 of the bounding-box diagonal), a vertex or curve node
 *  farther than twice that from a face it bounds, or a high-order node
 *  inside a face farther than 1% of the diagonal (such nodes are kept
 *  where the file puts them: gmsh leaves them off the surface where its
 *  projection fails). The message gives the distance, the limit and the
 *  model's tolerance. */
hoc_status hoc_mesh_read_msh(hoc_model *model, const char *path, hoc_mesh **mesh);

/** How a .msh file is written. */
typedef struct hoc_msh_options {
  int version;    /**< 41: MSH 4.1 (default), with $Entities; 22: MSH 2.2, the version
                       solvers that predate 4.1 read, whose elements carry physical tag 0
                       (no physical groups, as in 4.1) and elementary tag the CAD entity,
                       with a point element on each node at a CAD vertex so that every
                       node's entity follows from the elements */
  int binary;     /**< 0: ASCII (default); 1: binary, in the host's byte order */
  int parametric; /**< 0 (default): node positions only, which every reader opens;
                       1: also each node's parametric coordinates on its entity (t on a
                       curve, (u, v) on a face), as gmsh's Mesh.SaveParametric writes
                       them (4.1: parametric node blocks; 2.2: $ParametricNodes). Many
                       readers refuse such files (meshio: "parametric nodes not
                       implemented"); hoc_mesh_read_msh reads both */
} hoc_msh_options;

/** Fill options with the defaults: MSH 4.1, ASCII, no parametric coordinates. */
void hoc_msh_options_default(hoc_msh_options *options);

/** Write a gmsh .msh file of the mesh: high-order triangles (gmsh node
 *  ordering, equispaced nodes) on the CAD faces and lines of the same order
 *  on the CAD curves, every node classified on its CAD entity. Node tags
 *  are 1..n, grouped by entity; element tags 1..n. Coordinates are written
 *  so that they read back bit for bit (ASCII: 17 significant digits). The
 *  file is written to a temporary name and renamed on success.
 *  @param[in] mesh     the mesh (any node set: converted to equispaced)
 *  @param[in] path     output file
 *  @param[in] options  NULL for the defaults (hoc_msh_options_default)
 *  Fails with HOC_ERR_ARGUMENT for an option out of range, HOC_ERR_UNSUPPORTED
 *  for an order above 10 (MSH has no such triangle: write a .vtu) or a 2.2
 *  file of 2^31 nodes or elements or more (2.2 tags are int). */
hoc_status hoc_mesh_write_msh_with(const hoc_mesh *mesh, const char *path,
                                   const hoc_msh_options *options);

/** hoc_mesh_write_msh_with with the default options (MSH 4.1 ASCII, no
 *  parametric coordinates). */
hoc_status hoc_mesh_write_msh(const hoc_mesh *mesh, const char *path);

/** Write a VTK XML unstructured grid (.vtu) of Lagrange triangles with cell
 *  data "quality" (q, 0 if tangled), "tangled" (0/1) and "face" (CAD tag).
 *  @param[in] quality  per-element q, or NULL to compute it with the shape measure */
hoc_status hoc_mesh_write_vtu(const hoc_mesh *mesh, const double *quality, const char *path);

/** Destroy a mesh (NULL allowed); clears *mesh. */
void hoc_mesh_destroy(hoc_mesh **mesh);

size_t hoc_mesh_num_elements(const hoc_mesh *mesh);
size_t hoc_mesh_num_nodes(const hoc_mesh *mesh);
int hoc_mesh_order(const hoc_mesh *mesh);
hoc_nodeset hoc_mesh_nodeset(const hoc_mesh *mesh);
/** Number of faces the linear mesher could not mesh, and the CAD tag of the
 *  i-th of them (-1 if out of range). */
int hoc_mesh_num_failed_faces(const hoc_mesh *mesh);
int hoc_mesh_failed_face_tag(const hoc_mesh *mesh, int i);
/** Largest distance from a node to its CAD entity, recomputed from the
 *  nodes' parametric coordinates (a self-check of the mesh). Zero for
 *  meshes hocad makes; a mesh read from a file keeps its nodes where the
 *  file puts them (measured as written), which may be off the surface
 *  (gmsh leaves nodes off where its projection fails); hoc_mesh_optimize
 *  puts every node back on the CAD first. */
hoc_status hoc_mesh_max_cad_distance(const hoc_mesh *mesh, double *distance);
/** Largest distance between a node on a CAD curve or vertex and the point
 *  of a face around it where the node sits on that face: the model's
 *  curves lie off their faces within its tolerance (hoc_model_tolerance),
 *  and the mesh records how far, without refusing it. 0 for NULL. */
double hoc_mesh_face_gap(const hoc_mesh *mesh);

/* Arrays of a mesh, copied into the caller's arrays (what bindings turn into
 * arrays of their own). Nodes are numbered 0..hoc_mesh_num_nodes-1 and
 * elements 0..hoc_mesh_num_elements-1, in the order of every other per-node
 * and per-element array of this interface (hoc_mesh_measure, ...); a .msh
 * file hoc_mesh_write_msh writes numbers them differently (its node tags
 * are grouped by entity). */

/** Node positions.
 *  @param[out] xyz  [hoc_mesh_num_nodes][3] x, y, z of each node */
hoc_status hoc_mesh_nodes(const hoc_mesh *mesh, double *xyz);

/** Where each node lies on the CAD. Any output may be NULL.
 *  @param[out] dim    [hoc_mesh_num_nodes] 0: on a CAD vertex, 1: on a curve, 2: inside a face
 *  @param[out] tag    [hoc_mesh_num_nodes] the kernel's tag of that vertex, curve or face
 *  @param[out] param  [hoc_mesh_num_nodes][2] its parametric coordinates there: (u, v) on
 *                     the face, (t, 0) on the curve, (0, 0) at a vertex */
hoc_status hoc_mesh_node_entities(const hoc_mesh *mesh, int *dim, int *tag, double *param);

/** The nodes of each element, in gmsh's node ordering of the order-p
 *  triangle (also VTK's Lagrange triangle's): the 3 corners, then the p-1
 *  nodes of each edge (corner 0 to 1, 1 to 2, 2 to 0, each from its first
 *  corner), then the interior nodes, recursively as a triangle of order
 *  p-3 in the same ordering. The nodes sit at the mesh's node set
 *  (hoc_mesh_nodeset: convert to equispaced for the positions MSH and VTU
 *  files mean).
 *  @param[out] nodes  [hoc_mesh_num_elements][(p+1)(p+2)/2] 0-based node numbers */
hoc_status hoc_mesh_elements(const hoc_mesh *mesh, size_t *nodes);

/** The CAD face of each element (hoc_mesh_element_face_tag of all at once).
 *  @param[out] tags  [hoc_mesh_num_elements] the kernel's face tag */
hoc_status hoc_mesh_element_faces(const hoc_mesh *mesh, int *tags);

/* ------------------------------------------------------------------------ */
/* Quality                                                                  */

/** Statistics of q = 1/eta over a mesh (the paper's Table 2). */
typedef struct hoc_quality_stats {
  size_t elements; /**< number of elements */
  int order;       /**< element order */
  double min, max, mean, std; /**< of q over the elements (tangled count as 0) */
  size_t tangled;             /**< elements with sigma <= 0 somewhere: at a quadrature point, a
                                   node or a lattice point, or between them by the exact fold
                                   tests (docs/quality.md) */
  double seconds;  /**< wall time of the measurement (0 in a stage whose q came with making
                        it: the raises "high-order", "re-raised" and "re-placed") */
} hoc_quality_stats;

/** Measure every element with Definition 2 of the paper (surface high-order
 *  distortion through the tangent-plane embedding T).
 *  @param[in]  mesh     the mesh
 *  @param[in]  measure  shape or Oddy
 *  @param[out] quality  per-element q in element order, or NULL
 *  @param[out] tangled  per-element flag (1 = tangled), or NULL
 *  @param[out] stats    statistics, or NULL */
hoc_status hoc_mesh_measure(const hoc_mesh *mesh, hoc_measure measure, double *quality,
                            unsigned char *tangled, hoc_quality_stats *stats);

/** CAD face tag of element e (0-based), or -1 if out of range. */
int hoc_mesh_element_face_tag(const hoc_mesh *mesh, size_t e);

/** Bounds on the edge length for meshing again finer where flagged elements
 *  lie (hoc_linear_options.face_size): on the face of each flagged element,
 *  face_size[face index] becomes factor (0 < factor < 1) times the longest
 *  straight edge between its corners, unless already smaller (0: no bound).
 *  @param[in]     elements   per-element flag (e.g. tangled from hoc_mesh_measure)
 *  @param[in,out] face_size  [hoc_model_num_faces] */
hoc_status hoc_mesh_refine_bounds(const hoc_mesh *mesh, const unsigned char *elements,
                                  double factor, double *face_size);

/** How hoc_mesh_split keeps the mesh conforming. Each flagged element is
 *  split in four at the midpoints of its edges either way. */
typedef enum hoc_split_kind {
  /** Red-green: an element with two split edges gets its third split too;
   *  an element with one split edge is cut in two through its midpoint and
   *  the opposite corner; flagged elements give four children similar to
   *  themselves. */
  HOC_SPLIT_RED_GREEN = 0,
  /** Longest edge: an element with a split edge gets its longest edge
   *  (corner to corner in space) split too, and is bisected there first:
   *  two, three or four children. Slivers are cut across their length,
   *  never along it. */
  HOC_SPLIT_LONGEST_EDGE = 1
} hoc_split_kind;

/** Local refinement: each flagged element split in four at the midpoints
 *  of its edges, its neighbours as `kind` says, so that the mesh stays
 *  conforming. The new elements' nodes are placed as hoc_mesh_elevate
 *  places them, straight between their corners in the parent's (u, v) (in
 *  the curve's t on curve edges; midpoints halfway); elements not split
 *  keep all their nodes, and the children follow in their parent's place.
 *  Same order and node set as the input.
 *  @param[in]  elements  per-element flag (e.g. tangled from hoc_mesh_measure)
 *  @param[out] out       the new mesh (NULL on failure)
 *  @param[out] pieces    NULL, or [elements of mesh]: how many elements of *out each
 *                        element became (1: kept as it was; 2 to 4: split) */
hoc_status hoc_mesh_split(const hoc_mesh *mesh, const unsigned char *elements, hoc_split_kind kind,
                          hoc_mesh **out, unsigned char *pieces);

/** A corner of an element at a CAD vertex where both of the element's
 *  edges lie on CAD curves that meet there at a small angle (a cusp of the
 *  model). With evenly spaced edge nodes the element follows both curves
 *  ever more closely as the order grows, its angle at that corner tends to
 *  the curves' angle and its distortion grows without bound;
 *  hoc_mesh_elevate therefore grades the nodes of such edges away from
 *  the vertex. */
typedef struct hoc_cusp {
  int vertex_tag;       /* CAD vertex at the corner */
  int curve_tags[2];    /* the two curves */
  double angle_degrees; /* between the curves' tangents at the vertex */
} hoc_cusp;

/** The sharpest corner of element e at a CAD cusp of angle below
 *  max_angle_degrees. *found is 1 and *cusp filled if there is one, else 0.
 *  @return HOC_ERR_ARGUMENT on an element out of range, HOC_ERR_CAD if the
 *          kernel fails to evaluate a curve */
hoc_status hoc_mesh_element_cusp(const hoc_mesh *mesh, size_t e, double max_angle_degrees,
                                 hoc_cusp *cusp, int *found);

/* ------------------------------------------------------------------------ */
/* Untangling and smoothing                                                 */

/** One iteration (a sweep over the free nodes) of the optimiser. */
typedef struct hoc_optimize_iteration {
  int iteration;      /**< 1, 2, ... */
  double objective;   /**< f = sum over elements of int (eta - 1)^2 (regularised while tangled) */
  double min_q;       /**< smallest q */
  size_t tangled;     /**< tangled elements */
  size_t moved;       /**< nodes moved in this sweep */
  double seconds;     /**< since the start */
  int attempt;        /**< 1, or 2 in the second attempt (hoc_optimize_options.max_iterations) */
} hoc_optimize_iteration;

/** Called after each iteration; return nonzero to stop (HOC_ERR_INTERRUPTED). */
typedef int (*hoc_optimize_progress_fn)(void *user, const hoc_optimize_iteration *it);

typedef struct hoc_optimize_options {
  hoc_measure measure;  /**< distortion measure (default shape) */
  int fix_curves;       /**< 1: nodes on CAD curves stay where they are (the paper's choice) */
  int max_iterations;   /**< sweeps (0: 100); if elements are still tangled after them
                             (or after 40 sweeps without a new fewest tangled count), a
                             second attempt of up to half as many more restarts from the
                             best state reached, with boundary elements next to a fold
                             free to fold in (u, v) too (faces without a pole); it ends
                             early the same way (not in a local repair: free_elements) */
  double tolerance;     /**< a node whose move lowers f by less than tolerance * f / (free
                             nodes) goes to sleep; the optimisation ends when every node
                             sleeps, or when the last ten sweeps, all without a tangled
                             element, lowered f by less than 5% and raised the smallest q
                             by less than 0.005; once a phase ended so, a later one (the
                             exact phase after the samples') ends on two untangled
                             sweeps in a row, the last lowering f by less than 0.5% and
                             raising the smallest q by less than 0.0005
                             (0: 0.1) */
  hoc_optimize_progress_fn progress;
  void *progress_user;
  const unsigned char *free_elements; /**< NULL: every node not on a CAD vertex may move;
                             else [elements] flags: only the nodes of flagged elements, and
                             of the elements within free_rings rings of them (sharing a
                             node), move; the rest stay where they are (a local repair,
                             e.g. of the elements a split made). A local repair counts
                             tangled elements by the exact test from its first sweep
                             (no sampled first phase), never raises the
                             regularisation when untangling stalls, and makes neither
                             a second attempt nor a protected run */
  int free_rings;       /**< see free_elements (0: only the flagged elements' nodes) */
} hoc_optimize_options;

void hoc_optimize_options_default(hoc_optimize_options *options);

/** How a run went inside: the phases the optimiser went through and what
 *  its internal rules did. For diagnostics, reports and tests only: NOT a
 *  stable interface (fields may change meaning, appear or go with the
 *  algorithm). Sweep numbers count as hoc_optimize_result.iterations does;
 *  0: that phase did not happen. */
typedef struct hoc_optimize_diagnostics {
  int second_attempt;   /**< first sweep of the second attempt (0: none was needed) */
  int exact_phase;      /**< first sweep of the exact phase: sweeps after the samples
                             said untangled but the exact edge test found folds between
                             them (0: none was needed) */
  int protected_run;    /**< first sweep of the kept run when it is a second run from the start
                             in which steps may not fold an element between samples that the
                             exact test finds valid (made when the first left elements
                             tangled; 0: the first run is kept) */
  size_t polished;      /**< elements the final polish untangled: a pattern search, node by node,
                             on the exact verdict around each element the sweeps left tangled
                             (when at most 32 are) */
  size_t fragile;       /**< elements guarded as fragile: above order 5, those valid at the start
                             with q < 0.1, which no step may fold between the samples */
} hoc_optimize_diagnostics;

/** What a run of the optimiser did (stable fields), and its diagnostics
 *  (unstable, see hoc_optimize_diagnostics). */
typedef struct hoc_optimize_result {
  int iterations;       /**< sweeps made (numbered on through every phase and run) */
  int converged;        /**< a stopping rule of `tolerance` met, no tangled element */
  double objective_initial, objective_final;
  size_t tangled_initial, tangled_final; /**< by the exact test, as hoc_mesh_measure counts */
  int best_iteration;   /**< sweep after which the returned mesh's tangled count was
                             first reached (0: the start); long before `iterations`
                             when untangling stalled */
  int stopped_at_limit; /**< elements were still tangled when the last attempt had used all
                             its sweeps (not ended early by the 40-sweep stall rule or by
                             every node sleeping) */
  size_t free_nodes;    /**< nodes the optimiser could move */
  double seconds;
  hoc_optimize_diagnostics diagnostics; /**< unstable: see hoc_optimize_diagnostics */
} hoc_optimize_result;

/** Untangle and smooth at once (the paper's Section 4): minimise
 *  f = sum_e int_{t_I} (eta - 1)^2 over the parametric coordinates of the
 *  free nodes, with the regularised determinant of Escobar et al. while an
 *  element is tangled. Face-interior nodes move in their face's (u, v),
 *  nodes on CAD curves slide along the curve in t (unless fix_curves), CAD
 *  vertices are fixed; every position is evaluated on the CAD. A step never
 *  leaves a face's parametric domain and never tangles a valid element,
 *  except next to a fold while untangling stalls (docs/quality.md). The
 *  tangle test looks at samples until they say untangled, then, if the
 *  exact fold test of measuring finds folds between them, at the exact
 *  test too for the sweeps after (result.diagnostics.exact_phase);
 *  tangled_final counts by the exact test, as hoc_mesh_measure does. A run
 *  that leaves elements tangled (not for want of sweeps) is followed, up to
 *  order 5 and outside a local repair, by a protected run from the same
 *  start whose steps may not fold a valid element between the samples; the
 *  one leaving fewer tangled is kept (result.diagnostics.protected_run).
 *  Deterministic, whatever the thread count.
 *  @param[in,out] mesh  the mesh, changed in place: the final state, or, if
 *                       that has more tangled elements than an earlier one,
 *                       the earlier state with the fewest
 *  @param[in] options   NULL for defaults
 *  @param[out] result   may be NULL */
hoc_status hoc_mesh_optimize(hoc_mesh *mesh, const hoc_optimize_options *options,
                             hoc_optimize_result *result);

/** Compare the analytic gradient of f with respect to the free parametric
 *  coordinates (chain rule through the CAD parametrisation) with central
 *  finite differences, at up to `samples` nodes spread over the mesh.
 *  @param[out] max_rel_error  largest |analytic - fd| / (|fd| + scale) */
hoc_status hoc_mesh_check_gradient(hoc_mesh *mesh, hoc_measure measure, int fix_curves,
                                   int samples, double *max_rel_error);

/* ------------------------------------------------------------------------ */
/* The method end to end: what `hocad mesh` and `hocad optimize` do         */

/** One stage of a pipeline, measured: a row of the paper's Table 2. */
typedef struct hoc_stage {
  const char *name; /**< "linear", "high-order", "input", "re-placed", "split", "optimized",
                         "smoothed" or "written" (a static string) */
  hoc_quality_stats stats; /**< q of the stage's mesh */
  double seconds;          /**< wall time the pipeline took to make the stage (an "input"
                                stage: to copy it), its measurement (stats.seconds) apart;
                                a raise measures as it chooses its placement, and its
                                seconds include that */
  int optimized;           /**< the stage is an optimiser's result: the fields below are set */
  int iterations;          /**< the optimiser's sweeps */
  int converged;           /**< hoc_optimize_result.converged */
  double objective_initial, objective; /**< f before and after */
} hoc_stage;

/** What a pipeline event is about. */
typedef enum hoc_event_kind {
  HOC_EVENT_PROGRESS = 0,  /**< a step starts ("optimizing 7020 elements") */
  HOC_EVENT_STAGE = 1,     /**< a stage was measured (event->stage); a stage of an attempt
                                the pipeline then drops is reported too */
  HOC_EVENT_ITERATION = 2, /**< an optimiser sweep ended (event->iteration) */
  HOC_EVENT_REPAIR = 3,    /**< elements are left tangled or poor and a repair starts (a split,
                                meshing faces again, smoothing): how many, what, where */
  HOC_EVENT_NOTE = 4,      /**< what the pipeline found or kept */
  HOC_EVENT_WARNING = 5,   /**< what the result lacks (faces not meshed, tangled elements) */
  HOC_EVENT_CHECK = 6      /**< the gradient check of hoc_mesh_options.check_gradient
                                (event->value) */
} hoc_event_kind;

/** An event of a running pipeline. Every pointer is valid during the call only. */
typedef struct hoc_event {
  hoc_event_kind kind;
  const char *message;     /**< one line, no newline, never NULL */
  const hoc_stage *stage;  /**< HOC_EVENT_STAGE, else NULL */
  const hoc_optimize_iteration *iteration; /**< HOC_EVENT_ITERATION, else NULL */
  double value;            /**< HOC_EVENT_CHECK: the largest relative difference between the
                                analytic gradient and central differences */
} hoc_event;

/** Called on each event, on the thread that called the pipeline; return
 *  nonzero to cancel: the pipeline then fails with HOC_ERR_INTERRUPTED and
 *  returns neither a mesh nor a report. */
typedef int (*hoc_event_fn)(void *user, const hoc_event *event);

/** Options of hoc_mesh_model and hoc_mesh_repair (fill with
 *  hoc_mesh_options_default, then change what differs). */
typedef struct hoc_mesh_options {
  int order;              /**< hoc_mesh_model: element order, 1..HOC_MAX_ORDER (default 3);
                               hoc_mesh_repair keeps its input's */
  hoc_nodeset nodeset;    /**< hoc_mesh_model: reference nodes (default equispaced) */
  hoc_measure measure;    /**< distortion measure (default shape) */
  double size, size_min, curvature; /**< hoc_mesh_model: the linear mesher's size_max,
                               size_min and curvature (hoc_linear_options; 0: choose) */
  const hoc_mesh *linear; /**< hoc_mesh_model: NULL, or a mesh of the model whose corners
                               are the linear mesh (e.g. another mesher's), used instead of
                               meshing; it is split where elements stay tangled, never
                               meshed again */
  int optimize;           /**< 1 (default): untangle and smooth (at order 1 only a
                               linear mesh with tangled elements); 0: stop after
                               raising */
  int fix_curves;         /**< hoc_optimize_options.fix_curves */
  int max_iterations;     /**< hoc_optimize_options.max_iterations (0: its default) */
  int refinements;        /**< where elements stay tangled: at most this many remeshings of
                               their faces, and splits per chain (-1, the default: 2 for
                               hoc_mesh_model, 3 with a given linear mesh, 6 for
                               hoc_mesh_repair; 0: none); on faces that fold (their normal
                               reverses inside them) or at CAD cusps hoc_mesh_model makes
                               one split per chain and no remeshing, and no split if
                               each tangled element crosses a fold (not at a neck, an
                               iso-line with a short image) or is at a cusp */
  int keep_nodes;         /**< hoc_mesh_repair: optimise from the input's own high-order
                               nodes only, never from nodes re-placed from its corners */
  int equispaced;         /**< hoc_mesh_model: the result converted to equispaced nodes, what
                               MSH and VTU files hold, and measured as a "written" stage, when
                               the node set differs (from order 3: below it every node set is
                               the equispaced one) */
  int keep_stages;        /**< hoc_mesh_model: the report keeps the linear mesh and the raised
                               one before optimisation (hoc_report_linear, hoc_report_raised) */
  int check_gradient;     /**< before each optimisation, compare the analytic gradient with
                               finite differences (hoc_mesh_check_gradient, HOC_EVENT_CHECK) */
  hoc_event_fn event;     /**< NULL, or called on every event */
  void *event_user;       /**< passed to event */
  double mesher_timeout;  /**< hoc_mesh_model: hoc_linear_options.mesher_timeout */
  int grading;            /**< hoc_mesh_model: hoc_linear_options.grading (default 1) */
  double repair_time;     /**< where elements stay tangled after the first optimisation: the
                               seconds its repairs (remeshings, splits, their optimisations)
                               may take; past them the optimisation (or gmsh's mesher,
                               remeshing) under way stops, no repair starts, and the
                               attempt with the fewest
                               tangled elements is kept (0, the default: 4 x the time to the
                               first optimised mesh + 60 s; negative: no bound) */
} hoc_mesh_options;

/** Fill options with the defaults: order 3, equispaced nodes, shape
 *  measure, sizes chosen, optimised, curves free, default sweeps and
 *  refinements (-1), no event callback. */
void hoc_mesh_options_default(hoc_mesh_options *options);

/** A pipeline's report: its stages, how often it refined, the quality of
 *  its result and what it found about it. */
typedef struct hoc_report hoc_report;

/** `hocad mesh`: the paper's three steps and the repairs where they leave
 *  elements tangled. (1) A linear mesh (hoc_mesh_generate_linear, or
 *  options->linear), (2) raised to the order (hoc_mesh_elevate; per face,
 *  where it tangles fewer elements or raises the face's min q by over 1%,
 *  the new nodes at the feet of the straight elements' points on the
 *  surface instead: faces whose parametrisation varies within an element,
 *  as at a knot where a B-spline's derivative jumps), (3)
 *  optimised (hoc_mesh_optimize; unless options->optimize is 0; at order
 *  1 only if the linear mesh has tangled elements, which no split or
 *  remeshing follows). Where elements stay tangled: first (below order 6, or where
 *  their faces fold or they have a corner at a CAD cusp) their split on a copy
 *  (as hoc_mesh_repair splits), kept if it leaves none tangled (at folds and
 *  cusps, which no finer mesh opens: the fewest tangled kept, no
 *  remeshing, and no split where each element crosses a fold, not at a
 *  neck, or is at a cusp itself); else their faces meshed again with
 *  edges half as long and (unless options->size_min is set) a minimum
 *  size ten times smaller, unless that more than quadruples the mesh,
 *  and everything again, at
 *  most `refinements` times; once that is spent, the attempt with the
 *  fewest tangled elements split. An untangled result with elements below
 *  0.9 x the linear mesh's min q has them and two rings around them
 *  optimised once more (a "smoothed" stage, kept if it raises the min q).
 *  @param[in]  model    the CAD model; it must outlive the mesh
 *  @param[in]  options  NULL for defaults
 *  @param[out] mesh     NULL, or the result (destroy with hoc_mesh_destroy); NULL on failure
 *  @param[out] report   NULL, or the report (destroy with hoc_report_destroy); NULL on failure
 *  Fails with HOC_ERR_ARGUMENT on an option out of range, HOC_ERR_MISMATCH
 *  if options->linear is on another model, HOC_ERR_INTERRUPTED if the
 *  event callback cancels; tangled elements left in the result are no
 *  failure (see hoc_report_tangled). */
hoc_status hoc_mesh_model(hoc_model *model, const hoc_mesh_options *options, hoc_mesh **mesh,
                          hoc_report **report);

/** `hocad optimize`: untangle and smooth any high-order mesh of a model
 *  (e.g. another mesher's), refining it where it stays tangled. Where the
 *  input is tangled, the optimiser starts from its corners with the
 *  high-order nodes re-placed as hoc_mesh_model places them (a
 *  "re-placed" stage) unless that tangles over 10% more elements than the
 *  input or options->keep_nodes; if that stays tangled, from the input's
 *  own nodes too, and the result with fewer tangled elements (then the
 *  lower objective) is kept. Elements still tangled are split in two
 *  chains taken in turn, red-green from the optimised result and at
 *  longest edges from the mesh it was optimised from (hoc_mesh_split),
 *  each split optimised again (a split of an optimised result only in its
 *  new elements and two rings around them), until a result has no tangled
 *  element or each chain made `refinements` splits; the result with the
 *  fewest tangled elements is kept.
 *  @param[in]  in       the mesh; it is not changed
 *  @param[in]  options  NULL for defaults (order, nodeset, sizes, linear, optimize,
 *                       equispaced and keep_stages are not used)
 *  @param[out] mesh     NULL, or the result on the same model; NULL on failure
 *  @param[out] report   NULL, or the report; NULL on failure */
hoc_status hoc_mesh_repair(const hoc_mesh *in, const hoc_mesh_options *options, hoc_mesh **mesh,
                           hoc_report **report);

/** `hocad quality`: a report of one stage, "input", measuring a mesh.
 *  @param[out] report  the report (destroy with hoc_report_destroy) */
hoc_status hoc_mesh_quality_report(const hoc_mesh *mesh, hoc_measure measure,
                                   hoc_report **report);

/** Destroy a report (NULL allowed); clears *report. */
void hoc_report_destroy(hoc_report **report);

/** The stages of the result in order (a dropped attempt's are not kept):
 *  hoc_mesh_model's "linear", "high-order" (order above 1), then any
 *  "split", "optimized", "smoothed", "written"; hoc_mesh_repair's "input",
 *  then any "re-placed" or "split", and "optimized". The last stage is the
 *  result. */
size_t hoc_report_num_stages(const hoc_report *report);
/** Stage i (0-based), or NULL if out of range; valid while the report lives. */
const hoc_stage *hoc_report_stage(const hoc_report *report, size_t i);
/** The optimiser's whole result for stage i (its diagnostics may change
 *  between versions), or NULL if the stage is not optimised. */
const hoc_optimize_result *hoc_report_stage_result(const hoc_report *report, size_t i);

/** Times tangled elements were meshed again finer: remeshings of their
 *  faces and splits, those made in attempts not kept included. */
int hoc_report_refinements(const hoc_report *report);
/** Of those, remeshings of faces (hoc_mesh_model only). */
int hoc_report_remeshings(const hoc_report *report);
/** Tangled elements of the result (its last stage's count). */
size_t hoc_report_tangled(const hoc_report *report);
/** Faces the linear mesher could not mesh in the kept attempt (they have no
 *  elements; hoc_mesh_model only). */
int hoc_report_num_failed_faces(const hoc_report *report);
/** Wall seconds of the whole run: its stages (their `seconds`) and what
 *  they do not hold, the attempts not kept (an optimisation before a split
 *  or a remeshing, a split that left no fewer tangled) and the closing
 *  measure. Opening the model and writing files are not in it. */
double hoc_report_seconds(const hoc_report *report);
/** Elements and nodes of the result. */
size_t hoc_report_num_elements(const hoc_report *report);
size_t hoc_report_num_nodes(const hoc_report *report);
/** q of each element of the result, [hoc_report_num_elements] in element
 *  order (0: tangled), as hoc_mesh_measure gives it; valid while the report
 *  lives. */
const double *hoc_report_quality(const hoc_report *report);

/** What the report finds about the result, one line each: a warning
 *  naming the tangled elements (up to 20) with why they stay tangled and
 *  what may help; a note on elements below 0.9 x the linear mesh's min q
 *  at a cusp of the CAD (hoc_cusp). */
size_t hoc_report_num_findings(const hoc_report *report);
/** Finding i, or NULL if out of range; *kind (if not NULL) is
 *  HOC_EVENT_WARNING or HOC_EVENT_NOTE. */
const char *hoc_report_finding(const hoc_report *report, size_t i, hoc_event_kind *kind);

/** With hoc_mesh_options.keep_stages: the linear mesh of the result (a copy
 *  at order 1), and the raised mesh before optimisation (NULL when not
 *  optimised); else NULL. They belong to the report. */
const hoc_mesh *hoc_report_linear(const hoc_report *report);
const hoc_mesh *hoc_report_raised(const hoc_report *report);

/** What the JSON report says that the pipeline does not know: the files
 *  the caller read and the time it spent on them. */
typedef struct hoc_report_files {
  const char *model;    /**< "model": the model's file name (NULL: "") */
  const char *mesh;     /**< "mesh": the input mesh's file name (NULL: no such key) */
  double model_seconds; /**< "model_seconds": opening the model */
  double write_seconds; /**< "write_seconds": writing the result */
} hoc_report_files;

/** The report as JSON: "command" ("mesh", "optimize" or "quality" after
 *  hoc_mesh_model, hoc_mesh_repair, hoc_mesh_quality_report), "model",
 *  "mesh", "measure", "version", "stages" (each with the optimiser's
 *  diagnostics when optimised), "refinements", "remeshings", "nodes",
 *  "seconds" (hoc_report_seconds), "model_seconds", "write_seconds";
 *  numbers with 17 digits.
 *  @param[in]  files  NULL, or the caller's files
 *  @param[out] json   NUL-terminated text, free it with free(); NULL on failure */
hoc_status hoc_report_json(const hoc_report *report, const hoc_report_files *files, char **json);

/** hoc_report_json written to a file atomically. */
hoc_status hoc_report_write_json(const hoc_report *report, const hoc_report_files *files,
                                 const char *path);

/* ------------------------------------------------------------------------ */
/* Pictures                                                                 */

/** Options of the pictures (PNG, drawn in software: no display, no GPU). */
typedef struct hoc_picture_options {
  int width, height; /**< whole picture in pixels (0: 1600 x 1200 for one mesh,
                          900 n x 1000 up to 3600 wide for n side by side) */
  double view[3];    /**< direction from the model to the eye ((0,0,0): isometric (1,1,1)) */
  int zoom_worst;    /**< frame the worst elements of the first mesh instead of everything */
  int no_edges;      /**< do not draw the element edges */
  int transparent;   /**< transparent background instead of white */
} hoc_picture_options;

/** Fill options with defaults (1600 x 1200, isometric, edges, white). */
void hoc_picture_options_default(hoc_picture_options *options);

/** Draw `n` meshes side by side in one PNG with the same camera (so stages
 *  compare), curved elements tessellated for their order, faces coloured by
 *  q with a colour bar, tangled elements (q = 0) in magenta. Written
 *  atomically.
 *  @param[in] meshes   [n] meshes (1..16)
 *  @param[in] quality  [n] per-element q of each mesh (from hoc_mesh_measure),
 *                      or NULL (grey)
 *  @param[in] titles   [n] titles above the views, or NULL */
hoc_status hoc_picture_png(const char *path, int n, const hoc_mesh *const *meshes,
                           const double *const *quality, const char *const *titles,
                           const hoc_picture_options *options);

/** Histogram of q per mesh (bins of 0.05, tangled elements counted apart),
 *  one panel per mesh side by side, as a PNG. quality[i] must not be NULL. */
hoc_status hoc_histogram_png(const char *path, int n, const hoc_mesh *const *meshes,
                             const double *const *quality, const char *const *titles,
                             const hoc_picture_options *options);

/* ------------------------------------------------------------------------ */
/* Files                                                                    */

/** Write `size` bytes to `path` atomically (temporary file in the same
 *  directory, then rename): the target is either the old file or the new. */
hoc_status hoc_write_file_atomic(const char *path, const void *data, size_t size);

#ifdef __cplusplus
}
#endif
#endif /* HOC_HOCAD_H */
