/* SPDX-License-Identifier: MIT */
/* Counting malloc interposer shared by the heap proofs. The including executable defines malloc,
 * calloc, realloc, free and the aligned allocators itself; glibc resolves every allocation of the
 * process to them (glibc's documented malloc replacement), so the counter sees the C heap and
 * C++ operator new/delete (libstdc++ implements them on malloc). Include from one translation
 * unit per executable. Not usable with sanitizers (they own malloc). */
#ifndef SFD_HEAP_COUNTER_H
#define SFD_HEAP_COUNTER_H

#include <stddef.h>
#include <stdio.h>

/* glibc's exported underlying allocator (the names are glibc's, hence reserved identifiers). */
/* NOLINTBEGIN(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp) */
extern void *__libc_malloc(size_t);
extern void *__libc_calloc(size_t, size_t);
extern void *__libc_realloc(void *, size_t);
extern void __libc_free(void *);
extern void *__libc_memalign(size_t, size_t);
/* NOLINTEND(bugprone-reserved-identifier,cert-dcl37-c,cert-dcl51-cpp) */

static volatile unsigned long g_heap_calls;

void *malloc(size_t n) {
    g_heap_calls++;
    return __libc_malloc(n);
}
void *calloc(size_t a, size_t b) {
    g_heap_calls++;
    return __libc_calloc(a, b);
}
void *realloc(void *p, size_t n) {
    g_heap_calls++;
    return __libc_realloc(p, n);
}
void free(void *p) {
    if (p != NULL) g_heap_calls++;
    __libc_free(p);
}
void *memalign(size_t al, size_t n) {
    g_heap_calls++;
    return __libc_memalign(al, n);
}
void *aligned_alloc(size_t al, size_t n) {
    g_heap_calls++;
    return __libc_memalign(al, n);
}
int posix_memalign(void **out, size_t al, size_t n) {
    g_heap_calls++;
    *out = __libc_memalign(al, n);
    return *out ? 0 : 12;
}

static int g_failures;
#define CHECK(cond)                                            \
    do {                                                       \
        if (!(cond)) {                                         \
            printf("FAILED: %s (line %d)\n", #cond, __LINE__); \
            g_failures++;                                      \
        }                                                      \
    } while (0)

#endif /* SFD_HEAP_COUNTER_H */
