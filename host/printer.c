/* Printer presets. Figures are the makers' published display specifications,
   as quoted by the sources named; the display size in mm is pixels x pitch. */
#include "printer.h"
#include <string.h>

const printer PRINTERS[] = {
    {"2k-5.5", 2560, 1440, 0.04725,
     "5.5-inch 2K LCD (Elegoo Mars, Anycubic Photon class): 2560 x 1440 pixels of 47.25 um, "
     "120.96 x 68.04 mm (pixel figures: ChiTu Systems, \"5 things you need to know when choosing "
     "LCD screen\", 2020)"},
    {"photon-mono-4k", 3840, 2400, 0.035,
     "Anycubic Photon Mono 4K: 6.1-inch mono LCD, 3840 x 2400 pixels, XY 35 um, build 132 x 80 x 165 mm "
     "(xyzdims.com, \"MSLA Anycubic Photon Mono 4K\", 2023)"},
};
const int PRINTER_COUNT = (int)(sizeof PRINTERS / sizeof PRINTERS[0]);

const printer *printer_find(const char *name)
{
    int i;
    for (i = 0; i < PRINTER_COUNT; i++)
        if (!strcmp(PRINTERS[i].name, name)) return &PRINTERS[i];
    return NULL;
}
