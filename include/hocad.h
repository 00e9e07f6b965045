/* hocad: valid high-order triangle surface meshes on CAD models.
 *
 * Copyright (C) 2026 the hocad developers.
 * SPDX-License-Identifier: GPL-2.0-or-later
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
#ifndef HOCAD_H
#define HOCAD_H

#include <stddef.h>

#ifdef __cplusplus
extern "C" {
#endif

#define HOCAD_VERSION_MAJOR 0
#define HOCAD_VERSION_MINOR 1
#define HOCAD_VERSION_PATCH 0

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

/** Jacobian-based distortion measure eta of the seed's Table 1 (d = 2). */
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
 *  Fails with HOC_ERR_IO if the file cannot be read, HOC_ERR_CAD if it holds
 *  no usable face. */
hoc_status hoc_model_open(const char *path, hoc_model **model);

/** Destroy a model (NULL allowed); clears *model. */
void hoc_model_destroy(hoc_model **model);

/** Number of CAD faces, curves and vertices. */
int hoc_model_num_faces(const hoc_model *model);
int hoc_model_num_curves(const hoc_model *model);
int hoc_model_num_vertices(const hoc_model *model);

/** Axis-aligned bounding box [xmin, ymin, zmin, xmax, ymax, zmax]. */
void hoc_model_bbox(const hoc_model *model, double bbox[6]);

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
} hoc_linear_options;

/** Fill options with defaults (all "choose", order 1, no progress). */
void hoc_linear_options_default(hoc_linear_options *options);

/** The edge lengths the linear mesher uses for these options on this model:
 *  size_max, or the bounding-box diagonal / 20 if 0; size_min, or a tenth
 *  of that if 0. */
void hoc_linear_sizes(const hoc_model *model, const hoc_linear_options *options, double *size_max,
                      double *size_min);

/** Mesh every face of the model with linear triangles. Faces the kernel
 *  cannot mesh are skipped and counted in hoc_mesh_num_failed_faces().
 *  @param[in]  model    the CAD model; it must outlive the mesh
 *  @param[in]  options  NULL for defaults
 *  @param[out] mesh     new order-1 mesh */
hoc_status hoc_mesh_generate_linear(hoc_model *model, const hoc_linear_options *options,
                                    hoc_mesh **mesh);

/** Raise (or lower) a mesh to order p (1..HOC_MAX_ORDER): the new nodes of
 *  each element are placed in the face's parametric space by evaluating the
 *  element's parametric map at the reference nodes of the requested
 *  distribution, and mapped onto the surface; nodes on CAD curves are placed
 *  in the curve's parameter. From a linear mesh this is the seed's step 2
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
 *  Fails with HOC_ERR_MISMATCH if the mesh does not lie on the model. */
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

/* ------------------------------------------------------------------------ */
/* Quality                                                                  */

/** Statistics of q = 1/eta over a mesh (the seed's Table 2). */
typedef struct hoc_quality_stats {
  size_t elements; /**< number of elements */
  int order;       /**< element order */
  double min, max, mean, std; /**< of q over the elements (tangled count as 0) */
  size_t tangled;             /**< elements with sigma <= 0 somewhere: at a quadrature point, a
                                   node or a lattice point, or between them by the exact fold
                                   tests (docs/quality.md) */
  double seconds;  /**< wall time of the measurement */
} hoc_quality_stats;

/** Measure every element with Definition 2 of the seed (surface high-order
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
  int fix_curves;       /**< 1: nodes on CAD curves stay where they are (the seed's choice) */
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
                             by less than 0.005
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

typedef struct hoc_optimize_result {
  int iterations;
  int converged;        /**< a stopping rule of `tolerance` met, no tangled element */
  double objective_initial, objective_final;
  size_t tangled_initial, tangled_final;
  int best_iteration;   /**< sweep after which the returned mesh's tangled count was
                             first reached (0: the start); long before `iterations`
                             when untangling stalled */
  int second_attempt;   /**< first sweep of the second attempt (0: none was needed) */
  int exact_phase;      /**< first sweep of the exact phase: sweeps after the samples
                             said untangled but the exact edge test found folds between
                             them (0: none was needed) */
  int protected_run;    /**< first sweep of the kept run when it is a second run from the start
                             in which steps may not fold an element between samples that the
                             exact test finds valid (made when the first left elements
                             tangled; 0: the first run is kept) */
  int stopped_at_limit; /**< elements were still tangled when the last attempt had used all
                             its sweeps (not ended early by the 40-sweep stall rule or by
                             every node sleeping) */
  size_t polished;      /**< elements the final polish untangled: a pattern search, node by node,
                             on the exact verdict around each element the sweeps left tangled
                             (when at most 32 are) */
  size_t free_nodes;    /**< nodes the optimiser could move */
  size_t fragile;       /**< elements guarded as fragile: above order 5, those valid at the start
                             with q < 0.1, which no step may fold between the samples */
  double seconds;
} hoc_optimize_result;

/** Untangle and smooth at once (the seed's Section 4): minimise
 *  f = sum_e int_{t_I} (eta - 1)^2 over the parametric coordinates of the
 *  free nodes, with the regularised determinant of Escobar et al. while an
 *  element is tangled. Face-interior nodes move in their face's (u, v),
 *  nodes on CAD curves slide along the curve in t (unless fix_curves), CAD
 *  vertices are fixed; every position is evaluated on the CAD. A step never
 *  leaves a face's parametric domain and never tangles a valid element,
 *  except next to a fold while untangling stalls (docs/quality.md). The
 *  tangle test looks at samples until they say untangled, then, if the
 *  exact fold test of measuring finds folds between them, at the exact
 *  test too for the sweeps after (result.exact_phase); tangled_final
 *  counts by the exact test, as hoc_mesh_measure does.
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

/** Picture (and histogram, if histogram_path is not NULL) of a .msh file
 *  without its CAD model. Without the CAD normals, Definition 2 measures
 *  each element against the normal of the plane through its three corners
 *  (equal to the CAD's verdict on all but strongly curved elements).
 *  @param[out] stats  statistics of that measure, or NULL */
hoc_status hoc_picture_msh_file(const char *msh_path, hoc_measure measure, const char *png_path,
                                const char *histogram_path, const hoc_picture_options *options,
                                hoc_quality_stats *stats);

/* ------------------------------------------------------------------------ */
/* Files                                                                    */

/** Write `size` bytes to `path` atomically (temporary file in the same
 *  directory, then rename): the target is either the old file or the new. */
hoc_status hoc_write_file_atomic(const char *path, const void *data, size_t size);

/** From a signal handler: remove every temporary output file the library
 *  has open (async-signal-safe), so an interrupted run leaves the previous
 *  outputs intact and no partial file behind. */
void hoc_abort_outputs_from_signal(void);

#ifdef __cplusplus
}
#endif
#endif /* HOCAD_H */
