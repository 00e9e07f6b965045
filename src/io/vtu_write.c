/* VTK XML unstructured grid writer: Lagrange triangles (cell type 69; VTK's
 * point order for them equals gmsh's: vertices, edges 0-1, 1-2, 2-0, then the
 * interior recursively, see vtkHigherOrderTriangle::BarycentricIndex), with
 * raw appended binary data.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* One appended array: a UInt64 byte count then the bytes. */
static int put_block(FILE *fp, const void *data, uint64_t bytes) {
  return fwrite(&bytes, sizeof bytes, 1, fp) == 1 && (!bytes || fwrite(data, 1, (size_t)bytes, fp) == bytes);
}

hoc_status hoc_vtu_write(const char *path, const hoc_vtu_data *d) {
  HOC_CHECK(d && path, HOC_ERR_ARGUMENT, "NULL argument");
  HOC_CHECK(d->order >= 1 && d->order <= HOC_MAX_ORDER, HOC_ERR_ARGUMENT, "order %d out of range",
            d->order);
  int np = (d->order + 1) * (d->order + 2) / 2;
  for (size_t i = 0; i < 3 * d->n_points; ++i)
    HOC_CHECK(isfinite(d->xyz[i]), HOC_ERR_ARGUMENT,
              "point %zu has a non-finite coordinate: nothing written", i / 3 + 1);
  for (size_t k = 0; k < d->n_cells * (size_t)np; ++k)
    HOC_CHECK(d->cells[k] < d->n_points, HOC_ERR_ARGUMENT, "cell %zu refers to a missing point",
              k / (size_t)np + 1);
  size_t nc = d->n_cells;
  int64_t *conn = hoc_calloc(nc * (size_t)np + 1, sizeof *conn), *offs = hoc_calloc(nc + 1, sizeof *offs);
  uint8_t *types = hoc_calloc(nc + 1, sizeof *types);
  hoc_outfile out = {0};
  hoc_status status = HOC_OK;
  if (!conn || !offs || !types) {
    status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory writing '%s'", path);
    goto done;
  }
  for (size_t c = 0; c < nc; ++c) {
    for (int k = 0; k < np; ++k) conn[c * (size_t)np + (size_t)k] = (int64_t)d->cells[c * (size_t)np + (size_t)k];
    offs[c] = (int64_t)((c + 1) * (size_t)np);
    types[c] = d->order == 1 ? 5 : 69;
  }
  HOC_TRY_GOTO(hoc_outfile_open(&out, path), done);
  FILE *fp = out.fp;
  uint64_t off = 0, sz;
  fprintf(fp, "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" "
              "byte_order=\"LittleEndian\" header_type=\"UInt64\">\n<UnstructuredGrid>\n"
              "<Piece NumberOfPoints=\"%zu\" NumberOfCells=\"%zu\">\n<Points>\n",
          d->n_points, nc);
  fprintf(fp, "<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"appended\" offset=\"%llu\"/>\n",
          (unsigned long long)off);
  off += 8 + 24 * (uint64_t)d->n_points;
  fprintf(fp, "</Points>\n<Cells>\n");
  fprintf(fp, "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"appended\" offset=\"%llu\"/>\n",
          (unsigned long long)off);
  off += 8 + 8 * (uint64_t)nc * (uint64_t)np;
  fprintf(fp, "<DataArray type=\"Int64\" Name=\"offsets\" format=\"appended\" offset=\"%llu\"/>\n",
          (unsigned long long)off);
  off += 8 + 8 * (uint64_t)nc;
  fprintf(fp, "<DataArray type=\"UInt8\" Name=\"types\" format=\"appended\" offset=\"%llu\"/>\n",
          (unsigned long long)off);
  off += 8 + (uint64_t)nc;
  fprintf(fp, "</Cells>\n<CellData%s>\n", d->quality ? " Scalars=\"quality\"" : "");
  if (d->quality) {
    fprintf(fp, "<DataArray type=\"Float64\" Name=\"quality\" format=\"appended\" offset=\"%llu\"/>\n",
            (unsigned long long)off);
    off += 8 + 8 * (uint64_t)nc;
  }
  if (d->tangled) {
    fprintf(fp, "<DataArray type=\"UInt8\" Name=\"tangled\" format=\"appended\" offset=\"%llu\"/>\n",
            (unsigned long long)off);
    off += 8 + (uint64_t)nc;
  }
  if (d->face_tag) {
    fprintf(fp, "<DataArray type=\"Int32\" Name=\"face\" format=\"appended\" offset=\"%llu\"/>\n",
            (unsigned long long)off);
    off += 8 + 4 * (uint64_t)nc;
  }
  fprintf(fp, "</CellData>\n</Piece>\n</UnstructuredGrid>\n<AppendedData encoding=\"raw\">\n_");
  int ok = put_block(fp, d->xyz, 24 * (uint64_t)d->n_points) &&
           put_block(fp, conn, 8 * (uint64_t)nc * (uint64_t)np) && put_block(fp, offs, 8 * (uint64_t)nc) &&
           put_block(fp, types, (uint64_t)nc);
  if (ok && d->quality) ok = put_block(fp, d->quality, 8 * (uint64_t)nc);
  if (ok && d->tangled) ok = put_block(fp, d->tangled, (uint64_t)nc);
  if (ok && d->face_tag) {
    sz = 4 * (uint64_t)nc;
    int32_t *ft = hoc_calloc(nc + 1, sizeof *ft);
    if (!ft) {
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
      goto done;
    }
    for (size_t c = 0; c < nc; ++c) ft[c] = d->face_tag[c];
    ok = put_block(fp, ft, sz);
    free(ft);
  }
  fprintf(fp, "\n</AppendedData>\n</VTKFile>\n");
  if (!ok) {
    status = HOC_ERROR(HOC_ERR_IO, "cannot write '%s'", path);
    goto done;
  }
  status = hoc_outfile_commit(&out);
done:
  hoc_outfile_abort(&out);
  free(conn);
  free(offs);
  free(types);
  return status;
}
