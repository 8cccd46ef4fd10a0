/* adaslice - the command-line tool over adaslice.h: the command table.

   adaslice COMMAND [options]; adaslice COMMAND --help lists a command's options.

   Exit status: 0 done; 1 the work failed (a file that cannot be read or written,
   a malformed mesh, constraints that no plan meets); 2 the command line is wrong;
   3 a print paused. Every message is one line on stderr that starts with
   "adaslice: ". */
#include "../adaslice.h"
#include "commands.h"
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
};
enum { COMMAND_COUNT = sizeof COMMANDS / sizeof *COMMANDS };

static void usage(FILE *f)
{
    int i;
    fputs("usage: adaslice COMMAND [options]\n"
          "       adaslice help | --help | --version\n"
          "\n"
          "commands:\n", f);
    for (i = 0; i < COMMAND_COUNT; i++) fprintf(f, "  %-10s %s\n", COMMANDS[i].name, COMMANDS[i].summary);
    fputs("\n'adaslice COMMAND --help' lists the command's options.\n", f);
}

int main(int argc, char **argv)
{
    int i, rc;
    if (argc < 2) {
        usage(stderr);
        return RC_USAGE;
    }
    if (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h") || !strcmp(argv[1], "help")) {
        usage(stdout);
        rc = RC_OK;
    } else if (!strcmp(argv[1], "--version")) {
        printf("adaslice %s\n", ADASLICE_VERSION);
        rc = RC_OK;
    } else {
        for (i = 0; i < COMMAND_COUNT && strcmp(argv[1], COMMANDS[i].name); i++) {}
        if (i == COMMAND_COUNT)
            return complain(RC_USAGE, "unknown %s %s (see adaslice --help)",
                            argv[1][0] == '-' ? "option" : "command", argv[1]);
        rc = COMMANDS[i].run(argc - 1, argv + 1);
    }
    /* a full disk or closed pipe on stdout is a failure, not a silent success */
    if (fflush(stdout) != 0 || ferror(stdout)) return complain(RC_FAIL, "cannot write standard output: %s", strerror(errno));
    return rc;
}

