/* Public file helpers on top of the atomic output files.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "core/cli_support.h"
#include "io/io.h"

hoc_status hoc_write_file_atomic(const char *path, const void *data, size_t size) {
  HOC_CHECK(path && path[0], HOC_ERR_ARGUMENT, "no file name given");
  HOC_CHECK(data || !size, HOC_ERR_ARGUMENT, "no data given");
  hoc_outfile out = {0};
  HOC_TRY(hoc_outfile_open(&out, path));
  if (size && fwrite(data, 1, size, out.fp) != size) {
    hoc_outfile_abort(&out);
    return HOC_ERROR(HOC_ERR_IO, "cannot write '%s'", path);
  }
  return hoc_outfile_commit(&out);
}

void hoc_abort_outputs_from_signal(void) { hoc_outfile_abort_all_from_signal(); }
