/* SPDX-License-Identifier: MIT */
/* Firmware example for a Cortex-M7 (STM32F767ZI memory map, stm32f767zi.ld): runs the core once
 * on a constant scene (fw_window.c) and leaves the result in fw_report for a debugger
 * (`print fw_report` in gdb). Build-only in CI: qemu-user cannot run M-profile images; the same
 * fw_window.c runs on the host as example.firmware_window. */
#include "fw_window.h"

#ifdef SFD_FW_CANARY
/* Positive control of the stack check: a 24 KiB frame on the call path from Reset_Handler, above
 * both SPEC's 16 KiB per call and the 20 KiB stack the linker script reserves. */
double sfd_fw_canary_deep(int n);
__attribute__((noinline)) double sfd_fw_canary_deep(int n) {
    volatile double big[3072];
    for (int i = 0; i < 3072; ++i) big[i] = (double)(i ^ n);
    return big[(unsigned)n % 3072u];
}
#endif

volatile sfd_fw_report_t fw_report;
volatile double fw_canary_sink;

int main(void) {
    sfd_fw_report_t r;
    (void)sfd_fw_run_window(&r);
    fw_report = r;
#ifdef SFD_FW_CANARY
    fw_canary_sink = sfd_fw_canary_deep(r.frames_judged);
#endif
    return 0;
}
