/* A serial line or pseudo-terminal in raw mode: the POSIX end of the link,
   shared by adaslice print, the firmware simulator and the test relay
   (termios only; never part of an MCU image). */
#ifndef LINK_TTY_H
#define LINK_TTY_H
/* Raw bytes both ways, 8N1: no echo, no line editing, no CR/LF translation,
   no parity check, no XON/XOFF, modem lines ignored; reads return what has
   arrived. The modem lines stay up when the port is closed (no HUPCL): a
   board whose USB bridge resets it on DTR (an Arduino's) sees no edge when
   a host opens the port again, so a crashed host's resume finds the print
   as it was. baud: a standard rate, or 0 to leave the speed. 0 on success,
   -1 with errno set. */
int tty_raw(int fd, long baud);
/* 1 if baud is a rate tty_raw takes (9600 ... 230400). */
int tty_baud_ok(long baud);
#endif
