/* The RAMPS 1.4 / Arduino Mega 2560 board layer (board.h has the pin map).
   Timing is done by the timers' compare units, not by code:
     - Timer5 runs free at 2 MHz (prescaler 8) and is the tick; its overflow
       interrupt counts the upper bits. The core arms each step of its
       queue (board_step_arm): OCR5A with COM5A "set on match", so the STEP
       pin rises in hardware at its tick; the compare interrupt runs
       fw_step_interrupt, which ends the pulse (board_step_pulse) and arms
       the next. A step too close or past to be armed is refused (the core
       stops: STEP_LATE), never sent late.
     - Timer4 runs in step with Timer5 (both started together under GTCCR's
       TSM: datasheet section 19, GTCCR) and switches the UV MOSFET on and off
       with COM4C at an exposure's two ticks, so its end does not wait for
       the main loop.
     - Timer3 (in step too) wakes the idle loop at its deadline.
   One invariant keeps the pins clean under simavr too: a compare unit's
   COM mode always matches its pin's level ("set on match" while low,
   "clear on match" while high, disconnected with PORT equal to the level
   while waiting). simavr 1.6 re-runs the timer setup on every OCR write and
   drives each connected OC pin to the level opposite its mode then; with
   the invariant that is the level the pin already has. A real ATmega2560
   does nothing on those writes, so the same code is right on both.
   Register names and bits are avr-libc's <avr/io.h> for the ATmega2560
   (ATmega2560 datasheet, Atmel 2549: section 17, the 16-bit timers, and
   17.11 their registers TCCRnA/B, OCRnx, TIMSKn, TIFRn, with table 17-3 for
   the non-PWM compare output modes; 22, the USART; 12, reset and the
   watchdog; 8, the EEPROM). File-static state here is the hardware's: one
   UART, one Z axis, one UV output. */
#include "board.h"
#include <avr/eeprom.h>
#include <avr/interrupt.h>
#include <avr/io.h>
#include <avr/sleep.h>
#include <avr/wdt.h>

/* ---- reset ---------------------------------------------------------------
   After a watchdog reset the watchdog stays enabled at its shortest period
   (16 ms) with WDRF set: clear MCUSR and stop it before the C runtime
   clears .bss (which can take longer). .init3 runs after r1 is zeroed. */
static uint8_t reset_cause __attribute__((section(".noinit")));
void ramps_init3(void) __attribute__((naked, used, section(".init3")));
void ramps_init3(void)
{
    GPIOR0 = BOARD_MARK_BOOT;
    reset_cause = MCUSR;
    MCUSR = 0;
    wdt_disable();
}

uint8_t board_reset_cause(void) { return reset_cause; }

/* ---- the tick ----------------------------------------------------------------
   TCNT5 extended to 64 bits by the last reading: a reading below the one
   before is in the next turn of the counter. Readings come at least once a
   turn (the overflow interrupt takes one), so none is ambiguous. This does
   not lean on TOV5 being visible the moment the counter wraps: under
   simavr 1.6 the flag came late now and then, a reading just past the wrap
   came out a turn early, and a step armed from it waited a turn (32 ms). */
static uint64_t last_ticks BOARD_SAFETY;

/* Set by the interrupts that end the loop's sleep (board_idle): its alarm,
   Timer5's overflow (a deadline past the alarm's reach is looked at again
   each turn), and a step that left the queue empty or could not arm the
   next (the loop refills it, or stops). A step taken from a queue that
   holds more does not: the loop sleeps on, and steps cost it no pass. */
static volatile uint8_t wake;

ISR(TIMER5_OVF_vect) { (void)board_ticks(); wake = 1; }

/* the ticks since the last reading, as 16 bits: a reading below the one
   before wraps */
uint64_t board_ticks(void)
{
    uint8_t sreg = SREG;
    uint64_t now;
    cli();
    now = last_ticks + (uint16_t)(TCNT5 - (uint16_t)last_ticks);
    last_ticks = now;
    SREG = sreg;
    return now;
}

/* ---- steps ---------------------------------------------------------------------
   The core's step queue (fw_steps) is the only one: board_step_arm puts the
   next step's tick in OCR5A with COM5A "set on match" (datasheet 17.11,
   TCCR5A; 17.7, the output compare units), so STEP rises in hardware at that
   tick; the compare interrupt (OCF5A in TIFR5) calls
   ramps_step_due, which runs fw_step_interrupt: board_step_pulse ends the
   pulse and the core arms the next step. */
#define STEP_PULSE 4u          /* ticks high at least: 2 us (A4988 needs 1 us, DRV8825 1.9 us) */
#define ARM_LEAD   64u         /* ticks: the least time from arming a compare to its match (32 us: simavr 1.6 mistimed closer ones) */
#define FAR        0xF000u     /* further than this: wait for the next pass of the counter */
#define COM5A_BITS (_BV(COM5A1) | _BV(COM5A0))
#define COM4C_BITS (_BV(COM4C1) | _BV(COM4C0))
enum { IDLE, WAIT, ARMED };

static uint64_t step_when BOARD_SAFETY;
static volatile uint8_t step_state BOARD_SAFETY;
static volatile uint8_t uv_state BOARD_SAFETY, uv_target BOARD_SAFETY;
static void uv_compare(void);

/* Interrupts off. The pin low through its PORT bit (COM5A disconnected:
   table 17-3); PORTL is written so that simavr, which does not
   re-drive a pin the compare unit let go of, sees it low too. */
static void step_pin_low(void)
{
    TCCR5A &= (uint8_t)~COM5A_BITS;
    PORTL &= (uint8_t)~_BV(PL3);
}

/* Interrupts off: the compare for step_when, or a wait while it is more
   than one turn of the 16-bit counter away. 0 if too close. */
static int step_compare(void)
{
    uint64_t now = board_ticks();
    uint64_t ahead = step_when > now ? step_when - now : 0;
    if (ahead < ARM_LEAD) return 0;
    if (ahead >= FAR) {
        step_state = WAIT;
        OCR5A = (uint16_t)(TCNT5 + 0x8000u);
    } else {
        /* set on match, then the compare value (simavr drives the pin
           opposite the mode on the OCR write: low, as it is) */
        TCCR5A |= COM5A_BITS;
        OCR5A = (uint16_t)step_when;
        step_state = ARMED;
    }
    TIFR5 = _BV(OCF5A);
    TIMSK5 |= _BV(OCIE5A);
    return 1;
}

/* M112's latch (emergency(), below): the light stays off until the core
   has read the line and stopped (its disarm here, or its light-off). */
static volatile uint8_t killed BOARD_SAFETY;

int board_step_arm(uint64_t when, int dir)
{
    uint8_t sreg = SREG;
    int ok = 1;
    cli();
    if (when == UINT64_MAX) {
        TIMSK5 &= (uint8_t)~_BV(OCIE5A);
        step_state = IDLE;
        step_pin_low();
        killed = 0; /* the core's stop (M112's, a fault's): the light is its own again */
    } else {
        /* DIR now: the pin is low, the step at least ARM_LEAD away (the
           drivers need 200 ns / 650 ns of DIR before STEP) */
        if (dir > 0) PORTL |= _BV(PL1);
        else PORTL &= (uint8_t)~_BV(PL1);
        step_when = when;
        ok = step_compare();
        if (!ok) {
            GPIOR0 = BOARD_MARK_LATE;
            TIMSK5 &= (uint8_t)~_BV(OCIE5A);
            step_state = IDLE;
        }
    }
    SREG = sreg;
    return ok;
}

/* In the compare interrupt: the pin rose at the match; it falls once it has
   been high STEP_PULSE ticks. */
void board_step_pulse(void)
{
    uint16_t rise = OCR5A;
    while ((uint16_t)(TCNT5 - rise) < STEP_PULSE) {}
    step_pin_low();
    step_state = IDLE;
}

ISR(TIMER5_COMPA_vect)
{
    if (step_state == WAIT) {
        if (!step_compare()) { /* cannot happen: a wait ends FAR - 0x8000 ticks early */
            GPIOR0 = BOARD_MARK_LATE;
            TIMSK5 &= (uint8_t)~_BV(OCIE5A);
            step_state = IDLE;
        }
        return;
    }
    if (step_state != ARMED) return;
    TIMSK5 &= (uint8_t)~_BV(OCIE5A); /* the core arms the next */
    if (ramps_step_due()) wake = 1;
}

int board_endstop(void) { return (PIND & _BV(PD3)) != 0; }

void board_motor(int on)
{
    if (on) PORTK &= (uint8_t)~_BV(PK0);
    else PORTK |= _BV(PK0);
}

/* ---- UV --------------------------------------------------------------------------------
   Timer4's compare unit C switches the D8 MOSFET (PH5, OC4C) at the
   exposure's two ticks: "set on match" for its start, "clear on match" for
   its end (TCCR4A, table 17-3). An exposure whose start has passed
   when it is handed over (the loop gets to it a little after its tick)
   starts ARM_LEAD from now and ends as much later, so the light is on for
   exactly until - when ticks; an early end (pause, M107, a fault) is moved
   by the same shift, so the light given is still what the core counts.
   Between transitions COM4C is disconnected and PORTH5 holds the level.
   simavr 1.6 drives a connected OC pin at every overflow, as if in PWM
   ("clear on match" sets it, "set on match" clears it), which lit the
   panel again between the end's match and its interrupt: the end toggles
   (which the overflow leaves alone), and a start in the last UV_SETTLE
   ticks of Timer4's period moves past the overflow, so its interrupt
   disconnects COM4C before the next one. */
/* The least time from arming a UV transition to it, and from a match to
   arming the next: 128 us (simavr 1.6 lost or advanced compares armed
   closer, by 39 ticks; the part itself needs a few cycles). An exposure
   is at least 1 ms. */
#define UV_SETTLE 256u
static uint64_t uv_on_at BOARD_SAFETY, uv_off_at BOARD_SAFETY, uv_shift BOARD_SAFETY;
static volatile uint8_t uv_level BOARD_SAFETY, uv_want BOARD_SAFETY;

/* The port bit first: while COM4C is connected it does not drive the pin,
   and the moment COM4C lets go the pin takes the port bit, which must
   already be the level (the other order put out a stale one). */
static void uv_hold(void)
{
    if (uv_level) PORTH |= _BV(PH5);
    else PORTH &= (uint8_t)~_BV(PH5);
    TCCR4A &= (uint8_t)~COM4C_BITS;
}

/* Interrupts off: arms the next transition, or switches now if it is due. */
static void uv_arm(void)
{
    for (;;) {
        uint64_t at, now, ahead;
        uint8_t to;
        if (!uv_level && uv_want) { at = uv_on_at; to = 1; }
        else if (uv_level) { at = uv_off_at; to = 0; }
        else {
            uv_state = IDLE;
            TIMSK4 &= (uint8_t)~_BV(OCIE4C);
            uv_hold();
            return;
        }
        now = board_ticks();
        ahead = at > now ? at - now : 0;
        if (ahead < ARM_LEAD) { /* due: switch now */
            uv_level = to;
            if (!to) uv_want = 0;
            uv_hold();
            continue;
        }
        uv_hold();
        if (ahead >= FAR) {
            uv_state = WAIT;
            OCR4C = (uint16_t)(TCNT4 + 0x8000u);
        } else {
            TCCR4A |= to ? COM4C_BITS : _BV(COM4C0);
            OCR4C = (uint16_t)at;
            uv_target = to;
            uv_state = ARMED;
        }
        TIFR4 = _BV(OCF4C);
        TIMSK4 |= _BV(OCIE4C);
        return;
    }
}

ISR(TIMER4_COMPC_vect) { uv_compare(); }

static void uv_compare(void)
{
    if (uv_state == ARMED) { /* the pin switched at the match */
        uv_level = uv_target;
        if (!uv_level) uv_want = 0;
        if (uv_level) {
            /* the next compare a while after this one, COM4C disconnected:
               simavr 1.6 switched the pin at once when the end was armed
               straight from the start's match */
            uv_state = WAIT;
            uv_hold();
            OCR4C = (uint16_t)(OCR4C + UV_SETTLE);
            return;
        }
    }
    uv_arm();
}

void board_uv(int on, uint64_t when, uint64_t until)
{
    uint8_t sreg = SREG;
    cli();
    if (on && killed) {
        /* dark until the core has read the M112 and put the light out itself */
    } else if (on) {
        uint64_t earliest = board_ticks() + UV_SETTLE;
        uint16_t in_period;
        uv_shift = when < earliest ? earliest - when : 0;
        in_period = (uint16_t)(when + uv_shift); /* TCNT4 at the start */
        if (in_period > 0xFFFFu - UV_SETTLE) uv_shift += 0x10000u - in_period;
        uv_on_at = when + uv_shift;
        uv_off_at = until + uv_shift;
        uv_want = 1;
    } else if (!on && killed) {
        killed = 0;
    } else if (uv_want) {
        uint64_t off = when + uv_shift;
        if (!uv_level) uv_want = 0; /* not on yet: it never goes on */
        else if (off < uv_off_at) uv_off_at = off;
    }
    uv_arm();
    SREG = sreg;
}

uint8_t board_uv_lit(void) { return uv_level; }

/* ---- UART0 ------------------------------------------------------------------------------ */
static uint8_t rx_buf[BOARD_RX_SIZE], tx_buf[BOARD_TX_SIZE];
static volatile uint16_t rx_head, rx_tail, tx_head, tx_tail, rx_lost, tx_lost;

/* M112 from G-code puts the light out here, as its last byte arrives, not
   a loop pass later (a pass computing ramp steps at the top speed is about
   a millisecond), and nothing lights until the core has read the line and
   stopped Z itself (its own light-off ends the latch). */
static uint8_t rx_urgent;
static void emergency(void)
{
    killed = 1;
    uv_want = uv_level = 0;
    uv_arm(); /* nothing wanted: the compare let go, the pin held low */
}

ISR(USART0_RX_vect)
{
    uint8_t b = UDR0;
    uint16_t head = rx_head;
    if (ramps_gcode_mode() && fw_urgent_byte(&rx_urgent, b) == 112) emergency();
    if ((uint16_t)(head - rx_tail) == BOARD_RX_SIZE) { rx_lost++; return; }
    rx_buf[head % BOARD_RX_SIZE] = b;
    rx_head = (uint16_t)(head + 1u);
}

ISR(USART0_UDRE_vect)
{
    uint16_t tail = tx_tail;
    if (tail == tx_head) { UCSR0B &= (uint8_t)~_BV(UDRIE0); return; }
    UDR0 = tx_buf[tail % BOARD_TX_SIZE];
    tx_tail = (uint16_t)(tail + 1u);
}

size_t board_rx_peek(const uint8_t **data)
{
    uint16_t head, tail = rx_tail, to_end = (uint16_t)(BOARD_RX_SIZE - tail % BOARD_RX_SIZE), n;
    cli();
    head = rx_head;
    sei();
    n = (uint16_t)(head - tail);
    *data = rx_buf + tail % BOARD_RX_SIZE;
    return n < to_end ? n : to_end;
}

void board_rx_consume(size_t n)
{
    cli();
    rx_tail = (uint16_t)(rx_tail + n);
    sei();
}

/* The room is read once: the interrupt only makes more. What does not fit
   is counted and dropped. */
void board_write(const uint8_t *data, size_t size)
{
    uint16_t head = tx_head, room, i;
    cli();
    room = (uint16_t)(BOARD_TX_SIZE - (uint16_t)(head - tx_tail));
    sei();
    if (size > room) {
        tx_lost = (uint16_t)(tx_lost + (size - room));
        size = room;
    }
    for (i = 0; i < size; i++) tx_buf[(uint16_t)(head + i) % BOARD_TX_SIZE] = data[i];
    cli();
    tx_head = (uint16_t)(head + size);
    if (size) UCSR0B |= _BV(UDRIE0);
    sei();
}

uint16_t board_rx_lost(void) { uint16_t n; cli(); n = rx_lost; sei(); return n; }
uint16_t board_tx_lost(void) { uint16_t n; cli(); n = tx_lost; sei(); return n; }

/* ---- the stack's canary ----------------------------------------------------------------
   The stack grows down from RAMEND towards the end of .bss and .noinit;
   stack.ld puts the canary at the first byte past them (__stack_canary)
   and has the link fail unless __stack_reserve bytes fit above it. A stack
   that outgrows all the room there is writes over the canary before any
   variable; the loop checks it every pass (fw_stack_fault). */
extern uint16_t __stack_canary;
#define CANARY 0xC0DEu /* not the paint avr-run fills SRAM with, nor zeros */

int board_stack_ok(void) { return *(volatile uint16_t *)&__stack_canary == CANARY; }

#ifdef RAMPS_TEST_OVERRUN
/* Test builds only: every byte from the stack pointer down to the canary
   written, as frames that went that deep would (SP is the next free byte,
   so nothing in use is touched; no variable lies above the canary). */
void board_test_overrun(void)
{
    volatile uint8_t *p = (volatile uint8_t *)SP;
    while (p >= (volatile uint8_t *)&__stack_canary) *p-- = 0;
}
#endif

/* ---- idle, watchdog, EEPROM ------------------------------------------------------------------ */
/* The wake-up alarm is Timer3's compare A (Timer3 runs with 4 and 5): an
   OCR write on Timer5 itself made simavr miss the step compare's match. */
ISR(TIMER3_COMPA_vect) { TIMSK3 &= (uint8_t)~_BV(OCIE3A); wake = 1; }

void board_idle(uint64_t deadline)
{
    uint64_t now;
    cli();
    now = board_ticks();
    /* a deadline closer than ARM_LEAD is not slept for: the alarm's compare
       could be written after the counter passed it, and the loop would
       sleep on to the overflow while a step's interrupt does not wake it */
    if (rx_head != rx_tail || now + ARM_LEAD >= deadline) { sei(); return; }
    if (deadline - now < FAR) {
        OCR3A = (uint16_t)deadline;
        TIFR3 = _BV(OCF3A);
        TIMSK3 |= _BV(OCIE3A);
    }
    GPIOR0 = BOARD_MARK_IDLE;
    /* sei's next instruction runs before any interrupt: none is missed
       between the checks and sleep; the overflow wakes it within 33 ms.
       An interrupt that does not end the wait (a step, a byte sent) sleeps
       again. */
    wake = 0;
    sleep_enable();
    while (!wake && rx_head == rx_tail) {
        sei();
        sleep_cpu();
        __asm__ __volatile__("nop");
        __asm__ __volatile__("nop");
        cli();
    }
    sei();
    sleep_disable();
}

void board_watchdog(void) { wdt_reset(); }

static uint32_t boots;
uint32_t board_boot_count(void) { return boots; }

static uint32_t rows_counted;
static uint8_t shown;
void board_mask_row(void) { rows_counted++; }
void board_show(int slot)
{
    shown = (uint8_t)(slot + 1);
    GPIOR1 = shown;
}

#if BOARD_WDT_MS == 120u
#define WDT_PERIOD WDTO_120MS
#elif BOARD_WDT_MS == 250u
#define WDT_PERIOD WDTO_250MS
#else
#error "BOARD_WDT_MS: 120 or 250"
#endif

void board_init(void)
{
    uint32_t *const counter = (uint32_t *)0;
    uint32_t was;
    *(volatile uint16_t *)&__stack_canary = CANARY;
    /* pins: STEP and DIR low, the driver off, UV off, the endstop pulled up */
    PORTL &= (uint8_t)~(_BV(PL3) | _BV(PL1));
    DDRL |= _BV(PL3) | _BV(PL1);
    PORTK |= _BV(PK0);
    DDRK |= _BV(PK0);
    PORTH &= (uint8_t)~_BV(PH5);
    DDRH |= _BV(PH5);
    DDRD &= (uint8_t)~_BV(PD3);
    PORTD |= _BV(PD3);
    /* Timers 3, 4 and 5 at clk/8, started together */
    GTCCR = _BV(TSM) | _BV(PSRSYNC);
    TCCR5A = 0;
    TCCR5B = _BV(CS51);
    TCCR4A = 0;
    TCCR4B = _BV(CS41);
    TCCR3A = 0;
    TCCR3B = _BV(CS31);
    TCNT5 = 0;
    TCNT4 = 0;
    TCNT3 = 0;
    GTCCR = 0;
    TIMSK5 = _BV(TOIE5);
    /* UART0: 8N1, double speed */
    UBRR0 = (uint16_t)(BOARD_CPU_HZ / 8u / BOARD_BAUD - 1u);
    UCSR0A = _BV(U2X0);
    UCSR0C = _BV(UCSZ01) | _BV(UCSZ00);
    UCSR0B = _BV(RXCIE0) | _BV(RXEN0) | _BV(TXEN0);
    /* the boot counter: an erased EEPROM reads all ones */
    was = eeprom_read_dword(counter);
    boots = (was == 0xFFFFFFFFu ? 0u : was) + 1u;
    eeprom_update_dword(counter, boots);
    set_sleep_mode(SLEEP_MODE_IDLE);
    wdt_enable(WDT_PERIOD);
    sei();
}
