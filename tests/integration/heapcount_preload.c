/* SPDX-License-Identifier: MIT */
/* LD_PRELOAD library for integration tests: counts every heap call of the process (malloc,
 * calloc, realloc, free, aligned allocators; C++ new/delete go through malloc in libstdc++) and
 * exports the process-wide count (sfd_heapcount_get) and the calling thread's
 * (sfd_heapcount_thread), which sfd-node looks up with dlsym to attribute heap calls to its own
 * per-frame path (its thread, inside the handler) versus the LCM library (everything else).
 * Forwards to glibc's __libc_* allocator.
 */
#include <stddef.h>

/* NOLINTBEGIN(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp) */
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);
extern void *__libc_memalign(size_t, size_t);
/* NOLINTEND(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp) */

static volatile unsigned long long g_count; /* whole process */
/* the calling thread's count (LCM's udpm provider runs a receive thread of its own) */
static __thread unsigned long long tl_count;

unsigned long long sfd_heapcount_get(void) {
    return __atomic_load_n(&g_count, __ATOMIC_RELAXED);
}

unsigned long long sfd_heapcount_thread(void) {
    return tl_count;
}

static void bump(void) {
    __atomic_fetch_add(&g_count, 1ULL, __ATOMIC_RELAXED);
    tl_count++;
}

void *malloc(size_t n) {
    bump();
    return __libc_malloc(n);
}
void *calloc(size_t a, size_t b) {
    bump();
    return __libc_calloc(a, b);
}
void *realloc(void *p, size_t n) {
    bump();
    return __libc_realloc(p, n);
}
void free(void *p) {
    if (p != NULL) bump();
    __libc_free(p);
}
void *memalign(size_t al, size_t n) {
    bump();
    return __libc_memalign(al, n);
}
void *aligned_alloc(size_t al, size_t n) {
    bump();
    return __libc_memalign(al, n);
}
int posix_memalign(void **out, size_t al, size_t n) {
    bump();
    *out = __libc_memalign(al, n);
    return *out ? 0 : 12;
}
