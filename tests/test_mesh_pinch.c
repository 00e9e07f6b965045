/* Pinches (mesh/pinch.c): iso-lines inside a face's (u, v) that the CAD
 * maps to one point, and the poor elements' note that names the elements
 * across them (hocad mesh, docs/quality.md).
 * - Analytic faces: a cone's apex is a side of its (u, v), not inside it;
 *   the folded square's fold line maps to a line, not a point; a plane
 *   has neither: no pinch on any of them.
 * - pinched_sheet.step (a bicubic sheet whose middle control row is one
 *   point, a triple knot at u = 1): one pinch, u = 1. surf114.igs's face 1
 *   (an IGES spline surface): a pinch near u = 7.64, where its iso-line
 *   spreads 0.003 of the face's 90.
 * - pinched_sheet's linear mesh is cut along its pinch (hoc_mesh_cut_pinches):
 *   no element across it, the point a node with pole slots; gmsh's mesh
 *   (keep_pinches) has elements across. At order 5 the cut mesh ends
 *   valid and within 0.9 x the linear mesh's min q.
 * - surf114's face 1, cut at its pinch, past which it turns back: at
 *   order 3, no split, none tangled (the point's slots on the flap's side
 *   take the flap's normal, and the point stays where it is; without
 *   either, 2 tangled); read back, none tangled; each element's direction
 *   at the point follows its corners the optimiser moved (without
 *   hoc_mesh_pole_params_follow 0.113 off their mean: the mesh measures
 *   otherwise when read back).
 * - From gmsh's mesh, not cut, elements end below 0.9 x the linear mesh's
 *   min q at order 5, every one of them across the pinch, and the note
 *   says so.
 * - A tangled element across the sheet's pinch (one of its linear mesh's,
 *   turned over) is one no split or finer mesh opens: its face is
 *   HOC_UNREFINABLE_PINCHES, and, the only one tangled, it is EACH; the
 *   same element turned over away from the pinch is neither.
 * - surf114's face 3 at the whole model's sizes, order 2: the one element
 *   left tangled spans a neck (u = 0.62, whose iso-line spreads 0.046 on a
 *   face 90 across: more than the collapse distance, less than the
 *   pinch share), where the face turns back (phi_v reverses: a fold). Its
 *   face folds, but it is not EACH: one split opens it (0 tangled, as the
 *   whole model at order 2); counted as across a fold, it stays tangled.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"
#include "mesh/mesh.h"
#include "pipeline/pipeline.h"
#include "test_util.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DATA HOC_SOURCE_DIR "/tests/data/"

static void test_analytic(void) {
  const hoc_analytic_kind kinds[3] = {HOC_ANALYTIC_CONE, HOC_ANALYTIC_FOLD, HOC_ANALYTIC_PLANE};
  const double b[3] = {2.0, 0.5, 0.0};
  for (int k = 0; k < 3; ++k) {
    hoc_model *model = NULL;
    CHECK_OK(hoc_cad_create_analytic(kinds[k], 1.0, b[k], &model));
    if (!model) continue;
    hoc_pinch p[HOC_PINCHES];
    int n = -1;
    CHECK_OK(hoc_face_pinches(model, 0, HOC_PIPELINE_PINCH_SHARE, p, HOC_PINCHES, &n));
    printf("analytic face %d: %d pinch(es)\n", k, n);
    CHECK(n == 0);
    hoc_model_destroy(&model);
  }
}

/* The pinches of the first face of the model at path: *n of them in p. */
static void pinches_of(const char *path, hoc_pinch *p, int *n) {
  hoc_model *model = NULL;
  *n = -1;
  CHECK_OK(hoc_model_open(path, &model));
  if (!model) return;
  CHECK_OK(hoc_face_pinches(model, 0, HOC_PIPELINE_PINCH_SHARE, p, HOC_PINCHES, n));
  hoc_model_destroy(&model);
}

static void test_files(void) {
  hoc_pinch p[HOC_PINCHES];
  int n;
  pinches_of(DATA "pinched_sheet.step", p, &n);
  printf("pinched_sheet: %d pinch(es)%s", n, n > 0 ? "," : "\n");
  for (int k = 0; k < n; ++k)
    printf(" %s = %.9f%s", p[k].dir ? "v" : "u", p[k].c, k + 1 < n ? "," : "\n");
  CHECK(n == 1 && p[0].dir == 0 && fabs(p[0].c - 1.0) < 1e-6);
  pinches_of(DATA "surf114_face1.brep", p, &n);
  int near = 0;
  for (int k = 0; k < n; ++k)
    near += p[k].dir == 0 && p[k].c > 7.6 && p[k].c < 7.7;
  printf("surf114's face 1: %d pinch(es), %d near u = 7.64\n", n, near);
  CHECK(near == 1);
}

/* The linear mesh of pinched_sheet, cut along its pinch or not. */
static hoc_mesh *sheet_mesh(hoc_model *model, int keep_pinches) {
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.keep_pinches = keep_pinches;
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_generate_linear(model, &lo, &lin));
  return lin;
}

/* Elements of m across one of the pinches of its face 0 found with the
 * report's share. */
static size_t count_across(const hoc_model *model, const hoc_mesh *m) {
  hoc_pinch p[HOC_PINCHES];
  int n = 0;
  CHECK_OK(hoc_face_pinches(model, 0, HOC_PIPELINE_PINCH_SHARE, p, HOC_PINCHES, &n));
  size_t across = 0;
  for (size_t e = 0; e < hoc_mesh_num_elements(m); ++e)
    across += (size_t)hoc_mesh_element_crosses_pinch(m, e, p, n);
  return across;
}

static void test_cut(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(DATA "pinched_sheet.step", &model));
  if (!model) return;
  hoc_mesh *kept = sheet_mesh(model, 1), *cut = sheet_mesh(model, 0), *mesh = NULL;
  if (kept && cut) {
    size_t across_kept = count_across(model, kept), across_cut = count_across(model, cut);
    /* the pinch's point: a node whose slots on the face are poles */
    size_t poles = 0;
    for (size_t s = 0; s < cut->n_slots; ++s)
      poles += cut->slot_pole[s] != 0 && cut->slot_face[s] == 0;
    printf("pinched_sheet's linear mesh: %zu element(s) across the pinch; cut along %d "
           "pinch(es): %zu across, %zu pole slot(s)\n",
           across_kept, cut->cut_pinches, across_cut, poles);
    CHECK(across_kept > 0 && cut->cut_pinches == 1 && across_cut == 0 && poles >= 2);
  }
  /* raised to order 5 and optimised: valid, within the quality bound */
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = 5;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  if (mesh && r) {
    size_t ne = hoc_mesh_num_elements(mesh);
    double lin_min = hoc_report_stage(r, 0)->stats.min;
    const hoc_stage *last = hoc_report_stage(r, hoc_report_num_stages(r) - 1);
    printf("pinched_sheet at order 5: %zu element(s), %zu tangled, min q %.4f (linear %.4f)\n",
           ne, last->stats.tangled, last->stats.min, lin_min);
    CHECK(last->stats.tangled == 0 && last->stats.min >= HOC_PIPELINE_POOR * lin_min &&
          lin_min > 0);
  }
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
  hoc_mesh_destroy(&cut);
  hoc_mesh_destroy(&kept);
  hoc_model_destroy(&model);
}

/* The largest gap between a pole slot's arbitrary coordinate in its
 * element and the mean of the element's other corners' (as assembly and
 * a file read back set it). */
static double pole_gap(const hoc_mesh *m) {
  double gap = 0;
  size_t np = (size_t)m->np;
  for (size_t e = 0; e < m->n_elems; ++e) {
    const size_t *sl = m->elem_slot + e * np;
    const double *uv = m->elem_uv + 2 * e * np;
    for (int k = 0; k < 3; ++k)
      for (int d = 0; d < 2; ++d) {
        if (m->dim[m->slot_node[sl[k]]] == HOC_ON_FACE || !(m->slot_pole[sl[k]] & (1 << d)))
          continue;
        double mean = 0.5 * (uv[2 * ((k + 1) % 3) + d] + uv[2 * ((k + 2) % 3) + d]);
        gap = fmax(gap, fabs(uv[2 * k + d] - mean));
      }
  }
  return gap;
}

/* surf114's face 1 (an IGES spline surface) pinches at u = 7.64 and turns
 * back past it (a flap 0.1 wide): cut there, the elements on the flap's
 * side see the flap's normal at the point (HOC_POLE_ABOVE: taken toward
 * u = 8, not toward the face's middle), and at order 3 none is tangled,
 * without any split or remeshing. */
static void test_flap(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(DATA "surf114_face1.brep", &model));
  if (!model) return;
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = 3;
  o.refinements = 0;
  hoc_mesh *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  if (mesh && r) {
    size_t above = 0;
    for (size_t s = 0; s < mesh->n_slots; ++s)
      above += (mesh->slot_pole[s] & HOC_POLE_ABOVE) != 0;
    const hoc_stage *last = hoc_report_stage(r, hoc_report_num_stages(r) - 1);
    /* read back, it measures the same */
    const char *path = "test_mesh_pinch_flap.msh";
    hoc_mesh *back = NULL;
    size_t ne = hoc_mesh_num_elements(mesh), tangled_back = SIZE_MAX;
    unsigned char *tangled = calloc(ne + 1, 1);
    CHECK_OK(hoc_mesh_write_msh(mesh, path));
    CHECK_OK(hoc_mesh_read_msh(model, path, &back));
    if (back && tangled && hoc_mesh_num_elements(back) == ne) {
      CHECK_OK(hoc_mesh_measure(back, HOC_MEASURE_SHAPE, NULL, tangled, NULL));
      tangled_back = 0;
      for (size_t e = 0; e < ne; ++e) tangled_back += tangled[e];
    }
    remove(path);
    double gap = pole_gap(mesh);
    printf("surf114's face 1 at order 3: %zu pole slot(s) on the flap's side, %zu tangled, "
           "%zu read back; pole directions off their corners' mean by %.3g\n",
           above, last->stats.tangled, tangled_back, gap);
    CHECK(above > 0 && last->stats.tangled == 0 && tangled_back == 0 && gap < 1e-12);
    free(tangled);
    hoc_mesh_destroy(&back);
  }
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
  hoc_model_destroy(&model);
}

/* The note on poor elements across a pinch, from a linear mesh not cut. */
static void test_note(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(DATA "pinched_sheet.step", &model));
  if (!model) return;
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = 5;
  hoc_mesh *given = sheet_mesh(model, 1), *mesh = NULL;
  o.linear = given;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  size_t ne = mesh ? hoc_mesh_num_elements(mesh) : 0, low = 0, across = 0;
  double *q = calloc(ne + 1, sizeof *q);
  if (mesh && r && q) {
    double bound = HOC_PIPELINE_POOR * hoc_report_stage(r, 0)->stats.min;
    CHECK_OK(hoc_mesh_measure(mesh, HOC_MEASURE_SHAPE, q, NULL, NULL));
    hoc_pinch p[HOC_PINCHES];
    int n = 0;
    CHECK_OK(hoc_face_pinches(model, 0, HOC_PIPELINE_PINCH_SHARE, p,
                              HOC_PINCHES, &n));
    for (size_t e = 0; e < ne; ++e) {
      if (!(q[e] < bound)) continue;
      ++low;
      across += (size_t)hoc_mesh_element_crosses_pinch(mesh, e, p, n);
    }
    int noted = 0;
    for (size_t i = 0; i < hoc_report_num_findings(r); ++i) {
      hoc_event_kind kind;
      const char *text = hoc_report_finding(r, i, &kind);
      noted += kind == HOC_EVENT_NOTE && strstr(text, "cross a pinch of their face") != NULL;
    }
    printf("pinched_sheet at order 5: %zu element(s) below %.4f, %zu across the pinch; "
           "%d note(s)\n",
           low, bound, across, noted);
    CHECK(low > 0 && across == low && noted == 1);
  }
  free(q);
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
  hoc_mesh_destroy(&given);
  hoc_model_destroy(&model);
}

/* Turn element e of an order-1 mesh over: swap its corners 1 and 2. */
static void turn_over(hoc_mesh *m, size_t e) {
  size_t *c = m->conn + 3 * e, *s = m->elem_slot + 3 * e, t = c[1];
  double *uv = m->elem_uv + 6 * e;
  c[1] = c[2], c[2] = t;
  t = s[1], s[1] = s[2], s[2] = t;
  for (int d = 0; d < 2; ++d) {
    double x = uv[2 + d];
    uv[2 + d] = uv[4 + d], uv[4 + d] = x;
  }
}

static void test_unrefinable(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(DATA "pinched_sheet.step", &model));
  if (!model) return;
  hoc_run run = {0};
  hoc_mesh_options_default(&run.o);
  hoc_linear_options lo;
  memset(&lo, 0, sizeof lo);
  lo.order = 1;
  lo.keep_pinches = 1;
  hoc_pinch p[HOC_PINCHES];
  int n = 0;
  CHECK_OK(hoc_face_pinches(model, 0, HOC_PIPELINE_PINCH_SHARE, p, HOC_PINCHES, &n));
  for (int across = 1; across >= 0; --across) {
    hoc_mesh *lin = NULL;
    CHECK_OK(hoc_mesh_generate_linear(model, &lo, &lin));
    if (!lin) break;
    size_t ne = hoc_mesh_num_elements(lin), e = 0;
    while (e < ne && hoc_mesh_element_crosses_pinch(lin, e, p, n) != across) ++e;
    int why = -1;
    if (e < ne) {
      turn_over(lin, e);
      CHECK_OK(hoc_repair_tangled_unrefinable(&run, lin, &why));
    }
    printf("pinched_sheet, element %zu of %zu (%s the pinch) turned over: unrefinable %d\n",
           e + 1, ne, across ? "across" : "away from", why);
    if (across)
      CHECK(why == (HOC_UNREFINABLE_PINCHES | HOC_UNREFINABLE_EACH));
    else
      CHECK(e < ne && why == 0);
    hoc_mesh_destroy(&lin);
  }
  hoc_model_destroy(&model);
}

static void test_neck(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(DATA "surf114_face3.brep", &model));
  if (!model) return;
  hoc_run run = {0};
  hoc_mesh_options_default(&run.o);
  run.o.order = 2;
  run.o.size = 8.1146; /* surf114.igs's default sizes (its diagonal / 20) */
  run.o.size_min = 0.81146;
  int why[2] = {-1, -1};
  size_t tangled[2] = {SIZE_MAX, SIZE_MAX}, made = 0;
  for (int k = 0; k < 2; ++k) {
    hoc_mesh_options o = run.o;
    o.refinements = k ? -1 : 0;
    hoc_mesh *mesh = NULL;
    hoc_report *r = NULL;
    CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
    if (mesh && r) {
      tangled[k] = hoc_report_tangled(r);
      if (!k) CHECK_OK(hoc_repair_tangled_unrefinable(&run, mesh, &why[k]));
      if (k) made = (size_t)hoc_report_refinements(r);
    }
    hoc_report_destroy(&r);
    hoc_mesh_destroy(&mesh);
  }
  printf("surf114's face 3 at order 2: %zu tangled unsplit (unrefinable %d), %zu after %zu "
         "split(s)\n",
         tangled[0], why[0], tangled[1], made);
  CHECK(tangled[0] > 0 && tangled[0] != SIZE_MAX && why[0] == HOC_UNREFINABLE_FOLDS);
  CHECK(tangled[1] == 0 && made > 0);
  hoc_model_destroy(&model);
}

int main(void) {
  test_analytic();
  test_files();
  test_cut();
  test_flap();
  test_note();
  test_unrefinable();
  test_neck();
  return test_report();
}
