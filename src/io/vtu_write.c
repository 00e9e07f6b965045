/* VTK XML unstructured grid writer (version 1.0, UInt64 headers, raw
 * appended binary data): Lagrange triangles of any order, with per-cell
 * quality, tangled flag and face tag.
 *
 * Point order inside a cell. VTK_LAGRANGE_TRIANGLE (69) lists its points as
 * gmsh does (src/basis/basis.h): the three vertices, the p-1 points of edge
 * 0-1, of edge 1-2, of edge 2-0 (each from its first vertex), then the
 * interior points recursively as a triangle of order p-3 in the same order;
 * so the connectivity is written unpermuted. Evidence:
 *  - VTK's source, Common/DataModel/vtkHigherOrderTriangle.cxx:
 *    BarycentricIndex(index, bindex, order) walks vertices, then edges, then
 *    recurses into the interior with order - 3 (and an offset), and
 *    ComputeOrder() derives the order from the number of points,
 *    (sqrt(8 n + 1) - 3) / 2.
 *  - Measured: with VTK 9.1 (Debian python3-vtk9), vtkLagrangeTriangle's
 *    GetParametricCoords() scaled by p equals hoc_tri_lattice(p) point for
 *    point for every p = 1..15, and equals gmsh 4.8's own reference nodes
 *    (gmshModelMeshGetElementProperties of types 2, 9, 21, ..., 46) for
 *    p = 1..10, interiors of interiors (p >= 6) included.
 * The order of a triangle comes from its number of points, so no
 * "HigherOrderDegrees" cell array is needed (VTK reads one only for
 * quadrilaterals, hexahedra and wedges: SetOrderFromCellData).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

enum { VTK_TRIANGLE = 5, VTK_LAGRANGE_TRIANGLE = 69, CHUNK = 8192 };

/* One appended array: its byte count (UInt64), then its bytes. */
typedef struct appender {
  FILE *fp;
  int err; /* errno of the first failed write */
} appender;

static void put(appender *a, const void *data, size_t bytes) {
  if (!a->err && bytes && fwrite(data, 1, bytes, a->fp) != bytes) a->err = errno ? errno : EIO;
}

static void put_header(appender *a, uint64_t bytes) { put(a, &bytes, sizeof bytes); }

static int host_is_little_endian(void) {
  const uint16_t one = 1;
  unsigned char b;
  memcpy(&b, &one, 1);
  return b == 1;
}

/* The XML part: one DataArray per block, with its offset in the appended
 * data; returns the offset after it. */
static uint64_t declare(FILE *fp, const char *type, const char *name, int components,
                        uint64_t offset, uint64_t bytes) {
  fprintf(fp, "        <DataArray type=\"%s\" Name=\"%s\"", type, name);
  if (components > 1) fprintf(fp, " NumberOfComponents=\"%d\"", components);
  fprintf(fp, " format=\"appended\" offset=\"%llu\"/>\n", (unsigned long long)offset);
  return offset + sizeof(uint64_t) + bytes;
}

hoc_status hoc_vtu_write(const char *path, const hoc_vtu_data *d) {
  HOC_CHECK(path && path[0], HOC_ERR_ARGUMENT, "no output file name given");
  HOC_CHECK(d, HOC_ERR_ARGUMENT, "no mesh given to write '%s'", path);
  int p = d->order;
  HOC_CHECK(p >= 1 && p <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT, "order %d out of range 1..%d", p,
            HOC_MAX_ORDER);
  HOC_CHECK(!d->n_points || d->xyz, HOC_ERR_ARGUMENT, "point coordinates missing");
  HOC_CHECK(!d->n_cells || d->cells, HOC_ERR_ARGUMENT, "cells missing");
  size_t np = (size_t)((p + 1) * (p + 2) / 2), nc = d->n_cells, nn = d->n_points;
  HOC_CHECK(nn <= UINT64_MAX / 24 && nc <= UINT64_MAX / (8 * np), HOC_ERR_ARGUMENT,
            "mesh too large for a .vtu file");
  for (size_t i = 0; i < nn; ++i)
    HOC_CHECK(isfinite(d->xyz[3 * i]) && isfinite(d->xyz[3 * i + 1]) && isfinite(d->xyz[3 * i + 2]),
              HOC_ERR_ARGUMENT, "point %zu has a non-finite coordinate: nothing written", i);
  for (size_t k = 0; k < nc * np; ++k)
    HOC_CHECK(d->cells[k] < nn, HOC_ERR_ARGUMENT, "cell %zu uses point %zu of %zu", k / np,
              d->cells[k], nn);

  void *buf = hoc_calloc(CHUNK, sizeof(int64_t)); /* conversion buffer, CHUNK 8-byte items */
  HOC_CHECK(buf, HOC_ERR_MEMORY, "out of memory");
  int64_t *b64 = buf;
  int32_t *b32 = buf;
  uint8_t *b8 = buf;
  hoc_outfile out = {0};
  hoc_status status = hoc_outfile_open(&out, path);
  if (status != HOC_OK) {
    free(buf);
    return status;
  }
  FILE *fp = out.fp;
  uint64_t off = 0;
  fprintf(fp,
          "<?xml version=\"1.0\"?>\n"
          "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"%s\" "
          "header_type=\"UInt64\">\n"
          "  <UnstructuredGrid>\n"
          "    <Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n"
          "      <Points>\n",
          host_is_little_endian() ? "LittleEndian" : "BigEndian", nn, nc);
  off = declare(fp, "Float64", "Points", 3, off, 24 * (uint64_t)nn);
  fprintf(fp, "      </Points>\n      <Cells>\n");
  off = declare(fp, "Int64", "connectivity", 1, off, 8 * (uint64_t)nc * np);
  off = declare(fp, "Int64", "offsets", 1, off, 8 * (uint64_t)nc);
  off = declare(fp, "UInt8", "types", 1, off, (uint64_t)nc);
  fprintf(fp, "      </Cells>\n");
  if (d->quality || d->tangled || d->face_tag) {
    fprintf(fp, "      <CellData%s>\n", d->quality ? " Scalars=\"quality\"" : "");
    if (d->quality) off = declare(fp, "Float64", "quality", 1, off, 8 * (uint64_t)nc);
    if (d->tangled) off = declare(fp, "UInt8", "tangled", 1, off, (uint64_t)nc);
    if (d->face_tag) off = declare(fp, "Int32", "face", 1, off, 4 * (uint64_t)nc);
    fprintf(fp, "      </CellData>\n");
  }
  fprintf(fp, "    </Piece>\n  </UnstructuredGrid>\n  <AppendedData encoding=\"raw\">\n   _");

  appender a = {fp, 0};
  put_header(&a, 24 * (uint64_t)nn); /* points: [nn][3] Float64 */
  put(&a, d->xyz, 24 * nn);
  put_header(&a, 8 * (uint64_t)nc * np); /* connectivity: [nc][np] Int64, gmsh = VTK order */
  for (size_t k = 0; k < nc * np; k += CHUNK) {
    size_t m = nc * np - k < CHUNK ? nc * np - k : CHUNK;
    for (size_t j = 0; j < m; ++j)
      b64[j] = (int64_t)d->cells[k + j];
    put(&a, b64, m * sizeof *b64);
  }
  put_header(&a, 8 * (uint64_t)nc); /* offsets: [nc] Int64, end of each cell */
  for (size_t c = 0; c < nc; c += CHUNK) {
    size_t m = nc - c < CHUNK ? nc - c : CHUNK;
    for (size_t j = 0; j < m; ++j)
      b64[j] = (int64_t)((c + j + 1) * np);
    put(&a, b64, m * sizeof *b64);
  }
  put_header(&a, (uint64_t)nc); /* types: [nc] UInt8 */
  for (size_t c = 0; c < nc; c += CHUNK) {
    size_t m = nc - c < CHUNK ? nc - c : CHUNK;
    memset(b8, p == 1 ? VTK_TRIANGLE : VTK_LAGRANGE_TRIANGLE, m);
    put(&a, b8, m);
  }
  if (d->quality) { /* [nc] Float64 */
    put_header(&a, 8 * (uint64_t)nc);
    put(&a, d->quality, 8 * nc);
  }
  if (d->tangled) { /* [nc] UInt8 */
    put_header(&a, (uint64_t)nc);
    put(&a, d->tangled, nc);
  }
  if (d->face_tag) { /* [nc] Int32 */
    put_header(&a, 4 * (uint64_t)nc);
    for (size_t c = 0; c < nc; c += CHUNK) {
      size_t m = nc - c < CHUNK ? nc - c : CHUNK;
      for (size_t j = 0; j < m; ++j)
        b32[j] = (int32_t)d->face_tag[c + j];
      put(&a, b32, m * sizeof *b32);
    }
  }
  fprintf(fp, "\n  </AppendedData>\n</VTKFile>\n");
  free(buf);
  if (a.err) {
    status = HOC_ERROR(HOC_ERR_IO, "cannot write '%s': %s", path, strerror(a.err));
    hoc_outfile_abort(&out);
    return status;
  }
  return hoc_outfile_commit(&out);
}
