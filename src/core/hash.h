/* Open-addressing hash map from 64-bit keys to size_t values (edges,
 * (node, face) pairs). Keys must not be HOC_HASH_EMPTY.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#ifndef HOC_CORE_HASH_H
#define HOC_CORE_HASH_H

#include "core/error.h"

#include <stdint.h>

#define HOC_HASH_EMPTY UINT64_MAX

typedef struct hoc_hash_slot {
  uint64_t key;
  size_t value;
} hoc_hash_slot;

typedef struct hoc_hash {
  hoc_hash_slot *slots; /* key and value side by side: one cache line per probe */
  size_t capacity; /* power of two */
  size_t count;
} hoc_hash;

/** Map sized for about `expected` keys (grows as needed). */
hoc_status hoc_hash_init(hoc_hash *h, size_t expected);
void hoc_hash_free(hoc_hash *h);

/** Value of key, or SIZE_MAX if absent. */
size_t hoc_hash_get(const hoc_hash *h, uint64_t key);

/** Insert key -> value unless present; *found (may be NULL) tells whether it
 *  was there, and *value_out (may be NULL) receives the stored value. */
hoc_status hoc_hash_insert(hoc_hash *h, uint64_t key, size_t value, int *found,
                           size_t *value_out);

/** Key of an unordered pair of indices below 2^32. */
static inline uint64_t hoc_pair_key(size_t a, size_t b) {
  return a < b ? ((uint64_t)a << 32) | (uint64_t)b : ((uint64_t)b << 32) | (uint64_t)a;
}

#endif
