/* The test runner: every group of cases, then "N passed, N failed". */
#define ADASLICE_IMPLEMENTATION
#include "../adaslice.h"
#include "check.h"
#include <stdlib.h>
#include <string.h>

static int passed, failed, case_failures;

void check_fail(const char *file, int line, const char *what)
{
    if (case_failures < 8) printf("    %s:%d: %s\n", file, line, what);
    case_failures++;
}

int check_case_failed(void) { return case_failures > 0; }

void check_run(const char *name, check_case_fn fn)
{
    case_failures = 0;
    fn();
    if (case_failures) { failed++; printf("FAIL %s (%d checks failed)\n", name, case_failures); }
    else { passed++; printf("ok   %s\n", name); }
    fflush(stdout);
}

void test_planner(void);
void test_profiles(void);
void test_loaders(void);
void test_cli(void);
void test_ldi(void);
void test_contours(void);
void test_masks(void);
void test_png(void);
void test_orient(void);
void test_saliency(void);
void test_cli_weights(void);
void test_codec(void);
void test_motion(void);
void test_gcode(void);
void test_firmware(void);
void test_print(void);
void test_link(void);

int main(int argc, char **argv)
{
    /* optional group names select what runs */
    int i, all = argc < 2;
    struct { const char *name; void (*fn)(void); } groups[] = {
        {"planner", test_planner}, {"profiles", test_profiles}, {"ldi", test_ldi}, {"contours", test_contours}, {"masks", test_masks}, {"png", test_png}, {"orient", test_orient}, {"loaders", test_loaders}, {"cli", test_cli},
        {"saliency", test_saliency}, {"cli_weights", test_cli_weights}, {"codec", test_codec}, {"link", test_link}, {"motion", test_motion}, {"gcode", test_gcode}, {"firmware", test_firmware},
        {"print", test_print}};
    for (i = 0; i < (int)(sizeof groups / sizeof groups[0]); i++) {
        int j, want = all;
        for (j = 1; j < argc; j++) if (!strcmp(argv[j], groups[i].name)) want = 1;
        if (want) groups[i].fn();
    }
    printf("%d passed, %d failed\n", passed, failed);
    return failed ? 1 : 0;
}
