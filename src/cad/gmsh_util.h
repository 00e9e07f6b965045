/* Helpers shared by the files that call gmsh (the CAD backend and the
 * linear mesher).
 * SPDX-License-Identifier: GPL-2.0-or-later */
#ifndef HOC_CAD_GMSH_UTIL_H
#define HOC_CAD_GMSH_UTIL_H

#include "core/error.h"

#include <stdio.h>

/** Initialise gmsh once (silent, no configuration files). */
hoc_status hoc_gmsh_start(void);

/** HOC_ERR_CAD with gmsh's last logged error, prefixed by `what`. */
hoc_status hoc_gmsh_error(const char *what);

/** stdout/stderr redirected to a scratch file while the kernel may print. */
typedef struct hoc_quiet {
  FILE *sink;
  int saved_out, saved_err;
} hoc_quiet;

hoc_status hoc_quiet_begin(hoc_quiet *q);
/** Restore the descriptors; copy the first error line printed (if any) into
 *  first_error (may be NULL). */
void hoc_quiet_end(hoc_quiet *q, char *first_error, size_t size);

/** In a child process whose stdout and stderr already go to `sink`:
 *  hoc_quiet_begin redirects nothing and hoc_quiet_end reads the sink, so
 *  that what the kernel prints stays in the sink if it crashes. */
void hoc_quiet_in_child(FILE *sink);

/** The first line of f that reports an error (gmsh's "Error", OpenCASCADE's
 *  "ERR"), without colour codes and decoration, into first_error ("" if
 *  none; f may be NULL). */
void hoc_first_error_line(FILE *f, char *first_error, size_t size);

/* Kernel work in a child process (child.c) ---------------------------------- */

#include <sys/types.h>

/** A running child: its process, the read end of its result pipe, and the
 *  scratch file that receives its stdout and stderr. */
typedef struct hoc_child {
  pid_t pid;
  int fd;
  FILE *sink;
  double idle_limit; /* > 0: seconds a read waits for the child's next byte
                        before the child is killed (hoc_child_start sets 0) */
  int timed_out;     /* a read waited idle_limit: the child was killed */
} hoc_child;

/** What the child runs: writes its results to fd (hoc_child_write) and
 *  returns the child's exit code. */
typedef int (*hoc_child_fn)(void *arg, int fd);

/** Exit code of a child whose parent ended before it started. */
enum { HOC_CHILD_ORPHAN = 125 };

/** Fork a child that runs fn(arg, fd) and exits with its value. */
hoc_status hoc_child_start(hoc_child *c, hoc_child_fn fn, void *arg);

/** Read exactly n bytes the child wrote: 1, or 0 if it ended before (or
 *  sent nothing for c->idle_limit seconds: it is then killed, c->timed_out). */
int hoc_child_read(hoc_child *c, void *buf, size_t n);

/** In the child: write n bytes to the parent: 1, or 0 on failure. */
int hoc_child_write(int fd, const void *buf, size_t n);

/** How a child ended: exit_code >= 0 if it exited, signal > 0 if a signal
 *  ended it (both unset if its status could not be collected), and the
 *  first error line it printed. */
typedef struct hoc_child_end {
  int exit_code, signal;
  int timed_out; /* hoc_child_read killed it (signal SIGKILL): idle_limit passed */
  char first_error[256];
} hoc_child_end;

/** Wait for the child (killed first if kill_it: the parent stopped
 *  reading), collect how it ended, release its pipe and scratch file. */
void hoc_child_finish(hoc_child *c, int kill_it, hoc_child_end *end);

/** "SIGSEGV", "SIGABRT", ... */
const char *hoc_signal_name(int sig);

/** Signals that mean "stop" (from a terminal or a supervisor), not a crash. */
int hoc_signal_is_interrupt(int sig);

#endif
