/* SPDX-License-Identifier: MIT */
/* newlib's system calls for the emulated Cortex-M7: stdout/stderr go to the host console by
 * semihosting, exit() ends QEMU with the status, malloc (newlib's stdio buffers, never the core)
 * takes the heap between the linker script's __heap_start__ and __heap_end__. No files: the
 * target tests read none, and _open fails with ENOSYS. */
#include <errno.h>
#include <stddef.h>
#include <stdint.h>
#include <sys/stat.h>

#include "semihost.h"

#undef errno
extern int errno;

extern char __heap_start__, __heap_end__;

int _write(int fd, const char *buf, int len);
int _read(int fd, char *buf, int len);
int _open(const char *path, int flags, int mode);
int _close(int fd);
int _fstat(int fd, struct stat *st);
int _isatty(int fd);
int _lseek(int fd, int offset, int whence);
void *_sbrk(ptrdiff_t increment);
int _getpid(void);
int _kill(int pid, int sig);
void _exit(int status);

int _write(int fd, const char *buf, int len) {
    if (fd != 1 && fd != 2) {
        errno = EBADF;
        return -1;
    }
    /* SYS_WRITE0 takes NUL-terminated strings: copy in chunks (a NUL inside buf is dropped). */
    char chunk[129];
    int done = 0;
    while (done < len) {
        int n = len - done;
        if (n > 128) n = 128;
        for (int i = 0; i < n; ++i) chunk[i] = buf[done + i];
        chunk[n] = '\0';
        m7_write0(chunk);
        done += n;
    }
    return len;
}

int _read(int fd, char *buf, int len) {
    (void)fd;
    (void)buf;
    (void)len;
    errno = EBADF;
    return -1;
}

int _open(const char *path, int flags, int mode) {
    (void)path;
    (void)flags;
    (void)mode;
    errno = ENOSYS;
    return -1;
}

int _close(int fd) {
    (void)fd;
    return 0;
}

int _fstat(int fd, struct stat *st) {
    (void)fd;
    st->st_mode = S_IFCHR;
    return 0;
}

int _isatty(int fd) {
    return fd >= 0 && fd <= 2;
}

int _lseek(int fd, int offset, int whence) {
    (void)fd;
    (void)offset;
    (void)whence;
    return 0;
}

static uintptr_t m7_heap_brk;

/* The linker script's heap bounds are addresses, compared as integers. */
void *_sbrk(ptrdiff_t increment) {
    const uintptr_t start = (uintptr_t)&__heap_start__, end = (uintptr_t)&__heap_end__;
    if (m7_heap_brk == 0u) m7_heap_brk = start;
    const uintptr_t next = m7_heap_brk + (uintptr_t)increment;
    if ((increment > 0 && (next > end || next < m7_heap_brk)) ||
        (increment < 0 && (next < start || next > m7_heap_brk))) {
        errno = ENOMEM;
        return (void *)-1;
    }
    const uintptr_t prev = m7_heap_brk;
    m7_heap_brk = next;
    return (void *)prev;
}

int _getpid(void) {
    return 1;
}

int _kill(int pid, int sig) {
    (void)pid;
    (void)sig;
    errno = EINVAL;
    return -1;
}

/* The stack's high-water mark (startup_an500.c), then the exit status, on the console. */
uint32_t m7_stack_used_bytes(void);

static void m7_put_dec(char *out, uint32_t v) {
    char rev[11];
    int n = 0;
    do {
        rev[n++] = (char)('0' + v % 10u);
        v /= 10u;
    } while (v != 0u);
    for (int i = 0; i < n; ++i) out[i] = rev[n - 1 - i];
    out[n] = '\0';
}

void _exit(int status) {
    char num[11];
    m7_write0("m7: stack high-water mark ");
    m7_put_dec(num, m7_stack_used_bytes());
    m7_write0(num);
    m7_write0(" bytes, heap ");
    m7_put_dec(num, m7_heap_brk ? (uint32_t)(m7_heap_brk - (uintptr_t)&__heap_start__) : 0u);
    m7_write0(num);
    m7_write0(" bytes, exit status ");
    m7_put_dec(num, (uint32_t)status);
    m7_write0(num);
    m7_write0("\n");
    m7_exit(status);
}
