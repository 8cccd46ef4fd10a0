/* A faulty serial line for tests: relays bytes between a pseudo-terminal it
   makes (the host's side) and the MCU's pty, dropping and corrupting bytes at
   random in both directions and, optionally, cutting the line for a while.

   usage: relay MCU_PTY [--drop P] [--corrupt P] [--seed N]
                [--outage-after BYTES --outage-for SECONDS [--outage-way up|down]]
                [--stats FILE]
   Prints "pty /dev/pts/N" for the host, then relays until SIGTERM, when it
   writes what it did to --stats: bytes each way, dropped, corrupted, and the
   outage's start and end (seconds since start). The outage begins once BYTES
   have gone from the host to the MCU, and cuts both ways, or only the way
   --outage-way names (up: host to MCU; down: MCU to host, a host that hears
   nothing while the MCU hears it). */
#define _XOPEN_SOURCE 600
#include "../link/tty.h"
#include <errno.h>
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

static volatile sig_atomic_t stop;
static void on_term(int sig) { (void)sig; stop = 1; }

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + ts.tv_nsec / 1e9;
}

static unsigned long long rng_state = 88172645463325252ull;
static double uniform(void)
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (rng_state >> 11) * (1.0 / 9007199254740992.0);
}

typedef struct direction { unsigned long bytes, dropped, corrupted; } direction;

static void put_all(int fd, const unsigned char *b, size_t n)
{
    while (n) {
        ssize_t w = write(fd, b, n);
        if (w > 0) { b += w; n -= (size_t)w; continue; }
        if (w < 0 && errno != EAGAIN && errno != EINTR) return;
        {
            struct pollfd p = {fd, POLLOUT, 0};
            (void)poll(&p, 1, 50);
        }
    }
}

/* Moves what `from` has to `to`, damaged as asked. */
static void pass(int from, int to, direction *d, double drop, double corrupt, int cut)
{
    unsigned char buf[4096], out[4096];
    ssize_t n = read(from, buf, sizeof buf), i;
    size_t m = 0;
    for (i = 0; i < n; i++) {
        double u = uniform();
        d->bytes++;
        if (cut || u < drop) { d->dropped++; continue; }
        if (u < drop + corrupt) { buf[i] ^= (unsigned char)(1u << (unsigned)(uniform() * 8)); d->corrupted++; }
        out[m++] = buf[i];
    }
    if (m) put_all(to, out, m);
}

int main(int argc, char **argv)
{
    double drop = 0, corrupt = 0, outage_for = 0, started = now_s(), cut_start = -1, cut_end = -1;
    unsigned long outage_after = 0;
    int cut_up = 1, cut_down = 1;
    const char *stats = NULL;
    int mcu, master, slave, i;
    direction up = {0, 0, 0}, down = {0, 0, 0};
    struct sigaction sa;
    if (argc < 2) { fprintf(stderr, "usage: relay MCU_PTY [options]\n"); return 2; }
    for (i = 2; i + 1 < argc; i += 2) {
        if (!strcmp(argv[i], "--drop")) drop = atof(argv[i + 1]);
        else if (!strcmp(argv[i], "--corrupt")) corrupt = atof(argv[i + 1]);
        else if (!strcmp(argv[i], "--seed")) rng_state = strtoull(argv[i + 1], NULL, 10) * 2654435761u + 1;
        else if (!strcmp(argv[i], "--outage-after")) outage_after = strtoul(argv[i + 1], NULL, 10);
        else if (!strcmp(argv[i], "--outage-for")) outage_for = atof(argv[i + 1]);
        else if (!strcmp(argv[i], "--outage-way")) { cut_up = strcmp(argv[i + 1], "down") != 0; cut_down = strcmp(argv[i + 1], "up") != 0; }
        else if (!strcmp(argv[i], "--stats")) stats = argv[i + 1];
        else { fprintf(stderr, "relay: unknown option %s\n", argv[i]); return 2; }
    }
    mcu = open(argv[1], O_RDWR | O_NOCTTY | O_NONBLOCK);
    master = posix_openpt(O_RDWR | O_NOCTTY);
    if (mcu < 0 || master < 0 || grantpt(master) || unlockpt(master) || tty_raw(mcu, 0)) {
        fprintf(stderr, "relay: cannot open %s or a pty: %s\n", argv[1], strerror(errno));
        return 1;
    }
    /* keep the host's side open ourselves so its hang-ups do not end the relay */
    slave = open(ptsname(master), O_RDWR | O_NOCTTY);
    if (slave < 0 || tty_raw(slave, 0)) { fprintf(stderr, "relay: cannot open %s\n", ptsname(master)); return 1; }
    fcntl(master, F_SETFL, O_NONBLOCK);
    printf("pty %s\n", ptsname(master));
    fflush(stdout);
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_term;
    sigaction(SIGTERM, &sa, NULL);
    sigaction(SIGINT, &sa, NULL);
    while (!stop) {
        struct pollfd p[2] = {{master, POLLIN, 0}, {mcu, POLLIN, 0}};
        double t = now_s() - started;
        int cut;
        if (outage_for > 0 && cut_start < 0 && up.bytes >= outage_after && outage_after) { cut_start = t; cut_end = t + outage_for; }
        cut = cut_start >= 0 && t < cut_end;
        if (poll(p, 2, 20) < 0) continue;
        if (p[0].revents & POLLIN) pass(master, mcu, &up, drop, corrupt, cut && cut_up);
        if (p[1].revents & POLLIN) pass(mcu, master, &down, drop, corrupt, cut && cut_down);
        if ((p[0].revents | p[1].revents) & (POLLHUP | POLLERR)) (void)poll(NULL, 0, 10);
    }
    if (stats) {
        FILE *f = fopen(stats, "w");
        if (f) {
            fprintf(f, "up %lu %lu %lu\ndown %lu %lu %lu\noutage %.3f %.3f\n", up.bytes, up.dropped, up.corrupted, down.bytes,
                    down.dropped, down.corrupted, cut_start, cut_end);
            fclose(f);
        }
    }
    close(slave);
    return 0;
}
