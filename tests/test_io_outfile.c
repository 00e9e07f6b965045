/* Atomic output: commit creates the file, abort leaves nothing, a failure
 * keeps the previous target, bad directories fail with HOC_ERR_IO.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"
#include "test_util.h"

#include <dirent.h>
#include <string.h>
#include <sys/stat.h>

static int count_temp_files(const char *dir) {
  DIR *d = opendir(dir);
  if (!d) return -1;
  int n = 0;
  struct dirent *e;
  while ((e = readdir(d)))
    if (strstr(e->d_name, ".tmp-")) ++n;
  closedir(d);
  return n;
}

static int file_is(const char *path, const char *content) {
  FILE *f = fopen(path, "r");
  if (!f) return 0;
  char buf[256] = {0};
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  fclose(f);
  return n == strlen(content) && !memcmp(buf, content, n);
}

int main(void) {
  mkdir("outdir", 0755);
  hoc_outfile out;
  CHECK_OK(hoc_outfile_open(&out, "outdir/a.txt"));
  fputs("first", out.fp);
  CHECK(count_temp_files("outdir") == 1);
  CHECK_OK(hoc_outfile_commit(&out));
  CHECK(file_is("outdir/a.txt", "first"));
  CHECK(count_temp_files("outdir") == 0);
  /* an aborted write leaves the old content and no temporary */
  CHECK_OK(hoc_outfile_open(&out, "outdir/a.txt"));
  fputs("second, never finished", out.fp);
  hoc_outfile_abort(&out);
  CHECK(file_is("outdir/a.txt", "first"));
  CHECK(count_temp_files("outdir") == 0);
  hoc_outfile_abort(&out); /* twice is harmless */
  /* the signal path removes open temporaries */
  CHECK_OK(hoc_outfile_open(&out, "outdir/b.txt"));
  hoc_outfile_abort_all_from_signal();
  CHECK(count_temp_files("outdir") == 0);
  hoc_outfile_abort(&out);
  /* missing directory, a directory as target */
  CHECK_STATUS(hoc_outfile_open(&out, "no/such/dir/x.txt"), HOC_ERR_IO);
  CHECK(strstr(hoc_last_error(), "no/such/dir/x.txt") != NULL);
  CHECK_STATUS(hoc_outfile_open(&out, "outdir"), HOC_ERR_IO);
  /* public helper */
  CHECK_OK(hoc_write_file_atomic("outdir/c.txt", "hello", 5));
  CHECK(file_is("outdir/c.txt", "hello"));
  CHECK_STATUS(hoc_write_file_atomic("no/such/dir/c.txt", "x", 1), HOC_ERR_IO);
  /* unwritable directory (skipped when running as root, who may write anyway) */
  mkdir("rodir", 0555);
  chmod("rodir", 0555);
  FILE *probe = fopen("rodir/probe", "w");
  if (probe) {
    fclose(probe);
    remove("rodir/probe");
  } else {
    CHECK_STATUS(hoc_outfile_open(&out, "rodir/x.txt"), HOC_ERR_IO);
  }
  return test_report();
}
