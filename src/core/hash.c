/* Open-addressing hash map with linear probing.
 * SPDX-License-Identifier: GPL-2.0-or-later */
#include "core/hash.h"

#include <stdlib.h>

static uint64_t mix(uint64_t k) {
  /* a 64-bit finaliser (xor-shift-multiply) */
  k ^= k >> 33;
  k *= 0xff51afd7ed558ccdULL;
  k ^= k >> 33;
  k *= 0xc4ceb9fe1a85ec53ULL;
  k ^= k >> 33;
  return k;
}

static hoc_status alloc_table(hoc_hash *h, size_t capacity) {
  h->keys = hoc_calloc(capacity, sizeof *h->keys);
  h->values = hoc_calloc(capacity, sizeof *h->values);
  if (!h->keys || !h->values) {
    free(h->keys);
    free(h->values);
    h->keys = NULL;
    h->values = NULL;
    return HOC_ERROR(HOC_ERR_MEMORY, "out of memory for a hash table of %zu entries", capacity);
  }
  for (size_t i = 0; i < capacity; ++i) h->keys[i] = HOC_HASH_EMPTY;
  h->capacity = capacity;
  h->count = 0;
  return HOC_OK;
}

hoc_status hoc_hash_init(hoc_hash *h, size_t expected) {
  size_t cap = 16;
  while (cap < 2 * expected + 16) cap *= 2;
  return alloc_table(h, cap);
}

void hoc_hash_free(hoc_hash *h) {
  if (!h) return;
  free(h->keys);
  free(h->values);
  h->keys = NULL;
  h->values = NULL;
  h->capacity = h->count = 0;
}

size_t hoc_hash_get(const hoc_hash *h, uint64_t key) {
  size_t mask = h->capacity - 1;
  for (size_t i = mix(key) & mask;; i = (i + 1) & mask) {
    if (h->keys[i] == key) return h->values[i];
    if (h->keys[i] == HOC_HASH_EMPTY) return SIZE_MAX;
  }
}

static hoc_status grow(hoc_hash *h) {
  hoc_hash old = *h;
  HOC_TRY(alloc_table(h, old.capacity * 2));
  for (size_t i = 0; i < old.capacity; ++i)
    if (old.keys[i] != HOC_HASH_EMPTY) HOC_TRY(hoc_hash_insert(h, old.keys[i], old.values[i], NULL, NULL));
  free(old.keys);
  free(old.values);
  return HOC_OK;
}

hoc_status hoc_hash_insert(hoc_hash *h, uint64_t key, size_t value, int *found,
                           size_t *value_out) {
  HOC_CHECK(key != HOC_HASH_EMPTY, HOC_ERR_INTERNAL, "reserved hash key");
  if (2 * (h->count + 1) > h->capacity) HOC_TRY(grow(h));
  size_t mask = h->capacity - 1;
  for (size_t i = mix(key) & mask;; i = (i + 1) & mask) {
    if (h->keys[i] == key) {
      if (found) *found = 1;
      if (value_out) *value_out = h->values[i];
      return HOC_OK;
    }
    if (h->keys[i] == HOC_HASH_EMPTY) {
      h->keys[i] = key;
      h->values[i] = value;
      h->count++;
      if (found) *found = 0;
      if (value_out) *value_out = value;
      return HOC_OK;
    }
  }
}
