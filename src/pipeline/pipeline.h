/* The pipelines of hoc_mesh_model and hoc_mesh_repair: their record of
 * stages, the run they share, and the repairs (repair.c) the drivers
 * (pipeline.c) call. The report and its JSON are in report.c.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#ifndef HOC_PIPELINE_H
#define HOC_PIPELINE_H

#include "core/error.h"

/* The pipelines' tunables, each with the class of problem it serves (the
 * messages and the public docs name their values). ------------------------ */

/* Default refinements: remeshings of the faces of tangled elements before
 * their split (a mesh too coarse for the curvature of its faces folds when
 * curved), splits per chain with a given linear mesh (which is never meshed
 * again), and splits per chain of hoc_mesh_repair (slivers of another
 * mesher's mesh: gmsh 4.8's aircraft at order 3 untangles at the sixth). */
#define HOC_PIPELINE_REMESHINGS 2
#define HOC_PIPELINE_SPLITS_GIVEN_LINEAR 3
#define HOC_PIPELINE_SPLITS_REPAIR 6
/* The repairs' time when hoc_mesh_options.repair_time is 0: where
 * elements stay tangled after the first optimisation, its remeshings,
 * splits and their optimisations may take HOC_PIPELINE_REPAIR_GROWTH
 * times the time to it plus HOC_PIPELINE_REPAIR_SECONDS; then the
 * optimisation under way stops at its best state and the attempt with the
 * fewest tangled elements is kept. A tangled element no repair opens
 * sends the chain through remeshings that multiply the mesh and splits,
 * each followed by a high-order optimisation that tests every step
 * exactly: bench/pinch_models.py's crescent_plate at order 10 keeps 5
 * elements tangled at its cusps through two splits (372 s after a first
 * optimised mesh of 86 s, were it split: HOC_UNREFINABLE_EACH) and two
 * remeshings from 824 elements to 11 586. The growth is the remeshing's
 * (HOC_PIPELINE_REMESH_GROWTH): one remeshing may quadruple the mesh. */
#define HOC_PIPELINE_REPAIR_GROWTH HOC_PIPELINE_REMESH_GROWTH
#define HOC_PIPELINE_REPAIR_SECONDS 60
/* A remeshing bounds the edges on the faces of tangled elements by this
 * fraction of their longest edge, and lowers the minimum size this many
 * times (features below the default minimum size, e.g. the end of a
 * thread), unless the mesh then grows more than HOC_PIPELINE_REMESH_GROWTH
 * times (the curvature sizing then goes finer on every face). */
#define HOC_PIPELINE_REMESH_EDGE 0.5
#define HOC_PIPELINE_REMESH_MIN_SIZE 10
#define HOC_PIPELINE_REMESH_GROWTH 4
/* A remeshing's linear mesh (gmsh's meshings, the grading, the other
 * algorithms' trials) may take HOC_PIPELINE_REMESH_GROWTH times the first
 * linear mesh's time plus this many seconds, within the repairs' time:
 * gmsh's MeshAdapt can go on without end on a face at finer sizes
 * (surf114.igs at order 10: over 300 s on a remeshing whose first linear
 * mesh took 12 s). */
#define HOC_PIPELINE_REMESH_SECONDS 10.0
/* Elements below this fraction of the linear mesh's min q are poor: an
 * untangled result has them optimised once more ("smoothed"), and those at
 * a CAD cusp (two curves meeting under HOC_PIPELINE_CUSP_DEGREES) are
 * named, since curving cannot open them. */
#define HOC_PIPELINE_POOR 0.9
#define HOC_PIPELINE_CUSP_DEGREES 2.0
/* A pinch of a face (hoc_face_pinches) is an iso-line inside its (u, v)
 * whose image spreads less than this share of the face's size: a spline
 * patch whose control row collapses to a point inside it, as a bow tie
 * (bench/freeform_models.py's pinched_sheet: the line maps to one point to
 * 1e-14; surf114.igs's face 1: 0.003 of 90). An element across it is
 * curved through that point and its q falls as the order grows
 * (pinched_sheet: min q 0.52, 0.43 and 0.25 at orders 3, 5 and 10, its
 * linear mesh 0.57): the poor elements' note names them (report.c), at
 * most HOC_PINCHES per face. */
#define HOC_PIPELINE_PINCH_SHARE 1e-3
#define HOC_PINCHES 4
/* hoc_mesh_repair starts from nodes re-placed from the corners unless they
 * tangle over 1/HOC_PIPELINE_REPLACED_SLACK more elements than the input's
 * (another mesher's placement and hocad's fold in different places). */
#define HOC_PIPELINE_REPLACED_SLACK 10
/* From this order on, the optimiser starts from a coarser solution: the
 * linear mesh raised to HOC_PIPELINE_COARSE_ORDER and optimised there
 * ("coarse"), then raised to the order asked ("re-raised"). A high order
 * raised from straight triangles folds wherever a face curves more than
 * its elements (the gear at order 10: 146 tangled straight in (u, v), 5
 * with the interiors blended with the curved edges, see below); raised
 * from the optimised order 3 it starts from curved elements that fit (3
 * tangled) near the optimum, and order 3 untangles at a sixth of the cost
 * per sweep. If the coarse optimisation leaves elements tangled, the
 * direct raise is used. */
#define HOC_PIPELINE_COARSE_FROM 6
/* Every raise (hoc_pipeline_raise) places the new nodes straight in each
 * face's (u, v). From order 3 the interior nodes of each element with an
 * edge on a CAD curve then follow that edge: its displacement from the
 * source element's (u, v) map is blended into the element
 * (hoc_mesh_blend_interior), kept per element where that makes the element
 * valid or raises its q; again after the feet, on the elements along the
 * curves whose nodes went to them. An element along a curve that bends
 * more than the element is wide has its edge nodes on the curve and its
 * interior nodes, straight in (u, v), beyond that edge: it folds
 * (gear_f360 raised to order 5: 115 elements folded straight, 5 blended;
 * at order 10 146 and 5; test: tests/test_mesh_blend.c). Then, on the
 * faces where the raise tangles elements or lowers the
 * face's min q by more than this share against the source, a second time
 * at the feet of the source elements' points (hoc_mesh_elevate_feet_from),
 * and such a face takes the feet where they tangle fewer of its elements,
 * or as many and raise its min q by more than this share. The feet exist
 * to undo a loss the parametrisation causes: where straight in (u, v)
 * loses nothing, they are not tried. Straight in (u, v) is the better
 * start where the parametrisation is even and the elements coarse against
 * the curvature (feet of a flat triangle crowd toward its middle); the
 * feet where the parametrisation varies within an element
 * (fuselage_occ28366: a knot at u = 2 where |phi_u| halves, every element
 * across it folded at order 10). */
#define HOC_PIPELINE_FOOT_GAIN 0.01
#define HOC_PIPELINE_COARSE_ORDER 3
/* From this order on, tangled elements left on faces that do not fold
 * have their faces meshed again before any split (hocad mesh, rule 4).
 * At such orders they are elements in which the surface bends more than
 * order p follows: their coarse optimum is valid, raised to p they fold
 * between their nodes. Split children, placed straight in the parent's
 * (u, v), fold again, and each split's local optimisation tests every
 * step exactly (one to three seconds per sweep at orders 8 to 10); a
 * remeshing lets the curvature sizing go finer and starts again at the
 * coarse order, where optimising is cheap. At order 8 (split first ->
 * remesh first): the D150 airliner 0 tangled but min q 0.0008 < 0.9 x
 * linear in 205 s -> bounds met in 169 s; wing_fuselage no result in
 * 480 s -> 1 tangled in 363 s; t106_turbine_blade 2 tangled in 830 s ->
 * 2 in 352 s. It costs more where a few local splits were enough:
 * fuselage_occ28366 at order 10, met in 446 s -> no result in 600 s
 * (each remeshing repeats a whole order-10 optimisation). */
#define HOC_PIPELINE_REMESH_FIRST_FROM HOC_PIPELINE_COARSE_FROM
/* A split of an optimised mesh is optimised locally: only the nodes of the
 * split's children and of HOC_PIPELINE_LOCAL_RINGS rings of elements
 * around them move (the rest of the mesh is where the first optimisation
 * left it), as do the poor elements of "smoothed". A whole optimisation
 * per split repeats the first one's cost for a few elements: at order 10
 * tens of minutes, at order 5 on repatch_hpdc (7 910 elements, two left
 * tangled) 65 s per split against 2-10 s locally. */
#define HOC_PIPELINE_LOCAL_RINGS 2

/* gmsh's 2D algorithms (mesh/mesh.h) the faces holding linear triangles
 * inverted on the CAD are meshed again with, in turn (hoc_repair_linear;
 * the T106 blade's face 2 at the default size: 2 inverted with gmsh's
 * default Frontal-Delaunay, 0 with MeshAdapt, 4 with Delaunay). */
#define HOC_PIPELINE_LINEAR_ALGORITHMS                                                             \
  { HOC_GMSH_MESH_ADAPT, HOC_GMSH_DELAUNAY }

/* Splits per chain where no finer mesh opens the tangled elements and
 * some of them neither cross a fold nor are at a cusp
 * (hoc_repair_tangled_unrefinable): a split adds elements across a fold
 * (surf114.igs, its inverted linear elements split: 29, 67, 148), and each
 * split's optimisation keeps the ones across it tangled to its last sweep. */
#define HOC_PIPELINE_FOLD_SPLITS 1

/* The most stages one attempt has: linear, high-order, split, optimized,
 * smoothed, written (hoc_mesh_repair: input, re-placed or split, optimized). */
enum { HOC_PIPELINE_MAX_STAGES = 6 };

/* A stage with the optimiser's whole result (when stage.optimized). */
typedef struct hoc_stage_record {
  hoc_stage stage;
  hoc_optimize_result result;
} hoc_stage_record;

/* The stages of an attempt and the refinements made. A value: an attempt
 * (a split on a copy, a remeshing) works on a copy, kept or dropped whole. */
typedef struct hoc_stages {
  hoc_stage_record s[HOC_PIPELINE_MAX_STAGES];
  int n;
  int refinements; /* times tangled elements were meshed again finer (their faces, or split) */
  int remeshings;  /* of those, remeshings of faces */
} hoc_stages;

/* Most findings a report holds: the tangled elements, the cusps. */
enum { HOC_REPORT_MAX_FINDINGS = 4 };

/* The public hoc_report. */
struct hoc_report {
  const char *command; /* "mesh", "optimize" or "quality" */
  hoc_measure measure;
  hoc_stages r;   /* the result's stages */
  double seconds; /* the whole run: its stages, attempts not kept, measuring */
  size_t elements, nodes;
  double *quality;  /* [elements] q of the result */
  int failed_faces; /* faces the linear mesher could not mesh */
  size_t n_findings;
  hoc_event_kind finding_kind[HOC_REPORT_MAX_FINDINGS];
  char *finding[HOC_REPORT_MAX_FINDINGS];
  hoc_mesh *linear, *raised; /* keep_stages: owned */
};

/* A running pipeline: its options, with the defaults resolved, and the
 * time its repairs end (hoc_now(); 0: not started or no bound). */
typedef struct hoc_run {
  hoc_mesh_options o;
  double deadline;
  double budget; /* the seconds the repairs were given */
  int *cut;      /* NULL, or set to 1 once the limit skipped or stopped a repair */
} hoc_run;

/* The repairs' time starts now, `first` seconds after the run's start
 * (hoc_mesh_options.repair_time; once per run). */
void hoc_run_start_repairs(hoc_run *run, double first);

/* 1 if the repairs' time is over; the caller then skips a repair (and
 * the run records that the limit cut it). */
int hoc_run_late(const hoc_run *run);

/* A note that the repairs' time cut a repair, if it did. */
hoc_status hoc_run_note_late(const hoc_run *run);

/** The source mesh raised to `order` with the run's node set: straight in
 *  (u, v), or at the feet on the faces where that does better
 *  (HOC_PIPELINE_FOOT_GAIN), by the run's measure. q: NULL, or [elements
 *  of in] the q of each element of *out. */
hoc_status hoc_pipeline_raise(const hoc_run *run, const hoc_mesh *in, int order, hoc_mesh **out,
                              double *q);

/* The last stage of r (r->n >= 1). */
static inline hoc_stage_record *hoc_stages_last(hoc_stages *r) { return &r->s[r->n - 1]; }

/* Tell the caller (run->o.event) of an event with a printf-style message;
 * HOC_ERR_INTERRUPTED if the caller cancels. */
hoc_status hoc_run_event(const hoc_run *run, hoc_event_kind kind, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

/* Measure `mesh` as a new stage `name` (a static string) of r, made in
 * `seconds`, and tell the caller. q: NULL, or [elements] q of each element
 * by the run's measure, known already (the stage's measure_seconds are then
 * 0); result: NULL, or the optimiser's result the stage is. */
hoc_status hoc_run_stage(const hoc_run *run, hoc_stages *r, const char *name, const hoc_mesh *mesh,
                         double seconds, const double *q, const hoc_optimize_result *result);

/* Repairs (repair.c) ------------------------------------------------------ */

/* The optimiser on mesh, in place, as a new stage `name` of r. free:
 * NULL, or [elements] flags of the elements whose nodes (and those of two
 * rings around them) alone may move. */
hoc_status hoc_repair_optimize(const hoc_run *run, hoc_stages *r, const char *name, hoc_mesh *mesh,
                               const unsigned char *free);

/* hoc_repair_optimize of the whole mesh for a mesh that is the start of a
 * costlier optimisation (the coarse order): every phase of it converges
 * by the first phase's rule (hoc_mesh_optimize_until's full). */
hoc_status hoc_repair_optimize_start(const hoc_run *run, hoc_stages *r, const char *name,
                                     hoc_mesh *mesh);

/* The optimiser from the input's high-order nodes or from nodes re-placed
 * from its corners (hoc_mesh_repair); *mesh becomes the result, *start (if
 * start is not NULL) the mesh it was optimised from. */
hoc_status hoc_repair_optimize_starts(const hoc_run *run, hoc_stages *r, hoc_mesh **mesh,
                                      hoc_mesh **start);

/* The two chains of splits from the optimised *mesh (see repair.c); *mesh
 * and *r become the result with the fewest tangled elements. trial: the
 * caller decides what it keeps (no closing note). */
hoc_status hoc_repair_refine_tangled(const hoc_run *run, hoc_stages *r, int n_keep, hoc_mesh **mesh,
                                     const hoc_mesh *start, int trial);

/* hoc_repair_refine_tangled on a copy of *ho, kept (*done = 1) only if it
 * leaves no element tangled; with unrefinable (hoc_repair_tangled_unrefinable's
 * nonzero answer, named in the event), at most HOC_PIPELINE_FOLD_SPLITS splits
 * per chain, kept if they leave fewer tangled than *ho has, and *done = 1
 * either way; none with HOC_UNREFINABLE_EACH. */
hoc_status hoc_repair_split_first(const hoc_run *run, hoc_stages *r, hoc_mesh **ho, int unrefinable,
                                  int *done);

/* Inverted linear triangles: gmsh's mesh of some B-spline faces has
 * straight triangles whose normal turns against the face's at a corner
 * (hoc_mesh_inverted_kinds: HOC_INVERTED_ON_CAD, away from a fold of the
 * face), which the optimiser carries into the curved mesh and seldom
 * undoes. The faces holding them are meshed again with gmsh's MeshAdapt,
 * then (for those still inverted) its Delaunay algorithm; each face keeps
 * the mesh with the fewest such elements (its own on a tie: a mesh without
 * them is never meshed again). *lin (order 1, meshed with lo) becomes the
 * result. Elements across a fold of their face (HOC_INVERTED_ACROSS_FOLD)
 * are only named: no mesh of the face avoids them. */
hoc_status hoc_repair_linear(const hoc_run *run, hoc_model *model, const hoc_linear_options *lo,
                             hoc_mesh **lin);

/* Where a finer mesh cannot open the tangled elements, *why says why
 * (HOC_UNREFINABLE_FOLDS | _CUSPS | _PINCHES), else it is 0: mesh has
 * tangled elements, and every face holding one
 * - folds (an element of it crosses a fold: hoc_mesh_element_folds). A
 *   finer mesh crosses the fold with more elements (surf114.igs: 26 linear
 *   elements across folds of faces 1, 3 and 4; splitting the inverted ones
 *   twice makes 148);
 * - or has a tangled element across a pinch of the face (hoc_face_pinches:
 *   a line of its (u, v) that maps to one point, within the collapse
 *   distance). A split's children cross the line again, and a finer mesh
 *   crosses it with more elements: only nodes on the line avoid them
 *   (pinched_sheet's mesh not cut, hoc_mesh_cut_pinches);
 * - or has all its tangled elements at a CAD cusp, where two curves meet
 *   under HOC_PIPELINE_CUSP_DEGREES (hoc_mesh_elements_at_cusps: a corner
 *   there, or next to such an element across the gap between the curves).
 *   The curved corner keeps the cusp's angle at every size, and the gap
 *   narrows to nothing (bench/pinch_models.py's crescent_plate at order 4
 *   with one sweep: 3 tangled at its cusps; remeshing gives 8, then 6).
 * These faces are never meshed again finer. HOC_UNREFINABLE_EACH is set
 * too where each tangled element itself crosses a fold or a pinch, or is
 * at a cusp, and none crosses a neck (a line whose image spreads less than
 * HOC_PIPELINE_PINCH_SHARE of the face but more than the collapse
 * distance: a fold along it has an image as short, and a split's children
 * meet it at a node; surf114_face3.brep at order 2, tests/test_mesh_pinch.c):
 * those are not split either (crescent_plate at order 10: a split per
 * chain took 372 s and left the same 5 tangled; surf114.igs at order 5:
 * 54 s, no fewer). A split serves the others: the element next to a fold
 * at the bottle's thread (face 4 of occt_bottle.brep, whose boundary
 * curls over) untangles when split. */
enum {
  HOC_UNREFINABLE_FOLDS = 1,
  HOC_UNREFINABLE_CUSPS = 2,
  HOC_UNREFINABLE_EACH = 4,
  HOC_UNREFINABLE_PINCHES = 8
};
hoc_status hoc_repair_tangled_unrefinable(const hoc_run *run, const hoc_mesh *mesh, int *why);

/* The faces of the tangled elements of ho (made from lin) get an edge
 * length bound of half their longest edge in *face_size (allocated on first
 * use); r starts again. */
hoc_status hoc_repair_refine_faces(const hoc_run *run, hoc_stages *r, const hoc_model *model,
                                   const hoc_mesh *lin, const hoc_mesh *ho, double **face_size);

/* Elements of an untangled optimised *mesh below 0.9 x the linear mesh's
 * min q optimised once more with two rings around them ("smoothed"), kept
 * if that raises the min q. */
hoc_status hoc_repair_smooth_low(const hoc_run *run, hoc_stages *r, hoc_mesh **mesh);

/* Reports (report.c) ------------------------------------------------------ */

/* An empty report of `command` ("mesh", "optimize", "quality"). */
hoc_status hoc_report_create(const char *command, hoc_measure measure, hoc_report **report);

/* What hoc_report_finish looks for. */
typedef enum hoc_findings {
  HOC_FIND_NOTHING = 0,  /* hocad quality: the stages only */
  HOC_FIND_TANGLED = 1,  /* tangled elements, and why */
  HOC_FIND_FROM_CAD = 2, /* with TANGLED: a finer linear mesh is possible (the advice says so) */
  HOC_FIND_POOR = 4      /* elements below 0.9 x the linear mesh's min q at a CAD cusp or a pinch */
} hoc_findings;

/* Fill the report with the stages r of the result `final`: its size, its q
 * and the findings asked for (hoc_findings flags), and the run's seconds
 * since t0 (hoc_now at its start). */
hoc_status hoc_report_finish(hoc_report *report, const hoc_stages *r, const hoc_mesh *final,
                             int findings, double t0);

#endif
