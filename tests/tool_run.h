/* Runs a program besides the tool for the tests (unzip, oiiotool), its
   stdout and stderr in files; a missing program fails the case naming the
   Debian package to install. */
#ifndef ADASLICE_TOOL_RUN_H
#define ADASLICE_TOOL_RUN_H
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L /* posix_spawn */
#endif
#include "check.h"

#include <errno.h>
#include <fcntl.h>
#include <spawn.h>
#include <stdio.h>
#include <string.h>
#include <sys/wait.h>

extern char **environ;

/* argv[0] found on PATH, stdin /dev/null, stdout into out_path and stderr
   into err_path (the same path: both into one file). Its exit status, or -1
   when it could not run or did not exit. */
static inline int tool_run(const char *package, char **argv, const char *out_path, const char *err_path)
{
    posix_spawn_file_actions_t fa;
    pid_t pid;
    int st = 0, rc, same = !strcmp(out_path, err_path);
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, out_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (same) posix_spawn_file_actions_adddup2(&fa, 1, 2);
    else posix_spawn_file_actions_addopen(&fa, 2, err_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    fflush(NULL);
    rc = posix_spawnp(&pid, argv[0], &fa, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc == 0 && waitpid(pid, &st, 0) == pid && WIFEXITED(st) && WEXITSTATUS(st) != 127) return WEXITSTATUS(st);
    CHECKF(0, rc == ENOENT || (rc == 0 && WIFEXITED(st)) ? "%s not found: install it with `apt-get install -y %s`"
                                                        : "%s did not run to its end (%s)", argv[0], package);
    return -1;
}
#endif
