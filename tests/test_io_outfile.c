/* Atomic output files: a commit creates the file with its content, an abort
 * leaves nothing, a failing commit (a write error, a full quota) keeps the
 * previous target and leaves no temporary file, bad directories fail with
 * HOC_ERR_IO naming the path, symbolic links and permissions survive, and
 * the signal path removes open temporaries.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"
#include "test_util.h"

#include <dirent.h>
#include <signal.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

/* Files whose name holds ".tmp-" in a directory (-1 if it cannot be read). */
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
  FILE *f = fopen(path, "rb");
  if (!f) return 0;
  char buf[256] = {0};
  size_t n = fread(buf, 1, sizeof buf - 1, f);
  fclose(f);
  return n == strlen(content) && !memcmp(buf, content, n);
}

static int exists(const char *path) {
  struct stat st;
  return lstat(path, &st) == 0;
}

static void write_file(const char *path, const char *content) {
  FILE *f = fopen(path, "wb");
  if (f) {
    fputs(content, f);
    fclose(f);
  }
}

static void test_commit_and_abort(void) {
  hoc_outfile out;
  remove("outdir/a.txt");
  CHECK_OK(hoc_outfile_open(&out, "outdir/a.txt"));
  CHECK(out.fp != NULL && count_temp_files("outdir") == 1);
  CHECK(!exists("outdir/a.txt")); /* nothing at the target until the commit */
  fputs("first", out.fp);
  CHECK_OK(hoc_outfile_commit(&out));
  CHECK(file_is("outdir/a.txt", "first"));
  CHECK(count_temp_files("outdir") == 0);
  CHECK(out.fp == NULL && out.path == NULL && out.tmp_path == NULL);
  hoc_outfile_abort(&out); /* after a commit: harmless */
  CHECK(file_is("outdir/a.txt", "first"));

  /* overwrite, then an abort that keeps the old content */
  CHECK_OK(hoc_outfile_open(&out, "outdir/a.txt"));
  fputs("second", out.fp);
  CHECK_OK(hoc_outfile_commit(&out));
  CHECK(file_is("outdir/a.txt", "second"));
  CHECK_OK(hoc_outfile_open(&out, "outdir/a.txt"));
  fputs("third, never finished", out.fp);
  hoc_outfile_abort(&out);
  CHECK(file_is("outdir/a.txt", "second"));
  CHECK(count_temp_files("outdir") == 0);
  hoc_outfile_abort(&out); /* twice */
  hoc_outfile zero = {0};
  hoc_outfile_abort(&zero); /* on a zeroed struct */
  hoc_outfile_abort(NULL);
  CHECK_STATUS(hoc_outfile_commit(&zero), HOC_ERR_ARGUMENT);

  /* a bare file name goes to the current directory */
  remove("bare.txt");
  CHECK_OK(hoc_outfile_open(&out, "bare.txt"));
  fputs("bare", out.fp);
  CHECK_OK(hoc_outfile_commit(&out));
  CHECK(file_is("bare.txt", "bare"));
  CHECK(count_temp_files(".") == 0);

  /* several open at once */
  hoc_outfile o1, o2;
  CHECK_OK(hoc_outfile_open(&o1, "outdir/m1.txt"));
  CHECK_OK(hoc_outfile_open(&o2, "outdir/m2.txt"));
  CHECK(count_temp_files("outdir") == 2);
  fputs("one", o1.fp);
  fputs("two", o2.fp);
  CHECK_OK(hoc_outfile_commit(&o2));
  hoc_outfile_abort(&o1);
  CHECK(!exists("outdir/m1.txt") && file_is("outdir/m2.txt", "two"));
  CHECK(count_temp_files("outdir") == 0);
}

/* A commit that fails keeps the previous target and removes the temporary. */
static void test_failing_commit(void) {
  remove("outdir/late/inside"); /* from an earlier run */
  rmdir("outdir/late");
  write_file("outdir/keep.txt", "previous");
  hoc_outfile out;
  /* a write error: the stream's descriptor is gone before the flush */
  CHECK_OK(hoc_outfile_open(&out, "outdir/keep.txt"));
  fputs("new content that cannot be flushed", out.fp);
  close(fileno(out.fp));
  CHECK_STATUS(hoc_outfile_commit(&out), HOC_ERR_IO);
  CHECK(strstr(hoc_last_error(), "outdir/keep.txt") != NULL);
  CHECK(file_is("outdir/keep.txt", "previous"));
  CHECK(count_temp_files("outdir") == 0);

  /* a full "disk": a file size limit of 4 KiB, and 1 MiB written */
  struct rlimit old, lim;
  if (getrlimit(RLIMIT_FSIZE, &old) == 0) {
    void (*prev)(int) = signal(SIGXFSZ, SIG_IGN); /* EFBIG instead of a signal */
    lim = old;
    lim.rlim_cur = 4096;
    if (setrlimit(RLIMIT_FSIZE, &lim) == 0) {
      CHECK_OK(hoc_outfile_open(&out, "outdir/keep.txt"));
      for (int k = 0; k < 1024; ++k)
        fprintf(out.fp, "%01023d\n", k);
      CHECK_STATUS(hoc_outfile_commit(&out), HOC_ERR_IO);
      CHECK(strstr(hoc_last_error(), "keep.txt") != NULL);
      setrlimit(RLIMIT_FSIZE, &old);
      CHECK(file_is("outdir/keep.txt", "previous"));
      CHECK(count_temp_files("outdir") == 0);
    }
    signal(SIGXFSZ, prev);
  }

  /* the target became a directory in the meantime: rename fails */
  CHECK_OK(hoc_outfile_open(&out, "outdir/late"));
  fputs("x", out.fp);
  mkdir("outdir/late", 0755);
  write_file("outdir/late/inside", "y"); /* not empty: rename cannot replace it */
  CHECK_STATUS(hoc_outfile_commit(&out), HOC_ERR_IO);
  CHECK(file_is("outdir/late/inside", "y"));
  CHECK(count_temp_files("outdir") == 0);
}

static void test_bad_targets(void) {
  hoc_outfile out;
  CHECK_STATUS(hoc_outfile_open(&out, "no/such/dir/x.txt"), HOC_ERR_IO);
  CHECK(strstr(hoc_last_error(), "no/such/dir/x.txt") != NULL);
  CHECK(out.fp == NULL && out.tmp_path == NULL);
  CHECK(!exists("no"));
  CHECK_STATUS(hoc_outfile_open(&out, "outdir"), HOC_ERR_IO);
  CHECK(strstr(hoc_last_error(), "directory") != NULL);
  CHECK_STATUS(hoc_outfile_open(&out, "outdir/"), HOC_ERR_IO);
  CHECK_STATUS(hoc_outfile_open(&out, "."), HOC_ERR_IO);
  CHECK_STATUS(hoc_outfile_open(&out, ""), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_outfile_open(&out, NULL), HOC_ERR_ARGUMENT);
  CHECK_STATUS(hoc_outfile_open(NULL, "x"), HOC_ERR_ARGUMENT);
  write_file("afile", "plain");
  CHECK_STATUS(hoc_outfile_open(&out, "afile/x.txt"), HOC_ERR_IO); /* a file as directory */
  CHECK(file_is("afile", "plain"));
  CHECK_STATUS(hoc_outfile_open(&out, "/dev/null"), HOC_ERR_IO); /* not a regular file */
  CHECK(count_temp_files("outdir") == 0 && count_temp_files(".") == 0);

  /* unwritable directory (skipped as root, who may write anyway) */
  mkdir("rodir", 0555);
  chmod("rodir", 0555);
  FILE *probe = fopen("rodir/probe", "w");
  if (probe) {
    fclose(probe);
    remove("rodir/probe");
  } else {
    CHECK_STATUS(hoc_outfile_open(&out, "rodir/x.txt"), HOC_ERR_IO);
    CHECK(strstr(hoc_last_error(), "rodir/x.txt") != NULL);
    CHECK(count_temp_files("rodir") == 0);
  }
  chmod("rodir", 0755);

  /* the public helper on top */
  CHECK_OK(hoc_write_file_atomic("outdir/c.txt", "hello", 5));
  CHECK(file_is("outdir/c.txt", "hello"));
  CHECK_STATUS(hoc_write_file_atomic("no/such/dir/c.txt", "x", 1), HOC_ERR_IO);
}

/* Links stay links, permissions of an existing target are kept. */
static void test_links_and_modes(void) {
  write_file("outdir/real.txt", "old");
  chmod("outdir/real.txt", 0640);
  remove("outdir/link.txt");
  if (symlink("real.txt", "outdir/link.txt") != 0) return;
  hoc_outfile out;
  CHECK_OK(hoc_outfile_open(&out, "outdir/link.txt"));
  fputs("through the link", out.fp);
  CHECK_OK(hoc_outfile_commit(&out));
  struct stat st;
  CHECK(lstat("outdir/link.txt", &st) == 0 && S_ISLNK(st.st_mode));
  CHECK(file_is("outdir/real.txt", "through the link"));
  CHECK(stat("outdir/real.txt", &st) == 0 && (st.st_mode & 0777) == 0640);
  CHECK(count_temp_files("outdir") == 0);
  /* a new file gets 0666 less the umask, not mkstemp's 0600 */
  mode_t mask = umask(022);
  remove("outdir/new.txt");
  CHECK_OK(hoc_outfile_open(&out, "outdir/new.txt"));
  CHECK_OK(hoc_outfile_commit(&out));
  CHECK(stat("outdir/new.txt", &st) == 0 && (st.st_mode & 0777) == 0644);
  umask(mask);
}

/* A signal handler removes the open temporaries (in a child process). */
static void on_signal(int sig) {
  hoc_outfile_abort_all_from_signal();
  _exit(128 + sig);
}

static void test_signal(void) {
  pid_t pid = fork();
  if (pid == 0) {
    signal(SIGINT, on_signal);
    hoc_outfile a, b;
    if (hoc_outfile_open(&a, "sigdir/a.txt") != HOC_OK ||
        hoc_outfile_open(&b, "sigdir/b.txt") != HOC_OK)
      _exit(1);
    fputs("partial", a.fp);
    fflush(a.fp);
    if (count_temp_files("sigdir") != 2) _exit(2);
    raise(SIGINT);
    _exit(3);
  }
  int status = 0;
  CHECK(pid > 0 && waitpid(pid, &status, 0) == pid);
  CHECK(WIFEXITED(status) && WEXITSTATUS(status) == 128 + SIGINT);
  CHECK(count_temp_files("sigdir") == 0);
  CHECK(!exists("sigdir/a.txt") && !exists("sigdir/b.txt"));
  /* in this process: the registry forgets committed and aborted files */
  hoc_outfile out;
  CHECK_OK(hoc_outfile_open(&out, "sigdir/c.txt"));
  fputs("c", out.fp);
  CHECK_OK(hoc_outfile_commit(&out));
  hoc_outfile_abort_all_from_signal();
  CHECK(file_is("sigdir/c.txt", "c"));
  CHECK_OK(hoc_outfile_open(&out, "sigdir/d.txt"));
  hoc_outfile_abort_all_from_signal();
  CHECK(count_temp_files("sigdir") == 0);
  hoc_outfile_abort(&out);
}

/* Remove a directory tree this test made (files and directories only). */
static void remove_tree(const char *dir) {
  DIR *d = opendir(dir);
  if (d) {
    struct dirent *e;
    while ((e = readdir(d))) {
      if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
      char path[4096];
      snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
      struct stat st;
      if (lstat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        chmod(path, 0755);
        remove_tree(path);
      } else {
        unlink(path);
      }
    }
    closedir(d);
  }
  rmdir(dir);
}

int main(void) {
  /* a directory of its own: tests running alongside make temporary files
   * in the shared working directory, which the counts below would see */
  char own[] = "outfile-test-XXXXXX", cwd[4096];
  if (!mkdtemp(own) || !getcwd(cwd, sizeof cwd) || chdir(own) != 0) {
    fprintf(stderr, "cannot make a working directory\n");
    return 1;
  }
  mkdir("outdir", 0755);
  mkdir("sigdir", 0755);
  test_commit_and_abort();
  test_failing_commit();
  test_bad_targets();
  test_links_and_modes();
  test_signal();
  int rc = test_report();
  if (chdir(cwd) == 0) remove_tree(own);
  return rc;
}
