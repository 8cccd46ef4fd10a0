/* The plan of adaslice print on the printer: the printer plans the profile
   itself (PROFILE, PROFILE_DATA) and its plan is read back and compared
   with the host's layer by layer, or it is given the host's (PLAN_SET,
   PLAN_DATA). link/PROTOCOL.md. */
#ifndef ADASLICE_HOST_PRINT_PLAN_UPLOAD_H
#define ADASLICE_HOST_PRINT_PLAN_UPLOAD_H
#include "print_job.h"

/* The profile goes to the printer as varints; its plan must equal ours.
   RC_OK, or a complaint made. */
int plan_upload_profile(serial_link *l, const plan_job *j, const adaslice_plan_options *o, const print_job *pj);
/* The host's plan given to the printer (layers of at most 255 bins). */
int plan_upload_plan(serial_link *l, const print_job *pj);
#endif
