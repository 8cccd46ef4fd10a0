/* The commands of the adaslice tool; argv[0] is the command's name. Each
   returns the exit status (report.h). */
#ifndef ADASLICE_HOST_COMMANDS_H
#define ADASLICE_HOST_COMMANDS_H
int cmd_plan(int argc, char **argv);
int cmd_slice(int argc, char **argv);
int cmd_orient(int argc, char **argv);
int cmd_saliency(int argc, char **argv);
int cmd_print(int argc, char **argv);
int cmd_printers(int argc, char **argv);
int cmd_show(int argc, char **argv);
int cmd_contour(int argc, char **argv);
#endif
