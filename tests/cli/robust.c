/*
 * The tool never crashes on any input: every fixture of data/golden and data/formats is
 * mutated many times (bytes flipped, replaced, deleted, duplicated, huge numbers inserted,
 * the file cut short), deterministically, and `nbs detect` must end with exit 0 (and an
 * output file) or 3/4 (and no output file), never by a signal or another code. Run under
 * the sanitizer build too, where a memory error is a crash.
 *
 *   cli_robust NBS DATA WORK [mutations per file]
 */
#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <spawn.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

extern char **environ;

static uint64_t rng_state = 0x1234567887654321ull;
static uint64_t rng(void) {
  uint64_t z = (rng_state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

static unsigned char *slurp(const char *path, size_t *len) {
  FILE *f = fopen(path, "rb");
  if (!f) return NULL;
  fseek(f, 0, SEEK_END);
  long n = ftell(f);
  rewind(f);
  unsigned char *b = malloc((size_t)n + 64);
  if (b && fread(b, 1, (size_t)n, f) != (size_t)n) {
    free(b);
    b = NULL;
  }
  fclose(f);
  *len = (size_t)n;
  return b;
}

/* One mutation of buf (capacity cap) in place; returns the new length. */
static size_t mutate(unsigned char *buf, size_t len, size_t cap) {
  static const char *const inserts[] = {"99999999999999999999", "-1", "nan", "1e308", "<", "\"",
                                        "\n", "ITEM: ATOMS x\n", "0", "inf", "-0", "4294967295"};
  if (len == 0) return 0;
  size_t at = (size_t)(rng() % len);
  switch (rng() % 7) {
  case 0: /* flip a bit */
    buf[at] ^= (unsigned char)(1u << (rng() % 8));
    return len;
  case 1: /* a random byte */
    buf[at] = (unsigned char)rng();
    return len;
  case 2: /* a digit */
    buf[at] = (unsigned char)('0' + rng() % 10);
    return len;
  case 3: /* cut short */
    return at;
  case 4: /* delete a byte */
    memmove(buf + at, buf + at + 1, len - at - 1);
    return len - 1;
  default: { /* insert a hostile token */
    const char *s = inserts[rng() % (sizeof inserts / sizeof inserts[0])];
    size_t l = strlen(s);
    if (len + l > cap) return len;
    memmove(buf + at + l, buf + at, len - at);
    memcpy(buf + at, s, l);
    return len + l;
  }
  }
}

static int run(const char *nbs, const char *input, const char *output, const char *dim) {
  char *argv[12];
  int k = 0;
  argv[k++] = (char *)nbs;
  argv[k++] = "detect";
  argv[k++] = "-q";
  argv[k++] = "--input";
  argv[k++] = (char *)input;
  argv[k++] = "--output";
  argv[k++] = (char *)output;
  if (dim) {
    argv[k++] = "--dim";
    argv[k++] = (char *)dim;
  }
  argv[k] = NULL;
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_addopen(&fa, 1, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&fa, 2, "/dev/null", O_WRONLY, 0);
  pid_t pid;
  int e = posix_spawn(&pid, nbs, &fa, NULL, argv, environ);
  posix_spawn_file_actions_destroy(&fa);
  if (e != 0) {
    fprintf(stderr, "cannot run %s: %s\n", nbs, strerror(e));
    exit(2);
  }
  int status;
  while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return status;
}

int main(int argc, char **argv) {
  if (argc < 4) {
    fprintf(stderr, "usage: cli_robust NBS DATA WORK [mutations]\n");
    return 2;
  }
  const char *nbs = argv[1], *data = argv[2], *work = argv[3];
  int per = argc > 4 ? atoi(argv[4]) : 30;
  mkdir(work, 0777);
  static const char *const dirs[] = {"golden", "formats"};
  int runs = 0, failures = 0;
  for (int d = 0; d < 2; d++) {
    char dir[4096];
    snprintf(dir, sizeof dir, "%s/%s", data, dirs[d]);
    struct dirent **names;
    int count = scandir(dir, &names, NULL, alphasort);
    if (count < 0) {
      fprintf(stderr, "%s: %s\n", dir, strerror(errno));
      return 2;
    }
    for (int f = 0; f < count; f++) {
      const char *name = names[f]->d_name;
      const char *ext = strrchr(name, '.');
      int take = ext && (strcmp(ext, ".csv") == 0 || strcmp(ext, ".txt") == 0 ||
                         strcmp(ext, ".f64") == 0 || strcmp(ext, ".vtp") == 0 ||
                         strcmp(ext, ".vtu") == 0 || strcmp(ext, ".vtk") == 0 ||
                         strcmp(ext, ".dump") == 0) &&
                 !strstr(name, ".pairs.");
      if (!take) continue;
      char path[8192];
      snprintf(path, sizeof path, "%s/%s", dir, name);
      size_t len;
      unsigned char *orig = slurp(path, &len);
      if (!orig) {
        fprintf(stderr, "%s: cannot read\n", path);
        return 2;
      }
      size_t cap = len + 64;
      unsigned char *buf = malloc(cap);
      /* CSV and f64 need the dimension; the 3D golden files and all of formats/ are 3D. */
      const char *dim = strstr(name, "2d") ? "2" : "3";
      for (int m = 0; m < per; m++) {
        memcpy(buf, orig, len);
        size_t l = len;
        int times = 1 + (int)(rng() % 3);
        for (int t = 0; t < times; t++) l = mutate(buf, l, cap);
        char input[8192], output[8192];
        snprintf(input, sizeof input, "%s/mutant%s", work, ext);
        snprintf(output, sizeof output, "%s/mutant.pairs", work);
        FILE *o = fopen(input, "wb");
        if (!o || fwrite(buf, 1, l, o) != l || fclose(o) != 0) {
          fprintf(stderr, "%s: cannot write\n", input);
          return 2;
        }
        unlink(output);
        int status = run(nbs, input, output, dim);
        runs++;
        struct stat st;
        int has_output = stat(output, &st) == 0;
        const char *problem = NULL;
        if (WIFSIGNALED(status)) {
          problem = "killed by a signal";
        } else if (!WIFEXITED(status)) {
          problem = "did not exit";
        } else {
          int code = WEXITSTATUS(status);
          if (code == 0 && !has_output) problem = "exit 0 without an output file";
          if (code != 0 && has_output) problem = "an output file after a failure";
          if (code != 0 && code != 3 && code != 4) problem = "an unexpected exit code";
        }
        if (problem) {
          failures++;
          char keep[8192];
          snprintf(keep, sizeof keep, "%s/failure%d%s", work, failures, ext);
          rename(input, keep);
          fprintf(stderr, "FAILED: %s, mutation %d: %s (status %d); the input is %s\n", name, m,
                  problem, status, keep);
        }
      }
      free(buf);
      free(orig);
    }
    for (int f = 0; f < count; f++) free(names[f]);
    free(names);
  }
  printf("%d runs on mutated files: %d passed, %d failed\n", runs, runs - failures, failures);
  return failures ? 1 : 0;
}
