/* A model as every command reads it: loaded, repaired as a slicer repairs on
   load, with one warning line when anything was wrong. */
#ifndef ADASLICE_HOST_MODEL_H
#define ADASLICE_HOST_MODEL_H
#include <stdio.h>
#include "../adaslice.h"
#include "json.h"

/* Loads and repairs path (coordinates times scale; 0 means 1) into mesh;
   report (may be NULL) says what the repair found. RC_OK or a complaint made. */
int model_load(const char *path, double scale, adaslice_mesh *mesh, adaslice_mesh_report *report);
/* The same, and the milliseconds the repair took into *ms_repair. */
int model_load_timed(const char *path, double scale, adaslice_mesh *mesh, adaslice_mesh_report *report, double *ms_repair);
/* The report as a JSON object, member key of w's open object (NULL in an array). */
void model_report_json(json_writer *w, const char *key, const adaslice_mesh_report *r);
#endif
