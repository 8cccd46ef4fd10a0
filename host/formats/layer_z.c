/* Per-layer Z by job format: see layer_z.h. The field reports are UVtools'
   (sn4k3/UVtools; CHANGELOG and CoreSettings.cs at 7b510f0d). */
#include "layer_z.h"
#include <string.h>

static const layer_z LAYER_Z[] = {
    {"dir", LAYER_Z_OURS,
     "adaslice print sends each layer's thickness to the adaslice firmware (PLAN_SET), which moves by it", NULL},
    {"chitu-zip", LAYER_Z_BY_CONSTRUCTION, "run.gcode moves to every layer's Z with an absolute G0 Z", NULL},
    {"ctb", LAYER_Z_PER_FORMAT,
     "every layer's table entry holds its Z and the PerLayerSettings flag is set (CTB v3, v4); no field report either way",
     NULL},
    {"goo", LAYER_Z_FIELD_TROUBLE,
     "the advance-mode flag makes the printer take every layer's Z; UVtools 5.1.6 turned per-layer settings off by "
     "default for GOO after a Saturn 4 froze mid-print (sn4k3/UVtools#997) and a Phrozen Mega 8K S started several mm "
     "high (#1040)",
     "the GOO's advance-mode flag is on so that the printer takes each layer's own Z; UVtools leaves it off for GOO "
     "since a Saturn 4 froze mid-print (UVtools #997) and a Phrozen Mega 8K S started several mm high (#1040): "
     "watch the first layers of a first print"},
    {"ctb-encrypted", LAYER_Z_PER_FORMAT,
     "every layer's record holds its Z and the per-layer settings flag (0x40) is set, as UVtools writes it; no field "
     "report either way",
     NULL},
    {"prz", LAYER_Z_FIELD_TROUBLE,
     "a GOO file (UVtools reads both with GooFile.cs): the advance-mode flag makes the printer take every layer's Z; "
     "the Phrozen Mega 8K S that started several mm high (sn4k3/UVtools#1040) printed a .prz",
     "the .prz's advance-mode flag is on so that the printer takes each layer's own Z; UVtools leaves it off for "
     "GOO and .prz since a Phrozen Mega 8K S .prz started several mm high (UVtools #1040): watch the first layers "
     "of a first print"},
    {"uvj", LAYER_Z_PER_FORMAT,
     "config.json lists every layer's Z; the printer reads what UVtools converts it to, whose row here applies", NULL},
    {"sl1", LAYER_Z_NO, "config.ini holds one layer height: adaptive plans are refused", NULL},
};
enum { LAYER_Z_ROWS = sizeof LAYER_Z / sizeof LAYER_Z[0] };

const layer_z *layer_z_of(const char *format)
{
    static const layer_z unknown = {"?", LAYER_Z_UNKNOWN, "not known", NULL};
    int i;
    for (i = 0; i < LAYER_Z_ROWS; i++)
        if (!strcmp(LAYER_Z[i].format, format)) return &LAYER_Z[i];
    return &unknown;
}

const char *layer_z_says(layer_z_support support)
{
    switch (support) {
    case LAYER_Z_NO: return "no";
    case LAYER_Z_FIELD_TROUBLE: return "per the format, field reports of trouble";
    case LAYER_Z_PER_FORMAT: return "per the format, not field-verified";
    case LAYER_Z_BY_CONSTRUCTION: return "yes by construction";
    case LAYER_Z_OURS: return "yes (adaslice print and firmware)";
    default: return "not known";
    }
}

void layer_z_table(FILE *f)
{
    int i;
    fputs("per-layer Z (what adaptive layers need of the printer), by the format it reads:\n", f);
    for (i = 0; i < LAYER_Z_ROWS; i++)
        fprintf(f, "  %-13s %s: %s\n", LAYER_Z[i].format, layer_z_says(LAYER_Z[i].support), LAYER_Z[i].why);
}
