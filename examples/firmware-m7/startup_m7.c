/* SPDX-License-Identifier: MIT */
/* Reset and exception entry of the firmware example (ARMv7-M: the vector table's first word is
 * the initial main stack pointer, the second the reset handler; ARMv7-M ARM B1.5.3). Only the 16
 * system exceptions are listed: the example enables no peripheral interrupt. */
#include <stdint.h>

extern uint32_t __stack_top__;
extern uint32_t __data_start__, __data_end__, __data_load__;
extern uint32_t __bss_start__, __bss_end__;

int main(void);
void Reset_Handler(void);
void Default_Handler(void);

/* Faults and unexpected exceptions stop here, visible to a debugger. */
void Default_Handler(void) {
    for (;;) {
        __asm volatile("bkpt #0");
    }
}

typedef void (*fw_vector_t)(void);

__attribute__((section(".isr_vector"), used)) static const fw_vector_t fw_vectors[16] = {
    (fw_vector_t)(uintptr_t)&__stack_top__, /* initial MSP */
    Reset_Handler,
    Default_Handler, /* NMI */
    Default_Handler, /* HardFault */
    Default_Handler, /* MemManage */
    Default_Handler, /* BusFault */
    Default_Handler, /* UsageFault */
    0,
    0,
    0,
    0,
    Default_Handler, /* SVCall */
    Default_Handler, /* DebugMonitor */
    0,
    Default_Handler, /* PendSV */
    Default_Handler, /* SysTick */
};

/* Coprocessor Access Control Register (ARMv7-M ARM B3.2.20): CP10 and CP11 full access turns the
 * FPU on; it must precede the first floating-point instruction. */
#define FW_SCB_CPACR (*(volatile uint32_t *)0xE000ED88u)

void Reset_Handler(void) {
    FW_SCB_CPACR |= (0xFu << 20);
    __asm volatile("dsb\n\tisb" ::: "memory");
    /* .data from its load address in flash, .bss zeroed (word loops: both are 8-aligned). */
    const uint32_t *src = &__data_load__;
    for (uint32_t *dst = &__data_start__; dst < &__data_end__; ++dst, ++src) *dst = *src;
    for (uint32_t *dst = &__bss_start__; dst < &__bss_end__; ++dst) *dst = 0u;
    /* No static constructors are run: neither the core nor this example has any, and
     * tools/firmware_report.py fails the image if a non-empty .init_array appears. */
    (void)main();
    for (;;) {
        __asm volatile("wfi");
    }
}
