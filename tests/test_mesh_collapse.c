/* Collapsed sides the model does not mark (mesh/collapse.c): a face side
 * of zero length whose curve gmsh meshes like any other, with nodes along
 * it and at both ends, all at one point. Without the rule the triangles
 * along the side have two corners at that point (q = 0, and no curved
 * element over them is valid).
 *
 * Analytic cone: a grid whose apex row is one vertex node and the apex
 * curve's nodes at every u, as gmsh meshes an unmarked collapsed side;
 * assembled, every element has three distinct corners and q > 0, the apex
 * is one node, and raising to order 4 leaves none tangled.
 *
 * pygeo_nose.brep: the nose cap of an IGES fuselage, whose collapsed side
 * (v = pi) is an unmarked curve between two vertices at one point; gmsh's
 * linear mesh puts three nodes there. The two vertices become one node,
 * the curves that ended at the other vertex end at it, and the mesh raised
 * to order 5 is untangled with min q above 0.5 (0.05 without the rule,
 * after 176 sweeps).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "hocad.h"
#include "mesh/mesh.h"
#include "test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DATA HOC_SOURCE_DIR "/tests/data/"

static const double TWO_PI = 6.28318530717958647692;

/* Elements with two corners within `tol` of each other. */
static size_t pinched(const hoc_mesh *m, double tol) {
  size_t n = 0;
  for (size_t e = 0; e < m->n_elems; ++e) {
    const size_t *c = m->conn + e * (size_t)m->np;
    for (int k = 0; k < 3; ++k) {
      const double *a = m->xyz + 3 * c[k], *b = m->xyz + 3 * c[(k + 1) % 3];
      if (fabs(a[0] - b[0]) + fabs(a[1] - b[1]) + fabs(a[2] - b[2]) <= tol) {
        ++n;
        break;
      }
    }
  }
  return n;
}

/* nu x nv grid of the cone (periodic in u); row v = 0 is the apex: node 0
 * on the apex vertex, nodes 1..nu-1 on the apex curve at t = u. */
static void test_cone(void) {
  enum { NU = 12, NV = 6 };
  hoc_model *model = NULL;
  CHECK_OK(hoc_cad_create_analytic(HOC_ANALYTIC_CONE, 1.0, 2.0, &model));
  if (!model) return;
  CHECK(model->curves[1].degenerate);
  const hoc_cad_face *f = &model->faces[0];
  size_t n = (size_t)NU * (NV + 1);
  double xyz[3 * NU * (NV + 1)], par[2 * NU * (NV + 1)];
  signed char dim[NU * (NV + 1)];
  int ent[NU * (NV + 1)], face[2 * NU * NV];
  size_t conn[6 * NU * NV];
  for (int j = 0; j <= NV; ++j)
    for (int i = 0; i < NU; ++i) {
      size_t k = (size_t)j * NU + (size_t)i;
      double uv[2] = {TWO_PI * i / NU, f->lo[1] + (f->hi[1] - f->lo[1]) * j / NV};
      CHECK_OK(hoc_cad_face_eval(model, 0, 1, uv, xyz + 3 * k, NULL, NULL));
      if (j == 0 && i == 0) {
        dim[k] = HOC_ON_VERTEX, ent[k] = 0, par[2 * k] = par[2 * k + 1] = 0;
      } else if (j == 0) {
        dim[k] = HOC_ON_CURVE, ent[k] = 1, par[2 * k] = uv[0], par[2 * k + 1] = 0;
      } else if (i == 0) {
        dim[k] = j == NV ? HOC_ON_VERTEX : HOC_ON_CURVE;
        ent[k] = j == NV ? 1 : 0, par[2 * k] = uv[1], par[2 * k + 1] = 0;
      } else if (j == NV) {
        dim[k] = HOC_ON_CURVE, ent[k] = 2, par[2 * k] = uv[0], par[2 * k + 1] = 0;
      } else {
        dim[k] = HOC_ON_FACE, ent[k] = 0, par[2 * k] = uv[0], par[2 * k + 1] = uv[1];
      }
    }
  size_t ne = 0;
  for (int j = 0; j < NV; ++j)
    for (int i = 0; i < NU; ++i) {
      size_t a = (size_t)j * NU + (size_t)i, b = (size_t)j * NU + (size_t)(i + 1) % NU,
             c = a + NU, d = b + NU;
      size_t t[2][3] = {{a, b, d}, {a, d, c}};
      for (int k = 0; k < 2; ++k) {
        memcpy(conn + 3 * ne, t[k], sizeof t[k]);
        face[ne++] = 0;
      }
    }
  hoc_mesh_source src = {.order = 1, .nodeset = HOC_NODES_EQUISPACED, .n_nodes = n, .xyz = xyz,
                         .param = par, .dim = dim, .entity = ent, .n_elems = ne, .conn = conn,
                         .elem_face = face};
  hoc_mesh *lin = NULL, *ho = NULL;
  CHECK_OK(hoc_mesh_assemble(model, &src, &lin));
  if (lin) {
    hoc_quality_stats st;
    CHECK_OK(hoc_mesh_measure(lin, HOC_MEASURE_SHAPE, NULL, NULL, &st));
    size_t apex = 0;
    for (size_t i = 0; i < lin->n_nodes; ++i)
      apex += fabs(lin->xyz[3 * i]) + fabs(lin->xyz[3 * i + 1]) + fabs(lin->xyz[3 * i + 2]) < 1e-12;
    printf("cone: %zu -> %zu elements (%zu dropped), %zu -> %zu nodes, %zu at the apex, "
           "%zu pinched, min q %.4f, %zu tangled\n",
           ne, lin->n_elems, lin->n_collapsed, n, lin->n_nodes, apex, pinched(lin, 1e-12),
           st.min, st.tangled);
    CHECK(lin->n_collapsed == NU && lin->n_elems == ne - NU && lin->n_nodes == n - (NU - 1));
    CHECK(apex == 1 && pinched(lin, 1e-12) == 0);
    CHECK(st.min > 0.1 && st.tangled == 0);
    CHECK_OK(hoc_mesh_elevate(lin, 4, HOC_NODES_EQUISPACED, &ho));
  }
  if (ho) {
    hoc_quality_stats st;
    CHECK_OK(hoc_mesh_measure(ho, HOC_MEASURE_SHAPE, NULL, NULL, &st));
    printf("cone at order 4: min q %.4f, %zu tangled\n", st.min, st.tangled);
    CHECK(st.min > 0.1 && st.tangled == 0);
  }
  hoc_mesh_destroy(&ho);
  hoc_mesh_destroy(&lin);
  hoc_model_destroy(&model);
}

static int on_event(void *user, const hoc_event *ev) {
  if (ev->kind == HOC_EVENT_NOTE && ev->message && strstr(ev->message, "zero length"))
    ++*(int *)user;
  return 0;
}

static void test_nose(void) {
  hoc_model *model = NULL;
  CHECK_OK(hoc_model_open(DATA "pygeo_nose.brep", &model));
  if (!model) return;
  int unmarked = 0;
  for (int c = 0; c < model->n_curves; ++c) unmarked += model->curves[c].degenerate;
  CHECK(unmarked == 1);
  hoc_linear_options lo;
  hoc_linear_options_default(&lo);
  lo.order = 5;
  hoc_mesh *lin = NULL;
  CHECK_OK(hoc_mesh_generate_linear(model, &lo, &lin));
  if (lin) {
    hoc_quality_stats st;
    CHECK_OK(hoc_mesh_measure(lin, HOC_MEASURE_SHAPE, NULL, NULL, &st));
    double tol = hoc_mesh_collapse_distance(model);
    printf("nose, linear: %zu elements, %zu dropped, %zu pinched, min q %.4f\n", lin->n_elems,
           lin->n_collapsed, pinched(lin, tol), st.min);
    CHECK(lin->n_collapsed > 0 && pinched(lin, tol) == 0 && st.min > 0.01);
  }
  hoc_mesh_destroy(&lin);

  int notes = 0;
  hoc_mesh_options o;
  hoc_mesh_options_default(&o);
  o.order = 5;
  o.event = on_event;
  o.event_user = &notes;
  hoc_mesh *mesh = NULL;
  hoc_report *r = NULL;
  CHECK_OK(hoc_mesh_model(model, &o, &mesh, &r));
  if (mesh) {
    hoc_quality_stats st;
    CHECK_OK(hoc_mesh_measure(mesh, HOC_MEASURE_SHAPE, NULL, NULL, &st));
    printf("nose at order 5: %zu elements, min q %.4f, %zu tangled, %d note(s)\n",
           hoc_mesh_num_elements(mesh), st.min, st.tangled, notes);
    CHECK(st.tangled == 0 && st.min > 0.5 && notes == 1);
  }
  hoc_report_destroy(&r);
  hoc_mesh_destroy(&mesh);
  hoc_model_destroy(&model);
}

int main(void) {
  test_cone();
  test_nose();
  return test_report();
}
