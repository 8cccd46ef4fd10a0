/* Printers: a display of pixels of a given pitch under the vat. */
#ifndef ADASLICE_HOST_PRINTER_H
#define ADASLICE_HOST_PRINTER_H

typedef struct printer {
    const char *name;
    int width, height;      /* pixels along x and y, as the image is sent */
    double pitch;           /* mm per pixel */
    const char *about;      /* the machine, and where its figures come from */
} printer;

extern const printer PRINTERS[];
extern const int PRINTER_COUNT;

/* The preset called `name`, or NULL. */
const printer *printer_find(const char *name);

#endif
