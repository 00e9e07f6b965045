/* The layout of the public structures as the compiler sees them, for the
 * Python package's test that its ctypes mirrors (python/hocad/_capi.py)
 * match: one line "struct size" per structure, then "struct.field offset"
 * per field.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"

#include <stddef.h>
#include <stdio.h>

#define SIZE(type) printf(#type " %zu\n", sizeof(type))
#define FIELD(type, field) printf(#type "." #field " %zu\n", offsetof(type, field))

int main(void) {
  SIZE(hoc_quality_stats);
  FIELD(hoc_quality_stats, elements);
  FIELD(hoc_quality_stats, order);
  FIELD(hoc_quality_stats, min);
  FIELD(hoc_quality_stats, max);
  FIELD(hoc_quality_stats, mean);
  FIELD(hoc_quality_stats, std);
  FIELD(hoc_quality_stats, tangled);
  FIELD(hoc_quality_stats, seconds);
  SIZE(hoc_msh_options);
  FIELD(hoc_msh_options, version);
  FIELD(hoc_msh_options, binary);
  FIELD(hoc_msh_options, parametric);
  SIZE(hoc_linear_options);
  FIELD(hoc_linear_options, size_max);
  FIELD(hoc_linear_options, size_min);
  FIELD(hoc_linear_options, curvature);
  FIELD(hoc_linear_options, order);
  FIELD(hoc_linear_options, face_size);
  FIELD(hoc_linear_options, progress);
  FIELD(hoc_linear_options, progress_user);
  FIELD(hoc_linear_options, mesher_timeout);
  FIELD(hoc_linear_options, grading);
  FIELD(hoc_linear_options, keep_pinches);
  SIZE(hoc_optimize_iteration);
  FIELD(hoc_optimize_iteration, iteration);
  FIELD(hoc_optimize_iteration, objective);
  FIELD(hoc_optimize_iteration, min_q);
  FIELD(hoc_optimize_iteration, tangled);
  FIELD(hoc_optimize_iteration, moved);
  FIELD(hoc_optimize_iteration, seconds);
  FIELD(hoc_optimize_iteration, attempt);
  SIZE(hoc_optimize_options);
  FIELD(hoc_optimize_options, measure);
  FIELD(hoc_optimize_options, fix_curves);
  FIELD(hoc_optimize_options, max_iterations);
  FIELD(hoc_optimize_options, tolerance);
  FIELD(hoc_optimize_options, progress);
  FIELD(hoc_optimize_options, progress_user);
  FIELD(hoc_optimize_options, free_elements);
  FIELD(hoc_optimize_options, free_rings);
  SIZE(hoc_optimize_diagnostics);
  FIELD(hoc_optimize_diagnostics, second_attempt);
  FIELD(hoc_optimize_diagnostics, exact_phase);
  FIELD(hoc_optimize_diagnostics, protected_run);
  FIELD(hoc_optimize_diagnostics, polished);
  FIELD(hoc_optimize_diagnostics, fragile);
  SIZE(hoc_optimize_result);
  FIELD(hoc_optimize_result, iterations);
  FIELD(hoc_optimize_result, converged);
  FIELD(hoc_optimize_result, objective_initial);
  FIELD(hoc_optimize_result, objective_final);
  FIELD(hoc_optimize_result, tangled_initial);
  FIELD(hoc_optimize_result, tangled_final);
  FIELD(hoc_optimize_result, best_iteration);
  FIELD(hoc_optimize_result, stopped_at_limit);
  FIELD(hoc_optimize_result, free_nodes);
  FIELD(hoc_optimize_result, seconds);
  FIELD(hoc_optimize_result, diagnostics);
  SIZE(hoc_stage);
  FIELD(hoc_stage, name);
  FIELD(hoc_stage, stats);
  FIELD(hoc_stage, seconds);
  FIELD(hoc_stage, optimized);
  FIELD(hoc_stage, iterations);
  FIELD(hoc_stage, converged);
  FIELD(hoc_stage, objective_initial);
  FIELD(hoc_stage, objective);
  SIZE(hoc_event);
  FIELD(hoc_event, kind);
  FIELD(hoc_event, message);
  FIELD(hoc_event, stage);
  FIELD(hoc_event, iteration);
  FIELD(hoc_event, value);
  SIZE(hoc_mesh_options);
  FIELD(hoc_mesh_options, order);
  FIELD(hoc_mesh_options, nodeset);
  FIELD(hoc_mesh_options, measure);
  FIELD(hoc_mesh_options, size);
  FIELD(hoc_mesh_options, size_min);
  FIELD(hoc_mesh_options, curvature);
  FIELD(hoc_mesh_options, linear);
  FIELD(hoc_mesh_options, optimize);
  FIELD(hoc_mesh_options, fix_curves);
  FIELD(hoc_mesh_options, max_iterations);
  FIELD(hoc_mesh_options, refinements);
  FIELD(hoc_mesh_options, keep_nodes);
  FIELD(hoc_mesh_options, equispaced);
  FIELD(hoc_mesh_options, keep_stages);
  FIELD(hoc_mesh_options, check_gradient);
  FIELD(hoc_mesh_options, event);
  FIELD(hoc_mesh_options, event_user);
  FIELD(hoc_mesh_options, mesher_timeout);
  FIELD(hoc_mesh_options, grading);
  FIELD(hoc_mesh_options, repair_time);
  SIZE(hoc_report_files);
  FIELD(hoc_report_files, model);
  FIELD(hoc_report_files, mesh);
  FIELD(hoc_report_files, model_seconds);
  FIELD(hoc_report_files, write_seconds);
  SIZE(hoc_picture_options);
  FIELD(hoc_picture_options, width);
  FIELD(hoc_picture_options, height);
  FIELD(hoc_picture_options, view);
  FIELD(hoc_picture_options, zoom_worst);
  FIELD(hoc_picture_options, no_edges);
  FIELD(hoc_picture_options, transparent);
  return 0;
}
