/* Atomic output files: written under a temporary name beside the target
 * (".NAME.tmp-XXXXXX" from mkstemp), renamed over it only once complete and
 * synced, so a reader never sees half a file and a failed or interrupted
 * run leaves an existing target as it was.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#if !defined(_XOPEN_SOURCE) || _XOPEN_SOURCE < 700
#undef _XOPEN_SOURCE
#define _XOPEN_SOURCE 700 /* realpath */
#endif
#include "io/io.h"

#include <errno.h>
#include <fcntl.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Registry of the temporary files open right now, for a signal handler.
 * A slot is claimed with a compare-and-swap (FREE -> BUSY), filled, then
 * published (READY); the handler only reads READY slots and calls unlink,
 * which is async-signal-safe. A path too long for a slot, or a 33rd file
 * open at once, is simply not registered. */
_Static_assert(ATOMIC_INT_LOCK_FREE == 2, "the signal handler needs lock-free atomics");
enum { SLOTS = 32, SLOT_PATH = 4096 };
enum { SLOT_FREE = 0, SLOT_BUSY = 1, SLOT_READY = 2 };
static char slot_path[SLOTS][SLOT_PATH];
static atomic_int slot_state[SLOTS];

static void registry_add(const char *tmp) {
  size_t n = strlen(tmp);
  if (n >= SLOT_PATH) return;
  for (int k = 0; k < SLOTS; ++k) {
    int expected = SLOT_FREE;
    if (atomic_compare_exchange_strong(&slot_state[k], &expected, SLOT_BUSY)) {
      memcpy(slot_path[k], tmp, n + 1);
      atomic_store(&slot_state[k], SLOT_READY);
      return;
    }
  }
}

static void registry_remove(const char *tmp) {
  for (int k = 0; k < SLOTS; ++k) {
    int expected = SLOT_READY;
    if (atomic_load(&slot_state[k]) == SLOT_READY && !strcmp(slot_path[k], tmp) &&
        atomic_compare_exchange_strong(&slot_state[k], &expected, SLOT_BUSY)) {
      slot_path[k][0] = '\0';
      atomic_store(&slot_state[k], SLOT_FREE);
      return;
    }
  }
}

void hoc_outfile_abort_all_from_signal(void) {
  int saved = errno; /* a handler must not change errno */
  for (int k = 0; k < SLOTS; ++k)
    if (atomic_load(&slot_state[k]) == SLOT_READY) unlink(slot_path[k]);
  errno = saved;
}

/* Permissions of a new file: 0666 less the umask, read once (umask can only
 * be read by setting it). */
static mode_t default_mode;
static pthread_once_t default_mode_once = PTHREAD_ONCE_INIT;
static void read_umask(void) {
  mode_t mask = umask(022);
  umask(mask);
  default_mode = 0666 & ~mask;
}

static void outfile_clear(hoc_outfile *out) {
  free(out->path);
  free(out->tmp_path);
  memset(out, 0, sizeof *out);
}

hoc_status hoc_outfile_open(hoc_outfile *out, const char *path) {
  HOC_CHECK(out, HOC_ERR_ARGUMENT, "no output file structure given");
  memset(out, 0, sizeof *out);
  HOC_CHECK(path && path[0], HOC_ERR_ARGUMENT, "no output file name given");
  size_t n = strlen(path);
  HOC_CHECK(path[n - 1] != '/', HOC_ERR_IO, "cannot write '%s': it names a directory", path);
  /* a symbolic link stays a link: write beside and over what it points to */
  char *target = NULL;
  struct stat st;
  int exists = 0;
  mode_t mode = 0;
  if (lstat(path, &st) == 0 && S_ISLNK(st.st_mode) && stat(path, &st) == 0) {
    target = realpath(path, NULL);
    if (!target) return HOC_ERROR(HOC_ERR_IO, "cannot write '%s': %s", path, strerror(errno));
  } else {
    target = hoc_calloc(n + 1, 1);
    HOC_CHECK(target, HOC_ERR_MEMORY, "out of memory");
    memcpy(target, path, n + 1);
  }
  if (stat(target, &st) == 0) {
    exists = 1;
    if (S_ISDIR(st.st_mode)) {
      free(target);
      return HOC_ERROR(HOC_ERR_IO, "cannot write '%s': it is a directory", path);
    }
    if (!S_ISREG(st.st_mode)) {
      free(target);
      return HOC_ERROR(HOC_ERR_IO, "cannot write '%s': it exists and is not a regular file", path);
    }
    mode = st.st_mode & 07777;
  }
  size_t tn = strlen(target);
  const char *slash = strrchr(target, '/');
  size_t dir_len = slash ? (size_t)(slash - target) + 1 : 0;
  size_t cap = tn + 16; /* "." + name + ".tmp-XXXXXX" + NUL */
  out->path = target;
  out->tmp_path = hoc_calloc(cap, 1);
  if (!out->tmp_path) {
    outfile_clear(out);
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory");
  }
  memcpy(out->tmp_path, target, dir_len);
  snprintf(out->tmp_path + dir_len, cap - dir_len, ".%s.tmp-XXXXXX", target + dir_len);
  int fd = mkstemp(out->tmp_path);
  if (fd < 0) {
    int err = errno;
    outfile_clear(out);
    if (err == ENOENT || err == ENOTDIR)
      return HOC_ERROR(HOC_ERR_IO, "cannot write '%s': its directory does not exist", path);
    return HOC_ERROR(HOC_ERR_IO, "cannot write '%s': %s", path, strerror(err));
  }
  registry_add(out->tmp_path);
  if (!exists) {
    pthread_once(&default_mode_once, read_umask);
    mode = default_mode;
  }
  (void)fchmod(fd, mode); /* mkstemp made it 0600; a failure here is harmless */
  out->fp = fdopen(fd, "wb");
  if (!out->fp) {
    int err = errno;
    close(fd);
    hoc_outfile_abort(out);
    return HOC_ERROR(HOC_ERR_IO, "cannot write '%s': %s", path, strerror(err));
  }
  return HOC_OK;
}

/* Make the rename durable: sync the directory (best effort). */
static void sync_directory(const char *path) {
  const char *slash = strrchr(path, '/');
  char *dir = NULL;
  if (!slash) {
    dir = hoc_calloc(2, 1);
    if (dir) dir[0] = '.';
  } else {
    size_t n = slash == path ? 1 : (size_t)(slash - path);
    dir = hoc_calloc(n + 1, 1);
    if (dir) memcpy(dir, path, n);
  }
  if (!dir) return;
  int fd = open(dir, O_RDONLY | O_DIRECTORY);
  if (fd >= 0) {
    (void)fsync(fd);
    close(fd);
  }
  free(dir);
}

hoc_status hoc_outfile_commit(hoc_outfile *out) {
  HOC_CHECK(out && out->fp && out->path && out->tmp_path, HOC_ERR_ARGUMENT,
            "output file is not open");
  int err = 0;
  errno = 0;
  int had_error = ferror(out->fp);
  if (fflush(out->fp) != 0)
    err = errno ? errno : EIO;
  else if (had_error)
    err = EIO; /* an earlier write failed; its errno is gone */
  if (!err && fsync(fileno(out->fp)) != 0 && errno != EINVAL) err = errno;
  if (fclose(out->fp) != 0 && !err) err = errno ? errno : EIO;
  out->fp = NULL;
  if (!err && rename(out->tmp_path, out->path) != 0) err = errno;
  if (err) {
    hoc_status st = HOC_ERROR(HOC_ERR_IO, "cannot write '%s': %s", out->path, strerror(err));
    hoc_outfile_abort(out);
    return st;
  }
  registry_remove(out->tmp_path);
  sync_directory(out->path);
  outfile_clear(out);
  return HOC_OK;
}

void hoc_outfile_abort(hoc_outfile *out) {
  if (!out) return;
  if (out->fp) fclose(out->fp);
  out->fp = NULL;
  if (out->tmp_path && out->tmp_path[0]) {
    unlink(out->tmp_path);
    registry_remove(out->tmp_path);
  }
  outfile_clear(out);
}
