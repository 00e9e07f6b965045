/* The optimiser's tunables: every threshold, budget and step rule of
 * hoc_mesh_optimize, hoc_mesh_polish and hoc_mesh_check_gradient in one
 * table. Each entry says what it bounds and the class of meshes or
 * problems it serves; a model named is an example of its class.
 * SPDX-License-Identifier: GPL-2.0-or-later
 */
#ifndef HOC_OPTIMIZE_TUNABLES_H
#define HOC_OPTIMIZE_TUNABLES_H

/* Options --------------------------------------------------------------- */

/* Sweeps of the first attempt when hoc_optimize_options.max_iterations is
 * 0 or negative; and the largest number a caller may ask for (a guard
 * against nonsense input, far above any useful run). */
#define HOC_OPT_DEFAULT_MAX_ITERATIONS 100
#define HOC_OPT_MAX_ITERATIONS_LIMIT 1000000

/* hoc_optimize_options.tolerance when not positive: a block whose step
 * lowers f by less than this share of the average free node's part of f
 * goes to sleep. */
#define HOC_OPT_DEFAULT_TOLERANCE 0.1

/* Sweeps of each later stage (the second attempt, the exact phase, the
 * smoothing after a polish) for max_iterations of the first: half as many,
 * since each starts from a state the earlier sweeps already improved. */
#define HOC_OPT_LATER_SWEEPS(max_iterations) (((max_iterations) + 1) / 2)

/* Stopping rules -------------------------------------------------------- */

/* Sweeps without a new fewest tangled count that end an attempt while the
 * tangle test looks at samples. Untangling at high orders can sit on a
 * plateau for 30 sweeps and more before the count falls again. */
#define HOC_OPT_STALL_SWEEPS 40

/* The same in the exact phase: its folds between the samples are few and
 * local, and the sweeps open them within a few sweeps or not at all (the
 * counts left after 15 sweeps are those left after 40, in half the time;
 * `hocad` splits the elements that stay folded). */
#define HOC_OPT_EXACT_STALL_SWEEPS 15

/* Smoothing stagnates, and the run ends converged, when the last
 * STAGNATION_SWEEPS sweeps, all without a tangled element, lowered the
 * free part of f by less than STAGNATION_F of it and raised the smallest q
 * by less than STAGNATION_Q: the rest of a smoothing run would change f
 * and the worst element little for its cost. */
#define HOC_OPT_STAGNATION_SWEEPS 10
#define HOC_OPT_STAGNATION_F 0.05
#define HOC_OPT_STAGNATION_Q 0.005

/* Once a phase's smoothing converged (it stagnated, or nothing moved any
 * more, with no element tangled), a later phase of the same run (the
 * exact phase, the smoothing after a polish) repairs a few folds in a mesh
 * smoothed already: it stagnates over a window of SETTLED_SWEEPS untangled
 * sweeps, its bounds STAGNATION_F and STAGNATION_Q scaled by
 * SETTLED_SWEEPS / STAGNATION_SWEEPS (the same rate). Ten sweeps there
 * smooth the whole mesh once more for about 1 % of f (impeller_laufrad at
 * order 3: 10 of its 37 sweeps). Not in the pipeline's coarse order
 * (hoc_mesh_optimize_until's full): its end is where a costlier order starts,
 * and a start a few sweeps short of converged changes which elements that
 * order leaves tangled and so which faces it meshes again (wing_fuselage
 * at order 8: min q 0.0058 against 0.0474 with the coarse order
 * converged). Tests: tests/test_optimize_settled.c, and
 * tests/test_pipeline_coarse.c for the coarse order. */
#define HOC_OPT_SETTLED_SWEEPS 1

/* Sleeping and waking --------------------------------------------------- */

/* Nodes of elements with q below this share of the mean q never sleep:
 * those elements set the mesh's worst quality, the number smoothing is
 * judged by. */
#define HOC_OPT_POOR_Q_SHARE 0.5

/* A moved block wakes the nodes around it if its gain is at least this
 * many times the sleeping threshold: every move while some element is
 * tangled (untangling makes room by moving nodes further out), only
 * significant ones while smoothing (small ones would spread waves of
 * smaller ones through the whole mesh). */
#define HOC_OPT_WAKE_UNTANGLING 1
#define HOC_OPT_WAKE_SMOOTHING 10
/* From this order on, while untangling, only blocks within
 * HOC_OPT_NEAR_RINGS of a tangled element wake on every move; elsewhere a
 * move must be significant as when smoothing. With a fold or two left in
 * a large mesh, every-move waking sends a wave through the whole mesh each
 * sweep; at high orders each visit costs p^2 sample points and such waves
 * dominate (gear_f360 at order 10: 79 s of CPU on one thread with this
 * rule; without it, not ended after 170 s of CPU on two). Test:
 * tests/test_optimize_wake_near.c (a fold kept on a plane at order 6:
 * without the rule, ten times the moves far from it). */
#define HOC_OPT_WAKE_NEAR_MIN_ORDER 6

/* While the exact phase untangles, only blocks within this many rings of
 * elements (sharing a node) of a tangled element move: its folds are few
 * and local, and waking the whole mesh moves nodes far from any fold, each
 * move testing its elements exactly. */
#define HOC_OPT_NEAR_RINGS 3

/* Regularisation of tangled elements ------------------------------------ */

/* Regularisation scale delta of a tangled element relative to its size
 * (Escobar et al.'s sigma_delta). When untangling stalls for EPS_STALL
 * sweeps it is multiplied by EPS_RAISE while below EPS_RAISE_BELOW, then
 * back to EPS: the cycle 1e-3 -> 1e-2 -> 1e-1 -> 1e-3. A large delta
 * smooths the landscape, a small one pushes the last folds open (in the
 * exact phase too: folds at the sharp corners of a cylinder's patch open
 * only so). As soon as the count falls it is back to EPS. */
#define HOC_OPT_EPS 1e-3
#define HOC_OPT_EPS_RAISE 10
#define HOC_OPT_EPS_RAISE_BELOW 0.05
#define HOC_OPT_EPS_STALL 3

/* Any raised regularisation is above this: the tangled region is then
 * relaxed (its valid elements may pass through sigma = 0, see relaxed in
 * step.c). */
#define HOC_OPT_EPS_RAISED 2e-3

/* Orders above this have no protected run (every trial of its sampled
 * phase runs the exact tests, whose cost grows as p^4: at order 10 a sweep
 * of the exact phase costs several times one of the sampled phase), relax
 * tangled regions only in the exact phase (in the sampled phase their
 * folds between the samples outnumber the folds they open), and guard
 * fragile elements. */
#define HOC_OPT_PROTECT_MAX_ORDER 5

/* From this order on, the exact phase relaxes the (u, v) rule from its
 * start, as the second attempt does (relaxed_uv in step.c). Its folds are
 * those the samples missed, mostly in elements on a face's boundary (a
 * plane's edge along a curved CAD curve, between the teeth of a gear):
 * the raised regularisation lets their neighbourhood pass through
 * sigma = 0 in 3D while the (u, v) rule holds the same nodes, so the
 * phase's sweeps stall until HOC_OPT_EXACT_STALL_SWEEPS end them and the
 * second attempt relaxes the rule anyway. At order 10 each of those
 * sweeps tests its elements exactly (p^4 each): gear_f360 spends 16
 * sweeps, over half its time, so. The exact tests see every fold the
 * relaxed elements make, so the reason the sampled phase keeps the rule
 * (it trades one fold for several between the samples) does not hold
 * here. Not below: orders up to PROTECT_MAX_ORDER have the protected run
 * and their exact sweeps cost little. Test: tests/test_optimize_exact_relax.c
 * (folds between the samples on a plane's boundary at order 6: the exact
 * phase opens them in 7 sweeps; without the rule it stalls, and the
 * second attempt opens them 15 sweeps later). */
#define HOC_OPT_EXACT_RELAX_UV_MIN_ORDER 6

/* Above PROTECT_MAX_ORDER, in a whole-mesh run, a valid element with q
 * below this is fragile: no step may fold it between the samples. Thin
 * valid elements (aspect 20-50: a strip of needles across a narrow face,
 * slivers where a wing meets a fuselage) fold between the samples of a
 * high order at node moves of a small share of their width, and once
 * folded are seldom opened again. They are few (under 1% of the elements
 * on such meshes), so their exact tests cost little. */
#define HOC_OPT_FRAGILE_Q 0.1

/* A curve node's step may not make its line's parameter turn back
 * (line_turns_back in trial.c): the Bernstein coefficients of dt/ds and
 * halvings down to 2^-LINE_DEPTH of the line decide. Its class: curve
 * nodes that slide until two bunch up (towards a cusp, beside a short
 * neighbour) fold every element on their line between its samples, where
 * only the exact phase sees it (crescent_plate at order 3: 8 such folds
 * and 143 sweeps without the rule, 1 and 49 with it). Test:
 * tests/test_optimize_line_monotone.c. */
#define HOC_OPT_LINE_DEPTH 10

/* Steps ------------------------------------------------------------------ */

/* A block's step moves no node further than this share of its local length
 * (the longest edge of the linear sub-triangles around it): a Gauss-Newton
 * step from a regularised model can otherwise jump across neighbouring
 * elements. Steps moving less than STEP_MIN of the local length are not
 * taken. */
#define HOC_OPT_STEP_CAP 0.25
#define HOC_OPT_STEP_MIN 1e-12

/* Backtracking line search of each colour: at most LINE_SEARCH_TRIES
 * halvings of every block's step, accepting a step that lowers the local
 * objective by ARMIJO times the predicted decrease; before each trial, up
 * to RANGE_HALVINGS halvings to bring the parameters inside a bounded
 * (non-periodic) range. */
#define HOC_OPT_LINE_SEARCH_TRIES 12
#define HOC_OPT_ARMIJO 1e-4
#define HOC_OPT_BACKTRACK 0.5
#define HOC_OPT_RANGE_HALVINGS 40

/* Damping of the Gauss-Newton matrix H (Levenberg-Marquardt on its
 * diagonal): mu from MU_FIRST, times MU_GROWTH until the Cholesky
 * factorisation succeeds, giving up at MU_LAST; a zero diagonal entry counts
 * as DIAG_FLOOR times the largest (nodes whose elements barely depend on
 * them). */
#define HOC_OPT_MU_FIRST 1e-10
#define HOC_OPT_MU_GROWTH 100
#define HOC_OPT_MU_LAST 1e6
#define HOC_OPT_DIAG_FLOOR 1e-12

/* Memory ----------------------------------------------------------------- */

/* Bytes of the pool of element frames (hoc_opt_frames: 9 numbers per
 * sample point, 43 KB an element at order 10, 2.5 KB at order 3): 1 500
 * elements at order 10. A mesh with more elements lends the places at
 * each sweep's start to the elements of awake nodes; the others are
 * evaluated from their nodes, at the cost of the frames (p^4 a visit
 * instead of p^2). After the first sweeps the awake elements are few, so
 * a pool the size of a large mesh's (nist_ftc_07 at order 10: 4.9 GB)
 * buys little: one of 512 MB took as long there as none. */
#define HOC_OPT_FRAME_POOL_BYTES ((size_t)64 << 20)
/* The frames are kept from this order on: below it an element has at most
 * 21 nodes and its frames cost little more from its nodes, while the pool
 * would more than double the memory of a large mesh (nist_ftc_07, 114 600
 * elements at order 3: 462 MB without, 1 156 MB with). */
#define HOC_OPT_FRAME_MIN_ORDER 6

/* Threads ---------------------------------------------------------------- */

/* A loop of a sweep over n blocks or elements runs on a team of threads
 * only if n * np * nq (nodes times quadrature points of an element: its
 * evaluation's cost) reaches PARALLEL_WORK, and n exceeds PARALLEL_CHUNK,
 * the blocks a thread takes at a time (fewer give one thread all of
 * them). Waking a team costs tens of microseconds under
 * OMP_WAIT_POLICY=passive, an order-3 block a few: the late sweeps of
 * small meshes (a few dozen blocks per colour, 2 families of up to 20
 * colours) spent more on waking than on work (crescent_plate at order 3
 * on 2 threads: 0.71 s, 0.34 s on 1, 0.32 s with this rule). The
 * threshold is about 100 blocks at order 3, the chunk's 9 at order 10;
 * large meshes keep their speed (nist_ftc_08 at order 5: 21.0 s of the
 * whole run before, 19.6-20.9 s with it). The result does not depend on
 * it: the blocks of a colour share no element. */
#define HOC_OPT_PARALLEL_WORK 50000.0
#define HOC_OPT_PARALLEL_CHUNK 8

/* Nodes whose trial state a colour's line search holds at once: a colour
 * of large blocks (the interiors of every element) holds most nodes of
 * the mesh (nist_ftc_07 at order 10: 4 million, 560 MB of trial state).
 * Its blocks share no element, so their line searches are independent and
 * run in parts of this many nodes with the same result; a part of 2^17
 * nodes (17 MB) still gives the threads thousands of blocks. */
#define HOC_OPT_TRIAL_NODES ((size_t)1 << 17)

/* A run's saved states (the best reached while untangling, the state
 * before the polish) log the nodes that move after them (journal.c): the
 * exact phase moves only the nodes near its folds. A log that would pass
 * 1/JOURNAL_SHARE of a copy of every node's parameters (nist_ftc_07 at
 * order 10: 97 MB) takes that copy instead and logs no more, so a saved
 * state never costs much more than the copy. */
#define HOC_OPT_JOURNAL_SHARE 4

/* Polish ----------------------------------------------------------------- */

/* The polish is a search for the last few folds: with more tangled
 * elements than POLISH_MAX_TANGLED it does not run (the sweeps failed too
 * widely for a node-by-node search to pay), and each patch gets at most
 * POLISH_MAX_MEASURES element measures. Its steps start at POLISH_SHARE of
 * a node's local length and halve, when no move helps, down to
 * POLISH_MIN_SHARE. A move that keeps the count must make the negative
 * margins less negative by a relative POLISH_GAIN (rounding is no
 * progress). */
#define HOC_OPT_POLISH_MAX_TANGLED 32
#define HOC_OPT_POLISH_MAX_MEASURES 30000
#define HOC_OPT_POLISH_SHARE 0.25
#define HOC_OPT_POLISH_MIN_SHARE (1.0 / 4096)
#define HOC_OPT_POLISH_GAIN 1e-12

/* Polish margin of an element folded between its samples only (no
 * negative sigma at them): tangled, by a small amount. */
#define HOC_OPT_POLISH_HIDDEN_FOLD (-1e-9)

/* Numerical tolerances --------------------------------------------------- */

/* A face's normal from its derivatives is singular where |phi_u x phi_v| <
 * SINGULAR_NORMAL |D phi|^2 (a pole, a degenerate edge); it is then taken
 * NORMAL_OFFSET of the face's parameter range inside the face. */
#define HOC_OPT_SINGULAR_NORMAL 1e-10
#define HOC_OPT_NORMAL_OFFSET 1e-5

/* A vertex block carries a high-order node of its star whose barycentric
 * weight for the vertex is above this (nodes on the opposite edge stay). */
#define HOC_OPT_CARRY_MIN_WEIGHT 1e-12

/* Gradient check: step of its fourth-order central differences as a
 * share of the node's local length. */
#define HOC_OPT_FD_STEP 1e-5

#endif
