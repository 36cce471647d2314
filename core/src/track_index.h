/* SPDX-License-Identifier: MIT */
/* Private to the core (C and C++ sources): the one track-id -> entry table of the core (the
 * parity detector's frame index, the window filter's tracks, the navigation's previous frame,
 * the pipeline's duplicate count, the landmark map). Open addressing with linear probing over a
 * caller-owned, fixed-size array of slots (int16_t or int32_t), each -1 (empty) or an entry
 * index; the keys are the callers' own: an int64_t track id per entry, key_stride bytes apart
 * (a field of an array of structs, or an int64_t array). The caller keeps the load factor
 * <= 1/2 (at least twice as many slots as entries), so a probe sequence reaches an empty slot;
 * every loop is still bounded by the slot count. A slot holding an entry outside
 * [0, num_entries) (a corrupted caller-owned struct) ends a probe as if empty: nothing is read
 * outside the caller's arrays. */
#ifndef SFD_TRACK_INDEX_H
#define SFD_TRACK_INDEX_H

#include <stddef.h>
#include <stdint.h>
#include <string.h>

/* A conversion that is a static_cast in the C++ sources (built with -Wold-style-cast). */
#ifdef __cplusplus
#define SFD_TRACK_INDEX_CAST(type, value) (static_cast<type>(value))
#define SFD_TRACK_INDEX_UNCONST(type, value) (const_cast<type>(value))
#else
#define SFD_TRACK_INDEX_CAST(type, value) ((type)(value))
#define SFD_TRACK_INDEX_UNCONST(type, value) ((type)(value))
#endif

/* One table: its slots and the keys of its entries. */
typedef struct {
    int16_t *slots16;    /* the slots [num_slots] when they are int16_t, else NULL */
    int32_t *slots32;    /* the slots [num_slots] when they are int32_t (slots16 NULL) */
    int32_t num_slots;   /* >= 1 */
    const void *keys;    /* the int64_t key of entry e is key_stride * e bytes after keys */
    size_t key_stride;   /* bytes */
    int32_t num_entries; /* entries 0..num_entries-1 may be indexed */
} sfd_track_index_t;

/* A table of int16_t slots. */
static inline sfd_track_index_t sfd_track_index_i16(int16_t *slots, int32_t num_slots,
                                                    const void *keys, size_t key_stride,
                                                    int32_t num_entries) {
    sfd_track_index_t t;
    t.slots16 = slots;
    t.slots32 = NULL;
    t.num_slots = num_slots;
    t.keys = keys;
    t.key_stride = key_stride;
    t.num_entries = num_entries;
    return t;
}

/* A table of int32_t slots. */
static inline sfd_track_index_t sfd_track_index_i32(int32_t *slots, int32_t num_slots,
                                                    const void *keys, size_t key_stride,
                                                    int32_t num_entries) {
    sfd_track_index_t t;
    t.slots16 = NULL;
    t.slots32 = slots;
    t.num_slots = num_slots;
    t.keys = keys;
    t.key_stride = key_stride;
    t.num_entries = num_entries;
    return t;
}

/* Read-only views of a const table: for sfd_track_index_probe() and _find() only. */
static inline sfd_track_index_t sfd_track_index_view_i16(const int16_t *slots, int32_t num_slots,
                                                         const void *keys, size_t key_stride,
                                                         int32_t num_entries) {
    return sfd_track_index_i16(SFD_TRACK_INDEX_UNCONST(int16_t *, slots), num_slots, keys,
                               key_stride, num_entries);
}

static inline sfd_track_index_t sfd_track_index_view_i32(const int32_t *slots, int32_t num_slots,
                                                         const void *keys, size_t key_stride,
                                                         int32_t num_entries) {
    return sfd_track_index_i32(SFD_TRACK_INDEX_UNCONST(int32_t *, slots), num_slots, keys,
                               key_stride, num_entries);
}

/* Home slot of @p id in a table of @p num_slots (1 <= num_slots < 2^31): Fibonacci hashing
 * (multiply by 2^64 / golden ratio, keep the high 32 bits) scaled to [0, num_slots) without a
 * division. Consecutive ids spread evenly. */
static inline int32_t sfd_track_index_home(int64_t id, int32_t num_slots) {
    const uint64_t h = SFD_TRACK_INDEX_CAST(uint64_t, id) * 0x9E3779B97F4A7C15ULL;
    return SFD_TRACK_INDEX_CAST(int32_t,
                                ((h >> 32U) * SFD_TRACK_INDEX_CAST(uint64_t, num_slots)) >> 32U);
}

/* The slot after @p s (wrapping). */
static inline int32_t sfd_track_index_next(int32_t s, int32_t num_slots) {
    return (s + 1 == num_slots) ? 0 : s + 1;
}

/* The entry in slot @p s (-1: empty). */
static inline int32_t sfd_track_index_get(const sfd_track_index_t *t, int32_t s) {
    if (t->slots16 != NULL) return t->slots16[s];
    if (t->slots32 != NULL) return t->slots32[s];
    return -1;
}

/* Sets slot @p s to @p entry (-1: empty). */
static inline void sfd_track_index_set(const sfd_track_index_t *t, int32_t s, int32_t entry) {
    if (t->slots16 != NULL) {
        t->slots16[s] = SFD_TRACK_INDEX_CAST(int16_t, entry);
    } else if (t->slots32 != NULL) {
        t->slots32[s] = entry;
    }
}

/* Empties every slot. */
static inline void sfd_track_index_clear(const sfd_track_index_t *t) {
    for (int32_t s = 0; s < t->num_slots; ++s) sfd_track_index_set(t, s, -1);
}

/* The key of entry @p e. */
static inline int64_t sfd_track_index_key(const sfd_track_index_t *t, int32_t e) {
    int64_t k = 0;
    memcpy(&k,
           SFD_TRACK_INDEX_CAST(const unsigned char *, t->keys) +
               SFD_TRACK_INDEX_CAST(size_t, e) * t->key_stride,
           sizeof k);
    return k;
}

/* Linear probe for @p id: returns its entry (the first indexed with that key), or -1; in
 * @p slot_out the slot where it was found, or the first empty slot of its cluster (where an
 * insert goes), or -1 when the probe ran through the whole table. At most num_slots probes. */
static inline int32_t sfd_track_index_probe(const sfd_track_index_t *t, int64_t id,
                                            int32_t *slot_out) {
    int32_t s = sfd_track_index_home(id, t->num_slots);
    for (int32_t probe = 0; probe < t->num_slots; ++probe) {
        const int32_t e = sfd_track_index_get(t, s);
        if (e < 0 || e >= t->num_entries) {
            *slot_out = s;
            return -1;
        }
        if (sfd_track_index_key(t, e) == id) {
            *slot_out = s;
            return e;
        }
        s = sfd_track_index_next(s, t->num_slots);
    }
    *slot_out = -1;
    return -1;
}

/* The entry of @p id, or -1. */
static inline int32_t sfd_track_index_find(const sfd_track_index_t *t, int64_t id) {
    int32_t slot = -1;
    return sfd_track_index_probe(t, id, &slot);
}

/* Puts @p entry (keyed @p id) into the first empty slot of its probe sequence; the caller knows
 * that @p id is not indexed yet. Returns the slot, or -1 when the table is full (a load factor
 * <= 1/2 rules that out). */
static inline int32_t sfd_track_index_insert(const sfd_track_index_t *t, int64_t id,
                                             int32_t entry) {
    int32_t s = sfd_track_index_home(id, t->num_slots);
    for (int32_t probe = 0; probe < t->num_slots; ++probe) {
        if (sfd_track_index_get(t, s) < 0) {
            sfd_track_index_set(t, s, entry);
            return s;
        }
        s = sfd_track_index_next(s, t->num_slots);
    }
    return -1;
}

/* Indexes @p entry under @p id unless @p id is indexed already (then the earlier entry stays,
 * as a front-to-back search would find it). Returns the entry now indexed under @p id, or -1
 * when the table is full. */
static inline int32_t sfd_track_index_add_first(const sfd_track_index_t *t, int64_t id,
                                                int32_t entry) {
    int32_t slot = -1;
    const int32_t e = sfd_track_index_probe(t, id, &slot);
    if (e >= 0) return e;
    if (slot < 0) return -1;
    sfd_track_index_set(t, slot, entry);
    return entry;
}

#endif /* SFD_TRACK_INDEX_H */
