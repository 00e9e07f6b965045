/* Reference triangle: node distributions, Lagrange bases, quadrature.
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * Reference triangle t_R: vertices (0,0), (1,0), (0,1); a point is xi = (r, s).
 * Nodes of an order-p element are listed in gmsh's ordering (which is also
 * VTK's Lagrange-triangle ordering):
 *   - the 3 vertices v0 = (0,0), v1 = (1,0), v2 = (0,1);
 *   - the p-1 nodes of edge 0 (v0 -> v1), then of edge 1 (v1 -> v2), then of
 *     edge 2 (v2 -> v0), each listed from its first vertex to its second;
 *   - the (p-1)(p-2)/2 interior nodes, recursively as an order p-3 triangle
 *     in the same ordering.
 * Every node set (equispaced, Fekete, warp & blend) uses that ordering: the
 * k-th node of any set sits at the same lattice position (i, j) as the k-th
 * equispaced node (i/p, j/p), only moved.
 */
#ifndef HOC_BASIS_H
#define HOC_BASIS_H

#include "core/error.h"

/** Nodes of an order-p triangle: (p+1)(p+2)/2. */
static inline int hoc_tri_num_nodes(int p) { return (p + 1) * (p + 2) / 2; }

/** Lattice indices of the order-p nodes in gmsh ordering.
 *  @param[in]  p   order >= 1
 *  @param[out] ij  [np][2]: node k is at (ij[2k], ij[2k+1]), 0 <= i, j, i + j <= p */
hoc_status hoc_tri_lattice(int p, int *ij);

/** 1D node positions on [0, 1] of an edge of an order-p element of a set:
 *  s[0] = 0, s[p] = 1, increasing (equispaced: k/p; Fekete and warp & blend:
 *  Gauss-Lobatto-Legendre points).
 *  @param[out] s  [p+1] */
hoc_status hoc_edge_nodes(int p, hoc_nodeset set, double *s);

/** Reference coordinates of the nodes of an order-p element, gmsh ordering.
 *  Symmetric under the permutations of the vertices; edge nodes equal
 *  hoc_edge_nodes of the same set. Fekete points are computed once per order
 *  (maximal |det V| with the edge nodes held at GLL points) and cached; the
 *  function is thread-safe.
 *  @param[out] rs  [np][2] */
hoc_status hoc_tri_nodes(int p, hoc_nodeset set, double *rs);

/** Quadrature rule on t_R: sum_q w[q] f(rs[q]) ~ int_{t_R} f; weights sum to
 *  1/2 and are positive; exact on polynomials of total degree <= degree. */
typedef struct hoc_quadrature {
  int degree; /**< degree of exactness */
  int n;      /**< number of points */
  double *rs; /**< [n][2] points strictly inside t_R */
  double *w;  /**< [n] weights */
} hoc_quadrature;

/** Build a rule of at least the given degree (0..60).
 *  @param[out] q  filled; free with hoc_quadrature_free */
hoc_status hoc_quadrature_triangle(int degree, hoc_quadrature *q);
void hoc_quadrature_free(hoc_quadrature *q);

/** Gauss-Legendre rule on [0, 1] with n points (n >= 1): x[n], w[n] (sum 1). */
hoc_status hoc_gauss_legendre01(int n, double *x, double *w);

/** Lagrange basis of order p on a set of nodes of the reference triangle. */
typedef struct hoc_lagrange hoc_lagrange;

/** Create the Lagrange basis {N_i} with N_i(node_j) = delta_ij.
 *  @param[in] p      order >= 1 (the polynomial space P_p)
 *  @param[in] nodes  [np][2] distinct, unisolvent nodes (copied)
 *  Fails with HOC_ERR_ARGUMENT if the nodes are not unisolvent. */
hoc_status hoc_lagrange_create(int p, const double *nodes, hoc_lagrange **basis);
void hoc_lagrange_destroy(hoc_lagrange **basis);
int hoc_lagrange_num_nodes(const hoc_lagrange *basis);

/** Evaluate the basis at n points.
 *  @param[in]  rs    [n][2]
 *  @param[out] N     [n][np] values, or NULL
 *  @param[out] dN    [n][np][2] derivatives d/dr, d/ds, or NULL */
hoc_status hoc_lagrange_eval(const hoc_lagrange *basis, int n, const double *rs, double *N,
                             double *dN);

/** 1D Lagrange basis on nodes s[0..p] of [0, 1], evaluated at x:
 *  L[k] = prod_{m != k} (x - s_m) / (s_k - s_m); dL may be NULL. */
void hoc_lagrange_1d(int p, const double *s, double x, double *L, double *dL);

#endif
