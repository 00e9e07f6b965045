/* MSH files: round trips of synthetic meshes of orders 1..10 (positions
 * bit-exact, classification, parameters, connectivity), gmsh itself reads
 * our files, we read gmsh's ASCII, binary and 2.2 files, and corrupt input
 * of every kind fails cleanly.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "basis/basis.h"
#include "io/io.h"
#include "test_util.h"

#include <gmshc.h>
#include <stdint.h>
#include <string.h>

/* Two order-p triangles sharing an edge, on surfaces 1 and 2, with nodes on
 * points 1..4, curves 1..5 and the surfaces; lines on the curves. */
typedef struct synth {
  int p;
  size_t nn, nt, nl;
  double xyz[3 * 400], par[2 * 400];
  int dim[400], ent[400];
  size_t tri[2 * 66], line[5 * 11];
  int tri_tag[2], line_tag[5];
} synth;

static void build(synth *m, int p) {
  memset(m, 0, sizeof *m);
  m->p = p;
  int np = (p + 1) * (p + 2) / 2;
  double rs[2 * 66];
  hoc_tri_nodes(p, HOC_NODES_EQUISPACED, rs);
  /* element 0: (0,0),(1,0),(0,1); element 1: (1,0),(1,1),(0,1) */
  const double V[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
  const int T[2][3] = {{0, 1, 2}, {1, 3, 2}};
  size_t vnode[4];
  for (int v = 0; v < 4; ++v) {
    vnode[v] = m->nn;
    m->xyz[3 * m->nn] = V[v][0], m->xyz[3 * m->nn + 1] = V[v][1], m->xyz[3 * m->nn + 2] = 0.25 * v;
    m->dim[m->nn] = 0, m->ent[m->nn] = v + 1;
    ++m->nn;
  }
  /* edges: (0,1) c1, (1,2) c2 (shared, interior: surface nodes of surface 1), (2,0) c3, (1,3) c4, (3,2) c5 */
  for (int e = 0; e < 2; ++e) {
    m->tri_tag[e] = e + 1;
    for (int k = 0; k < np; ++k) {
      size_t idx;
      double r = rs[2 * k], s = rs[2 * k + 1], l0 = 1 - r - s;
      if (k < 3) {
        idx = vnode[T[e][k]];
      } else {
        /* find an existing node at this position (shared edge) */
        double x = l0 * V[T[e][0]][0] + r * V[T[e][1]][0] + s * V[T[e][2]][0];
        double y = l0 * V[T[e][0]][1] + r * V[T[e][1]][1] + s * V[T[e][2]][1];
        idx = SIZE_MAX;
        for (size_t i = 0; i < m->nn; ++i)
          if (fabs(m->xyz[3 * i] - x) < 1e-12 && fabs(m->xyz[3 * i + 1] - y) < 1e-12) idx = i;
        if (idx == SIZE_MAX) {
          idx = m->nn++;
          m->xyz[3 * idx] = x, m->xyz[3 * idx + 1] = y, m->xyz[3 * idx + 2] = 0.1 * x * y + 1.0 / 3;
          int on_curve = k < 3 * p && !(e == 0 && k >= 3 + (p - 1) && k < 3 + 2 * (p - 1));
          if (on_curve) {
            int c = e == 0 ? (k < 3 + (p - 1) ? 1 : 3) : (k < 3 + (p - 1) ? 4 : 5);
            m->dim[idx] = 1, m->ent[idx] = c, m->par[2 * idx] = x + 0.5 * y;
          } else {
            m->dim[idx] = 2, m->ent[idx] = e + 1, m->par[2 * idx] = x, m->par[2 * idx + 1] = y;
          }
        }
      }
      m->tri[e * (size_t)np + k] = idx;
    }
  }
  m->nt = 2;
  /* lines along curves 1, 3, 4, 5 from the triangles' edges */
  const int edge_of[4][2] = {{0, 0}, {0, 2}, {1, 0}, {1, 1}};
  const int tags[4] = {1, 3, 4, 5};
  for (int l = 0; l < 4; ++l) {
    int e = edge_of[l][0], k = edge_of[l][1];
    size_t *ln = m->line + l * (size_t)(p + 1);
    ln[0] = m->tri[e * (size_t)np + k];
    ln[1] = m->tri[e * (size_t)np + (k + 1) % 3];
    for (int j = 0; j < p - 1; ++j) ln[2 + j] = m->tri[e * (size_t)np + 3 + k * (p - 1) + j];
    m->line_tag[l] = tags[l];
  }
  m->nl = 4;
}

static hoc_status write_synth(const synth *m, const char *path) {
  int ptag[4] = {1, 2, 3, 4}, ctag[5] = {1, 2, 3, 4, 5}, stag[2] = {1, 2};
  double pxyz[12] = {0, 0, 0, 1, 0, 0.25, 0, 1, 0.5, 1, 1, 0.75}, bb[6 * 5] = {0};
  int cstart[6] = {0, 2, 4, 6, 8, 10}, cbnd[10] = {1, -2, 2, -3, 3, -1, 2, -4, 4, -3};
  int sstart[3] = {0, 3, 6}, sbnd[6] = {1, 2, 3, 4, 5, -2};
  hoc_msh_write_data d = {0};
  d.n_points = 4, d.point_tag = ptag, d.point_xyz = pxyz;
  d.n_curves = 5, d.curve_tag = ctag, d.curve_bbox = bb, d.curve_bnd_start = cstart, d.curve_bnd = cbnd;
  d.n_surfaces = 2, d.surface_tag = stag, d.surface_bbox = bb, d.surface_bnd_start = sstart, d.surface_bnd = sbnd;
  d.n_nodes = m->nn, d.xyz = m->xyz, d.param = m->par, d.node_dim = m->dim, d.node_entity_tag = m->ent;
  d.order = m->p, d.n_tris = m->nt, d.tri_nodes = m->tri, d.tri_surface_tag = m->tri_tag;
  d.n_lines = m->nl, d.line_nodes = m->line, d.line_curve_tag = m->line_tag;
  return hoc_msh_write(path, &d);
}

static void test_round_trip(int p) {
  synth m;
  build(&m, p);
  char path[64];
  snprintf(path, sizeof path, "synth_p%d.msh", p);
  CHECK_OK(write_synth(&m, path));
  hoc_msh_raw raw;
  CHECK_OK(hoc_msh_read(path, &raw));
  CHECK(raw.order == p && raw.n_tris == 2 && raw.n_lines == 4);
  CHECK(raw.n_nodes == m.nn);
  int np = (p + 1) * (p + 2) / 2, same = 1;
  /* compare through positions: each triangle node of ours and of the file */
  for (int e = 0; e < 2 && raw.n_tris == 2; ++e)
    for (int k = 0; k < np; ++k) {
      size_t a = m.tri[e * (size_t)np + k], b = raw.tri_nodes[e * (size_t)np + k];
      same &= !memcmp(m.xyz + 3 * a, raw.xyz + 3 * b, 3 * sizeof(double));
      same &= raw.node_dim[b] == m.dim[a] && raw.node_entity_tag[b] == m.ent[a];
      if (m.dim[a] >= 1) same &= raw.has_param[b] && raw.param[2 * b] == m.par[2 * a];
      if (m.dim[a] == 2) same &= raw.param[2 * b + 1] == m.par[2 * a + 1];
      if (m.dim[a] == 0) same &= !raw.has_param[b];
    }
  CHECK(same);
  CHECK(raw.tri_surface_tag[0] == 1 && raw.tri_surface_tag[1] == 2);
  hoc_msh_raw_free(&raw);
  CHECK(raw.xyz == NULL && raw.n_nodes == 0);

  /* gmsh reads it: same counts, parameters back */
  int ierr = 0;
  gmshClear(&ierr);
  gmshOpen(path, &ierr);
  CHECK(ierr == 0);
  size_t *tags = NULL, ntags = 0, nc = 0, npar = 0;
  double *coord = NULL, *par = NULL;
  gmshModelMeshGetNodes(&tags, &ntags, &coord, &nc, &par, &npar, 2, 1, 0, 1, &ierr);
  CHECK(ierr == 0);
  size_t expect = 0;
  for (size_t i = 0; i < m.nn; ++i) expect += m.dim[i] == 2 && m.ent[i] == 1;
  CHECK(ntags == expect && npar == 2 * expect);
  gmshFree(tags);
  gmshFree(coord);
  gmshFree(par);
  size_t *et = NULL, net = 0, *en = NULL, nen = 0;
  gmshModelMeshGetElementsByType(hoc_msh_triangle_type(p), &et, &net, &en, &nen, -1, 0, 1, &ierr);
  CHECK(ierr == 0 && net == 2 && nen == 2 * (size_t)np);
  gmshFree(et);
  gmshFree(en);
}

/* A file gmsh wrote itself, in its three formats. */
static void test_gmsh_written(void) {
  int ierr = 0;
  gmshClear(&ierr);
  gmshModelAdd("square", &ierr);
  gmshModelOccAddRectangle(0, 0, 0, 1, 1, -1, 0, &ierr);
  gmshModelOccSynchronize(&ierr);
  gmshOptionSetNumber("Mesh.MeshSizeMax", 0.3, &ierr);
  gmshModelMeshGenerate(2, &ierr);
  gmshModelMeshSetOrder(3, &ierr);
  CHECK(ierr == 0);
  const char *files[3] = {"gmsh41.msh", "gmsh41bin.msh", "gmsh22.msh"};
  for (int f = 0; f < 3; ++f) {
    gmshOptionSetNumber("Mesh.Binary", f == 1, &ierr);
    gmshOptionSetNumber("Mesh.MshFileVersion", f == 2 ? 2.2 : 4.1, &ierr);
    gmshOptionSetNumber("Mesh.SaveParametric", f == 0, &ierr);
    gmshWrite(files[f], &ierr);
    CHECK(ierr == 0);
  }
  gmshOptionSetNumber("Mesh.Binary", 0, &ierr);
  gmshOptionSetNumber("Mesh.MshFileVersion", 4.1, &ierr);
  gmshOptionSetNumber("Mesh.SaveParametric", 0, &ierr);
  size_t *et = NULL, net = 0, *en = NULL, nen = 0;
  gmshModelMeshGetElementsByType(21, &et, &net, &en, &nen, -1, 0, 1, &ierr);
  gmshFree(et);
  gmshFree(en);
  for (int f = 0; f < 3; ++f) {
    hoc_msh_raw raw;
    CHECK_OK(hoc_msh_read(files[f], &raw));
    CHECK(raw.order == 3 && raw.n_tris == net && raw.n_lines > 0);
    int classified = 1, params = 1;
    for (size_t i = 0; i < raw.n_nodes; ++i) {
      classified &= raw.node_dim[i] >= 0 && raw.node_dim[i] <= 2;
      if (raw.node_dim[i] == 2) params &= raw.has_param[i] == (f == 0);
    }
    CHECK(classified);
    CHECK(params);
    hoc_msh_raw_free(&raw);
  }
}

static char *slurp(const char *path, size_t *n) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long s = ftell(f);
  rewind(f);
  char *d = malloc((size_t)s + 1);
  *n = fread(d, 1, (size_t)s, f);
  fclose(f);
  return d;
}

static int clean_failure(hoc_status st) {
  return st == HOC_ERR_FORMAT || st == HOC_ERR_UNSUPPORTED;
}

/* Corrupt inputs: every prefix length, flipped bytes, garbage. */
static void test_corrupt(const char *path) {
  size_t n;
  char *d = slurp(path, &n);
  CHECK(d != NULL);
  if (!d) return;
  hoc_msh_raw raw;
  int all_clean = 1;
  size_t step = n > 4000 ? n / 2000 : 1;
  for (size_t len = 0; len < n; len += step) {
    hoc_status st = hoc_msh_read_buffer(d, len, "truncated", &raw);
    if (st == HOC_OK) hoc_msh_raw_free(&raw); /* a prefix ending right after a section can be whole */
    else all_clean &= clean_failure(st);
  }
  CHECK(all_clean);
  unsigned long long seed = 12345;
  all_clean = 1;
  for (int trial = 0; trial < 2000; ++trial) {
    char *c = malloc(n);
    memcpy(c, d, n);
    for (int k = 0; k < 4; ++k) {
      seed = seed * 6364136223846793005ULL + 1442695040888963407ULL;
      c[(seed >> 33) % n] = (char)(seed >> 17);
    }
    hoc_status st = hoc_msh_read_buffer(c, n, "flipped", &raw);
    if (st == HOC_OK) hoc_msh_raw_free(&raw);
    else all_clean &= clean_failure(st) || st == HOC_ERR_MEMORY;
    free(c);
  }
  CHECK(all_clean);
  free(d);
}

int main(void) {
  int ierr = 0;
  gmshInitialize(0, NULL, 0, &ierr);
  gmshOptionSetNumber("General.Terminal", 0, &ierr);
  int orders[] = {1, 2, 3, 5, 10};
  for (size_t k = 0; k < sizeof orders / sizeof *orders; ++k) test_round_trip(orders[k]);
  test_gmsh_written();
  gmshFinalize(&ierr);
  test_corrupt("synth_p3.msh");
  test_corrupt("gmsh41bin.msh");
  test_corrupt("gmsh22.msh");
  hoc_msh_raw raw;
  CHECK_STATUS(hoc_msh_read("missing.msh", &raw), HOC_ERR_IO);
  CHECK_STATUS(hoc_msh_read_buffer("", 0, "empty", &raw), HOC_ERR_FORMAT);
  CHECK_STATUS(hoc_msh_read_buffer("\x89PNG\r\n\x1a\n", 8, "png", &raw), HOC_ERR_FORMAT);
  const char *huge = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 99999999999 1 99999999999\n";
  CHECK_STATUS(hoc_msh_read_buffer(huge, strlen(huge), "huge", &raw), HOC_ERR_FORMAT);
  const char *nan = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 1 1 1\n2 1 0 1\n1\nnan 0 0\n$EndNodes\n";
  CHECK_STATUS(hoc_msh_read_buffer(nan, strlen(nan), "nan", &raw), HOC_ERR_FORMAT);
  const char *v3 = "$MeshFormat\n3.0 0 8\n$EndMeshFormat\n";
  CHECK_STATUS(hoc_msh_read_buffer(v3, strlen(v3), "v3", &raw), HOC_ERR_UNSUPPORTED);
  /* an order-11 mesh has no MSH type */
  hoc_msh_write_data d = {0};
  d.order = 11;
  CHECK_STATUS(hoc_msh_write("p11.msh", &d), HOC_ERR_UNSUPPORTED);
  FILE *f = fopen("p11.msh", "r");
  CHECK(f == NULL);
  if (f) fclose(f);
  return test_report();
}
