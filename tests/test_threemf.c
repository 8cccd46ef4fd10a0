/* adaslice plan --3mf: PrusaSlicer slices the project layer for layer as
   planned (prusa_check.h), and bounds an FDM nozzle cannot lay are refused
   before anything is written. */
#include "prusa_check.h"

/* The hand is closed and thick: every planned layer is printed. */
static void prusaslicer_slices_the_bundled_hand_as_planned(void)
{
    prusa_result r;
    CHECK(prusa_slices_the_plan("examples/models/hand_closed.obj", 88.7, &r));
    CHECKF(r.planned > 150 && r.printed == r.planned, "%zu of %zu layers printed", r.printed, r.planned);
}

static void bounds_a_nozzle_cannot_lay_are_refused(void)
{
    static const char *const cases[][6] = {
        {"--tmax", "0.35", NULL, NULL, "0.4 mm nozzle lays layers up to 0.3 mm"},
        {"--tmax", "0.35", "--nozzle", "0.6", NULL},
        {"--tmin", "0.005", "--tmax", "0.2", "thinnest layer is 0.01 mm"},
        {"--nozzle", "0", NULL, NULL, "--nozzle"},
    };
    size_t c;
    for (c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        char out[256];
        cli_result r;
        snprintf(out, sizeof out, "%s", cli_path("bounds.3mf"));
        r = cli_run("plan", "examples/models/hand_closed.obj", "--scale", "88.7", "--3mf", out, cases[c][0], cases[c][1],
                    cases[c][2], cases[c][3], NULL);
        if (cases[c][4]) {
            CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, cases[c][4]), "%s %s: exit %d: %s", cases[c][0],
                   cases[c][1], r.status, r.err);
            CHECKF(!cli_exists(out), "%s %s: %s written", cases[c][0], cases[c][1], out);
        } else {
            CHECKF(r.status == 0 && cli_exists(out), "%s %s %s %s: exit %d: %s", cases[c][0], cases[c][1], cases[c][2],
                   cases[c][3], r.status, r.err);
        }
        remove(out);
        cli_free(&r);
    }
    {
        cli_result r = cli_run("plan", "--profile", "examples/models/README.md", "--3mf", cli_path("p.3mf"), NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "--3mf needs a MODEL"), "%d %s", r.status, r.err);
        cli_free(&r);
        r = cli_run("slice", "examples/models/hand_closed.obj", "-o", cli_path("j"), "--3mf", cli_path("p.3mf"), NULL);
        CHECKF(r.status == 2 && cli_one_message(r.err) && strstr(r.err, "--3mf"), "%d %s", r.status, r.err);
        cli_free(&r);
    }
}

void test_threemf(void)
{
    if (!cli_begin("adaslice-3mf")) { CHECK(!"no temporary directory"); return; }
    RUN_NEEDING("prusa-slicer", prusaslicer_slices_the_bundled_hand_as_planned);
    RUN(bounds_a_nozzle_cannot_lay_are_refused);
    cli_end();
}
