/* The high-order surface mesh: nodes classified on CAD entities with their
 * parametric coordinates, triangles of one order on CAD faces.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef HOC_MESH_H
#define HOC_MESH_H

#include "cad/cad.h"

/* The side of a pole slot's element at a pinch (hoc_mesh.slot_pole). */
enum { HOC_POLE_BELOW = 4, HOC_POLE_ABOVE = 16, HOC_POLE_SIDES = 60 };

/* Node classification: the CAD entity a node lies on. */
enum { HOC_ON_VERTEX = 0, HOC_ON_CURVE = 1, HOC_ON_FACE = 2 };

/* Is a node classified (dim, entity) on curve c: on the curve itself or
 * at a vertex at one of its ends? */
static inline int hoc_node_on_curve(const hoc_model *model, int dim, int entity, int c) {
  if (dim == HOC_ON_CURVE) return entity == c;
  return dim == HOC_ON_VERTEX && (entity == model->curves[c].v0 || entity == model->curves[c].v1);
}

/* A mesh "slot" is a (node, face) pair: the node seen from one face that
 * uses it, with its parameters on that face. Face-interior nodes have one
 * slot; nodes on curves and vertices have one per face around them, except
 * at a pole of a face (a degenerate side, where one coordinate is
 * arbitrary): there each element has a slot of its own, whose arbitrary
 * coordinate is the element's (elem_uv), because the surface's normal at
 * a pole is the limit along the direction of approach and differs from one
 * element to the next where the surface has no tangent plane (a cone's
 * apex). */

struct hoc_mesh {
  hoc_model *model; /* borrowed */
  int order;        /* p */
  hoc_nodeset nodeset;
  int np;           /* nodes per element (p+1)(p+2)/2 */

  size_t n_nodes;
  double *xyz;          /* [n_nodes][3] position, always phi(param) of its entity */
  double *param;        /* [n_nodes][2] (u,v) on its face, (t,0) on its curve, (0,0) on a vertex */
  signed char *dim;     /* [n_nodes] HOC_ON_VERTEX/CURVE/FACE */
  int *entity;          /* [n_nodes] index of the vertex/curve/face */

  size_t n_elems;
  size_t *conn;         /* [n_elems][np] node indices, gmsh ordering */
  int *elem_face;       /* [n_elems] face index */
  double *elem_uv;      /* [n_elems][np][2] the element's nodes on its face, unwrapped */
  size_t *elem_slot;    /* [n_elems][np] slot of each element node */

  size_t n_slots;
  size_t *slot_node;    /* [n_slots] */
  int *slot_face;       /* [n_slots] */
  double *slot_uv;      /* [n_slots][2] parameters of the node on the face */
  unsigned char *slot_pole; /* [n_slots] bit 0: u is arbitrary here (phi_u = 0), bit 1: v is;
                               such a slot of a vertex or curve node belongs to one element;
                               at a pole inside the face's range (a pinch), HOC_POLE_BELOW
                               or HOC_POLE_ABOVE shifted by the fixed coordinate (0: u, 1:
                               v) says on which side of it the element lies */

  /* 1D elements on CAD curves (the curve edges of the triangles) */
  size_t n_lines;
  size_t *line_conn;    /* [n_lines][p+1] gmsh line ordering: end0, end1, interior from end0 */
  int *line_curve;      /* [n_lines] curve index */
  double *line_t;       /* [n_lines][2] curve parameter at end0 and end1, unwrapped along the line */

  signed char *face_orient; /* [n_faces] +1 if element normals follow phi_u x phi_v, -1 if
                               opposite, 0 if the face has no elements */
  size_t n_collapsed;       /* triangles dropped at collapsed sides (collapse.c) */
  /* a linear mesh graded down to this many short CAD curves and thin faces
   * (grading.c), and gmsh's own mesh's triangles and min q */
  int graded_curves, graded_faces;
  size_t ungraded_elements;
  double ungraded_min_q;
  double graded_budget;      /* > 0: the graded meshing did not finish in these seconds */
  size_t swapped_edges;      /* edges of the linear mesh swapped (swap.c), and its min q */
  double swap_min_q[2];      /* before and after */
  int n_failed_faces;
  int *failed_faces;        /* [n_failed_faces] face indices the mesher could not mesh */
  int small_faces;          /* faces meshed only with the minimum size lowered to
                               small_min (HOC_LINEAR_SMALL_FACE_EDGES) */
  double small_min;
  size_t unextended_elements; /* > 0: gmsh's mesh with the curves' sizes extended into the
                                 faces had this many triangles (HOC_LINEAR_UNEXTENDED) */
  int cut_pinches;          /* pinches the linear mesh is cut along (hoc_mesh_cut_pinches) */
  int timed_out_faces;      /* how many of them gmsh did not finish meshing in
                               mesher_timeout seconds (hoc_linear_options) */
  int known_failed_faces;   /* how many of them were left out from the model's record
                               of an earlier meshing, the mesher not run on them */
  double mesher_timeout;    /* (a mesh raised or split from another has its failed faces:
                               hoc_mesh_copy_failed) */
  double off_cad;           /* largest distance of a given node position from its entity
                               (nonzero only for meshes kept as read) */
  double face_gap;          /* largest distance between a curve or vertex node and its
                               slot's point on a face around it: the model's curves lie
                               off their faces within its tolerance (hoc_cad_tolerance) */
};

/** Input of hoc_mesh_assemble: a triangulation with classified nodes, as
 *  produced by a mesher or read from a file. Arrays are borrowed. */
typedef struct hoc_mesh_source {
  int order;
  hoc_nodeset nodeset;
  size_t n_nodes;
  const double *xyz;         /* [n][3] */
  const double *param;       /* [n][2] or NULL: parameters on the node's entity */
  const unsigned char *has_param; /* [n] or NULL (all valid if param != NULL) */
  const signed char *dim;    /* [n] */
  const int *entity;         /* [n] entity index */
  size_t n_elems;
  const size_t *conn;        /* [n_elems][np] */
  const int *elem_face;      /* [n_elems] */
  size_t n_lines;            /* may be 0: curve edges are then inferred */
  const size_t *line_conn;   /* [n_lines][p+1] */
  const int *line_curve;     /* [n_lines] */
  const size_t *node_tag;    /* [n] node labels for messages (file tags), or NULL */
  int keep_xyz;              /* keep the given positions (a file measured as written);
                                otherwise positions are recomputed from the parameters */
  const signed char *face_orient; /* [n_faces] known orientation (a mesh raised from one
                                     that has it), or NULL: found from the elements */
  int given;                 /* the mesh comes from outside (a file): checked against the
                                model (hoc_mesh_given_limit); otherwise it is hocad's own,
                                whose nodes are never refused */
} hoc_mesh_source;

/** How far a node of a given mesh may lie from its CAD vertex or curve, or
 *  an element's corner from its face: 4 times the model's tolerance
 *  (hoc_cad_tolerance, which samples bound from below: at most 2.5 times
 *  short of a dense measure on the corpus), and at least 1e-6 of the
 *  diagonal (positions a file's writer rounded to 7 digits). A curve or
 *  vertex node may lie twice that from a face it bounds (that far from its
 *  curve, the curve as far from the face). */
hoc_status hoc_mesh_given_limit(hoc_model *model, double *limit);

/** Owned arrays of a source rewritten by hoc_mesh_collapse_sides. */
typedef struct hoc_mesh_collapse {
  double *xyz, *param;
  unsigned char *has_param;
  signed char *dim;
  int *entity, *elem_face, *line_curve;
  size_t *conn, *line_conn, *node_tag;
  size_t n_dropped; /* triangles with two corners at one point, dropped */
} hoc_mesh_collapse;

/** Linear sources only: the nodes of each degenerate curve (one that
 *  evaluates to a point: a collapsed side the kernel left unmarked, which
 *  gmsh meshes like any curve) and of the vertices at its ends become one
 *  node (a vertex's if any); triangles and lines left with two corners at
 *  it are dropped. Rewrites `src` to point into `c`'s arrays if anything
 *  changes (free them with hoc_mesh_collapse_free after assembly), else
 *  leaves it untouched. */
hoc_status hoc_mesh_collapse_sides(const hoc_model *model, hoc_mesh_source *src,
                                   hoc_mesh_collapse *c);
void hoc_mesh_collapse_free(hoc_mesh_collapse *c);
/** Distance within which nodes are one point for hoc_mesh_collapse_sides,
 *  and a vertex that stands for another may end a curve there. */
double hoc_mesh_collapse_distance(const hoc_model *model);

/** Build a mesh from a triangulation: locate nodes without parameters on
 *  their entities, reparametrise curve and vertex nodes on the faces around
 *  them (slots), unwrap each element's parameters across seams, give pole
 *  nodes a usable parameter and a slot per element, orient the faces from the
 *  elements, and recompute every node position from its parameters.
 *  A curve or vertex node's place on a face is its curve's on that face
 *  (the pcurve at its parameter; the face's nearest point only where that
 *  gives none or leaves the face's bounds), for every mesh alike, and its
 *  distance from the node is recorded (face_gap). A given mesh
 *  (src->given) fails with HOC_ERR_MISMATCH when a node lies farther from
 *  the model than hoc_mesh_given_limit allows, or a high-order node inside
 *  a face farther than the larger of 1% of the diagonal and that limit
 *  (such nodes are kept
 *  where the file puts them: gmsh leaves them off the surface where its
 *  projection fails). hocad's own meshes are never refused. */
hoc_status hoc_mesh_assemble(hoc_model *model, const hoc_mesh_source *src, hoc_mesh **mesh);
/** After the parameters of the nodes flagged in which[n_nodes] changed:
 *  their positions, their slots' parameters on the faces around and every
 *  element's parameters made again, as hoc_mesh_assemble (hocad's own
 *  mesh) makes them; face_gap grows to cover the
 *  moved slots. Pole flags stay: *at_pole is set where a moved slot lands
 *  on a pole side (the mesh is then not the assembled one). */
hoc_status hoc_mesh_move_nodes(hoc_mesh *m, const unsigned char *which, int *at_pole);

/** The faces the linear mesher left out of `from` (failed_faces and what
 *  timed out) given to `to`, a mesh raised or split from it. */
hoc_status hoc_mesh_copy_failed(const hoc_mesh *from, hoc_mesh *to);

/** The whole record of how `from` was meshed (its failed faces and every
 *  field the pipeline's notes read: collapsed, graded, swapped, small
 *  faces, unextended, cut pinches) given to `to`, the same mesh rebuilt. */
hoc_status hoc_mesh_copy_record(const hoc_mesh *from, hoc_mesh *to);

/* Steps of hoc_mesh_assemble once the slots are built (poles.c), in order. */
/** One slot per element at each pole slot shared with other faces: the
 *  first element keeps it, each further one gets a copy. */
hoc_status hoc_mesh_split_pole_slots(hoc_mesh *m);
/** Each element's parameters (elem_uv), unwrapped around a regular node;
 *  pole nodes take the mean of the element's regular vertices. */
void hoc_mesh_element_params(hoc_mesh *m);
/** The arbitrary coordinate of each element's pole slot: the element's own
 *  parameter, wrapped into the face's range. */
void hoc_mesh_per_element_pole_params(hoc_mesh *m);

/** After the optimiser moved nodes: each pole slot's arbitrary coordinate
 *  follows its element's other corners again (the mean of theirs, as
 *  hoc_mesh_element_params sets it), so that the mesh measures as it does
 *  when read back. At an apex or a pinch the normal there depends on it. */
void hoc_mesh_pole_params_follow(hoc_mesh *m);

/** Allocate an empty mesh with its arrays for the given sizes. */
hoc_status hoc_mesh_alloc(hoc_model *model, int order, size_t n_nodes, size_t n_elems,
                          hoc_mesh **mesh);

/** The same elements with the nodes of another reference distribution:
 *  each element's parametric map (t on curve edges, (u,v) inside) evaluated
 *  at the new set's reference nodes, mapped onto the CAD. */
/** hoc_mesh_elevate, except that on the faces flagged in face_foot[n_faces]
 *  each new node goes to the foot of the perpendicular from the source
 *  element's point at that node (from a linear element its flat triangle,
 *  from a curved one its polynomial), starting from the parameter-space
 *  place (hoc_cad_face_foot); on a curve along such a face likewise. Where
 *  a face's parametrisation varies within an element (a knot where its
 *  derivative jumps, a stretched patch), nodes straight in (u, v) crowd on
 *  one side and can fold the element; the feet do not depend on the
 *  parametrisation. Elements at a pole, and graded edges at a cusp, keep
 *  the parameter-space rules. */
hoc_status hoc_mesh_elevate_feet(const hoc_mesh *in, int order, hoc_nodeset set,
                                 const unsigned char *face_foot, hoc_mesh **out);
/** The same from straight, in's hoc_mesh_elevate with the same order and
 *  set as made (not moved since): a copy of it with the nodes at the feet
 *  moved (hoc_mesh_move_nodes) instead of a mesh assembled anew (which it
 *  still is where a foot lands on a pole side); the same mesh but for
 *  face_gap, which is the larger of the two placements'. */
hoc_status hoc_mesh_elevate_feet_from(const hoc_mesh *in, const hoc_mesh *straight,
                                      const unsigned char *face_foot, hoc_mesh **out);
/** m (hoc_mesh_elevate of a source) becomes hoc_mesh_elevate_feet of that
 *  source with face_foot = take, its nodes copied from feet, the source's
 *  hoc_mesh_elevate_feet with face_foot flagging at least the faces of
 *  take: the faces' nodes and those of the curves along them. The mesh is
 *  the one a third raise would make, for a copy of nodes; face_gap is the
 *  larger of the two. */
hoc_status hoc_mesh_take_feet(hoc_mesh *m, const hoc_mesh *feet, const unsigned char *take);
/** Where out (a raise of in, order >= 3: the same elements) has edges on
 *  CAD curves, the interior nodes of the elements flagged in
 *  which[n_elems] follow them: each such edge's displacement in (u, v)
 *  from the source element's map (its nodes on the curve against the
 *  map's points there, d_k(s), 0 at the corners) is added to the map at
 *  each interior node, with barycentrics l, as
 *  (l_k + l_{k+1}) d_k(l_{k+1} / (l_k + l_{k+1})): the linear blending of
 *  the edges into the triangle. Nodes on edges stay, as do elements
 *  without such an edge and those with a node at a pole (their map is not
 *  in both parameters); if a moved node lands on a pole side, nothing
 *  moves. */
hoc_status hoc_mesh_blend_interior(const hoc_mesh *in, hoc_mesh *out, const unsigned char *which);
/** The curves whose nodes hoc_mesh_elevate_feet places at the feet with
 *  face_foot = faces: those along the faces' elements, flagged in
 *  curves[n_curves] (set to 1, others left); m of order >= 2. */
void hoc_mesh_feet_curves(const hoc_mesh *m, const unsigned char *faces, unsigned char *curves);
hoc_status hoc_mesh_convert_nodeset(const hoc_mesh *mesh, hoc_nodeset set, hoc_mesh **out);

/** Numbers of the edges between the elements' corners: elem_edge[3 e + k]
 *  is element e's edge k (corner k to k + 1), first[3 e + k] whether e is
 *  the first element using it; edge_line[edge] (room for 3 n_elems + 1) the
 *  first line on it or SIZE_MAX, line_edge[line] its edge or SIZE_MAX (no
 *  element uses it). An edge on no CAD curve that elements of two faces
 *  share has a number on each face (a node lies on one face). */
hoc_status hoc_mesh_edges(const hoc_mesh *mesh, size_t *elem_edge, unsigned char *first,
                          size_t *edge_line, size_t *line_edge, size_t *n_edges);

/** Classified nodes with parameters, grown one at a time (the input of a
 *  hoc_mesh_source being built). */
typedef struct hoc_node_builder {
  size_t n, cap;
  double *par;      /* [cap][2] */
  signed char *dim; /* [cap] */
  int *ent;         /* [cap] */
} hoc_node_builder;

/** Room for n nodes (an upper bound; adding more still works). */
hoc_status hoc_node_builder_reserve(hoc_node_builder *b, size_t n);
/** Append a node; *index receives its number. */
hoc_status hoc_node_builder_add(hoc_node_builder *b, int dim, int entity, double p0, double p1,
                                size_t *index);
void hoc_node_builder_free(hoc_node_builder *b);

/** Evaluate node positions from parameters (all nodes). */
hoc_status hoc_mesh_update_xyz(hoc_mesh *mesh);
/** The same for the nodes flagged in which[n_nodes]. */
hoc_status hoc_mesh_update_xyz_of(hoc_mesh *mesh, const unsigned char *which);

/** Work split for evaluating grouped items on several threads: items
 *  start[g]..start[g+1] of each group g in pieces of at most `size`, each
 *  within one group; pieces[2k] is the group, pieces[2k+1] the first item. */
hoc_status hoc_split_groups(const size_t *start, int n_groups, size_t size, size_t **pieces,
                            size_t *n_pieces);

/** Angle (radians) at CAD vertex `vertex` between curves c[0] and c[1]
 *  (indices), each tangent pointing into its curve towards parameter
 *  t_in[j] (a point of the curve near the vertex): 0 at a cusp. */
hoc_status hoc_curves_angle_at(const hoc_model *model, int vertex, const int c[2],
                               const double t_in[2], double *angle);

/** Unit normals at every slot (oriented by face_orient, NaN-free: at a pole
 *  the normal is the limit along the slot's element, taken just off the
 *  pole at the element's arbitrary coordinate). normal[n_slots][3]. */
hoc_status hoc_mesh_slot_normals(const hoc_mesh *mesh, double *normal);
/** Adds to to[2] the way from element e's local node k to the element's
 *  middle (its corners' mean), in the element's parameters. */
void hoc_mesh_add_inward(const hoc_mesh *m, size_t e, size_t k, double *to);
/** The rule of hoc_mesh_slot_normals for a curve or vertex slot on face f
 *  at parameters uv (its own or a trial's), its node at x: where the face
 *  turns over (its normal by more than 90 degrees) between uv and halfway
 *  along `to` (parameters into the face, toward its elements' middle) at a
 *  line within `tol` (the model's tolerance) of x, *normal (unit, oriented,
 *  in and out) becomes the face's past that line. */
hoc_status hoc_mesh_turned_normal(const hoc_mesh *m, int f, const double *uv, const double *x,
                                  const double *to, double tol, double *normal);
/** The same for the slots flagged in which[n_slots] (all if NULL); the
 *  others' normals are left as they are. */
hoc_status hoc_mesh_slot_normals_of(const hoc_mesh *mesh, const unsigned char *which,
                                    double *normal);

/** Structured triangulation of an analytic model's single face for tests:
 *  nu x nv cells of its parameter domain, split into triangles, order 1. */
hoc_status hoc_mesh_grid_linear(hoc_model *model, int nu, int nv, hoc_mesh **mesh);

/** The optimiser's final polish alone (optimize/polish.c): a pattern
 *  search, node by node in the parametric coordinates, around each element
 *  the exact test finds tangled (when at most 32 are), keeping only moves
 *  that untangle elements or shrink their negative sigma without tangling
 *  a valid one. *untangled: how many it untangled. */
hoc_status hoc_mesh_polish(hoc_mesh *mesh, hoc_measure measure, int fix_curves, size_t *untangled);

/* The most pairs of curves meeting at a cusp that
 * hoc_mesh_elements_at_cusps tells elements bridging (more are ignored). */
#define HOC_CUSP_PAIRS 64

/** at_cusp[e] = 1 for each element flagged in which[e] (every element if
 *  which is NULL) that is at a cusp of the CAD: it has a corner at one
 *  (hoc_mesh_element_cusp, under max_angle_degrees), or it shares a node
 *  with such an element and has corners on both curves of its cusp. The
 *  gap between those curves narrows to nothing at the vertex, so at every
 *  size the elements next to it bridge the gap and follow both curves
 *  (crescent_plate at order 10: the neighbour of a corner element, its
 *  corners 0.05 from the other curve along an edge of 0.47). A curve the
 *  kernel cannot evaluate counts as no cusp. at_cusp[n_elems]. */
hoc_status hoc_mesh_elements_at_cusps(const hoc_mesh *mesh, double max_angle_degrees,
                                      const unsigned char *which, unsigned char *at_cusp);

/** A line of a face's (u, v) that maps to one point (mesh/pinch.c): u = c
 *  (dir 0) or v = c (dir 1). */
typedef struct hoc_pinch {
  int dir;
  double c;
} hoc_pinch;

/** The pinches of face f (at most max, *n of them): iso-lines strictly
 *  inside its range of (u, v) whose image, over the face's whole range of
 *  the other parameter, spreads less than share x the face's size (the
 *  largest side of its box). Narrowest lines searched from 64 probes per
 *  direction. */
hoc_status hoc_face_pinches(const hoc_model *model, int f, double share, hoc_pinch *pinch, int max,
                           int *n);

/** *s: the largest distance of the image of face f's iso-line (dir 0:
 *  u = c, 1: v = c) from its first point, over the face's range of the
 *  other parameter (17 points). */
hoc_status hoc_face_line_spread(const hoc_model *model, int f, int dir, double c, double *s);

/** Whether a face's surface may pinch: any but the analytic kinds, whose
 *  degenerate lines are sides of their (u, v) (poles, apexes). */
int hoc_face_may_pinch(const hoc_cad_face *face);

/** Whether element e's nodes lie on both sides (in their (u, v)) of one of
 *  the n pinches of its face: its curved map passes through the pinch's
 *  point, where its Jacobian vanishes. */
int hoc_mesh_element_crosses_pinch(const hoc_mesh *mesh, size_t e, const hoc_pinch *pinch,
                                   int n);

/** The pinches of a model's faces, searched on first use (each face's at
 *  most once): hoc_face_pinches with `share` and up to `max` per face;
 *  with spread > 0 (0 after init) only lines whose image spreads less than
 *  that too (the share of each face's size lowered to it). */
typedef struct hoc_pinch_table {
  double share, spread;
  int max;
  int *n;          /* [n_faces] pinches found, -1: not searched yet */
  hoc_pinch *line; /* [n_faces][max] */
} hoc_pinch_table;

hoc_status hoc_pinch_table_init(hoc_pinch_table *t, const hoc_model *model, double share,
                                int max);
void hoc_pinch_table_free(hoc_pinch_table *t);

/** At most this many pinches per face are cut (hoc_mesh_cut_pinches), and
 *  a node beside a pinch's point closer to it than HOC_CUT_NEAR of its
 *  longest edge becomes the point (the triangles between it and the point
 *  reach along the pinch's line, and fold there when curved). */
#define HOC_CUT_PINCHES 4
#define HOC_CUT_NEAR 0.1

/** The linear mesh m cut along its faces' pinches (mesh/pinch.c): lines of
 *  a face's (u, v) that map to one point to within the collapse distance
 *  (hoc_mesh_collapse_distance), on faces other than the analytic kinds.
 *  The point becomes a node on the face's boundary curve that crosses the
 *  line, no triangle lies across the line, and the boundary curves' lines
 *  through the point (and the triangles beyond them) are split there.
 *  *out: the cut mesh and *n_cut the pinches cut, or NULL and 0 if none
 *  (also for a higher order, a line that closes inside its face, or one
 *  whose crossings lie farther apart). */
hoc_status hoc_mesh_cut_pinches(const hoc_mesh *m, hoc_mesh **out, int *n_cut);

/** *across: whether element e crosses a pinch of its face (the face
 *  searched through table t if not yet). */
hoc_status hoc_mesh_element_across_pinch(const hoc_mesh *mesh, size_t e, hoc_pinch_table *t,
                                         int *across);

/** Why an order-1 element the measure finds tangled is (mesh/inverted.c). */
typedef enum hoc_inverted_kind {
  HOC_INVERTED_NONE = 0,        /* not tangled */
  HOC_INVERTED_ON_CAD = 1,      /* its normal turns away from the face's at a corner: the
                                   straight triangle is inverted on the surface */
  HOC_INVERTED_AT_SINGULAR = 2, /* valid once the face's normal at a corner where
                                   phi_u x phi_v vanishes (a pole, an apex, a collapsed
                                   B-spline corner) is the limit along the element: the
                                   measure's one normal per slot is another there */
  HOC_INVERTED_ACROSS_FOLD = 3  /* inverted on the CAD, and the face's own normal reverses
                                   inside it (hoc_mesh_element_folds): no straight triangle
                                   across the fold is valid, however small */
} hoc_inverted_kind;

/** *folds: whether the normal phi_u x phi_v of element e's face reverses
 *  inside the (u, v) triangle of its corners (any order): two neighbouring
 *  points of a lattice of 1/8 of the element have opposite normals. A face
 *  folds so where its parametrisation turns back on itself along a curve
 *  (phi_u x phi_v changes sign there), as spline patches with a pinched
 *  strip at a side do (IGES type 114 surfaces converted to B-splines);
 *  points where phi_u x phi_v vanishes are not compared. */
hoc_status hoc_mesh_element_folds(const hoc_mesh *mesh, size_t e, int *folds);

/** kind[e] (hoc_inverted_kind) of each element flagged in tangled[e] (from
 *  hoc_mesh_measure) of an order-1 mesh. */
hoc_status hoc_mesh_inverted_kinds(const hoc_mesh *mesh, const unsigned char *tangled,
                                   unsigned char *kind);

/** Linear surface mesh of the current gmsh model (mesh/linear_gmsh.c). */
hoc_status hoc_mesh_generate_linear_gmsh(hoc_model *model, const hoc_linear_options *options,
                                         hoc_mesh **mesh);

/** gmsh's 2D meshing algorithms (its Mesh.Algorithm): 1 MeshAdapt,
 *  5 Delaunay, 6 Frontal-Delaunay (its default), ... up to 11. */
enum { HOC_GMSH_MESH_ADAPT = 1, HOC_GMSH_DELAUNAY = 5, HOC_GMSH_ALGORITHM_MAX = 11 };

/** hoc_mesh_generate_linear_gmsh with face f meshed by gmsh's 2D algorithm
 *  algorithm[f] (0: gmsh's default); algorithm NULL: the default on every
 *  face. The other faces' meshes do not depend on it: gmsh meshes each face
 *  from the same mesh of the curves. */
hoc_status hoc_mesh_generate_linear_with(hoc_model *model, const hoc_linear_options *options,
                                         const int *algorithm, hoc_mesh **mesh);

/* Grading toward short CAD curves and thin faces (mesh/grading.c). A CAD
 * curve whose length L is below 1 / HOC_LINEAR_SHORT_RATIO of the longest
 * edge at its nodes has slivers along it (q about sqrt(3) / ratio at best:
 * 0.17 at ten; the wing root's blunt trailing edge in wing_fuselage, 0.036
 * long among edges of 5.2: q 0.0065, tangled at order 10); so has a face
 * whose width L across a triangle with its corners on two of its curves is
 * below 1 / ratio of the triangle's longest edge, along all of it. The
 * linear mesh is made again with the size near it HOC_LINEAR_SHORT_SIZE x
 * L (triangles on it of q about sqrt(3) / 5 = 0.35), growing by
 * HOC_LINEAR_GRADE per unit of distance (each ring of elements about three
 * times the last), and kept if it has fewer failed faces, fewer inverted
 * triangles, or as many and a higher smallest q. A gentler grade (0.5) or
 * size (L) makes more of its triangles near the curve better, for up to 16
 * times the elements (impeller_laufrad's 143 short curves alone, among
 * edges a hundred times longer: 3 540 -> 55 558 elements, against 10 488
 * with these). */
#define HOC_LINEAR_SHORT_RATIO 10
#define HOC_LINEAR_SHORT_SIZE 5
#define HOC_LINEAR_GRADE 2
/* The graded mesh is kept only if it has at most this many times the
 * first mesh's elements (as a remeshing's lowered minimum size): where a
 * face curves more than gmsh's sizing follows and the minimum size is
 * low, the field's curvature sizes refine far beyond gmsh's mesh (a wing
 * face remeshed with the minimum lowered to 0.46: 207 triangles from
 * gmsh, 348 557 graded; tests/test_pipeline_remesh_first.c). */
#define HOC_LINEAR_GRADED_GROWTH 4
/* The graded meshing may take this many times the first meshing's time,
 * plus HOC_LINEAR_GRADED_SECONDS, else gmsh's mesh is kept: where a face
 * pinches to a point, the widths of its triangles near the tip, and so
 * the sizes asked there, go to almost nothing, and gmsh's mesher can take
 * far longer than the mesh is worth (surf114 at twice the default size:
 * 3 s, then no graded mesh within 600 s). On ../shared/cad at the default
 * size and twice it, the graded meshing takes 1.5 times the first's at
 * most. */
#define HOC_LINEAR_GRADED_SECONDS 10.0
/* A face under HOC_LINEAR_SMALL_FACE_EDGES x the default minimum size
 * across (the largest side of its box) that gmsh leaves without
 * triangles: its curves got one segment or two, too few to bound a mesh
 * (a sphere of radius 0.5 beside a box 1000 across, minimum size 6.2; a
 * torus 1 across with a tube 0.1 thick beside a cube 50 across, minimum
 * 0.46). Unless the user set the minimum size, the linear mesh is made
 * again with it lowered to the smallest such face's size /
 * HOC_LINEAR_SMALL_FACE_EDGES, and kept if fewer faces fail and it has at
 * most HOC_LINEAR_GRADED_GROWTH times the elements (the torus, 1.08
 * across: a quarter of that, 0.27, still gives its tube's circle two
 * segments and no triangles; 0.25 does, 0.135 serves). */
#define HOC_LINEAR_SMALL_FACE_EDGES 8
/* gmsh extends the sizes of the curves' edges into the faces they bound;
 * where a face holds curves shorter than the minimum size, their edges are
 * shorter still and the extension spreads those sizes over the face,
 * below the minimum (a plate 200 across with 25 bosses of radius 0.15:
 * 1.5 million triangles on its top face, in gmsh 4.8 and 5.0 alike; 1 866
 * without the extension). A mesh with more than HOC_LINEAR_UNEXTENDED x
 * the triangles its faces hold at the minimum size (their area over an
 * equilateral triangle of that edge, plus their sides' length over that
 * edge: a strip narrower than the minimum has triangles all along its
 * sides) is made again without the extension, kept if it has fewer
 * triangles and no more failed faces; the grading (above) then sizes it
 * down to the short curves. */
#define HOC_LINEAR_UNEXTENDED 2

/* Edge swaps of the linear mesh (mesh/swap.c): a swap is made where the
 * smaller q of the two new triangles exceeds the smaller of the two old
 * by this fraction (a strict gain: each swap raises the pair's minimum,
 * so the passes end), in at most this many passes over the edges, each
 * triangle swapped at most once per pass. */
#define HOC_LINEAR_SWAP_GAIN 1e-3
#define HOC_LINEAR_SWAP_PASSES 20

/** Swap the interior edges of linear mesh m (order 1) where that raises
 *  the smaller q of the two triangles on the edge (by HOC_LINEAR_SWAP_GAIN)
 *  and does not lower the smaller q of the two raised to order 2 (edge
 *  middles at the middle in (u, v)): valid triangles (none inverted on
 *  the CAD) of one face on an edge on no CAD curve, with no corner at a
 *  pole, and never into a triangle with
 *  all three corners on one CAD curve (raised, its edges along the curve
 *  meet at 180 degrees). Nodes, slots and lines stay; if the
 *  mesh then measures more elements tangled than before (the normals of
 *  curve slots depend on their elements), it is left as it was.
 *  *n_swapped: the swaps made; min_q (NULL, or [2]): the mesh's min q
 *  before and after. */
hoc_status hoc_mesh_swap_edges(hoc_mesh *m, size_t *n_swapped, double *min_q);

/* Seconds gmsh's mesher may take, by default (hoc_linear_options.
 * mesher_timeout): the whole linear mesh, then each face alone. gmsh's
 * mesher can go on inserting points for ever on a face (a lofted fin whose
 * rounded trailing edge has a radius of about a hundredth of its chord,
 * with each of its algorithms, curvature sizing or not: docs/kernel.md,
 * tests/test_cad_crash.c); the largest linear meshes of the corpus take
 * under 20 s. */
#define HOC_MESHER_TIMEOUT 300.0

/* hoc_mesh_generate_linear without that grading: gmsh's mesh at the
 * options' sizes alone (tests take it as the mesh gmsh makes). */
hoc_status hoc_mesh_generate_linear_ungraded(hoc_model *model, const hoc_linear_options *options,
                                             hoc_mesh **mesh);

/* *mesh (gmsh's, made with these options and algorithms) made again
 * graded down to its short curves and thin faces, if it has any, that
 * meshing finishes in budget seconds (0: no budget; else
 * (*mesh)->graded_budget is set) and its mesh is better (fewer failed
 * faces, fewer inverted triangles, or a higher min q away from poles;
 * HOC_LINEAR_GRADED_GROWTH). */
hoc_status hoc_mesh_grade(hoc_model *model, const hoc_linear_options *options,
                          const int *algorithm, double budget, hoc_mesh **mesh);

typedef struct hoc_linear_grading hoc_linear_grading;
/* The size field of a mesh made again from lin, made by gmsh with sizes
 * hmin..hmax, ncurv elements per 2 pi of curvature radius and face_size's
 * bounds (NULL: none; hoc_linear_options): those sizes, graded down to its
 * curves shorter than 1 / ratio of the edges at their nodes; *g NULL if
 * lin has no such curve. */
hoc_status hoc_linear_grading_make(const hoc_mesh *lin, double ratio, double hmin, double hmax,
                                   double ncurv, const double *face_size,
                                   hoc_linear_grading **g);
void hoc_linear_grading_free(hoc_linear_grading **g);
/* Segments of the short curves and thin faces, the curves, the faces; the
 * shortest curve's length or the least width, the smaller. */
size_t hoc_linear_grading_segments(const hoc_linear_grading *g);
int hoc_linear_grading_curves(const hoc_linear_grading *g);
int hoc_linear_grading_faces(const hoc_linear_grading *g);
double hoc_linear_grading_min_size(const hoc_linear_grading *g);
/* The size at x. */
double hoc_linear_grading_size(const hoc_linear_grading *g, const double *x);

#endif
