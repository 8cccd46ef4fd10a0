/* Raw serial lines: see tty.h. */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif
#include "tty.h"
#include <errno.h>
#include <termios.h>

static const struct { long baud; speed_t code; } BAUDS[] = {
    {9600, B9600}, {19200, B19200}, {38400, B38400}, {57600, B57600}, {115200, B115200}, {230400, B230400}};
enum { BAUD_COUNT = sizeof BAUDS / sizeof *BAUDS };

static int baud_index(long baud)
{
    int i;
    for (i = 0; i < BAUD_COUNT; i++) if (BAUDS[i].baud == baud) return i;
    return -1;
}

int tty_baud_ok(long baud) { return baud_index(baud) >= 0; }

int tty_raw(int fd, long baud)
{
    struct termios t;
    int b = baud_index(baud);
    if (baud && b < 0) { errno = EINVAL; return -1; }
    if (tcgetattr(fd, &t) != 0) return -1;
    t.c_iflag &= ~(tcflag_t)(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL | IXON | IXOFF | IXANY | INPCK);
    t.c_oflag &= ~(tcflag_t)OPOST;
    t.c_lflag &= ~(tcflag_t)(ECHO | ECHONL | ICANON | ISIG | IEXTEN);
    t.c_cflag &= ~(tcflag_t)(CSIZE | PARENB | CSTOPB | HUPCL);
    t.c_cflag |= CS8 | CREAD | CLOCAL;
    t.c_cc[VMIN] = 0;
    t.c_cc[VTIME] = 0;
    if (baud && (cfsetispeed(&t, BAUDS[b].code) != 0 || cfsetospeed(&t, BAUDS[b].code) != 0)) return -1;
    return tcsetattr(fd, TCSANOW, &t);
}
