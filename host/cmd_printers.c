/* adaslice printers: the presets, and whether each printer takes every
   layer's own Z (layer_z.h), which an adaptive plan needs. */
#include "commands.h"
#include "formats/layer_z.h"
#include "printer.h"
#include "report.h"

#include <stdio.h>
#include <string.h>

void printers_list(FILE *f)
{
    int i;
    fprintf(f, "%-24s %-13s %-13s %-12s %-10s %s\n", "PRESET", "FORMAT", "PIXELS", "PITCH (um)", "BUILD (mm)",
            "PER-LAYER Z");
    for (i = 0; i < PRINTER_COUNT; i++) {
        const printer *p = &PRINTERS[i];
        char pixels[32], pitch[32];
        snprintf(pixels, sizeof pixels, "%d x %d", p->width, p->height);
        if (p->pitch[1] != p->pitch[0]) snprintf(pitch, sizeof pitch, "%g x %g", p->pitch[0] * 1000, p->pitch[1] * 1000);
        else snprintf(pitch, sizeof pitch, "%g", p->pitch[0] * 1000);
        fprintf(f, "%-24s %-13s %-13s %-12s %-10g %s\n", p->name, p->format, pixels, pitch, p->z_max,
                layer_z_says(layer_z_of(p->format)->support));
    }
    fputc('\n', f);
    layer_z_table(f);
}

static void printers_usage(FILE *f)
{
    fputs("usage: adaslice printers\n"
          "\n"
          "Lists the printer presets (slice --printer NAME; also slice --printer list): the\n"
          "format each reads, its pixels and their pitch, its build height, and whether it\n"
          "takes each layer's own Z, which adaptive layers need.\n"
          "\n", f);
    layer_z_table(f);
}

int cmd_printers(int argc, char **argv)
{
    if (argc > 1 && (!strcmp(argv[1], "--help") || !strcmp(argv[1], "-h"))) {
        printers_usage(stdout);
        return RC_OK;
    }
    if (argc > 1) return complain(RC_USAGE, "printers %s: printers takes no arguments", argv[1]);
    printers_list(stdout);
    return RC_OK;
}
