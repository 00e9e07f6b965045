/* Kernel work in a child process: gmsh's mesher aborts the process on some
 * models (an uncaught C++ exception) and its STEP importer crashes
 * (SIGSEGV) on some malformed files. Run in a forked child, such a crash ends
 * the child; the caller learns of it from the child's exit status and
 * carries on.
 * SPDX-License-Identifier: GPL-2.0-or-later
 *
 * The child is forked from the calling thread and runs gmsh on its own
 * copy of the parent's memory (the loaded model included). It writes its
 * results to a pipe the parent reads as they come (the pipe holds 64 KB,
 * so the parent must read while the child writes). Its stdout and stderr
 * go to a scratch file, from which the parent takes the first error line
 * once the child has ended, even if it crashed.
 *
 * In the child: the signals a terminal or a supervisor sends (SIGINT,
 * SIGTERM, SIGHUP, ...) and the fatal ones get their default action, so a
 * handler the parent installed (which may remove the parent's temporary
 * files, or print) does not run in the child; the child is killed when the
 * thread that forked it ends (the parent was interrupted or killed); it
 * leaves with _exit, so no atexit handler of the parent (gmsh's, a leak
 * checker's) runs twice. The parent's signal dispositions are untouched.
 *
 * OpenMP: GNU libgomp's thread pool is not carried across fork; a child
 * that starts a parallel region with more than one thread after the
 * parent used OpenMP waits forever for workers that do not exist. Callers
 * set one OpenMP thread in the child before calling gmsh.
 */
#include "cad/gmsh_util.h"

#include <ctype.h>
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/prctl.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

const char *hoc_signal_name(int sig) {
  switch (sig) {
  case SIGABRT: return "SIGABRT";
  case SIGSEGV: return "SIGSEGV";
  case SIGBUS: return "SIGBUS";
  case SIGFPE: return "SIGFPE";
  case SIGILL: return "SIGILL";
  case SIGTRAP: return "SIGTRAP";
  case SIGSYS: return "SIGSYS";
  case SIGKILL: return "SIGKILL";
  case SIGINT: return "SIGINT";
  case SIGTERM: return "SIGTERM";
  case SIGHUP: return "SIGHUP";
  case SIGQUIT: return "SIGQUIT";
  case SIGPIPE: return "SIGPIPE";
  case SIGXCPU: return "SIGXCPU";
  case SIGXFSZ: return "SIGXFSZ";
  default: return "a signal";
  }
}

int hoc_signal_is_interrupt(int sig) {
  return sig == SIGINT || sig == SIGTERM || sig == SIGHUP || sig == SIGQUIT;
}

/* Signals whose default action the child gets back. */
static const int child_defaults[] = {SIGINT,  SIGTERM, SIGHUP,  SIGQUIT, SIGPIPE, SIGALRM,
                                     SIGUSR1, SIGUSR2, SIGABRT, SIGSEGV, SIGBUS,  SIGFPE,
                                     SIGILL,  SIGTRAP, SIGSYS,  SIGXCPU, SIGXFSZ};

static void set_cloexec(int fd) {
  int flags = fcntl(fd, F_GETFD);
  if (flags >= 0) fcntl(fd, F_SETFD, flags | FD_CLOEXEC);
}

hoc_status hoc_child_start(hoc_child *c, hoc_child_fn fn, void *arg) {
  c->pid = -1;
  c->fd = -1;
  c->sink = NULL;
  c->idle_limit = 0;
  c->timed_out = 0;
  int p[2];
  if (pipe(p) != 0)
    return HOC_ERROR(HOC_ERR_INTERNAL, "cannot make a pipe to a child process: %s",
                     strerror(errno));
  set_cloexec(p[0]);
  set_cloexec(p[1]);
  c->sink = tmpfile(); /* NULL: the child's output goes nowhere, its message is lost */
  /* what the parent has buffered is written once, by the parent */
  fflush(stdout);
  fflush(stderr);
  pid_t parent = getpid();
  pid_t pid = fork();
  if (pid < 0) {
    int e = errno;
    close(p[0]);
    close(p[1]);
    if (c->sink) fclose(c->sink);
    c->sink = NULL;
    return HOC_ERROR(HOC_ERR_MEMORY, "cannot start a child process for the CAD kernel: %s",
                     strerror(e));
  }
  if (pid == 0) {
    close(p[0]);
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = SIG_DFL;
    sigemptyset(&sa.sa_mask);
    for (size_t i = 0; i < sizeof child_defaults / sizeof *child_defaults; ++i)
      sigaction(child_defaults[i], &sa, NULL);
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, NULL);
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) _exit(HOC_CHILD_ORPHAN); /* the parent ended before prctl */
    int out = c->sink ? fileno(c->sink) : open("/dev/null", O_WRONLY);
    if (out >= 0) {
      dup2(out, STDOUT_FILENO);
      dup2(out, STDERR_FILENO);
    }
    hoc_quiet_in_child(c->sink);
    _exit(fn(arg, p[1]));
  }
  close(p[1]);
  c->pid = pid;
  c->fd = p[0];
  return HOC_OK;
}

/* Waits until the child's pipe has data or is closed: 1, or 0 (the child
 * killed) once c->idle_limit seconds passed without either. */
static int wait_readable(hoc_child *c) {
  if (!(c->idle_limit > 0)) return 1;
  double end = hoc_now() + c->idle_limit;
  for (;;) {
    double left = end - hoc_now();
    if (left > 0) {
      struct pollfd pfd = {c->fd, POLLIN, 0};
      int r = poll(&pfd, 1, (int)fmin(ceil(1e3 * left), 1e9));
      if (r > 0) return 1;
      if (r < 0 && errno != EINTR) return 1; /* (the read reports the error) */
      if (r < 0) continue;
    }
    if (hoc_now() < end) continue;
    if (c->pid > 0) kill(c->pid, SIGKILL);
    c->timed_out = 1;
    return 0;
  }
}

int hoc_child_read(hoc_child *c, void *buf, size_t n) {
  unsigned char *b = buf;
  while (n) {
    if (!wait_readable(c)) return 0;
    ssize_t r = read(c->fd, b, n);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) return 0;
    b += r;
    n -= (size_t)r;
  }
  return 1;
}

int hoc_child_write(int fd, const void *buf, size_t n) {
  const unsigned char *b = buf;
  while (n) {
    ssize_t w = write(fd, b, n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) return 0;
    b += w;
    n -= (size_t)w;
  }
  return 1;
}

void hoc_first_error_line(FILE *f, char *first_error, size_t size) {
  if (!size) return;
  first_error[0] = '\0';
  if (!f) return;
  char line[512];
  rewind(f);
  while (fgets(line, sizeof line, f)) {
    if (!strstr(line, "ERR") && !strstr(line, "rror")) continue;
    /* strip terminal colour codes and the "****" decoration */
    size_t k = 0;
    for (const char *c = line; *c && k + 1 < size; ++c) {
      if (*c == '\033') {
        while (*c && *c != 'm') ++c;
        if (!*c) break;
        continue;
      }
      if (*c == '*' || *c == '\n' || *c == '\r') continue;
      first_error[k++] = *c;
    }
    first_error[k] = '\0';
    while (k && isspace((unsigned char)first_error[k - 1])) first_error[--k] = '\0';
    char *s = first_error;
    while (isspace((unsigned char)*s)) ++s;
    memmove(first_error, s, strlen(s) + 1);
    break;
  }
  /* a child's sink is written on through its descriptors after this */
  fseek(f, 0, SEEK_END);
}

void hoc_child_finish(hoc_child *c, int kill_it, hoc_child_end *end) {
  end->exit_code = -1;
  end->signal = 0;
  end->timed_out = c->timed_out;
  end->first_error[0] = '\0';
  if (c->pid > 0) {
    if (kill_it) kill(c->pid, SIGKILL);
    if (c->fd >= 0) close(c->fd);
    c->fd = -1;
    int st = 0;
    pid_t r;
    do
      r = waitpid(c->pid, &st, 0);
    while (r < 0 && errno == EINTR);
    /* r < 0 (ECHILD): the caller's process reaps its children itself
     * (SIGCHLD ignored): the status is unknown and the caller judges by
     * what the child wrote */
    if (r == c->pid) {
      if (WIFEXITED(st)) end->exit_code = WEXITSTATUS(st);
      else if (WIFSIGNALED(st)) end->signal = WTERMSIG(st);
    }
  }
  if (c->fd >= 0) close(c->fd);
  if (c->sink) {
    hoc_first_error_line(c->sink, end->first_error, sizeof end->first_error);
    fclose(c->sink);
  }
  c->pid = -1;
  c->fd = -1;
  c->sink = NULL;
}
