/* Open-addressing hash map with linear probing; keys and values are stored
 * side by side so that a probe touches one cache line.
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

/* A new empty table in *h (left as it was on failure). */
static hoc_status alloc_table(hoc_hash *h, size_t capacity) {
  hoc_hash_slot *slots = hoc_realloc(NULL, capacity, sizeof *slots); /* keys set below */
  HOC_CHECK(slots, HOC_ERR_MEMORY, "out of memory for a hash table of %zu entries", capacity);
  for (size_t i = 0; i < capacity; ++i)
    slots[i].key = HOC_HASH_EMPTY;
  h->slots = slots;
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
  free(h->slots);
  h->slots = NULL;
  h->capacity = h->count = 0;
}

size_t hoc_hash_get(const hoc_hash *h, uint64_t key) {
  size_t mask = h->capacity - 1;
  for (size_t i = mix(key) & mask;; i = (i + 1) & mask) {
    if (h->slots[i].key == key) return h->slots[i].value;
    if (h->slots[i].key == HOC_HASH_EMPTY) return SIZE_MAX;
  }
}

static hoc_status grow(hoc_hash *h) {
  hoc_hash old = *h;
  HOC_TRY(alloc_table(h, old.capacity * 2));
  /* reinserting cannot grow again (the new table is half full at most) */
  for (size_t i = 0; i < old.capacity; ++i)
    if (old.slots[i].key != HOC_HASH_EMPTY)
      (void)hoc_hash_insert(h, old.slots[i].key, old.slots[i].value, NULL, NULL);
  free(old.slots);
  return HOC_OK;
}

hoc_status hoc_hash_insert(hoc_hash *h, uint64_t key, size_t value, int *found,
                           size_t *value_out) {
  HOC_CHECK(key != HOC_HASH_EMPTY, HOC_ERR_INTERNAL, "reserved hash key");
  if (2 * (h->count + 1) > h->capacity) HOC_TRY(grow(h));
  size_t mask = h->capacity - 1;
  for (size_t i = mix(key) & mask;; i = (i + 1) & mask) {
    hoc_hash_slot *s = &h->slots[i];
    if (s->key == key) {
      if (found) *found = 1;
      if (value_out) *value_out = s->value;
      return HOC_OK;
    }
    if (s->key == HOC_HASH_EMPTY) {
      s->key = key;
      s->value = value;
      h->count++;
      if (found) *found = 0;
      if (value_out) *value_out = value;
      return HOC_OK;
    }
  }
}
