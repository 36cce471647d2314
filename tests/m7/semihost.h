/* SPDX-License-Identifier: MIT */
/* Arm semihosting (Arm "Semihosting for AArch32 and AArch64", v2.0) on the emulated board: the
 * target's only channel to the host. QEMU serves it with -semihosting-config enable=on. */
#ifndef SFD_M7_SEMIHOST_H
#define SFD_M7_SEMIHOST_H

#include <stdint.h>

#define M7_SYS_WRITEC 0x03u
#define M7_SYS_WRITE0 0x04u
#define M7_SYS_EXIT 0x18u
#define M7_SYS_EXIT_EXTENDED 0x20u
/* SYS_EXIT reason: normal application exit (the status code travels as the subcode). */
#define M7_ADP_STOPPED_APPLICATION_EXIT 0x20026u

/* One semihosting call: operation in r0, parameter in r1, result in r0; on M-profile the trap
 * is BKPT 0xAB. */
static inline uint32_t m7_semihost(uint32_t op, const void *arg) {
    register uint32_t r0 __asm__("r0") = op;
    register const void *r1 __asm__("r1") = arg;
    __asm__ volatile("bkpt 0xab" : "+r"(r0) : "r"(r1) : "memory");
    return r0;
}

/* Writes a NUL-terminated string to the host console (SYS_WRITE0). */
static inline void m7_write0(const char *s) {
    (void)m7_semihost(M7_SYS_WRITE0, s);
}

/* Ends the emulation with `status` as QEMU's exit status (SYS_EXIT_EXTENDED: the AArch32
 * SYS_EXIT cannot carry a status, QEMU maps it to 0 or 1). */
__attribute__((noreturn)) static inline void m7_exit(int status) {
    const uint32_t block[2] = {M7_ADP_STOPPED_APPLICATION_EXIT, (uint32_t)status};
    (void)m7_semihost(M7_SYS_EXIT_EXTENDED, block);
    for (;;) {
    }
}

#endif /* SFD_M7_SEMIHOST_H */
