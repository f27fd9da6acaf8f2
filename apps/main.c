/*
 * nbs: the command-line tool. Dispatches to the subcommands (cmd_*.c).
 */
#include "cli.h"

#include <string.h>

static const char cli_main_help[] =
    "Usage: nbs COMMAND [options]\n"
    "\n"
    "Contact detection for discrete element simulations.\n"
    "\n"
    "Commands:\n"
    "  demo       every algorithm on a million spheres, checked; a ParaView file and a picture\n"
    "  detect     find the contacting pairs of a file of elements\n"
    "  generate   write a scene (uniform, lattice, clustered, sparse, wide, ...)\n"
    "  info       what a file holds, and what each algorithm needs in memory for it\n"
    "\n"
    "  nbs COMMAND --help   the options of a command, with examples\n"
    "  nbs --version        the tool's and the library's versions\n"
    "\n"
    "Examples:\n"
    "  nbs demo\n"
    "  nbs detect --input spheres.csv --dim 3 --output pairs.csv\n";

static int cli_dispatch(int argc, char **argv);

int main(int argc, char **argv) {
  int code = cli_dispatch(argc, argv);
  /* A result that could not be printed (a full disk, a closed pipe) is a failure too. */
  if (fflush(stdout) != 0 || ferror(stdout)) {
    fprintf(stderr, "nbs: standard output: write error\n");
    if (code == CLI_OK) code = CLI_RESOURCE;
  }
  return code;
}

static int cli_dispatch(int argc, char **argv) {
  if (argc < 2) {
    fputs(cli_main_help, stderr);
    return CLI_USAGE;
  }
  const char *cmd = argv[1];
  if (strcmp(cmd, "--help") == 0 || strcmp(cmd, "-h") == 0 || strcmp(cmd, "help") == 0) {
    fputs(cli_main_help, stdout);
    return CLI_OK;
  }
  if (strcmp(cmd, "--version") == 0 || strcmp(cmd, "-V") == 0) {
    printf("nbs %s (library %s)\n", NBS_VERSION_STRING, nbs_version());
    return CLI_OK;
  }
  if (strcmp(cmd, "detect") == 0) return cli_detect(argc - 1, argv + 1);
  if (strcmp(cmd, "generate") == 0) return cli_generate(argc - 1, argv + 1);
  if (strcmp(cmd, "info") == 0) return cli_info(argc - 1, argv + 1);
  if (strcmp(cmd, "demo") == 0) return cli_demo(argc - 1, argv + 1);
  return cli_usage(NULL, "unknown command '%s'", cmd);
}
