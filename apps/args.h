/*
 * A small option scanner shared by the subcommands: "--name value", "--name=value", flags,
 * and positional arguments, in any order.
 */
#ifndef NBS_CLI_ARGS_H
#define NBS_CLI_ARGS_H

#include <stdbool.h>
#include <string.h>

typedef struct cli_args {
  int argc;
  char **argv;
  int k;           /* the argument being looked at */
  const char *cmd; /* for messages */
  const char *val; /* the value of the last option matched by cli_opt */
  bool missing;    /* the last option matched lacks its value */
} cli_args;

/* True when argv[k] is the option `name` taking a value (the value goes to a->val; a missing
 * value sets a->missing, reported by the caller as a usage error). */
static inline bool cli_opt(cli_args *a, const char *name) {
  const char *s = a->argv[a->k];
  size_t n = strlen(name);
  if (strncmp(s, name, n) != 0) return false;
  if (s[n] == '=') {
    a->val = s + n + 1;
    a->missing = false;
    return true;
  }
  if (s[n] != '\0') return false;
  if (a->k + 1 >= a->argc) {
    a->val = NULL;
    a->missing = true;
    return true;
  }
  a->val = a->argv[++a->k];
  a->missing = false;
  return true;
}

/* True when argv[k] is the flag `name` (or its short form, which may be NULL). */
static inline bool cli_flag(const cli_args *a, const char *name, const char *shortname) {
  const char *s = a->argv[a->k];
  return strcmp(s, name) == 0 || (shortname && strcmp(s, shortname) == 0);
}

#endif
