/* Mesh a CAD model at order 3, print the paper's Table 2 rows, write a .msh.
 *   cc quickstart.c $(pkg-config --cflags --libs hocad) -o quickstart
 *   ./quickstart examples/models/screw.step screw_p3.msh
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include <hocad.h>
#include <stdio.h>

int main(int argc, char **argv) {
  if (argc != 3) {
    fprintf(stderr, "usage: %s MODEL.step OUT.msh\n", argv[0]);
    return 2;
  }
  hoc_model *model = NULL;
  hoc_mesh *mesh = NULL;
  hoc_report *report = NULL;
  hoc_mesh_options options;
  hoc_mesh_options_default(&options); /* linear mesh, raise, untangle and smooth */
  options.order = 3;
  hoc_status st = hoc_model_open(argv[1], &model);
  if (st == HOC_OK) st = hoc_mesh_model(model, &options, &mesh, &report);
  if (st == HOC_OK) {
    printf("stage       order elements   min q  mean q tangled\n");
    for (size_t i = 0; i < hoc_report_num_stages(report); ++i) {
      const hoc_stage *s = hoc_report_stage(report, i);
      printf("%-11s %5d %8zu %7.4f %7.4f %7zu\n", s->name, s->stats.order, s->stats.elements,
             s->stats.min, s->stats.mean, s->stats.tangled);
    }
    st = hoc_mesh_write_msh(mesh, argv[2]);
  }
  if (st != HOC_OK) fprintf(stderr, "error: %s\n", hoc_last_error());
  hoc_report_destroy(&report);
  hoc_mesh_destroy(&mesh); /* meshes before their model */
  hoc_model_destroy(&model);
  return st == HOC_OK ? 0 : 1;
}
