/* Reading a gmsh MSH file from disk: the whole file into memory, which
 * hoc_msh_read_buffer (msh_read.c) then parses; and freeing the result.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

hoc_status hoc_msh_read(const char *path, hoc_msh_raw *raw) {
  HOC_CHECK(raw, HOC_ERR_ARGUMENT, "no output given");
  memset(raw, 0, sizeof *raw);
  HOC_CHECK(path && path[0], HOC_ERR_ARGUMENT, "no mesh file name given");
  FILE *f = fopen(path, "rb");
  if (!f) return HOC_ERROR(HOC_ERR_IO, "cannot open '%s': %s", path, strerror(errno));
  struct stat st;
  if (fstat(fileno(f), &st) == 0 && S_ISDIR(st.st_mode)) {
    fclose(f);
    return HOC_ERROR(HOC_ERR_IO, "cannot read '%s': it is a directory", path);
  }
  /* the size is a hint only (pipes have none) */
  size_t cap = st.st_size > 0 ? (size_t)st.st_size + 1 : 1 << 16, len = 0;
  char *data = malloc(cap);
  hoc_status status = HOC_OK;
  for (;;) {
    if (!data) {
      status = HOC_ERROR(HOC_ERR_MEMORY, "out of memory reading '%s' (%zu bytes)", path, cap);
      break;
    }
    len += fread(data + len, 1, cap - len, f);
    if (ferror(f)) {
      status = HOC_ERROR(HOC_ERR_IO, "cannot read '%s': %s", path, strerror(errno ? errno : EIO));
      break;
    }
    if (feof(f)) break;
    if (len == cap) {
      char *more = cap < SIZE_MAX / 2 ? realloc(data, 2 * cap) : NULL;
      if (!more) free(data);
      data = more;
      cap *= 2;
    }
  }
  fclose(f);
  if (status == HOC_OK) status = hoc_msh_read_buffer(data, len, path, raw);
  free(data);
  return status;
}

void hoc_msh_raw_free(hoc_msh_raw *raw) {
  if (!raw) return;
  free(raw->node_tag);
  free(raw->xyz);
  free(raw->node_dim);
  free(raw->node_entity_tag);
  free(raw->param);
  free(raw->has_param);
  free(raw->tri_nodes);
  free(raw->tri_surface_tag);
  free(raw->line_nodes);
  free(raw->line_curve_tag);
  memset(raw, 0, sizeof *raw);
}
