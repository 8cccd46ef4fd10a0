/* What the Cortex-M3 ports share: the reset path (.data, .bss, a stack
   canary), the system half of the vector table and the fault handler, a
   64-bit tick counted on SysTick, the receive ring that a UART interrupt
   fills, the idle wait, and main (main.c) with the core's port. A board
   (mps2/, stm32f103/) supplies board.h (the printer's figures, BOARD_*), its
   interrupt vectors (CM3_IRQ_VECTORS), its linker script and the board_*
   functions below; the serving loop that runs the core is in serve.c.

   Registers are the ARMv7-M architecture's (ARMv7-M ARM, B3.2-B3.4), the same
   on every Cortex-M3. */
#ifndef FW_CM3_H
#define FW_CM3_H
#include <stddef.h>
#include <stdint.h>

#define CM3_REG(addr) (*(volatile uint32_t *)(uintptr_t)(addr))

#define SYST_CSR  CM3_REG(0xE000E010u)
#define SYST_RVR  CM3_REG(0xE000E014u)
#define SYST_CVR  CM3_REG(0xE000E018u)
#define SCB_ICSR  CM3_REG(0xE000ED04u)
#define SCB_AIRCR CM3_REG(0xE000ED0Cu)
#define NVIC_ISER(n) CM3_REG(0xE000E100u + 4u * (n))
#define NVIC_ICER(n) CM3_REG(0xE000E180u + 4u * (n))
#define NVIC_ISPR(n) CM3_REG(0xE000E200u + 4u * (n))
#define NVIC_ICPR(n) CM3_REG(0xE000E280u + 4u * (n))

#define SCB_ICSR_PENDSTSET (1u << 26)
#define SCB_AIRCR_SYSRESETREQ 0x05FA0004u /* VECTKEY and SYSRESETREQ */

static inline void cm3_irq_enable(unsigned irq) { NVIC_ISER(irq / 32u) = 1u << (irq % 32u); }
static inline void cm3_irq_pend(unsigned irq) { NVIC_ISPR(irq / 32u) = 1u << (irq % 32u); }
static inline void cm3_irq_unpend(unsigned irq) { NVIC_ICPR(irq / 32u) = 1u << (irq % 32u); }
/* Priorities (NVIC_IPR, a byte per interrupt; a part implements the top
   bits): the alarms stay at 0, the highest; the UARTs and the wake-up timer
   go below them, so a step never waits behind a byte. */
#define CM3_PRIORITY_LOW 0x80u
static inline void cm3_irq_priority(unsigned irq, uint8_t prio) { *(volatile uint8_t *)(uintptr_t)(0xE000E400u + irq) = prio; }
static inline void cm3_interrupts_off(void) { __asm__ volatile("cpsid i" ::: "memory"); }
static inline void cm3_interrupts_on(void) { __asm__ volatile("cpsie i" ::: "memory"); }

/* Why a board stops itself (board_fault). */
enum { CM3_FAULT_STACK = 1, CM3_FAULT_HARD = 2, CM3_FAULT_CLOCK = 3 };

/* ---- supplied by the board ------------------------------------------- */
/* Clocks, UART, timers, pins; SysTick is started by cm3_tick_start. */
void board_init(void);
/* Queues one whole reply for the host (cm3_tx_write) and starts the UART's
   transmit interrupt; never waits for the line. */
void board_write(const uint8_t *data, size_t size);
/* The board's one-shot alarms (CM3_ALARM_*): interrupts `delay` ticks from
   now, or as far as the timer counts (cm3 arms it again for the rest), that
   call cm3_alarm(which); delay 0 stops it. */
void board_alarm(int which, uint64_t delay);
/* Arms the wake-up timer to interrupt at or after tick `deadline` (or
   earlier when the delay is past its range; the loop arms it again) and to
   call cm3_wake() then; UINT64_MAX (FW_NEVER) disarms it. */
void board_wake_at(uint64_t deadline, uint64_t now);
/* Makes the UART receive interrupt run again (cm3_rx_consume calls this
   after the ring had stalled). */
void board_rx_resume(void);
/* Starts (on the first call) and refreshes the hardware watchdog; from
   port.watchdog, i.e. fw_run, only. */
void board_watchdog(void);
/* The non-maskable interrupt: mps2's watchdog warning; a board without a
   source for it treats it as a fault. */
void board_nmi(void);
/* Leaves the firmware: semihosting exit under QEMU, a reset on a board. */
void board_exit(int code) __attribute__((noreturn));
/* Stops everything safely after a fault (UV off first). */
void board_fault(int why) __attribute__((noreturn));
/* The printer's pins: a Z step (dir +1 up, -1 down), the endstop (1 closed),
   the UV light, the stepper driver's enable. */
void board_step(int dir);
int board_endstop(void);
void board_uv(int on);
void board_motor(int on);
/* A decoded mask row into display buffer `slot`; a buffer shown, -1 dark. */
void board_mask_row(int slot, uint32_t y, const uint8_t *row, uint32_t size);
void board_show(int slot);

/* The external interrupts' vectors, in the board's order: place this table
   after the system vectors (the linker scripts keep .vectors.irq there);
   entries without a handler take cm3_fault_handler. */
typedef void (*cm3_vector)(void);
void cm3_fault_handler(void);
#define CM3_IRQ_VECTORS __attribute__((section(".vectors.irq"), used)) static const cm3_vector

/* ---- provided here ------------------------------------------------------ */
/* SysTick free-running at the core clock, reload 2^24: the tick. */
void cm3_tick_start(void);
/* Ticks since cm3_tick_start: exact and monotonic, also with interrupts off
   as long as they were off for less than half a SysTick period. */
uint64_t cm3_ticks(void);

/* The receive ring. The UART interrupt pushes while there is room; when the
   ring is full it leaves the byte in the UART (which then holds the line:
   QEMU stops reading the pty) and calls cm3_rx_stall. */
int cm3_rx_full(void);
void cm3_rx_push(uint8_t byte);
void cm3_rx_stall(void);
/* The oldest received bytes, contiguous (0 when empty); the pointer stays
   valid until cm3_rx_consume. */
size_t cm3_rx_peek(const uint8_t **data);
void cm3_rx_consume(size_t n);
/* Bytes the ring had to refuse since reset (only a board whose UART cannot
   hold the line counts these, through cm3_rx_lost). */
void cm3_rx_lost(void);
uint32_t cm3_rx_lost_count(void);

/* The transmit ring. The loop puts whole replies in (cm3_tx_write); the
   UART's transmit interrupt takes bytes out (cm3_tx_pop) as the line
   drains them, so a reply never stalls the loop. The boards size it
   (CM3_TX_SIZE) for the protocol's worst case: the host's window of frames,
   each answered by at most one reply of LINK_FRAME_MAX bytes. Should it
   still be full (a host that ignores the window, G-code chatter faster than
   the line), the reply that does not fit is dropped whole and counted, never
   cut: the host repeats a request whose answer does not come, and an ACK is
   superseded by the next (link/PROTOCOL.md). */
#ifndef CM3_TX_SIZE
#define CM3_TX_SIZE 1024u /* a power of two */
#endif
int cm3_tx_write(const uint8_t *data, size_t size); /* 0: dropped */
int cm3_tx_pop(uint8_t *byte);                       /* 0: empty */
int cm3_tx_empty(void);
uint32_t cm3_tx_dropped(void);

/* Alarms at absolute ticks, from hardware timers, so that what they do
   happens on time whatever the loop is doing: the next Z step
   (fw_step_interrupt) and the end of an exposure (UV off). */
enum { CM3_ALARM_STEP, CM3_ALARM_UV, CM3_ALARMS };
/* The ticks an alarm needs to be armed ahead: a step closer than this is
   refused (the core stops the motion rather than step late). */
#define CM3_ALARM_LEAD 64u
/* Arms alarm `which` for tick `when` (UINT64_MAX stops it); 0 if `when` is
   closer than CM3_ALARM_LEAD. */
int cm3_alarm_at(int which, uint64_t when);
/* From the board's alarm interrupts. */
void cm3_alarm(int which);
/* Supplied by main.c: what an alarm does when its tick has come (`late`:
   the ticks it came after it). */
void cm3_alarm_due(int which, uint64_t late);

/* Called by the board's wake-up timer interrupt. */
void cm3_wake(void);
/* Sleeps until a byte arrives or the tick reaches `deadline`. */
void cm3_idle(uint64_t deadline);

/* 1 while the word at the bottom of the stack is intact. */
int cm3_stack_ok(void);

#ifdef CM3_TRACE
/* Test images only: the step alarm's scheduled and actual ticks (cm3_alarm,
   before the step goes out), a line to the emulator's log, the worst
   loop pass in ticks (serve.c) and the deepest the stack went. */
void board_trace_step(uint64_t scheduled, uint64_t emitted);
void board_trace_text(const char *prefix, uint64_t value);
extern uint64_t cm3_worst_pass, cm3_worst_moving_pass;
uint32_t cm3_stack_used(void);
/* The board's interrupt handlers call these first and last: the ticks they
   took, so that a loop pass's own work can be told from the interrupts
   that came in it (serve.c). Under QEMU those bunch up: its UART sends a
   reply's bytes, and takes a burst of the host's, as fast as the handler
   runs, so one pass can carry all of their interrupts. */
void cm3_trace_isr_enter(void);
void cm3_trace_isr_leave(void);
extern volatile uint64_t cm3_isr_ticks;
extern uint64_t cm3_worst_work, cm3_worst_moving_work, cm3_miscounted_passes;
#endif

/* ---- serve.c ---------------------------------------------------------------- */
struct fw_state;
/* Runs the core for ever: received bytes to fw_receive, fw_run at each
   deadline, idle in between, the stack canary checked on every pass. */
void cm3_serve(struct fw_state *fw) __attribute__((noreturn));
/* The Z axis both boards drive (10 mm/s, 50 mm/s^2, homing at 5 mm/s,
   200 mm of travel) and a 1 s link timeout, at tick_hz and steps_per_mm. */
struct fw_config;
void cm3_z_config(struct fw_config *config, uint32_t tick_hz, uint32_t steps_per_mm);
#endif
