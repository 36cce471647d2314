/* SPDX-License-Identifier: MIT */
/* Reset and exception entry of the target unit tests on QEMU's mps2-an500 (Cortex-M7 with the
 * double-precision FPU; memory map in mps2_an500.ld). ARMv7-M: the vector table's first word is
 * the initial main stack pointer, the second the reset handler (ARMv7-M ARM B1.5.3); QEMU reads
 * both from address 0 at reset. The reset handler turns the FPU on, copies .data, zeroes .bss
 * runs the constructor tables and calls exit(main()): newlib's exit flushes stdout and _exit
 * (syscalls.c) hands the status to QEMU. A fault prints its registers on the semihosting console
 * and exits with status 134. */
#include <stdint.h>
#include <stdlib.h>

#include "semihost.h"

extern uint32_t __stack_bottom__, __stack_top__;
extern uint32_t __data_start__, __data_end__, __data_load__;
extern uint32_t __bss_start__, __bss_end__;

int main(int argc, char **argv);
void Reset_Handler(void);
void m7_start(void);
void m7_fault_entry(void);
void m7_fault_report(const uint32_t *frame, uint32_t ipsr);
void __libc_init_array(void);
void _init(void);
void _fini(void);

/* crti's _init/_fini, which __libc_init_array / __libc_fini_array call: nothing to do here
 * (-nostartfiles leaves crti out). */
void _init(void) {}
void _fini(void) {}

typedef void (*m7_vector_t)(void);

__attribute__((section(".isr_vector"), used)) static const m7_vector_t m7_vectors[16] = {
    (m7_vector_t)(uintptr_t)&__stack_top__, /* initial MSP */
    Reset_Handler,
    m7_fault_entry, /* NMI */
    m7_fault_entry, /* HardFault */
    m7_fault_entry, /* MemManage */
    m7_fault_entry, /* BusFault */
    m7_fault_entry, /* UsageFault */
    0,
    0,
    0,
    0,
    m7_fault_entry, /* SVCall */
    m7_fault_entry, /* DebugMonitor */
    0,
    m7_fault_entry, /* PendSV */
    m7_fault_entry, /* SysTick */
};

/* Coprocessor Access Control Register (ARMv7-M ARM B3.2.20): CP10 and CP11 full access turns
 * the FPU on. Done in assembly, before any C code the compiler may give VFP instructions. */
__attribute__((naked)) void Reset_Handler(void) {
    __asm volatile(
        "ldr r0, =0xE000ED88\n\t"
        "ldr r1, [r0]\n\t"
        "orr r1, r1, #(0xF << 20)\n\t"
        "str r1, [r0]\n\t"
        "dsb\n\t"
        "isb\n\t"
        "b m7_start\n\t"
        ".ltorg");
}

/* System Handler Control and State Register: MemManage, BusFault and UsageFault enabled, so a
 * fault reports its own kind instead of escalating to HardFault. */
#define M7_SCB_SHCSR (*(volatile uint32_t *)0xE000ED24u)

/* The stack is painted with this word at reset; m7_stack_used_bytes finds the deepest word a
 * run overwrote (its high-water mark, reported at exit by syscalls.c). */
#define M7_STACK_PAINT 0x5AFEC0DEu

/* The linker script's symbols are addresses, not objects: the loops run over uintptr_t. */
#define M7_ADDR(sym) ((uintptr_t) & (sym))
#define M7_WORD(addr) (*(volatile uint32_t *)(addr))

uint32_t m7_stack_used_bytes(void);
uint32_t m7_stack_used_bytes(void) {
    uintptr_t a = M7_ADDR(__stack_bottom__);
    while (a < M7_ADDR(__stack_top__) && M7_WORD(a) == M7_STACK_PAINT) a += 4u;
    return (uint32_t)(M7_ADDR(__stack_top__) - a);
}

/* Paints the stack below the current frame (plain volatile stores: no library call yet). */
static void m7_paint_stack(void) {
    const uintptr_t limit = (uintptr_t)__builtin_frame_address(0) - 256u;
    for (uintptr_t a = M7_ADDR(__stack_bottom__); a < limit; a += 4u) M7_WORD(a) = M7_STACK_PAINT;
}

void m7_start(void) {
    m7_paint_stack();
    uintptr_t src = M7_ADDR(__data_load__);
    for (uintptr_t a = M7_ADDR(__data_start__); a < M7_ADDR(__data_end__); a += 4u, src += 4u) {
        M7_WORD(a) = M7_WORD(src);
    }
    for (uintptr_t a = M7_ADDR(__bss_start__); a < M7_ADDR(__bss_end__); a += 4u) M7_WORD(a) = 0u;
    M7_SCB_SHCSR |= (1u << 16) | (1u << 17) | (1u << 18);
    /* Constructors (newlib registers its stdio cleanup with one; the core has none). */
    __libc_init_array();
    static char name[] = "test";
    static char *argv[] = {name, 0};
    exit(main(1, argv));
}

/* Which stack the fault frame is on (EXC_RETURN bit 2), then the report in C. */
__attribute__((naked)) void m7_fault_entry(void) {
    __asm volatile(
        "tst lr, #4\n\t"
        "ite eq\n\t"
        "mrseq r0, msp\n\t"
        "mrsne r0, psp\n\t"
        "mrs r1, ipsr\n\t"
        "b m7_fault_report");
}

static void m7_put_hex(char *out, uint32_t v) {
    static const char digits[] = "0123456789abcdef";
    out[0] = '0';
    out[1] = 'x';
    for (int i = 0; i < 8; ++i) out[2 + i] = digits[(v >> (28 - 4 * i)) & 0xFu];
    out[10] = '\0';
}

static void m7_write_reg(const char *name, uint32_t v) {
    char hex[11];
    m7_put_hex(hex, v);
    m7_write0(name);
    m7_write0(hex);
}

/* Straight to the console (no stdio: the fault may have come from inside it). */
void m7_fault_report(const uint32_t *frame, uint32_t ipsr) {
    m7_write0("\nm7: fault, exception ");
    m7_write_reg("", ipsr & 0x1FFu);
    m7_write_reg(" CFSR ", *(volatile uint32_t *)0xE000ED28u);
    m7_write_reg(" HFSR ", *(volatile uint32_t *)0xE000ED2Cu);
    m7_write_reg(" MMFAR ", *(volatile uint32_t *)0xE000ED34u);
    m7_write_reg(" BFAR ", *(volatile uint32_t *)0xE000ED38u);
    m7_write_reg(" PC ", frame[6]);
    m7_write_reg(" LR ", frame[5]);
    m7_write0("\n");
    m7_exit(134);
}
