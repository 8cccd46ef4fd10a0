/* The STM32F103C8's hardware layer: clocks, USART1, the wake-up timer, the
   printer's pins and the vector table. Register addresses and bit positions
   are from ST's reference manual RM0008 (its RCC, embedded flash, GPIO,
   general-purpose timer, USART and interrupt vector chapters) and, for the
   flash wait states, PM0075; see board.h for the pins. */
#include "../cm3/cm3.h"
#include "board.h"

#define RCC_CR      CM3_REG(0x40021000u)
#define RCC_CFGR    CM3_REG(0x40021004u)
#define RCC_APB2ENR CM3_REG(0x40021018u)
#define RCC_APB1ENR CM3_REG(0x4002101Cu)
#define RCC_CR_HSEON  (1u << 16)
#define RCC_CR_HSERDY (1u << 17)
#define RCC_CR_PLLON  (1u << 24)
#define RCC_CR_PLLRDY (1u << 25)
#define RCC_CFGR_SW_PLL    2u
#define RCC_CFGR_SWS_MASK  (3u << 2)
#define RCC_CFGR_SWS_PLL   (2u << 2)
#define RCC_CFGR_PPRE1_DIV2 (4u << 8)
#define RCC_CFGR_ADCPRE_DIV6 (2u << 14)
#define RCC_CFGR_PLLSRC_HSE (1u << 16)
#define RCC_CFGR_PLLMUL9   (7u << 18)
#define RCC_APB2ENR_IOPA   (1u << 2)
#define RCC_APB2ENR_IOPB   (1u << 3)
#define RCC_APB2ENR_IOPC   (1u << 4)
#define RCC_APB2ENR_USART1 (1u << 14)
#define RCC_APB1ENR_TIM2   (1u << 0)
#define RCC_APB1ENR_TIM3   (1u << 1)
#define RCC_APB1ENR_TIM4   (1u << 2)

#define FLASH_ACR CM3_REG(0x40022000u)
#define FLASH_ACR_LATENCY2 2u        /* 48 MHz < SYSCLK <= 72 MHz */
#define FLASH_ACR_PRFTBE   (1u << 4)

#define GPIOA 0x40010800u
#define GPIOB 0x40010C00u
#define GPIOC 0x40011000u
#define GPIO_CRL(port)  CM3_REG((port) + 0x00u)
#define GPIO_CRH(port)  CM3_REG((port) + 0x04u)
#define GPIO_IDR(port)  CM3_REG((port) + 0x08u)
#define GPIO_BSRR(port) CM3_REG((port) + 0x10u)
/* A pin's 4-bit CNF:MODE field */
#define PIN_OUT_10MHZ  0x1u  /* push-pull output, 10 MHz */
#define PIN_OUT_2MHZ   0x2u  /* push-pull output, 2 MHz */
#define PIN_AF_50MHZ   0xBu  /* alternate function push-pull, 50 MHz */
#define PIN_IN_PULL    0x8u  /* input with pull-up/down (ODR picks up) */

#define PIN_STEP    12u /* port B */
#define PIN_DIR     13u
#define PIN_ENABLE  14u
#define PIN_UV      15u
#define PIN_ENDSTOP 11u
#define PIN_LED     13u /* port C */
#define PIN_TX       9u /* port A */
#define PIN_RX      10u

#define USART1_SR  CM3_REG(0x40013800u)
#define USART1_DR  CM3_REG(0x40013804u)
#define USART1_BRR CM3_REG(0x40013808u)
#define USART1_CR1 CM3_REG(0x4001380Cu)
#define USART_SR_ORE  (1u << 3)
#define USART_SR_RXNE (1u << 5)
#define USART_SR_TXE  (1u << 7)
#define USART_CR1_RE     (1u << 2)
#define USART_CR1_TE     (1u << 3)
#define USART_CR1_RXNEIE (1u << 5)
#define USART_CR1_UE     (1u << 13)
#define USART1_IRQ 37u

#define TIM2_CR1  CM3_REG(0x40000000u)
#define TIM2_DIER CM3_REG(0x4000000Cu)
#define TIM2_SR   CM3_REG(0x40000010u)
#define TIM2_EGR  CM3_REG(0x40000014u)
#define TIM2_PSC  CM3_REG(0x40000028u)
#define TIM2_ARR  CM3_REG(0x4000002Cu)
#define TIM_CR1_CEN (1u << 0)
#define TIM_CR1_URS (1u << 2)
#define TIM_CR1_OPM (1u << 3)
#define TIM2_IRQ 28u
/* TIM3 (steps) and TIM4 (the UV light): the same registers at their bases */
#define TIM3 0x40000400u
#define TIM4 0x40000800u
#define TIM_CR1(t)  CM3_REG((t) + 0x00u)
#define TIM_DIER(t) CM3_REG((t) + 0x0Cu)
#define TIM_SR(t)   CM3_REG((t) + 0x10u)
#define TIM_EGR(t)  CM3_REG((t) + 0x14u)
#define TIM_PSC(t)  CM3_REG((t) + 0x28u)
#define TIM_ARR(t)  CM3_REG((t) + 0x2Cu)
#define TIM3_IRQ 29u
#define TIM4_IRQ 30u

#ifndef BAUD
#define BAUD 115200u
#endif

static void pin_set(uint32_t port, unsigned pin) { GPIO_BSRR(port) = 1u << pin; }
static void pin_clear(uint32_t port, unsigned pin) { GPIO_BSRR(port) = 1u << (pin + 16u); }

static void pin_mode(uint32_t port, unsigned pin, uint32_t mode)
{
    volatile uint32_t *cr = pin < 8u ? &GPIO_CRL(port) : &GPIO_CRH(port);
    unsigned shift = (pin % 8u) * 4u;
    *cr = (*cr & ~(0xFu << shift)) | mode << shift;
}

/* SysTick counts the core clock: a busy wait of a few microseconds. */
static void delay_ticks(uint32_t n)
{
    uint32_t start = SYST_CVR;
    while (((start - SYST_CVR) & 0xFFFFFFu) < n) {}
}

/* ---- clock ---------------------------------------------------------------------
   8 MHz crystal -> PLL x9 -> 72 MHz SYSCLK and AHB; APB1 must stay at or
   under 36 MHz (/2), APB2 at 72; flash needs two wait states above 48 MHz. */
static int clock_init(void)
{
    uint32_t i;
    RCC_CR |= RCC_CR_HSEON;
    for (i = 0; !(RCC_CR & RCC_CR_HSERDY); i++)
        if (i > 1000000u) return 0; /* no crystal: stay on the 8 MHz HSI */
    FLASH_ACR = FLASH_ACR_PRFTBE | FLASH_ACR_LATENCY2;
    RCC_CFGR = RCC_CFGR_PLLSRC_HSE | RCC_CFGR_PLLMUL9 | RCC_CFGR_PPRE1_DIV2 | RCC_CFGR_ADCPRE_DIV6;
    RCC_CR |= RCC_CR_PLLON;
    while (!(RCC_CR & RCC_CR_PLLRDY)) {}
    RCC_CFGR |= RCC_CFGR_SW_PLL;
    while ((RCC_CFGR & RCC_CFGR_SWS_MASK) != RCC_CFGR_SWS_PLL) {}
    return 1;
}

/* ---- the printer's pins ----------------------------------------------------------- */
static int last_dir;

void board_step(int dir)
{
    if (dir != last_dir) {
        if (dir > 0) pin_set(GPIOB, PIN_DIR);
        else pin_clear(GPIOB, PIN_DIR);
        last_dir = dir;
        delay_ticks(BOARD_CLOCK_HZ / 1000000u); /* direction setup: 1 us */
    }
    /* 2 us high covers the slowest common driver (DRV8825: 1.9 us); steps
       come from the step alarm, never closer than the speed limit allows,
       so the low time is always long */
    pin_set(GPIOB, PIN_STEP);
    delay_ticks(2u * (BOARD_CLOCK_HZ / 1000000u));
    pin_clear(GPIOB, PIN_STEP);
}

int board_endstop(void)
{
    return !(GPIO_IDR(GPIOB) & (1u << PIN_ENDSTOP));
}

void board_uv(int on)
{
    if (on) pin_set(GPIOB, PIN_UV);
    else pin_clear(GPIOB, PIN_UV);
}

void board_motor(int on)
{
    if (on) pin_clear(GPIOB, PIN_ENABLE);
    else pin_set(GPIOB, PIN_ENABLE);
}

static void pins_init(void)
{
    RCC_APB2ENR |= RCC_APB2ENR_IOPA | RCC_APB2ENR_IOPB | RCC_APB2ENR_IOPC | RCC_APB2ENR_USART1;
    /* levels first, so each output comes up safe: light off, driver off */
    pin_clear(GPIOB, PIN_UV);
    pin_set(GPIOB, PIN_ENABLE);
    pin_clear(GPIOB, PIN_STEP);
    pin_clear(GPIOB, PIN_DIR);
    pin_set(GPIOB, PIN_ENDSTOP); /* ODR high: pull-up */
    pin_set(GPIOC, PIN_LED);     /* LED off */
    pin_mode(GPIOB, PIN_UV, PIN_OUT_2MHZ);
    pin_mode(GPIOB, PIN_ENABLE, PIN_OUT_2MHZ);
    pin_mode(GPIOB, PIN_STEP, PIN_OUT_10MHZ);
    pin_mode(GPIOB, PIN_DIR, PIN_OUT_10MHZ);
    pin_mode(GPIOB, PIN_ENDSTOP, PIN_IN_PULL);
    pin_mode(GPIOC, PIN_LED, PIN_OUT_2MHZ);
    pin_set(GPIOA, PIN_RX);
    pin_mode(GPIOA, PIN_TX, PIN_AF_50MHZ);
    pin_mode(GPIOA, PIN_RX, PIN_IN_PULL);
}

/* ---- USART1 ------------------------------------------------------------------------ */
void usart1_handler(void);
void usart1_handler(void)
{
    for (;;) {
        uint32_t sr = USART1_SR;
        if (!(sr & (USART_SR_RXNE | USART_SR_ORE))) return;
        if (cm3_rx_full()) {
            /* unlike QEMU's, this UART cannot hold the line: the byte in DR
               waits, the next ones overrun. The window keeps this from
               happening (the ring holds window full frames). */
            USART1_CR1 &= ~USART_CR1_RXNEIE;
            cm3_rx_stall();
            return;
        }
        /* a byte came while the last was unread: it is gone (the protocol's
           CRC and go-back-N recover it); counted for diagnosis */
        if (sr & USART_SR_ORE) cm3_rx_lost();
        cm3_rx_push((uint8_t)USART1_DR); /* reading SR then DR clears RXNE and ORE */
    }
}

void board_rx_resume(void)
{
    /* RXNE is a level: enabling its interrupt again takes the waiting byte */
    USART1_CR1 |= USART_CR1_RXNEIE;
}

void board_write(const uint8_t *data, size_t size)
{
    size_t i;
    for (i = 0; i < size; i++) {
        while (!(USART1_SR & USART_SR_TXE)) {}
        USART1_DR = data[i];
    }
}

static void usart_init(uint32_t pclk2)
{
    /* BRR holds pclk / baud in sixteenths of the 16x oversampled bit */
    USART1_BRR = (pclk2 + BAUD / 2u) / BAUD;
    USART1_CR1 = USART_CR1_UE | USART_CR1_TE | USART_CR1_RE | USART_CR1_RXNEIE;
    cm3_irq_enable(USART1_IRQ);
}

/* ---- the wake-up alarm ---------------------------------------------------------------
   TIM2 counts microseconds (72 MHz timer clock / 72) in one-pulse mode and
   interrupts once at the end. It only wakes the loop, which reads the
   absolute tick, so an alarm a microsecond early just costs one more pass;
   a delay past its 16 bits (65 ms) wakes early and is armed again. */
void tim2_handler(void);
void tim2_handler(void)
{
    TIM2_SR = 0;
    cm3_wake();
}

void board_wake_at(uint64_t deadline, uint64_t now)
{
    uint64_t ticks_per_us = BOARD_CLOCK_HZ / 1000000u;
    uint64_t us = (deadline - now + ticks_per_us - 1u) / ticks_per_us;
    TIM2_CR1 = TIM_CR1_URS | TIM_CR1_OPM;
    if (deadline == UINT64_MAX) return; /* FW_NEVER: only a byte can wake us */
    if (us > 0x10000u) us = 0x10000u;
    if (us < 1u) us = 1u;
    TIM2_ARR = (uint32_t)(us - 1u); /* the update comes after ARR + 1 counts */
    TIM2_EGR = 1u;                  /* UG: counter and prescaler from zero (URS: no interrupt) */
    TIM2_SR = 0;
    TIM2_CR1 = TIM_CR1_URS | TIM_CR1_OPM | TIM_CR1_CEN;
}

/* ---- the alarms ------------------------------------------------------------------------
   TIM3 (steps) and TIM4 (the UV light's end) count the 72 MHz timer clock
   itself, in one-pulse mode: a delay past their 16 bits (910 us) interrupts
   early and cm3_alarm arms the rest. */
static uint32_t alarm_timer(int which) { return which == CM3_ALARM_STEP ? TIM3 : TIM4; }

void tim3_handler(void);
void tim3_handler(void)
{
    TIM_SR(TIM3) = 0;
    cm3_alarm(CM3_ALARM_STEP);
}

void tim4_handler(void);
void tim4_handler(void)
{
    TIM_SR(TIM4) = 0;
    cm3_alarm(CM3_ALARM_UV);
}

void board_alarm(int which, uint64_t delay)
{
    uint32_t t = alarm_timer(which);
    TIM_CR1(t) = TIM_CR1_URS | TIM_CR1_OPM;
    if (!delay) return;
    if (delay > 0x10000u) delay = 0x10000u;
    TIM_ARR(t) = (uint32_t)(delay - 1u);
    TIM_EGR(t) = 1u;
    TIM_SR(t) = 0;
    TIM_CR1(t) = TIM_CR1_URS | TIM_CR1_OPM | TIM_CR1_CEN;
}

static void alarm_init(uint32_t t, unsigned irq)
{
    TIM_PSC(t) = 0;
    TIM_CR1(t) = TIM_CR1_URS | TIM_CR1_OPM;
    TIM_EGR(t) = 1u;
    TIM_SR(t) = 0;
    TIM_DIER(t) = 1u;
    cm3_irq_enable(irq);
}

static void timer_init(void)
{
    RCC_APB1ENR |= RCC_APB1ENR_TIM3 | RCC_APB1ENR_TIM4;
    alarm_init(TIM3, TIM3_IRQ);
    alarm_init(TIM4, TIM4_IRQ);
    RCC_APB1ENR |= RCC_APB1ENR_TIM2;
    TIM2_PSC = BOARD_CLOCK_HZ / 1000000u - 1u;
    TIM2_CR1 = TIM_CR1_URS | TIM_CR1_OPM;
    TIM2_EGR = 1u; /* loads the prescaler */
    TIM2_SR = 0;
    TIM2_DIER = 1u; /* update interrupt */
    cm3_irq_enable(TIM2_IRQ);
}

/* ---- start and stop ---------------------------------------------------------------------- */
void board_init(void)
{
    int crystal = clock_init();
    pins_init();
    if (!crystal) board_fault(CM3_FAULT_CLOCK); /* every tick and baud rate would be wrong */
    usart_init(BOARD_CLOCK_HZ);
    timer_init();
    cm3_tick_start();
}

void board_exit(int code)
{
    (void)code;
    board_uv(0);
    board_motor(0);
    SCB_AIRCR = SCB_AIRCR_SYSRESETREQ;
    for (;;) {}
}

void board_fault(int why)
{
    /* Stop dead, light off, driver off, LED on, until the reset button: a
       printer that restarted itself mid-print could expose the wrong layer. */
    cm3_interrupts_off();
    board_uv(0);
    board_motor(0);
    pin_clear(GPIOC, PIN_LED);
    (void)why;
    for (;;) {}
}

/* ---- the display --------------------------------------------------------------
   A resin printer's LCD is fed by its own controller (an FPGA or a bridge chip
   on the mainboard), and the bus to it differs from board to board. The core
   checks each mask's CRC-32 as it decodes and hands rows and "show" here,
   which count them until a driver for a particular display goes here. */
static uint32_t mask_rows, masks_shown;

void board_mask_row(int slot, uint32_t y, const uint8_t *row, uint32_t size)
{
    (void)slot;
    (void)y;
    (void)row;
    (void)size;
    mask_rows++;
}

void board_show(int slot) { if (slot >= 0) masks_shown++; }

/* ---- the interrupt vectors ---------------------------------------------------------------- */
#define F cm3_fault_handler
CM3_IRQ_VECTORS irq_vectors[60] = { /* RM0008 table 63: positions 0-59 */
    F, F, F, F, F, F, F, F, F, F,  F, F, F, F, F, F, F, F, F, F,
    F, F, F, F, F, F, F, F, tim2_handler, tim3_handler, tim4_handler, F, F, F, F, F, F, usart1_handler, F, F,
    F, F, F, F, F, F, F, F, F, F,  F, F, F, F, F, F, F, F, F, F
};
#undef F
