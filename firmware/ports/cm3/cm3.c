/* The Cortex-M3 ports' shared hardware layer: reset, tick, receive ring,
   idle. File-static state here is the hardware's (one SysTick, one UART). */
#include "cm3.h"
#include <string.h>

/* From the board's linker script. */
extern uint32_t __data_load[], __data_start[], __data_end[];
extern uint32_t __bss_start[], __bss_end[];
extern uint32_t __stack_bottom[];

#define CM3_CANARY 0xC0DEFA11u

int main(void);

/* The vector table's reset entry. No C before this has run: .data is still
   in flash and .bss is garbage, so the copy loops touch only linker symbols
   (their bounds are word aligned by the scripts). */
void cm3_reset(void) __attribute__((noreturn));
void cm3_reset(void)
{
    uint32_t *from = __data_load, *to = __data_start;
    while (to < __data_end) *to++ = *from++;
    for (to = __bss_start; to < __bss_end; ) *to++ = 0;
    /* The stack grows down into this word; main's loop checks it. */
    __stack_bottom[0] = CM3_CANARY;
#ifdef CM3_TRACE
    {   /* the rest painted, to see how deep it went (cm3_stack_used) */
        uint32_t *sp;
        __asm__ volatile("mov %0, sp" : "=r"(sp));
        for (to = __stack_bottom + 1; to < sp - 16; ) *to++ = CM3_CANARY;
    }
#endif
    board_exit(main());
}

void cm3_fault_handler(void)
{
    board_fault(CM3_FAULT_HARD);
}

/* The system half of the vector table: the stack's top, reset, the faults,
   SysTick; the board's CM3_IRQ_VECTORS follow it. */
void SysTick_Handler(void);
extern uint32_t __stack_top[];
struct cm3_system_vectors {
    void *stack_top;
    cm3_vector system[15]; /* reset, NMI, faults, SVC, debug, PendSV, SysTick */
};
#define F cm3_fault_handler
__attribute__((section(".vectors"), used))
static const struct cm3_system_vectors system_vectors = {
    __stack_top,
    { cm3_reset, board_nmi, F, F, F, F, 0, 0, 0, 0, F, F, 0, F, SysTick_Handler }
};
#undef F

int cm3_stack_ok(void)
{
    return __stack_bottom[0] == CM3_CANARY;
}

#ifdef CM3_TRACE
uint32_t cm3_stack_used(void)
{
    const uint32_t *p = __stack_bottom + 1;
    while (p < __stack_top && *p == CM3_CANARY) p++;
    return (uint32_t)((uintptr_t)__stack_top - (uintptr_t)p);
}

/* The outermost handler's ticks, entry to return: one that preempts
   another is inside it (and runs whole before it resumes). Each step runs
   with interrupts held: an alarm that preempted a UART handler between its
   depth's decrement and its sum took the depth for its own outermost entry,
   and the two handlers' ticks were counted twice over, a pass's interrupts
   longer than the pass (CI read a pass's own work as 2^64 - a few cycles). */
volatile uint64_t cm3_isr_ticks;
static uint32_t isr_depth;
static uint64_t isr_entered;

static uint32_t interrupts_hold(void)
{
    uint32_t primask;
    __asm__ volatile("mrs %0, primask\n\tcpsid i" : "=r"(primask)::"memory");
    return primask;
}

static void interrupts_restore(uint32_t primask)
{
    __asm__ volatile("msr primask, %0" ::"r"(primask) : "memory");
}

void cm3_trace_isr_enter(void)
{
    uint32_t held = interrupts_hold();
    if (isr_depth++ == 0) isr_entered = cm3_ticks();
    interrupts_restore(held);
}

void cm3_trace_isr_leave(void)
{
    uint32_t held = interrupts_hold();
    if (--isr_depth == 0) cm3_isr_ticks += cm3_ticks() - isr_entered;
    interrupts_restore(held);
}
#endif

/* ---- the tick ------------------------------------------------------------
   SysTick counts the core clock down from 2^24 - 1 and interrupts at each
   wrap; the wraps are the tick's upper bits. */
static volatile uint32_t tick_wraps;

void SysTick_Handler(void);
void SysTick_Handler(void)
{
    tick_wraps++; /* a few instructions: not counted in cm3_isr_ticks */
}

void cm3_tick_start(void)
{
    SYST_RVR = 0xFFFFFFu;
    SYST_CVR = 0;
    SYST_CSR = 7u; /* enable, interrupt, processor clock */
}

uint64_t cm3_ticks(void)
{
    for (;;) {
        uint32_t wraps = tick_wraps;
        uint32_t elapsed = 0xFFFFFFu - SYST_CVR;
        uint32_t pending = SCB_ICSR & SCB_ICSR_PENDSTSET;
        if (wraps != tick_wraps) continue; /* the handler ran meanwhile */
        /* A wrap whose handler has not run yet (interrupts off, or QEMU
           delivering it a few instructions late): the counter has reloaded
           if it reads near the top, and the wrap belongs to this reading. */
        if (pending && elapsed < 0x800000u) wraps++;
        return ((uint64_t)wraps << 24) | elapsed;
    }
}

/* ---- the receive ring -------------------------------------------------- */
/* A power of two, so the free-running indices wrap with the buffer. A board
   whose UART cannot hold the line sizes it for the protocol's window. */
#ifndef CM3_RX_SIZE
#define CM3_RX_SIZE 512u
#endif
#define RX_SIZE CM3_RX_SIZE

static uint8_t rx_buf[RX_SIZE];
static volatile uint32_t rx_head;   /* advanced by the interrupt */
static volatile uint32_t rx_tail;   /* advanced by the main loop */
static volatile int rx_stalled;
static volatile uint32_t rx_lost;

int cm3_rx_full(void)
{
    return rx_head - rx_tail == RX_SIZE;
}

void cm3_rx_push(uint8_t byte)
{
    uint32_t head = rx_head;
    rx_buf[head % RX_SIZE] = byte;
    rx_head = head + 1u;
}

void cm3_rx_stall(void)
{
    rx_stalled = 1;
}

size_t cm3_rx_peek(const uint8_t **data)
{
    uint32_t tail = rx_tail, n = rx_head - tail;
    uint32_t to_end = RX_SIZE - tail % RX_SIZE;
    *data = rx_buf + tail % RX_SIZE;
    return n < to_end ? n : to_end;
}

void cm3_rx_consume(size_t n)
{
    rx_tail += (uint32_t)n;
    /* The interrupt stopped reading when the ring was full; it would never
       fire again on its own because the UART still holds an unread byte. */
    if (rx_stalled && n) {
        rx_stalled = 0;
        board_rx_resume();
    }
}

void cm3_rx_lost(void)
{
    rx_lost++;
}

uint32_t cm3_rx_lost_count(void)
{
    return rx_lost;
}

/* ---- the transmit ring ------------------------------------------------- */
#define TX_SIZE CM3_TX_SIZE
typedef char cm3_tx_size_is_a_power_of_two[(TX_SIZE & (TX_SIZE - 1u)) == 0 ? 1 : -1];

static uint8_t tx_buf[TX_SIZE];
static volatile uint32_t tx_head;   /* advanced by the main loop */
static volatile uint32_t tx_tail;   /* advanced by the transmit interrupt */
static uint32_t tx_dropped;

int cm3_tx_write(const uint8_t *data, size_t size)
{
    uint32_t head = tx_head, i;
    if (size > TX_SIZE - (head - tx_tail)) {
        tx_dropped++;
        return 0;
    }
    for (i = 0; i < size; i++) tx_buf[(head + i) % TX_SIZE] = data[i];
    __asm__ volatile("" ::: "memory");
    tx_head = head + (uint32_t)size; /* published after the bytes */
    return 1;
}

int cm3_tx_pop(uint8_t *byte)
{
    uint32_t tail = tx_tail;
    if (tail == tx_head) return 0;
    *byte = tx_buf[tail % TX_SIZE];
    __asm__ volatile("" ::: "memory");
    tx_tail = tail + 1u;
    return 1;
}

int cm3_tx_empty(void)
{
    return tx_tail == tx_head;
}

uint32_t cm3_tx_dropped(void)
{
    return tx_dropped;
}

/* ---- alarms ---------------------------------------------------------------- */
static volatile uint64_t alarm_when[CM3_ALARMS] = {UINT64_MAX, UINT64_MAX};

int cm3_alarm_at(int which, uint64_t when)
{
    uint64_t now;
    alarm_when[which] = UINT64_MAX;
    board_alarm(which, 0);
    if (when == UINT64_MAX) return 1;
    now = cm3_ticks();
    if (when < now + CM3_ALARM_LEAD) return 0;
    alarm_when[which] = when;
    board_alarm(which, when - now);
    return 1;
}

void cm3_alarm(int which)
{
    uint64_t when = alarm_when[which], now = cm3_ticks();
    if (when == UINT64_MAX) return;
    if (now < when) { /* the timer's range ended first */
        board_alarm(which, when - now);
        return;
    }
    alarm_when[which] = UINT64_MAX;
#ifdef CM3_TRACE
    if (which == CM3_ALARM_STEP) board_trace_step(when, now);
#endif
    cm3_alarm_due(which, now - when);
}

/* ---- idle ----------------------------------------------------------------- */
static volatile int woken;

void cm3_wake(void)
{
    woken = 1;
}

void cm3_idle(uint64_t deadline)
{
    uint64_t now = cm3_ticks();
    if (now >= deadline || rx_head != rx_tail) return;
#ifdef CM3_BUSY_WAIT
    /* For QEMU's -icount runs, where a core asleep in WFI sometimes gets its
       timer interrupt a whole period late; time only advances with
       instructions there, so spinning costs nothing real. */
    while (rx_head == rx_tail && cm3_ticks() < deadline) {}
#else
    woken = 0;
    board_wake_at(deadline, now);
    /* With interrupts masked, an interrupt that arrives between the checks
       and WFI stays pending, and a pending interrupt ends WFI: no wake-up is
       lost. The handlers run at cpsie. */
    cm3_interrupts_off();
    if (!woken && rx_head == rx_tail && cm3_ticks() < deadline)
        __asm__ volatile("wfi" ::: "memory");
    cm3_interrupts_on();
#endif
}

/* ---- what the compiler may call ---------------------------------------------
   No C library is linked; gcc emits calls to these for struct copies and
   clears, and adaslice.h's trimmed build and the core use memset, memcpy,
   memmove and memchr. Byte loops: nothing large goes through them. */
void *memcpy(void *restrict to, const void *restrict from, size_t n)
{
    unsigned char *d = to;
    const unsigned char *s = from;
    while (n--) *d++ = *s++;
    return to;
}

void *memmove(void *to, const void *from, size_t n)
{
    unsigned char *d = to;
    const unsigned char *s = from;
    if (d < s) {
        while (n--) *d++ = *s++;
    } else {
        while (n--) d[n] = s[n];
    }
    return to;
}

void *memset(void *to, int c, size_t n)
{
    unsigned char *d = to;
    while (n--) *d++ = (unsigned char)c;
    return to;
}

int memcmp(const void *a, const void *b, size_t n)
{
    const unsigned char *p = a, *q = b;
    for (; n; n--, p++, q++)
        if (*p != *q) return *p < *q ? -1 : 1;
    return 0;
}

void *memchr(const void *s, int c, size_t n)
{
    const unsigned char *p = s;
    for (; n; n--, p++)
        if (*p == (unsigned char)c) return (void *)(uintptr_t)p;
    return NULL;
}
