/* VTK .vtu files: the XML header and every appended binary block read back
 * (sizes, points bit-exact, connectivity, offsets, cell types 5 / 69, cell
 * data), for orders 1, 3, 10 and 15; bad input refused before anything is
 * written. When /usr/bin/python3 has VTK, VTK itself reads the files and
 * interpolates each Lagrange triangle: a degree-p polynomial map is
 * reproduced exactly only if VTK's point order is gmsh's.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"
#include "test_util.h"
#include "test_fixtures.h"

#include <stdint.h>
#include <string.h>
#include <sys/stat.h>


/* A polynomial map of degree min(p, 2) of the reference triangle. */
static void map_point(int p, double r, double s, double *x) {
  double q = p >= 2 ? 1 : 0;
  x[0] = 2 * r + 0.5 * s + q * 0.3 * s * s;
  x[1] = s + q * 0.2 * r * s - 0.1;
  x[2] = q * (0.5 * r * r - 0.25 * s * s) + 0.1 * r;
}

/* n_cells order-p triangles; each has its own points (no sharing needed). */
typedef struct mesh {
  int p;
  size_t n_points, n_cells;
  double *xyz, *quality;
  size_t *cells;
  unsigned char *tangled;
  int *face;
} mesh;

static void build(mesh *m, int p, size_t n_cells) {
  int np = (p + 1) * (p + 2) / 2, ij[2 * 136];
  fixture_lattice(p, 0, 0, ij);
  m->p = p;
  m->n_cells = n_cells;
  m->n_points = n_cells * (size_t)np;
  m->xyz = malloc(3 * m->n_points * sizeof *m->xyz);
  m->cells = malloc(m->n_points * sizeof *m->cells);
  m->quality = malloc(n_cells * sizeof *m->quality);
  m->tangled = malloc(n_cells);
  m->face = malloc(n_cells * sizeof *m->face);
  for (size_t c = 0; c < n_cells; ++c) {
    for (int k = 0; k < np; ++k) {
      size_t i = c * (size_t)np + (size_t)k;
      map_point(p, (double)ij[2 * k] / p, (double)ij[2 * k + 1] / p, m->xyz + 3 * i);
      m->xyz[3 * i + 2] += (double)c / 3;         /* cells stacked in z */
      m->cells[i] = (i * 1009 + 3) % m->n_points; /* a permutation: 1009 is prime, n < 1009 */
    }
    m->quality[c] = c % 3 ? 1.0 / (double)(c + 1) : -0.0;
    m->tangled[c] = (unsigned char)(c % 3 == 0);
    m->face[c] = (int)c * 1000 - 7;
  }
  /* undo the permutation on the points so that cell c's nodes are where they were */
  double *perm = malloc(3 * m->n_points * sizeof *perm);
  for (size_t i = 0; i < m->n_points; ++i)
    memcpy(perm + 3 * m->cells[i], m->xyz + 3 * i, 3 * sizeof *perm);
  free(m->xyz);
  m->xyz = perm;
}

static void destroy(mesh *m) {
  free(m->xyz);
  free(m->cells);
  free(m->quality);
  free(m->tangled);
  free(m->face);
  memset(m, 0, sizeof *m);
}

static hoc_status write_mesh(const mesh *m, const char *path, int cell_data) {
  hoc_vtu_data d = {0};
  d.order = m->p;
  d.n_points = m->n_points;
  d.xyz = m->xyz;
  d.n_cells = m->n_cells;
  d.cells = m->cells;
  if (cell_data) {
    d.quality = m->quality;
    d.tangled = m->tangled;
    d.face_tag = m->face;
  }
  return hoc_vtu_write(path, &d);
}

/* The appended block of the DataArray named `name`: its bytes and size;
 * checks its declared type. NULL if absent or inconsistent. */
static const char *block(const char *file, size_t size, const char *name, const char *type,
                         uint64_t *bytes) {
  char key[128];
  snprintf(key, sizeof key, "Name=\"%s\"", name);
  const char *at = strstr(file, key), *app = strstr(file, "<AppendedData encoding=\"raw\">");
  if (!at || !app || at > app) return NULL;
  const char *open = at;
  while (open > file && *open != '<')
    --open;
  const char *close = strchr(at, '>');
  char want[64];
  snprintf(want, sizeof want, "type=\"%s\"", type);
  const char *t = strstr(open, want), *o = strstr(open, "offset=\"");
  if (!t || t > close || !o || o > close || !strstr(open, "format=\"appended\"")) return NULL;
  unsigned long long offset = strtoull(o + 8, NULL, 10);
  const char *base = strchr(app, '_');
  if (!base) return NULL;
  ++base;
  if ((size_t)(base - file) + offset + 8 > size) return NULL;
  memcpy(bytes, base + offset, 8);
  if ((size_t)(base - file) + offset + 8 + *bytes > size) return NULL;
  return base + offset + 8;
}

static void check_file(const mesh *m, const char *path, int cell_data) {
  size_t size;
  char *f = fixture_slurp(path, &size);
  CHECK(f != NULL);
  if (!f) return;
  int p = m->p, np = (p + 1) * (p + 2) / 2;
  size_t nc = m->n_cells, nn = m->n_points;
  CHECK(!strncmp(f, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\"",
                 67));
  CHECK(strstr(f, "header_type=\"UInt64\"") != NULL);
  const uint16_t one = 1;
  CHECK(strstr(f, *(const unsigned char *)&one ? "byte_order=\"LittleEndian\""
                                               : "byte_order=\"BigEndian\""));
  char counts[128];
  snprintf(counts, sizeof counts, "<Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">", nn, nc);
  CHECK(strstr(f, counts) != NULL);
  const char *tail = "\n  </AppendedData>\n</VTKFile>\n";
  CHECK(size > strlen(tail) && !strcmp(f + size - strlen(tail), tail));
  uint64_t bytes = 0;
  const char *b = block(f, size, "Points", "Float64", &bytes);
  CHECK(b && bytes == 24 * nn && strstr(f, "NumberOfComponents=\"3\""));
  if (b && bytes == 24 * nn) CHECK(!memcmp(b, m->xyz, bytes));
  b = block(f, size, "connectivity", "Int64", &bytes);
  CHECK(b && bytes == 8 * nn);
  int ok = b && bytes == 8 * nn;
  for (size_t k = 0; k < nn && ok; ++k) {
    int64_t v;
    memcpy(&v, b + 8 * k, 8);
    ok &= v == (int64_t)m->cells[k];
  }
  CHECK(ok);
  b = block(f, size, "offsets", "Int64", &bytes);
  ok = b && bytes == 8 * nc;
  for (size_t c = 0; c < nc && ok; ++c) {
    int64_t v;
    memcpy(&v, b + 8 * c, 8);
    ok &= v == (int64_t)((c + 1) * (size_t)np);
  }
  CHECK(ok);
  b = block(f, size, "types", "UInt8", &bytes);
  ok = b && bytes == nc;
  for (size_t c = 0; c < nc && ok; ++c)
    ok &= (unsigned char)b[c] == (p == 1 ? 5 : 69);
  CHECK(ok);
  if (cell_data) {
    b = block(f, size, "quality", "Float64", &bytes);
    CHECK(b && bytes == 8 * nc && !memcmp(b, m->quality, 8 * nc));
    b = block(f, size, "tangled", "UInt8", &bytes);
    CHECK(b && bytes == nc && !memcmp(b, m->tangled, nc));
    b = block(f, size, "face", "Int32", &bytes);
    ok = b && bytes == 4 * nc;
    for (size_t c = 0; c < nc && ok; ++c) {
      int32_t v;
      memcpy(&v, b + 4 * c, 4);
      ok &= v == m->face[c];
    }
    CHECK(ok);
    CHECK(strstr(f, "<CellData Scalars=\"quality\">") != NULL);
  } else {
    CHECK(strstr(f, "CellData") == NULL);
  }
  CHECK(strstr(f, "HigherOrderDegrees") == NULL);
  free(f);
}

static void test_orders(void) {
  const int orders[] = {1, 3, 10, 15};
  for (size_t k = 0; k < sizeof orders / sizeof *orders; ++k) {
    mesh m;
    build(&m, orders[k], 5);
    char path[64];
    snprintf(path, sizeof path, "mesh_p%d.vtu", orders[k]);
    CHECK_OK(write_mesh(&m, path, 1));
    check_file(&m, path, 1);
    snprintf(path, sizeof path, "mesh_p%d_nodata.vtu", orders[k]);
    CHECK_OK(write_mesh(&m, path, 0));
    check_file(&m, path, 0);
    destroy(&m);
  }
  /* an empty mesh */
  hoc_vtu_data e = {0};
  e.order = 2;
  CHECK_OK(hoc_vtu_write("empty.vtu", &e));
  size_t size;
  char *f = fixture_slurp("empty.vtu", &size);
  CHECK(f && strstr(f, "NumberOfPoints=\"0\" NumberOfCells=\"0\""));
  free(f);
}

static void test_bad_input(void) {
  mesh m;
  build(&m, 3, 2);
  FILE *f = fopen("keep.vtu", "w");
  fputs("previous", f);
  fclose(f);
  m.xyz[4] = NAN;
  CHECK_STATUS(write_mesh(&m, "keep.vtu", 1), HOC_ERR_ARGUMENT);
  CHECK_STATUS(write_mesh(&m, "new.vtu", 1), HOC_ERR_ARGUMENT);
  m.xyz[4] = -INFINITY;
  CHECK_STATUS(write_mesh(&m, "keep.vtu", 1), HOC_ERR_ARGUMENT);
  m.xyz[4] = 0;
  m.cells[3] = m.n_points;
  CHECK_STATUS(write_mesh(&m, "keep.vtu", 1), HOC_ERR_ARGUMENT);
  m.cells[3] = 0;
  m.p = 16;
  CHECK_STATUS(write_mesh(&m, "keep.vtu", 1), HOC_ERR_ARGUMENT);
  m.p = 0;
  CHECK_STATUS(write_mesh(&m, "keep.vtu", 1), HOC_ERR_ARGUMENT);
  m.p = 3;
  CHECK_STATUS(write_mesh(&m, "no/such/dir/x.vtu", 1), HOC_ERR_IO);
  CHECK_STATUS(hoc_vtu_write("keep.vtu", NULL), HOC_ERR_ARGUMENT);
  struct stat st;
  CHECK(stat("new.vtu", &st) != 0);
  size_t size;
  char *c = fixture_slurp("keep.vtu", &size);
  CHECK(c && !strcmp(c, "previous"));
  free(c);
  destroy(&m);
}

/* VTK interpolates each order's cell: the polynomial map must come back at
 * random parametric points (only with gmsh's point order = VTK's). */
static void test_with_vtk(void) {
  if (system("/usr/bin/python3 -c 'import vtk' >/dev/null 2>&1") != 0) {
    printf("skipping the VTK cross-check: no /usr/bin/python3 with vtk (Debian python3-vtk9)\n");
    return;
  }
  for (int p = 1; p <= 15; ++p) {
    mesh m;
    build(&m, p, 1);
    char path[64];
    snprintf(path, sizeof path, "vtk_p%d.vtu", p);
    CHECK_OK(write_mesh(&m, path, 1));
    destroy(&m);
  }
  FILE *py = fopen("vtk_check.py", "w");
  CHECK(py != NULL);
  if (!py) return;
  fputs("import random, sys, vtk\n"
        "random.seed(5)\n"
        "bad = 0\n"
        "for p in range(1, 16):\n"
        "    r = vtk.vtkXMLUnstructuredGridReader()\n"
        "    r.SetFileName('vtk_p%d.vtu' % p)\n"
        "    r.Update()\n"
        "    g = r.GetOutput()\n"
        "    c = g.GetCell(0)\n"
        "    if g.GetNumberOfCells() != 1 or c.GetCellType() != (5 if p == 1 else 69) or \\\n"
        "       c.GetNumberOfPoints() != (p + 1) * (p + 2) // 2:\n"
        "        bad += 1\n"
        "        continue\n"
        "    q = 1.0 if p >= 2 else 0.0\n"
        "    w = [0.0] * c.GetNumberOfPoints()\n"
        "    for t in range(20):\n"
        "        a, b = random.random(), random.random()\n"
        "        if a + b > 1: a, b = 1 - a, 1 - b\n"
        "        x = [0.0, 0.0, 0.0]\n"
        "        c.EvaluateLocation(vtk.reference(0), [a, b, 0.0], x, w)\n"
        "        e = [2 * a + 0.5 * b + q * 0.3 * b * b, b + q * 0.2 * a * b - 0.1,\n"
        "             q * (0.5 * a * a - 0.25 * b * b) + 0.1 * a]\n"
        "        if max(abs(x[k] - e[k]) for k in range(3)) > 1e-9:\n"
        "            bad += 1\n"
        "            print('order %d: VTK puts (%g, %g) at %s, expected %s' % (p, a, b, x, e))\n"
        "            break\n"
        "sys.exit(1 if bad else 0)\n",
        py);
  fclose(py);
  int rc = system("/usr/bin/python3 vtk_check.py");
  CHECK(rc == 0);
}

int main(void) {
  test_orders();
  test_bad_input();
  test_with_vtk();
  return test_report();
}
