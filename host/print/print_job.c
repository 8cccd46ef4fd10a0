/* What adaslice print sends a printer: see print_job.h. */
#include "print_job.h"
#include "../bytes.h"
#include "../codec/maskrows.h"
#include "../cure.h"
#include "../options.h"
#include "../report.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Layer k's (1-based) mask code into pj->code, with its CRC-32. */
int print_job_mask(print_job *pj, uint32_t k)
{
    int rc;
    size_t bound = adaslice_rle_bound(pj->width, pj->height, (int)pj->bits);
    if (!pj->from_model) {
        pj->crc = pj->file.crcs[k - 1];
        pj->code_size = pj->file.sizes[k - 1];
        pj->code = pj->file.codes[k - 1];
        return RC_OK;
    }
    if (k - 1 < pj->rendered) return complain(RC_FAIL, "layer %u: masks render bottom-up only", k);
    if (bound > pj->code_cap) {
        unsigned char *c = (unsigned char *)realloc(pj->code, bound);
        if (!c) return complain(RC_FAIL, "out of memory for a mask's code");
        pj->code = c;
        pj->code_cap = bound;
    }
    /* the masker sweeps upwards; layers below k were passed on the way */
    if ((rc = layer_masks_render(&pj->masks, k - 1, pj->masks.image))) return rc;
    pj->rendered = k;
    (void)adaslice_rle_encode(pj->masks.image, pj->masks.stride, pj->width, pj->height, (int)pj->bits, pj->code,
                              pj->code_cap, &pj->code_size);
    pj->crc = mask_crc32(pj->masks.image, pj->masks.stride, pj->masks.stride, (int)pj->height);
    return pj->code_size ? RC_OK : complain(RC_FAIL, "layer %u: the mask did not code", k);
}

size_t print_job_stride(const print_job *pj) { return pj->bits == 8 ? pj->width : (pj->width + 7u) / 8u; }

/* The current mask is about to be sent from its start. */
int print_job_send_begin(print_job *pj)
{
    size_t stride = print_job_stride(pj);
    if (!pj->sending_row && !(pj->sending_row = (unsigned char *)malloc(2 * stride)))
        return complain(RC_FAIL, "out of memory for a mask row");
    pj->sending_prev = pj->sending_row + stride;
    if (adaslice_rle_decoder_init(&pj->sending, pj->width, pj->height, (int)pj->bits, pj->sending_row, stride))
        return complain(RC_FAIL, "a %ux%u display of %u bits cannot take masks", pj->width, pj->height, pj->bits);
    return RC_OK;
}

/* A row's CRC as the printer's decoder counts it: the row's bytes, or
   ADASLICE_RLE_REPEAT_COST for a repeat of the row before (our encoder
   codes every such row as a repeat). */
static void count_row(void *ctx, uint32_t y, const unsigned char *row)
{
    print_job *pj = (print_job *)ctx;
    size_t stride = print_job_stride(pj);
    if (y && stride > ADASLICE_RLE_REPEAT_COST && !memcmp(row, pj->sending_prev, stride)) {
        pj->sending_cost += ADASLICE_RLE_REPEAT_COST;
    } else {
        pj->sending_cost += (uint32_t)stride;
        memcpy(pj->sending_prev, row, stride);
    }
}

/* The bytes of rows' CRC that the current mask's next n code bytes ask of
   the printer's decoder. */
uint32_t print_job_send_cost(print_job *pj, const unsigned char *code, size_t n)
{
    pj->sending_cost = 0;
    (void)adaslice_rle_decode(&pj->sending, code, n, count_row, pj);
    return pj->sending_cost;
}

void print_job_free(print_job *pj)
{
    free(pj->sending_row);
    if (pj->masks.image) layer_masks_close(&pj->masks);
    if (pj->from_model) { free(pj->code); free(pj->lengths); free(pj->exposure_ms); }
    job_masks_free(&pj->file);
    memset(pj, 0, sizeof *pj);
}

/* The job's hash, sent with PRINT and kept by the printer, so that a
   resume can tell this job from another: CRC-32 over the layers' lengths,
   bin_nm, the display, each layer's exposure and its mask's CRC. A MODEL's
   masks are rendered only as they are sent, so their CRCs are not known up
   front: for a MODEL the model's identity stands in for them, the mesh as
   planned (loaded, scaled and turned) and the options that place and draw it
   on the display. 0 means no job, so it is never 0. */
static uint32_t crc_u32(uint32_t crc, uint32_t v)
{
    unsigned char b[4];
    put_le32(b, v);
    return adaslice_crc32(crc, b, 4);
}

uint32_t print_job_hash(const print_job *pj, const adaslice_mesh *mesh, const slice_args *s)
{
    uint32_t crc = crc_u32(crc_u32(0, pj->layers), pj->bin_nm), k;
    crc = crc_u32(crc_u32(crc_u32(crc, pj->width), pj->height), pj->bits);
    for (k = 0; k < pj->layers; k++) {
        crc = crc_u32(crc_u32(crc, pj->lengths[k]), pj->exposure_ms[k]);
        if (!pj->from_model) crc = crc_u32(crc, pj->file.crcs[k]);
    }
    if (mesh) {
        int v[7];
        v[0] = s->supersample; v[1] = s->slice_at; v[2] = s->mirror_x; v[3] = s->mirror_y; v[4] = s->rotate;
        v[5] = s->placed ? (int)lround(s->place[0] * 1e6) : 0;
        v[6] = s->placed ? (int)lround(s->place[1] * 1e6) : 0;
        for (k = 0; k < 7; k++) crc = crc_u32(crc, (uint32_t)v[k]);
        crc = adaslice_crc32(crc, mesh->vertices, mesh->vertex_count * 3 * sizeof *mesh->vertices);
        crc = adaslice_crc32(crc, mesh->triangles, mesh->triangle_count * 3 * sizeof *mesh->triangles);
    }
    return crc ? crc : 1;
}

/* The printer's display decides the masks; the model is planned in printer
   units wherever the printer can plan it too. */
int print_job_from_model(print_job *pj, plan_args *a, plan_job *j, slice_args *s, const serial_link *l,
                         int plan_on_host, int *planned_by_printer)
{
    const adaslice_plan *p;
    job_layer *layers;
    uint32_t k;
    double nm;
    int rc;
    s->width = (s->rotate & 1) ? l->id.height : l->id.width;
    s->height = (s->rotate & 1) ? l->id.width : l->id.height;
    s->pitch[0] = s->pitch[1] = l->id.pitch_nm / 1e6;
    if (l->id.bits == 8 && s->supersample < 2) s->supersample = 4;
    if (l->id.bits == 1 && s->supersample > 1) return complain(RC_USAGE, "--aa: the printer's display is 1-bit");
    if ((rc = layer_masks_check(s, 1))) return rc;
    /* printer units wherever the printer can plan, so both plans are one */
    a->eps_units = a->metric != ADASLICE_METRIC_VOLUME && !a->budget ? ADASLICE_PRINTER_EPS_UNITS : 0;
    j->args = a;
    j->keep_mesh = 1;
    if ((rc = run_plan(a, j))) return rc;
    p = &j->plan[ADASLICE_METHOD_OPTIMAL];
    nm = j->profile.bin * 1e6;
    pj->layers = (uint32_t)p->layer_count;
    pj->bin_nm = (uint32_t)(nm + 0.5);
    if (fabs(nm - pj->bin_nm) > 1e-6 * nm) return complain(RC_USAGE, "--bin %g mm: a printer counts whole nanometres", j->profile.bin);
    if ((rc = cure_finish(&s->cure, a->tmin, a->tmax))) return rc;
    pj->lengths = (uint32_t *)malloc(pj->layers * sizeof *pj->lengths);
    pj->exposure_ms = (uint32_t *)malloc(pj->layers * sizeof *pj->exposure_ms);
    layers = (job_layer *)malloc(pj->layers * sizeof *layers);
    if (!pj->lengths || !pj->exposure_ms || !layers) { free(layers); return complain(RC_FAIL, "out of memory"); }
    cure_layers(&s->cure, p, layers);
    for (k = 0; k < pj->layers; k++) {
        pj->lengths[k] = p->planes[k + 1] - p->planes[k];
        pj->exposure_ms[k] = (uint32_t)(layers[k].exposure_s * 1000 + 0.5);
    }
    free(layers);
    pj->motion.peel_nm = (uint32_t)(s->cure.motion.lift_mm * 1e6 + 0.5);
    pj->motion.peel_speed_um_s = (uint32_t)(s->cure.motion.lift_speed * 1000 + 0.5);
    pj->motion.return_speed_um_s = (uint32_t)(s->cure.motion.retract_speed * 1000 + 0.5);
    pj->motion.settle_ms = (uint32_t)(s->cure.motion.wait_before_cure_s * 1000 + 0.5);
    if ((rc = layer_masks_open(&pj->masks, s, j, 1))) return rc;
    pj->width = (uint32_t)pj->masks.width;
    pj->height = (uint32_t)pj->masks.height;
    pj->bits = (uint32_t)pj->masks.bits;
    *planned_by_printer = !plan_on_host && a->eps_units && j->profile.bin_count <= l->id.max_bins &&
                          p->bins_max <= l->id.max_layer_bins;
    if (!*planned_by_printer && !plan_on_host)
        fprintf(stderr, "adaslice: the printer plans at most %u bins of layers up to %u bins (this part: %zu, %u%s): "
                        "the host plans\n", l->id.max_bins, l->id.max_layer_bins, j->profile.bin_count, p->bins_max,
                a->eps_units ? "" : ", and volume or --budget plans are the host's");
    return RC_OK;
}

int print_job_from_dir(print_job *pj, const char *dir)
{
    int rc = jobdir_read_masks(dir, &pj->file);
    if (!rc) rc = jobdir_check_layers(dir, &pj->file);
    if (rc) return rc;
    pj->layers = pj->file.layers;
    pj->bin_nm = pj->file.bin_nm;
    pj->lengths = pj->file.lengths;
    pj->exposure_ms = pj->file.exposure_ms;
    pj->motion.peel_nm = pj->file.peel_nm;
    pj->motion.peel_speed_um_s = pj->file.peel_speed_um_s;
    pj->motion.return_speed_um_s = pj->file.return_speed_um_s;
    pj->motion.settle_ms = pj->file.settle_ms;
    pj->width = pj->file.width;
    pj->height = pj->file.height;
    pj->bits = pj->file.bits;
    return RC_OK;
}
