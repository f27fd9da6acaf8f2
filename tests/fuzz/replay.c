/*
 * A main for the fuzz targets without libFuzzer: runs the target on every file named on the
 * command line (a directory stands for the files in it). It replays the committed seed
 * corpus, and any finding, with any compiler (gcc, sanitizers, valgrind), as a ctest test.
 */
#include <dirent.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
/* A target may say what its inputs reached. */
void fz_summary(void) __attribute__((weak));

static long replayed;

static int replay_file(const char *path) {
  FILE *f = fopen(path, "rb");
  if (!f) {
    fprintf(stderr, "replay: cannot open %s\n", path);
    return 1;
  }
  size_t cap = 1 << 16, size = 0;
  uint8_t *buf = malloc(cap);
  if (!buf) abort();
  size_t got;
  while ((got = fread(buf + size, 1, cap - size, f)) > 0) {
    size += got;
    if (size == cap) {
      cap *= 2;
      buf = realloc(buf, cap);
      if (!buf) abort();
    }
  }
  fclose(f);
  LLVMFuzzerTestOneInput(buf, size);
  free(buf);
  replayed++;
  return 0;
}

static int replay_path(const char *path) {
  struct stat st;
  if (stat(path, &st) != 0) {
    fprintf(stderr, "replay: no such file or directory: %s\n", path);
    return 1;
  }
  if (!S_ISDIR(st.st_mode)) return replay_file(path);
  DIR *d = opendir(path);
  if (!d) {
    fprintf(stderr, "replay: cannot read %s\n", path);
    return 1;
  }
  int bad = 0;
  struct dirent *e;
  while ((e = readdir(d)) != NULL) {
    if (e->d_name[0] == '.') continue;
    size_t len = strlen(path) + strlen(e->d_name) + 2;
    char *full = malloc(len);
    if (!full) abort();
    snprintf(full, len, "%s/%s", path, e->d_name);
    bad |= replay_file(full);
    free(full);
  }
  closedir(d);
  return bad;
}

int main(int argc, char **argv) {
  int bad = 0;
  for (int a = 1; a < argc; a++) bad |= replay_path(argv[a]);
  if (replayed == 0) {
    fprintf(stderr, "replay: no input replayed\n");
    return 1;
  }
  printf("%ld inputs replayed without a finding\n", replayed);
  if (fz_summary) fz_summary();
  return bad;
}
