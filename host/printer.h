/* Printers: a display of pixels under the vat, and the job file the printer
   reads from its USB stick. */
#ifndef ADASLICE_HOST_PRINTER_H
#define ADASLICE_HOST_PRINTER_H

typedef struct printer {
    const char *name;       /* --printer NAME */
    const char *machine;    /* the machine's name, as job headers carry it */
    int width, height;      /* pixels across and down, as the images are stored */
    double pitch[2];        /* mm per pixel across and down (many panels are not square) */
    double z_max;           /* build height, mm */
    int mirror_x, mirror_y; /* the printer wants its images flipped so (its LCD is seen from below) */
    int rotate;             /* quarter turns of the image, counter-clockwise, as --rotate */
    const char *format;     /* the job_format it reads (jobfile.h) */
    unsigned version;       /* the format's version (CTB 3 or 4), 0 for the format's one */
    const char *about;      /* the machine, and where its figures come from */
} printer;

extern const printer PRINTERS[];
extern const int PRINTER_COUNT;

/* The preset called `name`, or NULL. */
const printer *printer_find(const char *name);

#endif
