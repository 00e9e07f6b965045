/* Jacobian-based distortion of high-order surface triangles: the paper's
 * Table 1 (shape, Oddy), Definition 1 (L2 average over the ideal element)
 * and Definition 2 (surfaces, through the tangent-plane embedding T).
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * Notation. Reference triangle t_R: (0,0), (1,0), (0,1), coordinates xi.
 * Ideal element t_I: the equilateral triangle (0,0), (1,0), (1/2, sqrt(3)/2)
 * with the same node distribution, so phi_I(xi) = W xi is affine with
 * W = [1 1/2; 0 sqrt(3)/2]. The physical element is x(xi) = sum_i x_i N_i(xi)
 * and D phi = D phi_R W^{-1} (3 x 2), columns a1, a2.
 *
 * Surfaces (Definition 2): T maps D phi to S = M D phi with M = [e1; gamma e2]
 * from Gram-Schmidt on a1, a2, gamma = +-1 so that the basis turns like the
 * CAD face's normal n. Then S^T S = D phi^T D phi and
 * sigma = det S = gamma |a1 x a2|, gamma = sign((a1 x a2) . n),
 * so eta needs only the Gram matrix of a1, a2 and the signed area.
 *
 * The reference normal n at a quadrature point is the Lagrange interpolant of
 * the CAD face's unit normals at the element's nodes (exact to O(h^{p+1})
 * on smooth faces; only its side of the tangent plane matters).
 */
#ifndef HOC_QUALITY_H
#define HOC_QUALITY_H

#include "core/error.h"

/** Tables of one (order, node set): basis values and ideal-space gradients
 *  at the quadrature points and at the nodes. Shared, read-only. */
typedef struct hoc_quality_tables {
  int p, np, nq, degree;
  hoc_nodeset set;
  double *w;  /* [nq] quadrature weights normalised to sum 1 (mean over t_I) */
  double *N;  /* [nq][np] N_i at the quadrature points */
  double *G;  /* [nq][np][2] grad_{x~} N_i = W^{-T} grad_xi N_i at the quadrature points */
  double *Gn; /* [np][np][2] the same at the nodes (row j: node j) */
  double *rs; /* [np][2] reference coordinates of the nodes */
  int nv;     /* validation points: the equispaced lattice of order 2p (the first
               * nlat), nvpad copies of its last point (so that the points
               * after it start a block), then HOC_EDGE_REFINE - 1 more points
               * between two of its points on each edge (dense residuals only:
               * the exact edge test decides the edges) */
  int nlat, nvpad;
  double *Nv; /* [nv][np] basis values there (for the interpolated normal) */
  double *Gv; /* [nv][np][2] ideal-space gradients there */
  /* All nq + np + nv points again, for measuring: in blocks of HOC_QB
   * points (the last padded with copies of the last point), per block and
   * node the HOC_QB values side by side, so that the kernel works on HOC_QB
   * points at once. Normals at node points interpolate with the identity. */
  int n_blocks;
  int n_check_blocks; /* the blocks up to the lattice's last point: the tangle test's samples */
  double *Bx, *By; /* [n_blocks][np][HOC_QB] ideal-space gradients */
  double *Bn;      /* [n_blocks][np][HOC_QB] basis values (normal interpolation) */
  double *Bw;      /* [n_blocks][HOC_QB] weights: w at quadrature points, else 0 */
  /* The exact fold test of the edges (edges.c), for p >= 2: along edge k
   * (corner k to k + 1) the columns a1, a2 of D phi are polynomials of
   * degree p - 1 in the edge's coordinate s, the interpolated normal one
   * of degree p, and (a1 x a2) . n one of degree 3p - 2. */
  double *Ge; /* [3][p][np][2] ideal-space gradients at s = (j + 1/2) / p */
  double *Ca; /* [p][p] values at those s -> Bernstein coefficients, degree p - 1 */
  double *Cn; /* [p + 1][p + 1] values at the edge's nodes -> Bernstein coefficients, degree p */
  double *Wb; /* [p][p][p + 1] C(p-1, i) C(p-1, j) C(p, k) / C(3p-2, i+j+k) */
  int *enode; /* [3][p + 1] local nodes along each edge, from corner k to corner k + 1 */
  /* The exact fold test of the whole triangle (interior.c), for p >= 2 */
  double *Cb; /* [np][np] node values -> Bernstein coefficients of degree p on the triangle */
  double *Mb; /* multinomials |a|! / (a0! a1! a2!) of the degrees p - 1, 2p - 2, p, 3p - 2 */
  double *Pb; /* the products' weights C(a) C(c) / C(a + c): [n(p-1)][n(p-1)], then
               * [n(2p-2)][np] (n(m): coefficients of degree m) */
  struct hoc_lagrange *basis; /* the Lagrange basis on rs (points other than the tables') */
} hoc_quality_tables;

enum { HOC_QB = 4, HOC_EDGE_REFINE = 4 };

/** Quadrature degree used for order p (see docs/quality.md for why). */
int hoc_quality_degree(int p);

/** Tables for (p, set), built on first use and cached (thread-safe). */
hoc_status hoc_quality_tables_get(int p, hoc_nodeset set, const hoc_quality_tables **tables);

/** Uncached tables with a quadrature of a chosen degree (tests, studies). */
hoc_status hoc_quality_tables_create(int p, hoc_nodeset set, int degree,
                                     hoc_quality_tables **tables);
void hoc_quality_tables_destroy(hoc_quality_tables **tables);

/** q of every element of a mesh with given tables (hoc_mesh_measure's core).
 *  q[n_elems]. */
struct hoc_mesh;
hoc_status hoc_mesh_measure_tables(const struct hoc_mesh *mesh, const hoc_quality_tables *t,
                                   hoc_measure measure, double *q);
/** q[e] of the elements flagged in elements[n_elems] only (the CAD normals
 *  at their nodes only); the other q[e] are left as they are. */
hoc_status hoc_mesh_measure_some(const struct hoc_mesh *mesh, hoc_measure measure,
                                 const unsigned char *elements, double *q);

/** Statistics of q[ne] (seconds left 0). */
void hoc_quality_stats_from(const double *q, size_t ne, int order, hoc_quality_stats *stats);

/** Pointwise distortion eta(S) of Table 1 for d = 2, with the regularised
 *  determinant sigma_delta = (sigma + sqrt(sigma^2 + 4 delta^2)) / 2 (delta = 0:
 *  eta = +inf where sigma <= 0).
 *  @param[in]  a1, a2  columns of D phi (3)
 *  @param[in]  n       reference normal (3, any length > 0)
 *  @param[in]  delta   regularisation >= 0
 *  @param[out] sigma   signed area sigma = gamma |a1 x a2| (may be NULL)
 *  @param[out] g1, g2  d eta / d a1, d eta / d a2 (3 each), or NULL
 *  @return eta (>= 1 when sigma > 0) */
double hoc_distortion_point(hoc_measure measure, const double a1[3], const double a2[3],
                            const double n[3], double delta, double *sigma, double *g1,
                            double *g2);

/** Fill the edge tables (Ge, Ca, Cn, Wb, enode) of t from its basis
 *  (tables.c's builder; nothing for p = 1). */
struct hoc_lagrange;
hoc_status hoc_quality_edge_tables(hoc_quality_tables *t, const struct hoc_lagrange *basis);

/** Quality of one element (Definition 2 with delta = 0). Tangled (q = 0)
 *  if sigma <= 0 at a quadrature point, a node or a point of the
 *  validation lattice, or if the exact edge test finds a fold between them
 *  (hoc_element_edges_folded).
 *  @param[in] x  [np][3] node positions
 *  @param[in] n  [np][3] unit CAD normals at the nodes (oriented)
 *  @param[out] eta  element distortion (+inf if tangled)
 *  @param[out] min_sigma  smallest sigma / |D phi|^2 over quadrature points,
 *                         nodes and validation points (<= 0 means tangled)
 *  @return q = 1/eta, 0 if tangled */
double hoc_element_quality(const hoc_quality_tables *t, hoc_measure measure, const double *x,
                           const double *n, double *eta, double *min_sigma);

/** hoc_element_quality with the exact edge test only if `exact` (the
 *  optimiser's first phase checks the samples alone: see optimize/phases.c). */
double hoc_element_quality_test(const hoc_quality_tables *t, hoc_measure measure, const double *x,
                                const double *n, int exact, double *eta, double *min_sigma);

/** The smallest sigma (the tangent-plane determinant, unnormalised) over
 *  the points hoc_element_quality samples, over the area scale of the
 *  straight triangle of the element's corners: a measure of how deep a
 *  fold is that no node can shrink by moving far away (sigma / |D phi|^2
 *  tends to 0 as one node's pull dominates D phi). */
double hoc_element_min_sigma_area(const hoc_quality_tables *t, const double *x, const double *n);

/** Vector width of hoc_element_quality: 0 the widest the CPU runs (the
 *  default), 2 (SSE2) or 4 (AVX2, where the CPU has it). For tests; not
 *  to be changed while other threads measure. Returns the width in use. */
int hoc_quality_set_width(int width);

/** Residuals of the least-squares objective of one element,
 *  r_q = sqrt(w_q) (eta(x~_q) - 1), and their derivatives.
 *  @param[in]  need  [np] nonzero for the nodes whose columns of J are
 *                    wanted (the others are not written), or NULL for all
 *  @param[out] r     [nq]
 *  @param[out] J     [nq][np][3] d r_q / d x_i, or NULL
 *  @return smallest sigma / |D phi|^2 over the quadrature points */
double hoc_element_residuals(const hoc_quality_tables *t, hoc_measure measure, const double *x,
                             const double *n, double delta, const unsigned char *need, double *r,
                             double *J);

/** Frames of an element: the columns a1, a2 of D phi and the interpolated
 *  normal n at every point of the tangle test's samples (quadrature points,
 *  nodes, the order-2p lattice, padded to blocks): fr[9][npts] (a1 x, y, z,
 *  a2 x, y, z, n x, y, z; point k at k), npts = hoc_element_frame_points.
 *  The optimiser keeps them per element and moves them with its nodes. */
int hoc_element_frame_points(const hoc_quality_tables *t);
void hoc_element_frames(const hoc_quality_tables *t, const double *x, const double *n,
                        double *fr);

/** The frames after local node `node` moved by dx[3] and its normal by
 *  dn[3]: out = fr + the change (every frame is linear in the nodes'
 *  positions and normals); out may be fr. */
void hoc_element_frames_move(const hoc_quality_tables *t, const double *fr, int node,
                             const double dx[3], const double dn[3], double *out);

/** hoc_element_residuals from an element's frames (hoc_element_frames). */
double hoc_element_residuals_frames(const hoc_quality_tables *t, hoc_measure measure,
                                    const double *fr, double delta, const unsigned char *need,
                                    double *r, double *J);

/** 1 if sigma <= 0 at one of the frames' points first .. last - 1 (the
 *  nodes and lattice are nq .. hoc_element_frame_points). */
int hoc_element_frames_tangled(const hoc_quality_tables *t, const double *fr, int first,
                               int last);

/** Residuals at the element's nodes and validation points,
 *  r_j = sqrt(1/count) (eta(point j) - 1), for untangling: the tangle test
 *  also asks det > 0 there, which the quadrature points alone do not see.
 *  The points: the nodes and the order-2p lattice, and if `dense` the
 *  edge points between the lattice's too (count:
 *  hoc_element_node_points).
 *  @param[in]  need  as for hoc_element_residuals
 *  @param[out] r     [count]
 *  @param[out] J     [count][np][3] d r_j / d x_i, or NULL
 *  @return smallest sigma / |D phi|^2 over those points */
double hoc_element_node_residuals(const hoc_quality_tables *t, hoc_measure measure, const double *x,
                                  const double *n, double delta, int dense,
                                  const unsigned char *need, double *r, double *J);

/** Number of residuals of hoc_element_node_residuals. */
int hoc_element_node_points(const hoc_quality_tables *t, int dense);

/** Tangled test of Definition 2 (delta = 0): 1 if sigma <= 0 at a
 *  quadrature point, a node or a validation point, or (if `exact`) the
 *  exact edge test finds a fold. With exact = 1 the same test as
 *  hoc_element_quality. */
int hoc_element_tangled(const hoc_quality_tables *t, const double *x, const double *n, int exact);

/** Exact fold test of the element's edges: 1 if sigma is clearly negative
 *  somewhere on an edge, found by Bernstein coefficients of (a1 x a2) . n
 *  along it and subdivision (pieces down to 2^-14 of the edge); 0 if every
 *  piece is proven positive or nothing negative is found. 0 for p = 1
 *  (sigma is then linear along an edge). Sampled tests miss such folds:
 *  an optimiser that only checks samples can walk nodes until a fold lies
 *  between them (seen on edges next to slivers and at corners on curves).
 *  Part of measuring (hoc_element_quality): see docs/quality.md,
 *  "Tangled elements: samples, then exact tests". */
int hoc_element_edges_folded(const hoc_quality_tables *t, const double *x, const double *n);

/** 1 if the polynomial on [a, b] with Bernstein coefficients c[0..d]
 *  (d <= 3 HOC_MAX_ORDER - 2) is below -tol at an end of some piece of a
 *  subdivision into halves down to `depth` more levels (*where: that end);
 *  0 once every piece has all coefficients > 0 or nothing is found. */
int hoc_bernstein_negative(const double *c, int d, double tol, int depth, double a, double b,
                           double *where);

/** Reference coordinates rs[2] of the point at s of edge k (corner k at
 *  s = 0, corner k + 1 at s = 1). */
void hoc_quality_edge_point(int k, double s, double *rs);

/** inv[n][n] = V^-1 by Gauss-Jordan with partial pivoting (the Bernstein
 *  matrices of the exact tests). */
hoc_status hoc_quality_invert(int n, const double *V, double *inv);

/** Fill the tables of the whole-triangle test (Cb, Mb, Pb) of t (nothing for
 *  p = 1). */
hoc_status hoc_quality_interior_tables(hoc_quality_tables *t);

/** Exact fold test of the whole element: 1 if sigma is clearly negative
 *  somewhere on the triangle, found by the Bernstein coefficients of
 *  (x_r x x_s) . n (degree 3p - 2 on the triangle) and cuts in four down
 *  to 1/32 of the edges; 0 if proven positive or nothing negative found.
 *  (The edge test goes deeper along the edges, where folds between the
 *  samples were seen.) 0 for p = 1. */
int hoc_element_interior_folded(const hoc_quality_tables *t, const double *x, const double *n);

/** The exact tests together: edges, then the whole triangle. */
int hoc_element_folded(const hoc_quality_tables *t, const double *x, const double *n);

/** hoc_element_edges_folded, hoc_element_interior_folded and
 *  hoc_element_folded that also say where: on a fold, rs[2] receives the
 *  reference coordinates of a point where sigma < 0 (the end or corner of
 *  the subdivision's piece found negative: the Bernstein coefficient there
 *  is sigma's value; the piece's centre if sigma is degenerate). */
int hoc_element_edges_fold_point(const hoc_quality_tables *t, const double *x, const double *n,
                                 double rs[2]);
int hoc_element_interior_fold_point(const hoc_quality_tables *t, const double *x, const double *n,
                                    double rs[2]);
int hoc_element_fold_point(const hoc_quality_tables *t, const double *x, const double *n,
                           double rs[2]);

/** Ideal-space gradients of n basis functions: G[n][2] = grad_{x~} N =
 *  W^{-T} grad_xi N with W = [1 1/2; 0 sqrt(3)/2], from dN[n][2]. */
void hoc_quality_to_ideal(size_t n, const double *dN, double *G);

/** One residual at reference point rs[2] with weight w (a fold point, for
 *  untangling folds between the samples): r = sqrt(w) (eta - 1) there and
 *  J [np][3] = d r / d x_i (need as for hoc_element_residuals; J may be
 *  NULL). Returns sigma / |D phi|^2 there (NaN if rs is not usable). */
double hoc_element_point_residual(const hoc_quality_tables *t, hoc_measure measure,
                                  const double *x, const double *n, double delta,
                                  const double rs[2], double w, const unsigned char *need,
                                  double *r, double *J);

/** The rest of the tangle test, given the quadrature points' smallest
 *  sigma (the residual functions return it): 1 if sigma <= 0 at a node or
 *  at a point of the validation lattice, or (if `exact`) the exact edge
 *  test finds a fold. */
int hoc_element_nodes_tangled(const hoc_quality_tables *t, const double *x, const double *n,
                              int exact);

#endif
