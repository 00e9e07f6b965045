/* Internals of the optimiser (hoc_mesh_optimize, hoc_mesh_polish,
 * hoc_mesh_check_gradient): simultaneous untangling and smoothing in
 * parametric coordinates (the paper's Section 4).
 *
 * Objective: f(z) = sum_e sum_q r_eq^2, r_eq = sqrt(w_q) (eta(x~_q) - 1), the
 * quadrature of sum_e int_{t_I} (eta - 1)^2 (weights normalised per element),
 * with sigma replaced by sigma_delta = (sigma + sqrt(sigma^2 + 4 delta_e^2))/2
 * on tangled elements and their neighbours (Escobar et al.), where the
 * nodes also count as sample points (Definition 2 asks det > 0 there).
 * Unknowns z: (u, v) of face-interior nodes, t of nodes on CAD curves.
 * Positions x(z) = phi(u, v) or c(t) are always CAD evaluations.
 *
 * Solver: nonlinear block Gauss-Seidel. Each sweep visits the natural
 * blocks of the high-order mesh: each vertex of the linear mesh (a
 * face-interior vertex carries the high-order nodes of its star along,
 * displaced in (u,v) by their barycentric weight, so the star moves as a
 * whole), the nodes inside each element edge, and the nodes inside each
 * element; then every free node on its own (the two families reach
 * different places: blocks untangle high orders, single nodes let curve
 * vertices slide where a block's compromise stalls). A block takes a damped
 * Gauss-Newton step on the elements it touches (a small dense system),
 * followed by a backtracking line search that rejects any step that tangles
 * a valid element, folds an element in the parameter plane (so no node
 * leaves its face's domain) or reorders nodes along a curve. Blocks are
 * coloured so that blocks of a colour touch no common element: they are
 * updated in parallel and the result does not depend on the thread count.
 * A block whose step lowers f by less than a small share of f goes to
 * sleep; the iteration ends when every block sleeps.
 *
 * Two phases: the tangle test first looks at samples (quadrature points,
 * nodes, the order-2p lattice); once they say untangled, the exact fold
 * tests of measuring (Bernstein coefficients, quality.h) may still find
 * folds between them, and the sweeps go on with the exact test in every
 * verdict, residuals at dense edge points, and in each element that only
 * the exact tests find folded a residual at the point where they found
 * sigma < 0 (phases.c).
 *
 * Files: setup.c (adjacency, unknowns, state), blocks.c (block families,
 * carried nodes, colours, queues), objective.c (element residuals, the
 * state at a sweep's start, screening), trial.c (trial parameters, CAD
 * evaluation, commit), step.c (block model, damped solve, line search of a
 * colour), phases.c (a run: its sweeps and phases), polish.c, driver.c
 * (hoc_mesh_optimize, the protected run, snapshots), gradcheck.c;
 * tunables.h holds every threshold.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef HOC_OPTIMIZE_IMPL_H
#define HOC_OPTIMIZE_IMPL_H

#include "mesh/mesh.h"
#include "optimize/tunables.h"
#include "quality/quality.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>

/* hoc_opt_blockset.node_block of a node in no block; the end of a queue. */
#define HOC_OPT_NO_BLOCK UINT32_MAX

/* A family of blocks: each block a set of free nodes updated together.
 * Node, element and list indices are 32-bit (hoc_opt_setup checks the
 * mesh's sizes): the lists of single-node blocks hold several entries per
 * node of the mesh, most of the optimiser's memory at high orders. */
typedef struct hoc_opt_blockset {
  size_t n_blocks;
  uint32_t *bn_start, *bn_node; /* block -> its nodes (bn_start NULL: block b is node bn_node[b]) */
  uint32_t *be_start, *be_elem; /* block -> the elements it touches (be_start NULL: block b's are
                                   node bn_node[b]'s in the adjacency, ne_start, and be_elem is
                                   hoc_opt_adjacency.ne_elem) */
  const uint32_t *ne_start;     /* (hoc_opt_adjacency.ne_start where be_start is NULL) */
  uint32_t *bd_start;           /* block -> first of its unknowns */
  uint32_t *node_block;         /* [n_nodes] block of a free node (HOC_OPT_NO_BLOCK if fixed) */
  uint16_t *node_off;           /* [n_nodes] offset of the node's unknowns in its block
                                   (NULL: every block is a single node, offset 0) */
  uint32_t *carry_start;        /* [n_blocks+1] nodes a vertex block carries (NULL: none) ... */
  uint32_t *carry_node;
  uint16_t *carry_code; /* ... and their weights, as corner * np + local node of the element
                           they were found in (hoc_opt_carry_w) */
  int max_nd;      /* most unknowns in a block */
  int n_colors;
  size_t *color_start; /* [n_colors+1] */
  uint32_t *color_block;
  /* The block's place among its colour's blocks and the first of its
   * unknowns among theirs: where its trial values are (hoc_opt_trial) */
  uint32_t *cpos, *cbd;       /* [n_blocks] */
  size_t max_color, max_color_nd; /* most blocks and unknowns in a colour */
  /* Blocks woken since their colour last ran, per colour (most sleep: a
   * colour then looks at these instead of all its blocks) */
  uint16_t *block_color;   /* [n_blocks] (hoc_opt_build_blocks checks the colours' count) */
  uint32_t *queue_head;    /* [n_colors] first queued block, HOC_OPT_NO_BLOCK if none */
  uint32_t *queue_next;    /* [n_blocks] next in its colour's queue */
  unsigned char *queued;   /* [n_blocks] */
  unsigned char *scan_all; /* [n_colors] every block may be active: look at all */
} hoc_opt_blockset;

/* Adjacency and unknowns: fixed once set up. */
typedef struct hoc_opt_adjacency {
  unsigned char *ndof; /* [n_nodes] unknowns of the node: 0, 1 (t) or 2 (u, v) */
  uint32_t *ne_start; /* [n_nodes+1] node -> elements (32-bit, as the block lists) */
  uint32_t *ne_elem;  /* element */
  uint16_t *ne_local; /* local index of the node in it */
  uint32_t *ns_start; /* [n_nodes+1] node -> slots */
  uint32_t *ns_slot;
  uint32_t *nl_start; /* [n_nodes+1] node -> lines */
  uint32_t *nl_line;
  double *elem_h;             /* [n_elems] longest edge of the element's corners (hoc_opt_hsize) */
  unsigned char *on_boundary; /* [n_elems] has a node on a CAD curve or vertex: kept unfolded in
                                 (u,v) so no node leaves the trimmed face (inside, 3D validity
                                 of the neighbours is the barrier) */
  unsigned char *touched;     /* [n_elems] has a node that may move (NULL: no node is held by
                                 hoc_optimize_options.free_elements) */
} hoc_opt_adjacency;

/* Per-element state, as of the last hoc_opt_sweep_start unless said
 * otherwise. */
typedef struct hoc_opt_elements {
  double *fe, *qe;           /* [n_elems] objective part and q */
  unsigned char *valid;      /* [n_elems] not tangled (Definition 2); kept up to date as
                                blocks move */
  unsigned char *pvalid;     /* [n_elems] not folded in the (u,v) plane (as valid) */
  unsigned char *xvalid;     /* [n_elems] valid by the exact test too (as valid): a guarded
                                element's step may not fold it between samples (one folded
                                there already may stay so for a while) */
  unsigned char *fragile;    /* [n_elems] guarded as in a protected run (see mark_fragile) */
  unsigned char *region;     /* [n_elems] tangled or next to a tangled element: regularised,
                                and free to pass through sigma = 0 while untangling stalls */
  unsigned char *was_region; /* [n_elems] region of the previous sweep */
  unsigned char *dirty;      /* [n_elems] a node moved since the last hoc_opt_sweep_start */
  double *delta;             /* [n_elems] regularisation of the sweep */
  double *delta_own;         /* [n_elems] regularisation from the element's own tangling */
  unsigned char *has_fold;   /* [n_elems] tangled by the exact tests alone (exact phase): */
  double *fold_rs;           /* [n_elems][2] a point where they find sigma < 0, a residual there */
  unsigned char *near_e;     /* [n_elems] (scratch of hoc_opt_mark_near) */
} hoc_opt_elements;

/* Per-node (and per-slot) state. */
typedef struct hoc_opt_nodes {
  double *dz;            /* [n_nodes][6] dx/dz: (phi_u, phi_v) or (c', 0) */
  double *normal;        /* [n_slots][3] unit CAD normal at each slot, oriented */
  unsigned char *active; /* [n_nodes] awake: its blocks take steps */
  unsigned char *near;   /* [n_nodes] within HOC_OPT_NEAR_RINGS elements of a tangled one */
  unsigned char *moving; /* [n_nodes] use the trial state of this node */
} hoc_opt_nodes;

/* Settings of the run and its current phase. */
typedef struct hoc_opt_settings {
  int protect;        /* a protected run (see hoc_mesh_optimize): every element guarded */
  int exact;          /* the tangle test with the exact fold tests, and dense edge
                         residuals while untangling (the exact phase) */
  int relax_uv;       /* second attempt: relaxed elements may fold in (u, v) too */
  int local;          /* only blocks with a node near a tangled element move (the exact
                         phase while some element is tangled) */
  double eps;         /* regularisation scale of tangled elements (relative to their size) */
  double min_gain;    /* per node: a step that lowers f by less puts the block to sleep */
  double wake_factor; /* a move must gain this many times min_gain to wake its neighbours */
  int wake_near_only; /* the untangling factor only for blocks with a node in node.near */
} hoc_opt_settings;

/* Trial state of the blocks of a colour and of their nodes. A block's
 * values are at its place in its colour (hoc_opt_blockset.cpos, cbd): the
 * arrays hold one colour's blocks, not every block of the mesh. */
typedef struct hoc_opt_trial {
  double *step;         /* [unknowns of a colour] Gauss-Newton direction of each block */
  double *alpha;        /* [blocks of a colour] step length */
  double *f0, *fnew;    /* [blocks of a colour] local objective before / after */
  double *slope;        /* [blocks of a colour] g . step (< 0) */
  unsigned char *state; /* [blocks of a colour] 0 idle, 1 trying, 2 accepted */
  size_t *list;         /* [blocks of a colour] scratch */
  size_t *committed;    /* [blocks of a colour] blocks of the current colour that moved */
  /* The trial state of the nodes being tried (a colour's blocks, a polish
   * move): node k's at index tix[k] of the arrays below, its slots from
   * tsbase[tix[k]] on, in the order of adj.ns_slot (hoc_opt_trial_reserve).
   * Sized for the nodes of one trial, not the mesh: at high orders the
   * mesh's nodes and slots are many, a colour's a small share of them. */
  uint32_t *tix;        /* [n_nodes] the node's index in the current trial */
  size_t cap, scap;     /* nodes and slots the arrays hold */
  double *tpar;         /* [cap][2] trial parameters */
  double *txyz;         /* [cap][3] */
  double *tdz;          /* [cap][6] */
  size_t *tsbase;       /* [cap] first trial slot of the node */
  double *tslot_uv;     /* [scap][2] */
  double *tnormal;      /* [scap][3] */
} hoc_opt_trial;

/* Frames of elements (hoc_element_frames: D phi's columns and the
 * interpolated normal at every sample point), kept between the evaluations
 * of a sweep: a block's model reads them instead of recomputing them from
 * every node of the element, and an accepted step moves them by its nodes'
 * changes only. So a single node's visit costs in proportion to the points
 * of its elements (p^2), not to points times nodes (p^4). Refreshed from
 * the nodes at every sweep's start for the elements that moved. When the
 * pool holds every element a free node can change, each keeps its place;
 * otherwise the places go at each sweep's start to the elements of awake
 * nodes, in element order (hoc_opt_frames_assign): after the first sweeps
 * few nodes are awake, and those are the ones visited again and again. */
typedef struct hoc_opt_frames {
  int npts;       /* points per element (hoc_element_frame_points) */
  size_t cap;     /* elements the pool holds */
  int dynamic;    /* the pool holds fewer than the elements a free node can change */
  size_t *slot;   /* [n_elems] the element's place in the pool, SIZE_MAX if not kept */
  size_t *owner;  /* [cap] the element at each place, SIZE_MAX if none (dynamic) */
  size_t *fresh;  /* [cap] elements given a place at this sweep's start (dynamic) */
  unsigned char *want; /* [n_elems] scratch of hoc_opt_frames_assign (dynamic) */
  double *pool;   /* [cap][9][npts] */
} hoc_opt_frames;

/* Saved states of a run (journal.c): at most this many at once. */
#define HOC_OPT_JOURNALS 2
struct hoc_opt_journal;

/* The optimiser's state. */
typedef struct hoc_opt {
  hoc_mesh *m;
  const hoc_model *model;
  const hoc_quality_tables *t;
  hoc_measure measure;
  int np, nq;
  hoc_opt_adjacency adj;
  hoc_opt_blockset fam[2]; /* 0: vertices (with carried stars), edges, interiors; 1: single nodes */
  hoc_opt_blockset *B;     /* the family being swept */
  int max_nd;              /* most unknowns in a block of either family */
  size_t max_foot;         /* most elements a block of either family touches */
  hoc_opt_elements el;
  hoc_opt_nodes node;
  hoc_opt_settings cfg;
  hoc_opt_trial trial;
  hoc_opt_frames fc;
  struct hoc_opt_journal *journal[HOC_OPT_JOURNALS]; /* the saved states that log moves */
  size_t journal_entry_max; /* doubles of the largest node entry of a journal (0: not yet
                               known) */
} hoc_opt;

typedef struct hoc_opt_scratch {
  double *x, *n, *r, *J, *uv, *Jz, *H, *g, *L;
  double *fr;        /* [max_foot][9][npts] trial frames of a block's elements */
  double *w;         /* [np] hoc_opt_block_model: a node's weight in the block, */
  int *off;          /* its first unknown, */
  unsigned char *nd; /* and its unknowns (0: not moved by the block) */
} hoc_opt_scratch;

/* A growable array of indices. */
typedef struct hoc_growlist {
  size_t *v;
  size_t n, cap;
} hoc_growlist;

/* Parameter pairs kept where they differ from what the rest of a
 * snapshot gives: item at[k] has the values uv[2k], uv[2k + 1]. */
typedef struct hoc_opt_uv_list {
  size_t *at;
  double *uv;
  size_t n, cap;
} hoc_opt_uv_list;

/* The mesh state the optimiser changes (node parameters and positions, slot
 * and element parameters, line ends), kept while untangling so that a run
 * that ends with more tangled elements than it once had returns the best
 * state reached: a raised regularisation lets valid neighbours of a fold
 * pass through sigma = 0, which does not always pay off. Kept compactly,
 * since a mesh of order 10 has about 50 nodes per element: the nodes'
 * parameters and the lines' ends whole; a slot's parameters only where
 * they differ from its node's (curve and vertex nodes, pole slots), an
 * element's copy of a node's parameters only where it differs from its
 * slot's (unwrapped across a seam); positions not at all: restoring
 * evaluates them from the parameters for the nodes that moved since. */
typedef struct hoc_opt_snapshot {
  double *param, *line_t;
  hoc_opt_uv_list slot_uv, elem_uv;
  size_t tangled; /* SIZE_MAX: none taken */
  double objective;
} hoc_opt_snapshot;

/* A saved state of a run kept as the old values of the nodes that moved
 * since (journal.c): hoc_opt_commit logs a node before its first move.
 * The state itself is the mesh's with the log written back. */
typedef struct hoc_opt_journal {
  unsigned char *saved; /* [n_nodes] the node is in the log */
  size_t *node, *off;   /* log: node, and the first of its values in vals */
  double *vals;
  size_t n, cap, nv, vcap;
  hoc_opt_snapshot copy; /* frozen: every node's state when the log grew too large */
  int frozen;            /* the copy is taken: nothing more is logged */
  int broken;            /* out of memory while logging: cannot be restored */
  size_t tangled;        /* SIZE_MAX: none taken */
  double objective;
} hoc_opt_journal;

/* Block b's nodes bn_node[begin .. end) and elements be_elem[begin .. end):
 * single-node blocks keep no lists of their own (at order 10 a mesh has
 * 50 nodes per element, and these lists would be 77 MB for nist_ftc_07). */
static inline size_t hoc_opt_bn_begin(const hoc_opt_blockset *B, size_t b) {
  return B->bn_start ? B->bn_start[b] : b;
}
static inline size_t hoc_opt_bn_end(const hoc_opt_blockset *B, size_t b) {
  return B->bn_start ? B->bn_start[b + 1] : b + 1;
}
static inline size_t hoc_opt_be_begin(const hoc_opt_blockset *B, size_t b) {
  return B->be_start ? B->be_start[b] : B->ne_start[B->bn_node[b]];
}
static inline size_t hoc_opt_be_end(const hoc_opt_blockset *B, size_t b) {
  return B->be_start ? B->be_start[b + 1] : B->ne_start[B->bn_node[b] + 1];
}

/* Offset of node k's unknowns in its block of B. */
static inline int hoc_opt_node_off(const hoc_opt_blockset *B, size_t k) {
  return B->node_off ? B->node_off[k] : 0;
}
/* The nodes block b of B carries: carry_node[begin .. end). */
static inline size_t hoc_opt_carry_begin(const hoc_opt_blockset *B, size_t b) {
  return B->carry_start ? B->carry_start[b] : 0;
}
static inline size_t hoc_opt_carry_end(const hoc_opt_blockset *B, size_t b) {
  return B->carry_start ? B->carry_start[b + 1] : 0;
}

/* Whether a loop over n blocks or elements of o is worth a team of
 * threads (tunables.h, HOC_OPT_PARALLEL_WORK). */
static inline int hoc_opt_parallel(const hoc_opt *o, size_t n) {
  return n > HOC_OPT_PARALLEL_CHUNK &&
         (double)n * (double)o->np * (double)o->nq >= HOC_OPT_PARALLEL_WORK;
}

/* Block b's (of o->B) place in the trial's per-block arrays, and its step. */
static inline size_t hoc_opt_tb(const hoc_opt *o, size_t b) {
  return o->B->cpos[b];
}
static inline double *hoc_opt_step_of(const hoc_opt *o, size_t b) {
  return o->trial.step + o->B->cbd[b];
}

/* Local length of node k: the longest edge of the corners of its elements,
 * a bound on one step's displacement (kept per element: at high orders
 * nodes outnumber elements 50 to 1). */
static inline double hoc_opt_hsize(const hoc_opt *o, size_t k) {
  double h = 0;
  for (size_t a = o->adj.ne_start[k]; a < o->adj.ne_start[k + 1]; ++a)
    h = fmax(h, o->adj.elem_h[o->adj.ne_elem[a]]);
  return h;
}

/* Element e may not fold between the samples (its steps run the exact
 * tests): every element of a protected run, the fragile ones of any run. */
static inline int hoc_opt_guarded(const hoc_opt *o, size_t e) {
  return o->cfg.protect || o->el.fragile[e];
}

static inline void hoc_opt_cross(const double *a, const double *b, double *c) {
  c[0] = a[1] * b[2] - a[2] * b[1];
  c[1] = a[2] * b[0] - a[0] * b[2];
  c[2] = a[0] * b[1] - a[1] * b[0];
}

/* setup.c: adjacency, unknowns, state arrays ---------------------------- */

/* Clears *o and sets it up for mesh m: adjacency, each node's unknowns (only
 * the nodes of free_elements and free_rings rings around them if given),
 * both block families, every state array. */
hoc_status hoc_opt_setup(hoc_opt *o, hoc_mesh *m, hoc_measure measure, int fix_curves,
                         const unsigned char *free_elements, int free_rings);
void hoc_opt_free(hoc_opt *o);
/* Derivatives dx/dz of every free node and the normals of every slot. */
hoc_status hoc_opt_eval_all(hoc_opt *o);
/* Compressed rows: start[n+1] and items[total] allocated; counts summed
 * into starts; starts shifted back after filling. */
hoc_status hoc_opt_csr_alloc(size_t n, size_t total, size_t **start, size_t **items);
void hoc_opt_csr_finish_counts(size_t n, size_t *start);
void hoc_opt_csr_restore(size_t n, size_t *start);
/* elem[n_elems] grown by `rings` rings of elements; node[n_nodes]: their nodes. */
void hoc_opt_grow_rings(const hoc_mesh *m, unsigned char *elem, unsigned char *node, int rings);
hoc_status hoc_grow_push(hoc_growlist *g, size_t x);

/* blocks.c: families, carried nodes, colours, sleeping and waking ------- */

/* Family 0: vertices (carrying their stars), edges, interiors; 1: nodes. */
hoc_status hoc_opt_build_blocks(hoc_opt *o, int family);
/* Weight with which block b (of o->B) carries node (0: not carried). */
double hoc_opt_carry_weight(const hoc_opt *o, size_t b, size_t node);
/* Weight of the carried node carry_node[j] of o->B. */
double hoc_opt_carry_w(const hoc_opt *o, size_t j);
/* Flags block b's nodes and carried nodes as moving (v = 1) or not. */
void hoc_opt_set_moving(hoc_opt *o, size_t b, unsigned char v);
/* Node k awake, its blocks of both families queued on their colours. */
void hoc_opt_wake_node(hoc_opt *o, size_t k);
/* Every block of both families may be active: each colour scans all. */
void hoc_opt_wake_all(hoc_opt *o);
/* o->node.near: within HOC_OPT_NEAR_RINGS rings of a tangled element. */
void hoc_opt_mark_near(hoc_opt *o);
/* The active blocks of a colour of o->B into o->trial.list; their number. */
size_t hoc_opt_select_active(hoc_opt *o, int color);

/* objective.c: element residuals, per-sweep state, screening ------------ */

/* x[np][3], n[np][3] of element e (trial state of moving nodes). */
void hoc_opt_gather(const hoc_opt *o, size_t e, double *x, double *n);
/* Element e not folded in (u, v) (trial state of moving nodes); uv[np][2] scratch. */
int hoc_opt_param_valid(const hoc_opt *o, size_t e, double *uv);
/* Residuals r (and their Jacobian J if not NULL) of element e; their number.
 * fr: the element's frames (quadrature points from them), or NULL (from x, n). */
int hoc_opt_elem_residuals(const hoc_opt *o, size_t e, const double *x, const double *n,
                           const double *fr, const unsigned char *need, double *r, double *J,
                           double *smin);
/* The kept frames of element e, or NULL. */
static inline double *hoc_opt_frames_of(const hoc_opt *o, size_t e) {
  size_t k = o->fc.slot ? o->fc.slot[e] : SIZE_MAX;
  return k == SIZE_MAX ? NULL : o->fc.pool + k * 9 * (size_t)o->fc.npts;
}
/* Frames of element e in the trial state of moving nodes, from its kept
 * frames fr, into out (which may be fr). */
void hoc_opt_frames_trial(const hoc_opt *o, size_t e, const double *fr, double *out);
/* The frame pool of at most `bytes` and which elements it keeps (setup
 * gives it HOC_OPT_FRAME_POOL_BYTES); any pool o had before is freed. */
hoc_status hoc_opt_frames_setup(hoc_opt *o, size_t bytes);
/* A dynamic pool's places to the elements of awake nodes, at a sweep's
 * start (no node moving); their frames from their nodes. */
void hoc_opt_frames_assign(hoc_opt *o);
/* Per-element state at a sweep's start; f, smallest q and tangled count. */
hoc_status hoc_opt_sweep_start(hoc_opt *o, double *objective, double *min_q, size_t *tangled);
/* Puts nodes with nothing to gain to sleep (before the first sweep). */
hoc_status hoc_opt_screen(hoc_opt *o);

/* trial.c: trial parameters, CAD evaluation, acceptance ----------------- */

/* Trial state for nodes[0..n) (no node twice): node nodes[a] at index a. */
hoc_status hoc_opt_trial_reserve(hoc_opt *o, const size_t *nodes, size_t n);
/* Node k's trial parameters [2], position [3], derivatives [6] (k reserved). */
static inline double *hoc_opt_tpar(const hoc_opt *o, size_t k) {
  return o->trial.tpar + 2 * (size_t)o->trial.tix[k];
}
static inline double *hoc_opt_txyz(const hoc_opt *o, size_t k) {
  return o->trial.txyz + 3 * (size_t)o->trial.tix[k];
}
static inline double *hoc_opt_tdz(const hoc_opt *o, size_t k) {
  return o->trial.tdz + 6 * (size_t)o->trial.tix[k];
}
/* The trial index of slot s of reserved node k (a face node has one slot,
 * a curve node one per face around it). */
static inline size_t hoc_opt_tslot(const hoc_opt *o, size_t k, size_t s) {
  size_t j = o->adj.ns_start[k];
  while (o->adj.ns_slot[j] != s) ++j;
  return o->trial.tsbase[o->trial.tix[k]] + (j - o->adj.ns_start[k]);
}

/* (u, v) of node k's copy kk in element e in the trial state. */
void hoc_opt_trial_elem_uv(const hoc_opt *o, size_t k, size_t e, int kk, double *uv);
/* Trial parameters of block b at its step length; 0 if one leaves a range. */
int hoc_opt_set_trial_params(hoc_opt *o, size_t b);
/* CAD evaluation of node i's trial; of list[0..n) on nthreads threads. */
hoc_status hoc_opt_eval_trial(hoc_opt *o, size_t i);
hoc_status hoc_opt_eval_trials(hoc_opt *o, const size_t *list, size_t n, int nthreads);
/* Line l's nodes strictly in order along its curve (trial state of moving nodes). */
int hoc_opt_line_monotone(const hoc_opt *o, size_t l);
/* Accepts node k's trial. */
void hoc_opt_commit(hoc_opt *o, size_t k);

/* step.c: block model, damped Gauss-Newton, line search ----------------- */

/* Local f, gradient g[nd] and Gauss-Newton matrix H[nd][nd] of block b. */
void hoc_opt_block_model(const hoc_opt *o, size_t b, hoc_opt_scratch *s, double *f, double *g,
                         double *H);
/* One colour of o->B: a step per active block, a common line search. */
hoc_status hoc_opt_do_color(hoc_opt *o, int color, hoc_opt_scratch *scr, int nthreads,
                            size_t *moved);
/* Scratch of nthreads threads (*out set even on failure: free it). */
hoc_status hoc_opt_scratch_alloc(const hoc_opt *o, int nthreads, hoc_opt_scratch **out);
void hoc_opt_scratch_free(hoc_opt_scratch *s, int nthreads);

/* polish.c, phases.c, driver.c ------------------------------------------ */

/* journal.c: saved states that log the nodes that move ------------------ */

/* The mesh's state now as j (logged from here on by hoc_opt_commit). */
hoc_status hoc_opt_journal_take(hoc_opt *o, hoc_opt_journal *j, size_t tangled, double f);
/* Node k is about to change: the journals that have not logged it do. */
void hoc_opt_journal_note(hoc_opt *o, size_t k);
/* Up to `nodes` nodes are about to change in parallel: a journal whose log
 * could outgrow its limit takes its copy first (serial). */
hoc_status hoc_opt_journal_reserve(hoc_opt *o, size_t nodes);
/* The mesh back to j's state (positions from the parameters of the nodes
 * that differ); j stays the state of the mesh. */
hoc_status hoc_opt_journal_restore(hoc_opt *o, hoc_opt_journal *j);
/* j is no longer kept (its tangled count becomes SIZE_MAX). */
void hoc_opt_journal_free(hoc_opt *o, hoc_opt_journal *j);

/* The polish of the elements the exact test finds tangled. */
hoc_status hoc_opt_polish(hoc_opt *o);
/* One run from the mesh as it is; protect: a protected run; sweeps
 * numbered from it0 + 1, seconds from t0; *limited: its sampled phase used
 * all its sweeps with elements still tangled. */
hoc_status hoc_opt_run(hoc_mesh *mesh, const hoc_optimize_options *options, int protect, int it0,
                       double t0, hoc_optimize_result *result, int *limited);
/* The order thresholds of two rules of a run and the size of its frame
 * pool (tunables.h), which tests set otherwise to show what each does:
 * hoc_opt_run takes hoc_opt_rules_default's, the tunables themselves. */
typedef struct hoc_opt_rules {
  int wake_near_min_order;      /* HOC_OPT_WAKE_NEAR_MIN_ORDER */
  int exact_relax_uv_min_order; /* HOC_OPT_EXACT_RELAX_UV_MIN_ORDER */
  size_t frame_pool_bytes;      /* HOC_OPT_FRAME_POOL_BYTES */
  int settled_sweeps;           /* HOC_OPT_SETTLED_SWEEPS (1..HOC_OPT_STAGNATION_SWEEPS) */
  double deadline;              /* hoc_mesh_optimize_until (0: none) */
  int *timed_out;               /* NULL, or set to 1 when the deadline stops a run */
} hoc_opt_rules;
void hoc_opt_rules_default(hoc_opt_rules *rules);
/* hoc_opt_run with the given rules (NULL: the defaults). */
hoc_status hoc_opt_run_rules(hoc_mesh *mesh, const hoc_optimize_options *options,
                             const hoc_opt_rules *rules, int protect, int it0, double t0,
                             hoc_optimize_result *result, int *limited);
/* hoc_mesh_optimize with the given rules (NULL: the defaults). */
hoc_status hoc_mesh_optimize_rules(hoc_mesh *mesh, const hoc_optimize_options *options,
                                   const hoc_opt_rules *rules, hoc_optimize_result *result);
hoc_status hoc_opt_snapshot_take(hoc_opt_snapshot *s, const hoc_mesh *m, size_t tangled, double f);
hoc_status hoc_opt_snapshot_restore(const hoc_opt_snapshot *s, hoc_mesh *m);
void hoc_opt_snapshot_free(hoc_opt_snapshot *s);

#endif
