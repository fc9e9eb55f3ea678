/* rgbdmap: the command users run. It blocks SIGINT, SIGTERM and SIGUSR1 and ignores SIGXFSZ,
 * then replaces itself (same pid) with rgbdmap-core from the same folder.
 *
 * Why a separate program: rgbdmap-core links ~200 shared libraries (PCL, VTK, OpenCV, GDAL, ...)
 * and the dynamic loader spends 0.1-0.5 s mapping and relocating them before any of its own code
 * runs. A signal in that window takes its default action and kills the process. This program
 * links only libc, so it blocks the signals within microseconds of exec; a blocked signal stays
 * pending across execve, and rgbdmap-core's signal thread takes it once loaded. */
#include <errno.h>
#include <limits.h>
#include <signal.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

int main(int argc, char** argv) {
  (void)argc;
  sigset_t set;
  sigemptyset(&set);
  sigaddset(&set, SIGINT);
  sigaddset(&set, SIGTERM);
  sigaddset(&set, SIGUSR1);
  sigprocmask(SIG_BLOCK, &set, NULL);
  /* A file-size limit must fail the write (EFBIG), not kill the process. */
  signal(SIGXFSZ, SIG_IGN);

  char core[PATH_MAX];
  const ssize_t n = readlink("/proc/self/exe", core, sizeof core - 1);
  if (n <= 0) {
    fprintf(stderr, "rgbdmap: cannot find its own location (/proc/self/exe: %s)\n",
            strerror(errno));
    return 1;
  }
  core[n] = '\0';
  char* slash = strrchr(core, '/');
  const char name[] = "rgbdmap-core";
  if (!slash || (size_t)(slash + 1 - core) + sizeof name > sizeof core) {
    fprintf(stderr, "rgbdmap: unexpected location %s\n", core);
    return 1;
  }
  memcpy(slash + 1, name, sizeof name);
  execv(core, argv);
  fprintf(stderr, "rgbdmap: cannot start %s: %s\n", core, strerror(errno));
  return 1;
}
