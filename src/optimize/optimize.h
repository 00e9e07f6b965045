/* What the pipeline uses of the optimiser beyond hocad.h.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#ifndef HOC_OPTIMIZE_H
#define HOC_OPTIMIZE_H

#include "hocad.h"

/* hoc_mesh_optimize that stops at a time: once hoc_now() passes deadline
 * (0: never), the sweeps stop as if they ran out and no later phase or run
 * starts (no second attempt, exact phase, polish or protected run); the
 * mesh is the best state reached. timed_out: NULL, or set to whether the
 * deadline stopped it. full: every phase ends by the first phase's
 * stagnation rule (HOC_OPT_STAGNATION_SWEEPS; tunables.h), the shorter
 * window of a phase after a converged one (HOC_OPT_SETTLED_SWEEPS) off:
 * for a mesh that is the start of a costlier optimisation (the pipeline's
 * coarse order, raised to a high order), where the settled rule's earlier
 * end saves little and changes where that optimisation starts. */
hoc_status hoc_mesh_optimize_until(hoc_mesh *mesh, const hoc_optimize_options *options, int full,
                                   double deadline, hoc_optimize_result *result, int *timed_out);

#endif
