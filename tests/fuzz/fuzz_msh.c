/* libFuzzer target: the MSH reader on arbitrary bytes must fail cleanly or
 * succeed, never crash, leak or read out of bounds.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "io/io.h"

#include <stddef.h>
#include <stdint.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) {
  hoc_msh_raw raw;
  hoc_status st = hoc_msh_read_buffer((const char *)data, size, "fuzz", &raw);
  if (st == HOC_OK) hoc_msh_raw_free(&raw);
  return 0;
}
