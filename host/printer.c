/* Printer presets. Figures are the makers' published display specifications
   as the sources named carry them; pitch = display size / pixels. "UVtools
   ini" is sn4k3/UVtools, PrusaSlicer/printer/<name>.ini at the commit given:
   display_pixels_x/y, display_width/height, display_mirror_x/y,
   max_print_height and the FILEFORMAT_/FILEVERSION_ keys of printer_notes. */
#include "printer.h"
#include <string.h>

const printer PRINTERS[] = {
    {"2k-5.5", "2K 5.5-inch LCD", 2560, 1440, {0.04725, 0.04725}, 150, 0, 0, 0, "dir", 0,
     "5.5-inch 2K LCD (Elegoo Mars, Anycubic Photon class): 2560 x 1440 pixels of 47.25 um, "
     "120.96 x 68.04 mm (pixel figures: ChiTu Systems, \"5 things you need to know when choosing "
     "LCD screen\", 2020)"},
    {"photon-mono-4k", "Anycubic Photon Mono 4K", 3840, 2400, {0.035, 0.035}, 165, 0, 0, 0, "dir", 0,
     "Anycubic Photon Mono 4K: 6.1-inch mono LCD, 3840 x 2400 pixels, XY 35 um, build 132 x 80 x 165 mm "
     "(xyzdims.com, \"MSLA Anycubic Photon Mono 4K\", 2023). It reads Anycubic's own .pwma, whose per-layer "
     "settings UVtools lists as problematic: a job directory"},
    {"elegoo-mars-2-pro", "ELEGOO MARS 2 PRO", 1620, 2560, {0.051, 0.051}, 160, 1, 0, 0, "ctb", 4,
     "Elegoo Mars 2 Pro: 1620 x 2560 pixels, 82.62 x 130.56 mm, Z 160 mm; CTB v4 "
     "(UVtools ini \"Elegoo Mars 2 Pro\" @6dc26f74)"},
    {"elegoo-saturn", "ELEGOO SATURN", 3840, 2400, {0.05, 0.05}, 200, 1, 0, 0, "ctb", 3,
     "Elegoo Saturn: 3840 x 2400 pixels, 192 x 120 mm, Z 200 mm; CTB v3 "
     "(UVtools ini \"Elegoo Saturn\" @097bbb86; the version: UVtools @7b510f0d)"},
    {"phrozen-sonic-mini-4k", "Phrozen Sonic Mini 4K", 3840, 2160, {0.035, 0.035}, 130, 1, 0, 0, "ctb", 3,
     "Phrozen Sonic Mini 4K: 3840 x 2160 pixels, 134.4 x 75.6 mm, Z 130 mm; CTB v3 "
     "(UVtools ini \"Phrozen Sonic Mini 4K\" @097bbb86; the version: UVtools @7b510f0d)"},
    /* The encrypted CTB's printers: version 0 is the writer's 5, which UVtools
       writes for them (CTBEncryptedFile.cs DEFAULT_VERSION @5f33a73e; the
       inis name no FILEVERSION). */
    {"elegoo-mars-3", "ELEGOO MARS 3", 4098, 2560, {0.035, 0.035}, 175, 1, 0, 0, "ctb-encrypted", 0,
     "Elegoo Mars 3: 4098 x 2560 pixels, 143.43 x 89.6 mm, Z 175 mm; encrypted CTB "
     "(UVtools ini \"Elegoo Mars 3\" @1386476b)"},
    {"elegoo-saturn-4-ultra", "ELEGOO SATURN 4 ULTRA", 11520, 5120, {0.019, 0.024}, 220, 1, 0, 0, "ctb-encrypted", 0,
     "Elegoo Saturn 4 Ultra (12K): 11520 x 5120 pixels, 218.88 x 122.88 mm, pixels of 19 x 24 um, Z 220 mm; "
     "encrypted CTB (UVtools ini \"Elegoo Saturn 4 Ultra 12K\" @702d5b13). It tilts its vat: UVtools writes "
     "every lift height and speed as 0.05 for it (CTBEncryptedFile.cs HaveTiltingVat @5f33a73e); the job holds "
     "the --peel motion as given"},
    {"phrozen-sonic-mini-8k", "Phrozen Sonic Mini 8K", 7500, 3240, {0.022, 0.022}, 180, 1, 0, 0, "ctb-encrypted", 0,
     "Phrozen Sonic Mini 8K: 7500 x 3240 pixels, 165 x 71.28 mm, Z 180 mm; encrypted CTB "
     "(UVtools ini \"Phrozen Sonic Mini 8K\" @1386476b)"},
    {"elegoo-mars-4-ultra", "ELEGOO MARS 4 ULTRA", 8520, 4320, {0.018, 0.018}, 165, 1, 0, 0, "goo", 0,
     "Elegoo Mars 4 Ultra: 8520 x 4320 pixels, 153.36 x 77.76 mm, Z 165 mm; GOO "
     "(UVtools ini \"Elegoo Mars 4 Ultra\" @92fb2bc7)"},
    {"elegoo-saturn-3", "ELEGOO SATURN 3", 11520, 5120, {0.019, 0.024}, 249.7, 1, 0, 0, "goo", 0,
     "Elegoo Saturn 3 (12K): 11520 x 5120 pixels, 218.88 x 122.88 mm, pixels of 19 x 24 um, Z 249.7 mm; GOO "
     "(UVtools ini \"Elegoo Saturn 3\" @92fb2bc7)"},
    {"elegoo-saturn-4", "ELEGOO SATURN 4", 11520, 5120, {0.019, 0.024}, 220, 1, 0, 0, "goo", 0,
     "Elegoo Saturn 4 (12K): 11520 x 5120 pixels, 218.88 x 122.88 mm, pixels of 19 x 24 um, Z 220 mm; GOO "
     "(UVtools ini \"Elegoo Saturn 4\" @a1afac02)"},
    {"phrozen-sonic-mini-8k-s", "Phrozen Sonic Mini 8K S", 7536, 3240, {0.022, 0.022}, 170, 1, 0, 0, "prz", 0,
     "Phrozen Sonic Mini 8K S: 7536 x 3240 pixels, 165.792 x 71.28 mm, Z 170 mm; PRZ, GOO without diff runs "
     "(UVtools ini \"Phrozen Sonic Mini 8K S\" @d8c42c6b, whose notes say FILEFORMAT_GOO; the .prz Lychee and "
     "UVtools write for it, and UVtools' GooFile.cs @f0de25c0)"},
    {"phrozen-shuffle-4k", "Phrozen Shuffle 4K", 2160, 3840, {0.0315, 0.0315}, 170, 0, 0, 0, "chitu-zip", 0,
     "Phrozen Shuffle 4K: 2160 x 3840 pixels, 68.04 x 120.96 mm, Z 170 mm; ChiTu G-code zip "
     "(UVtools ini \"Phrozen Shuffle 4K\" @097bbb86)"},
    {"wanhao-d8", "Wanhao D8", 2560, 1600, {0.075, 0.075}, 180, 1, 0, 0, "chitu-zip", 0,
     "Wanhao Duplicator 8: 2560 x 1600 pixels, 192 x 120 mm, Z 180 mm; ChiTu G-code zip "
     "(UVtools ini \"Wanhao D8\" @097bbb86)"},
    /* PrusaSlicer renders the SL1/SL1S portrait and mirrored: image column =
       y / pitch, image row = (plate x - x) / pitch (measured on 2.5.0), which
       is --rotate 90 with the y flip. */
    {"prusa-sl1s", "SL1S", 1620, 2560, {0.05, 0.05}, 150, 0, 1, 1, "sl1", 0,
     "Original Prusa SL1S SPEED: 2560 x 1620 pixels of 50 um (128 x 81 mm), stored portrait as 1620 x 2560, "
     "Z 150 mm (PrusaSlicer 2.5.0 profiles, PrusaResearch.ini [printer:Original Prusa SL1S SPEED]; "
     "slafw SL1S exposure screen 1620 x 2560)"},
    {"prusa-sl1", "SL1", 1440, 2560, {0.04725, 0.04725}, 150, 0, 1, 1, "sl1", 0,
     "Original Prusa SL1: 2560 x 1440 pixels of 47.25 um (120.96 x 68.04 mm), stored portrait as "
     "1440 x 2560, Z 150 mm (PrusaSlicer 2.5.0 profiles, [printer:Original Prusa SL1]; slafw SL1 screen)"},
};
const int PRINTER_COUNT = (int)(sizeof PRINTERS / sizeof PRINTERS[0]);

const printer *printer_find(const char *name)
{
    int i;
    for (i = 0; i < PRINTER_COUNT; i++)
        if (!strcmp(PRINTERS[i].name, name)) return &PRINTERS[i];
    return NULL;
}
