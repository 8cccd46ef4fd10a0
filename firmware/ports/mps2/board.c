/* The mps2-an385 board as QEMU models it: a Cortex-M3 at 25 MHz, CMSDK UART0
   (0x40004000, receive interrupt IRQ 0) to the host, CMSDK timer 0
   (0x40000000, IRQ 8) as the wake-up alarm, SysTick as the tick, and ARM
   semihosting to leave QEMU with an exit status. Register layouts are from
   ARM's CMSDK technical reference (DDI 0479); QEMU's behaviour as measured
   (the team's emulation notes). */
#include "../cm3/cm3.h"
#include "board.h"

#define UART0_DATA     CM3_REG(0x40004000u)
#define UART0_STATE    CM3_REG(0x40004004u)
#define UART0_CTRL     CM3_REG(0x40004008u)
#define UART0_INTCLEAR CM3_REG(0x4000400Cu)
#define UART0_BAUDDIV  CM3_REG(0x40004010u)
#define UART_STATE_TX_FULL 1u
#define UART_STATE_RX_FULL 2u
#define UART_CTRL_TX_EN    1u
#define UART_CTRL_RX_EN    2u
#define UART_CTRL_RX_IRQ   8u
#define UART_INT_RX        2u
#define UART0_RX_IRQ 0u

#define TIMER0_CTRL     CM3_REG(0x40000000u)
#define TIMER0_VALUE    CM3_REG(0x40000004u)
#define TIMER0_RELOAD   CM3_REG(0x40000008u)
#define TIMER0_INTCLEAR CM3_REG(0x4000000Cu)
#define TIMER_CTRL_EN  1u
#define TIMER_CTRL_IRQ 8u
#define TIMER0_IRQ 8u

/* timer 1: the step alarm */
#define TIMER1_CTRL     CM3_REG(0x40001000u)
#define TIMER1_VALUE    CM3_REG(0x40001004u)
#define TIMER1_RELOAD   CM3_REG(0x40001008u)
#define TIMER1_INTCLEAR CM3_REG(0x4000100Cu)
#define TIMER1_IRQ 9u

/* the dual timer's first counter (DDI 0479, "APB dual-input timers"): the UV
   alarm; one-shot, 32-bit, interrupt enabled, enabled */
#define DUAL1_LOAD     CM3_REG(0x40002000u)
#define DUAL1_CTRL     CM3_REG(0x40002008u)
#define DUAL1_INTCLEAR CM3_REG(0x4000200Cu)
#define DUAL_CTRL_ONESHOT 1u
#define DUAL_CTRL_32BIT   2u
#define DUAL_CTRL_IRQ     0x20u
#define DUAL_CTRL_EN      0x80u
#define DUAL_IRQ 10u

#define BAUD 115200u /* QEMU ignores it; a real CMSDK UART needs it */

/* ---- semihosting ---------------------------------------------------------- */
static void semihost(uint32_t op, const void *arg)
{
    /* bkpt 0xab with the operation in r0 and its argument block in r1: QEMU
       (-semihosting-config enable=on) traps it; r0 comes back as the result. */
    __asm__ volatile("mov r0, %0\n\tmov r1, %1\n\tbkpt 0xab"
                     : : "r"(op), "r"(arg) : "r0", "r1", "memory");
}

void board_exit(int code)
{
    /* SYS_EXIT_EXTENDED with ADP_Stopped_ApplicationExit: QEMU exits with
       `code` (plain SYS_EXIT cannot carry one on 32-bit ARM). */
    uint32_t block[2];
    block[0] = 0x20026u;
    block[1] = (uint32_t)code;
    semihost(0x20u, block);
    for (;;) {}
}

void board_fault(int why)
{
    /* SYS_WRITE0 to QEMU's stderr, so a failing test says what happened. */
    semihost(0x04u, why == CM3_FAULT_STACK ? "fw-mps2: stack overflow (canary overwritten)\n"
                                           : "fw-mps2: hard fault\n");
    board_exit(MPS2_EXIT_FAULT + why);
}

/* ---- UART ------------------------------------------------------------------ */
void uart0_rx_handler(void);
void uart0_rx_handler(void)
{
    /* Cleared before reading: a byte that lands while we read raises it again. */
    UART0_INTCLEAR = UART_INT_RX;
    while (UART0_STATE & UART_STATE_RX_FULL) {
        if (cm3_rx_full()) {
            cm3_rx_stall();
            return;
        }
        cm3_rx_push((uint8_t)UART0_DATA);
    }
}

void board_rx_resume(void)
{
    cm3_irq_pend(UART0_RX_IRQ);
}

void board_write(const uint8_t *data, size_t size)
{
    size_t i;
    for (i = 0; i < size; i++) {
        while (UART0_STATE & UART_STATE_TX_FULL) {}
        UART0_DATA = data[i];
    }
}

/* ---- the wake-up alarm -------------------------------------------------------
   Timer 0 runs at the core clock like the tick, so a delay in ticks is a
   count. It only wakes the loop, which then reads the absolute tick: the
   restart of the count on a reload write (notes, pitfall 5) costs nothing. */
void timer0_handler(void);
void timer0_handler(void)
{
    TIMER0_INTCLEAR = 1u;
    TIMER0_CTRL = 0;
    cm3_wake();
}

void board_wake_at(uint64_t deadline, uint64_t now)
{
    uint64_t delay = deadline - now;
    TIMER0_CTRL = 0;
    TIMER0_INTCLEAR = 1u;
    if (deadline == UINT64_MAX) return; /* FW_NEVER: only a byte can wake us */
    if (delay > 0xFFFFFFFFu) delay = 0xFFFFFFFFu; /* 171 s; the loop re-arms */
    TIMER0_RELOAD = (uint32_t)delay;
    TIMER0_VALUE = (uint32_t)delay;
    TIMER0_CTRL = TIMER_CTRL_EN | TIMER_CTRL_IRQ;
}

/* ---- the alarms: timer 1 for steps, the dual timer for the UV light --------- */
void timer1_handler(void);
void timer1_handler(void)
{
    TIMER1_INTCLEAR = 1u;
    TIMER1_CTRL = 0;
    cm3_alarm(CM3_ALARM_STEP);
}

void dualtimer_handler(void);
void dualtimer_handler(void)
{
    DUAL1_INTCLEAR = 1u;
    DUAL1_CTRL = 0;
    cm3_alarm(CM3_ALARM_UV);
}

void board_alarm(int which, uint64_t delay)
{
    uint32_t count = delay > 0xFFFFFFFFu ? 0xFFFFFFFFu : (uint32_t)delay;
    if (which == CM3_ALARM_STEP) {
        TIMER1_CTRL = 0;
        TIMER1_INTCLEAR = 1u;
        if (!count) return;
        TIMER1_RELOAD = count;
        TIMER1_VALUE = count;
        TIMER1_CTRL = TIMER_CTRL_EN | TIMER_CTRL_IRQ;
    } else {
        DUAL1_CTRL = 0;
        DUAL1_INTCLEAR = 1u;
        if (!count) return;
        DUAL1_LOAD = count;
        DUAL1_CTRL = DUAL_CTRL_ONESHOT | DUAL_CTRL_32BIT | DUAL_CTRL_IRQ | DUAL_CTRL_EN;
    }
}

void board_init(void)
{
    UART0_BAUDDIV = BOARD_CLOCK_HZ / BAUD;
    UART0_CTRL = UART_CTRL_TX_EN | UART_CTRL_RX_EN | UART_CTRL_RX_IRQ;
    cm3_irq_enable(UART0_RX_IRQ);
    cm3_irq_enable(TIMER0_IRQ);
    cm3_irq_enable(TIMER1_IRQ);
    cm3_irq_enable(DUAL_IRQ);
    cm3_tick_start();
}

/* ---- the printer's pins ------------------------------------------------------
   QEMU models no GPIO on this board, so the pins are a software model like
   the simulator's: the carriage starts MPS2_Z_START_MM above the endstop,
   which is closed while it is at or below its switching point, and the
   steps, the light and the masks shown are counted. The display buffers are
   not kept (20 KiB could not hold them): the core checks each mask's CRC-32
   as it decodes, which is what a test needs to know. */
static struct {
    int32_t true_position;     /* steps above the endstop's switching point */
    uint32_t steps, rows, shows;
    int uv, motor, shown;
} pins = {(int32_t)(MPS2_Z_START_MM * BOARD_STEPS_PER_MM), 0, 0, 0, 0, 0, -1};

void board_step(int dir) { pins.true_position += dir; pins.steps++; }
int board_endstop(void) { return pins.true_position <= 0; }
void board_uv(int on) { pins.uv = on; }
void board_motor(int on) { pins.motor = on; }
void board_show(int slot) { pins.shown = slot; if (slot >= 0) pins.shows++; }

void board_mask_row(int slot, uint32_t y, const uint8_t *row, uint32_t size)
{
    (void)slot;
    (void)y;
    (void)row;
    (void)size;
    pins.rows++;
}

/* ---- the interrupt vectors ------------------------------------------------------ */
#define F cm3_fault_handler
CM3_IRQ_VECTORS irq_vectors[32] = { /* the an385's external interrupts */
    uart0_rx_handler, F, F, F, F, F, F, F, timer0_handler, timer1_handler, dualtimer_handler, F, F, F, F, F,
    F, F, F, F, F, F, F, F, F, F, F, F, F, F, F, F
};
#undef F
