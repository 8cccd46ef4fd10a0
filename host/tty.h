/* A serial line or pseudo-terminal in raw mode, shared by adaslice print, the
   firmware simulator and the test relay (POSIX termios only). */
#ifndef ADASLICE_HOST_TTY_H
#define ADASLICE_HOST_TTY_H
/* Raw bytes both ways, 8N1: no echo, no line editing, no CR/LF translation,
   no parity check, no XON/XOFF, modem lines ignored; reads return what has
   arrived. baud: a standard rate, or 0 to leave the speed. 0 on success,
   -1 with errno set. */
int tty_raw(int fd, long baud);
/* 1 if baud is a rate tty_raw takes (9600 ... 230400). */
int tty_baud_ok(long baud);
#endif
