/* Atomic output files: written under a temporary name in the target's
 * directory, renamed over the target only when complete.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"

#include <errno.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Temporary files open right now, for a signal handler to remove. */
enum { MAX_OPEN = 16, PATH_CAP = 4096 };
static char open_paths[MAX_OPEN][PATH_CAP];
static volatile int open_used[MAX_OPEN];
static pthread_mutex_t open_lock = PTHREAD_MUTEX_INITIALIZER;

static void registry_add(const char *tmp) {
  pthread_mutex_lock(&open_lock);
  for (int i = 0; i < MAX_OPEN; ++i)
    if (!open_used[i] && strlen(tmp) < PATH_CAP) {
      strcpy(open_paths[i], tmp);
      open_used[i] = 1;
      break;
    }
  pthread_mutex_unlock(&open_lock);
}

static void registry_remove(const char *tmp) {
  pthread_mutex_lock(&open_lock);
  for (int i = 0; i < MAX_OPEN; ++i)
    if (open_used[i] && !strcmp(open_paths[i], tmp)) open_used[i] = 0;
  pthread_mutex_unlock(&open_lock);
}

void hoc_outfile_abort_all_from_signal(void) {
  for (int i = 0; i < MAX_OPEN; ++i)
    if (open_used[i]) unlink(open_paths[i]);
}

hoc_status hoc_outfile_open(hoc_outfile *out, const char *path) {
  HOC_CHECK(out, HOC_ERR_ARGUMENT, "NULL output file");
  memset(out, 0, sizeof *out);
  HOC_CHECK(path && path[0], HOC_ERR_ARGUMENT, "no output file name given");
  size_t n = strlen(path);
  HOC_CHECK(n + 32 < PATH_CAP, HOC_ERR_IO, "output file name too long");
  struct stat sb;
  if (stat(path, &sb) == 0 && S_ISDIR(sb.st_mode))
    return HOC_ERROR(HOC_ERR_IO, "cannot write '%s': it is a directory", path);
  out->path = hoc_calloc(n + 1, 1);
  out->tmp_path = hoc_calloc(n + 32, 1);
  if (!out->path || !out->tmp_path) {
    hoc_outfile_abort(out);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  memcpy(out->path, path, n + 1);
  /* ".name.tmp-XXXXXX" beside the target */
  const char *slash = strrchr(path, '/');
  size_t dir_len = slash ? (size_t)(slash - path) + 1 : 0;
  memcpy(out->tmp_path, path, dir_len);
  snprintf(out->tmp_path + dir_len, n + 32 - dir_len, ".%s.tmp-XXXXXX", path + dir_len);
  int fd = mkstemp(out->tmp_path);
  if (fd < 0) {
    int err = errno;
    hoc_outfile_abort(out);
    return HOC_ERROR(HOC_ERR_IO, "cannot write '%s': %s", path, strerror(err));
  }
  fchmod(fd, 0644);
  out->fp = fdopen(fd, "wb");
  if (!out->fp) {
    int err = errno;
    close(fd);
    unlink(out->tmp_path);
    hoc_outfile_abort(out);
    return HOC_ERROR(HOC_ERR_IO, "cannot write '%s': %s", path, strerror(err));
  }
  registry_add(out->tmp_path);
  return HOC_OK;
}

hoc_status hoc_outfile_commit(hoc_outfile *out) {
  HOC_CHECK(out && out->fp, HOC_ERR_ARGUMENT, "output file is not open");
  int failed = ferror(out->fp) || fflush(out->fp) != 0;
  int err = failed ? errno : 0;
  if (!failed && fsync(fileno(out->fp)) != 0 && errno != EINVAL) {
    failed = 1;
    err = errno;
  }
  if (fclose(out->fp) != 0 && !failed) {
    failed = 1;
    err = errno;
  }
  out->fp = NULL;
  if (!failed && rename(out->tmp_path, out->path) != 0) {
    failed = 1;
    err = errno;
  }
  if (failed) {
    char path[512];
    snprintf(path, sizeof path, "%s", out->path);
    hoc_outfile_abort(out);
    return HOC_ERROR(HOC_ERR_IO, "cannot write '%s': %s", path, strerror(err ? err : EIO));
  }
  registry_remove(out->tmp_path);
  free(out->path);
  free(out->tmp_path);
  memset(out, 0, sizeof *out);
  return HOC_OK;
}

void hoc_outfile_abort(hoc_outfile *out) {
  if (!out) return;
  if (out->fp) fclose(out->fp);
  if (out->tmp_path && out->tmp_path[0]) {
    unlink(out->tmp_path);
    registry_remove(out->tmp_path);
  }
  free(out->path);
  free(out->tmp_path);
  memset(out, 0, sizeof *out);
}
