/* The plan of adaslice print on the printer: see plan_upload.h. */
#include "plan_upload.h"
#include "../options.h"
#include "../report.h"

#include <stdlib.h>

static int plan_ready(const link_status *s, const void *ctx) { (void)ctx; return s->state != LINK_STATE_PLANNING; }

/* The profile goes to the printer as varints; its plan must equal ours. */
int plan_upload_profile(serial_link *l, const plan_job *j, const adaslice_plan_options *o, const print_job *pj)
{
    const adaslice_profile *p = &j->profile;
    uint32_t n = (uint32_t)p->bin_count, i, k;
    uint32_t *units = (uint32_t *)malloc(n * sizeof *units);
    unsigned char *forced = (unsigned char *)malloc(n);
    uint8_t buf[LINK_PAYLOAD_MAX];
    link_profile hdr;
    adaslice_error err;
    int rc = RC_OK;
    if (!units || !forced) { free(units); free(forced); return complain(RC_FAIL, "out of memory"); }
    if (adaslice_plan_units(p, o, units, forced, &err) != ADASLICE_OK) { rc = library_error(&err); goto done; }
    hdr.bins = n;
    hdr.bins_min = (uint8_t)j->plan[ADASLICE_METHOD_OPTIMAL].bins_min;
    hdr.bins_max = (uint8_t)j->plan[ADASLICE_METHOD_OPTIMAL].bins_max;
    hdr.eps_units = o->eps_units;
    hdr.bin_nm = pj->bin_nm;
    if ((rc = serial_send(l, LINK_MSG_PROFILE, buf, link_put_profile(buf, &hdr)))) goto done;
    for (i = 0; i < n;) {
        uint32_t from = i;
        size_t used = link_profile_chunk(buf, l->data_max, units, forced, n, &i);
        if ((rc = serial_send_profile_data(l, buf, used, i - from + (i == n ? n : 0)))) goto done;
    }
    if ((rc = serial_wait(l, plan_ready, NULL, 600000, "finish planning"))) goto done;
    if (l->st.state != LINK_STATE_READY) { rc = complain(RC_FAIL, "the printer could not plan: %s", link_error_name(l->st.error)); goto done; }
    if (l->st.layers != pj->layers) {
        rc = complain(RC_FAIL, "the printer planned %u layer%s, the host %u: the planners disagree", l->st.layers,
                      plural(l->st.layers), pj->layers);
        goto done;
    }
    /* read the plan back, page by page, and compare it layer by layer */
    for (k = 1; k <= pj->layers;) {
        size_t m;
        if (!serial_plan_page(l, k, &rc)) { if (rc) goto done; continue; }
        for (m = LINK_SIZE_PLAN; m < l->plan_size && k <= pj->layers; m++, k++)
            if (l->plan[m] != pj->lengths[k - 1]) {
                rc = complain(RC_FAIL, "layer %u: the printer planned %u bin%s, the host %u", k, l->plan[m],
                              plural(l->plan[m]), pj->lengths[k - 1]);
                goto done;
            }
    }
done:
    free(units);
    free(forced);
    return rc;
}

int plan_upload_plan(serial_link *l, const print_job *pj)
{
    uint8_t buf[LINK_PAYLOAD_MAX];
    link_plan_set m;
    uint32_t k;
    size_t used = 0;
    int rc;
    for (k = 0; k < pj->layers; k++)
        if (pj->lengths[k] > 255) return complain(RC_FAIL, "layer %u is %u bins: a printer takes at most 255", k + 1, pj->lengths[k]);
    m.layers = pj->layers;
    m.bin_nm = pj->bin_nm;
    if ((rc = serial_send(l, LINK_MSG_PLAN_SET, buf, link_put_plan_set(buf, &m)))) return rc;
    for (k = 0; k < pj->layers; k++) {
        if (used >= l->data_max) { if ((rc = serial_send(l, LINK_MSG_PLAN_DATA, buf, used))) return rc; used = 0; }
        buf[used++] = (uint8_t)pj->lengths[k];
    }
    if (used && (rc = serial_send(l, LINK_MSG_PLAN_DATA, buf, used))) return rc;
    if ((rc = serial_status(l))) return rc;
    if (l->st.state != LINK_STATE_READY || l->st.layers != pj->layers)
        return complain(RC_FAIL, "the printer refused the plan: %s", link_error_name(l->st.error));
    return RC_OK;
}
