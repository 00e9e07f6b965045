/* Decimal digits of an unsigned integer, two at a time: the MSH writer's
 * integers and the digits of its doubles (msh_numbers.c). Inline, as the
 * writer calls it for every integer it writes.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#ifndef HOC_IO_MSH_DIGITS_H
#define HOC_IO_MSH_DIGITS_H

#include <stddef.h>
#include <stdint.h>

static const char digit_pairs[201] =
    "00010203040506070809101112131415161718192021222324252627282930313233343536373839"
    "40414243444546474849505152535455565758596061626364656667686970717273747576777879"
    "8081828384858687888990919293949596979899";

/* Decimal digits of x into out (no NUL); returns the length. */
static inline size_t format_u64(uint64_t x, char *out) {
  char tmp[20];
  size_t n = 0;
  while (x >= 100) {
    unsigned r = (unsigned)(x % 100);
    x /= 100;
    tmp[n++] = digit_pairs[2 * r + 1];
    tmp[n++] = digit_pairs[2 * r];
  }
  if (x >= 10) {
    tmp[n++] = digit_pairs[2 * x + 1];
    tmp[n++] = digit_pairs[2 * x];
  } else {
    tmp[n++] = (char)('0' + x);
  }
  for (size_t k = 0; k < n; ++k)
    out[k] = tmp[n - 1 - k];
  return n;
}

#endif
