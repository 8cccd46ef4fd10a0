/* adaslice - the command-line tool over adaslice.h: the command table.

   adaslice COMMAND [options]; adaslice COMMAND --help (or adaslice help COMMAND)
   lists a command's options.

   Exit status (report.h's RC_*): 0 done; 1 the work failed (a file that cannot
   be read or written, a malformed mesh, constraints that no plan meets, a print
   the printer stopped); 2 the command line is wrong; 3 a print paused; 4 the
   printer restarted mid-print (Z must be homed again); 5 the printer stopped
   answering; 128 + the signal when SIGINT (130), SIGTERM (143) or SIGHUP (129)
   interrupted plan, slice, orient or saliency, which then leave nothing they
   wrote (output.h). Every message is one line on stderr that starts with
   "adaslice: ". */
#include "../adaslice.h"
#include "commands.h"
#include "output.h"
#include "report.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>

typedef struct command {
    const char *name, *summary;
    int (*run)(int argc, char **argv); /* argv[0] is the command's name */
} command;

static const command COMMANDS[] = {
    {"plan", "plan adaptive layers for a mesh or a metric profile", cmd_plan},
    {"slice", "plan a model and write its layer masks as a printable job", cmd_slice},
    {"orient", "search the build directions for the fewest layers and least error", cmd_orient},
    {"saliency", "per-face weights from mesh saliency, and the mesh coloured by them", cmd_saliency},
    {"print", "print a model or a job on a printer running the adaslice firmware", cmd_print},
    {"printers", "the printer presets, and which take each layer's own Z (adaptive layers)", cmd_printers},
    {"contour", "PrusaSlicer's G-code with the top surface's paths moved onto the mesh in Z", cmd_contour},
    {"show", "a job's layer or a test pattern on a DIY printer's screen (a framebuffer)", cmd_show},
};
enum { COMMAND_COUNT = sizeof COMMANDS / sizeof *COMMANDS };

static void usage(FILE *f)
{
    int i;
    fputs("usage: adaslice COMMAND [options]\n"
          "       adaslice help [COMMAND] | --help | --version\n"
          "\n"
          "commands:\n", f);
    for (i = 0; i < COMMAND_COUNT; i++) fprintf(f, "  %-10s %s\n", COMMANDS[i].name, COMMANDS[i].summary);
    fputs("\n'adaslice help COMMAND' or 'adaslice COMMAND --help' lists the command's options.\n", f);
}

/* The command called `name`, or NULL after saying it is unknown. */
static const command *find_command(const char *name)
{
    int i;
    for (i = 0; i < COMMAND_COUNT; i++)
        if (!strcmp(name, COMMANDS[i].name)) return &COMMANDS[i];
    complain(RC_USAGE, "unknown %s %s (see adaslice --help)", name[0] == '-' ? "option" : "command", name);
    return NULL;
}

int main(int argc, char **argv)
{
    const command *c;
    int rc;
    if (argc < 2) {
        usage(stderr);
        return RC_USAGE;
    }
    if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || (!strcmp(argv[1], "help") && argc == 2)) {
        usage(stdout);
        rc = RC_OK;
    } else if (!strcmp(argv[1], "help")) { /* help COMMAND: what COMMAND --help says */
        char *help[3];
        if (argc > 3) return complain(RC_USAGE, "help %s %s: help takes one COMMAND", argv[2], argv[3]);
        if (!(c = find_command(argv[2]))) return RC_USAGE;
        help[0] = argv[2];
        help[1] = (char *)"--help";
        help[2] = NULL;
        rc = c->run(2, help);
    } else if (!strcmp(argv[1], "--version")) {
        printf("adaslice %s\n", ADASLICE_VERSION);
        rc = RC_OK;
    } else {
        if (!(c = find_command(argv[1]))) return RC_USAGE;
        /* print keeps its own SIGINT (it pauses the printer); the others stop
           and leave nothing half-written (output.h) */
        if (c->run != cmd_print) outputs_catch_signals();
        rc = c->run(argc - 1, argv + 1);
        /* the summary is part of the work: when it cannot be written, the
           files written with it go too; but not a print's report, the record
           of what a printer did */
        if (c->run != cmd_print && c->run != cmd_show) rc = stdout_written(rc);
        rc = outputs_finish(rc);
    }
    return stdout_written(rc);
}

