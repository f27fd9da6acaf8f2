/*
 * nbs generate SCENE: writes a scene of the shared scene library (scenes/), the same
 * elements the tests, the benchmarks and the demo use.
 */
#include "args.h"
#include "cli.h"
#include "scenes.h"

#include <stdlib.h>
#include <string.h>
#include <strings.h>

static const char cli_generate_help[] =
    "Usage: nbs generate SCENE [options]\n"
    "\n"
    "Writes a scene of the shared scene library: the same elements for the same options\n"
    "(and the same C library: box sizes use pow).\n"
    "\n"
    "Scenes:\n"
    "  uniform     uniform random in a box sized for the volume (area) fraction\n"
    "  lattice     square/cubic lattice of spacing exactly the diameter: neighbours touch\n"
    "  clustered   99% of the elements packed at the fraction in a small box, 1% far away\n"
    "  sparse      uniform at the fraction plus a few outliers 1e6 diameters away\n"
    "  wide        radii spread over --size-ratio (largest / smallest), log-uniform\n"
    "  faces       centres exactly on the faces of the cells\n"
    "  identical   every element at one point\n"
    "  far         uniform, and one element 1e15 diameters away\n"
    "  huge        uniform over a domain of about 1e6 cells per element\n"
    "  slab        uniform in a layer two diameters thick (a bed; 2D: a strip)\n"
    "\n"
    "Options:\n"
    "  --dim 2|3           dimension (default 3)\n"
    "  --n N               number of elements (default 1000; 1e6 is accepted)\n"
    "  --seed S            random seed (default 1)\n"
    "  --fraction F        volume (3D) or area (2D) fraction, 0 < F < 1 (default 0.5)\n"
    "  --diameter D        diameter (the largest, for wide) (default 1)\n"
    "  --size-ratio R      wide: largest over smallest diameter (default 10)\n"
    "  --offset X          added to every coordinate (e.g. 1e9)\n"
    "  --sorted            order the elements along their cells (row-major)\n"
    "  --output FILE       where to write ('-' or none: standard output, CSV)\n"
    "  --format NAME       csv, f64, dump, vtk or vtp (default: from the extension, else csv)\n"
    "  --vtp-encoding E    appended (default), base64 or ascii; --no-compress: no zlib\n"
    "  -q, --quiet         no progress bar\n"
    "\n"
    "Every format carries the radius (CSV: x,y[,z],radius with a header line; f64: D+1\n"
    "doubles per element), so 'nbs detect' needs no --diameter for them.\n"
    "\n"
    "Examples:\n"
    "  nbs generate uniform --n 1e6 --output spheres.f64\n"
    "  nbs generate wide --dim 2 --n 5000 --size-ratio 20 --output disks.vtp\n";

static bool cli_ext(const char *path, const char *ext) {
  size_t a = strlen(path), b = strlen(ext);
  return a >= b && strcasecmp(path + a - b, ext) == 0;
}

/* The output format from --format or the file's extension. */
cli_format cli_output_format(const char *path, cli_format asked) {
  if (asked != CLI_FORMAT_AUTO) return asked;
  if (!path) return CLI_FORMAT_CSV;
  if (cli_ext(path, ".f64") || cli_ext(path, ".bin") || cli_ext(path, ".raw")) return CLI_FORMAT_F64;
  if (cli_ext(path, ".vtp")) return CLI_FORMAT_VTP;
  if (cli_ext(path, ".vtk")) return CLI_FORMAT_VTK;
  if (cli_ext(path, ".dump") || cli_ext(path, ".lammpstrj") || cli_ext(path, ".liggghts")) {
    return CLI_FORMAT_DUMP;
  }
  return CLI_FORMAT_CSV;
}

int cli_generate(int argc, char **argv) {
  const char *cmd = "generate";
  scene_def def = scene_default_def();
  const char *output = NULL, *name = NULL;
  cli_format format = CLI_FORMAT_AUTO;
  cli_vtp_opts vo = {CLI_VTP_APPENDED, true};
  cli_args a = {argc, argv, 1, cmd, NULL, false};
  for (; a.k < argc; a.k++) {
    const char *arg = argv[a.k];
    const char *v = NULL;
    if (cli_flag(&a, "--help", "-h")) {
      fputs(cli_generate_help, stdout);
      return CLI_OK;
    } else if (cli_opt(&a, "--dim")) {
      if (a.missing || (strcmp(a.val, "2") != 0 && strcmp(a.val, "3") != 0)) {
        return cli_usage(cmd, "--dim %s: the dimension must be 2 or 3", a.missing ? "" : a.val);
      }
      def.dim = a.val[0] - '0';
    } else if (cli_opt(&a, "--n")) {
      v = a.val;
      if (a.missing || !cli_parse_int64(v, &def.n) || def.n > INT32_MAX) {
        return cli_usage(cmd, "--n %s: give a count from 0 to 2^31 - 1", v ? v : "");
      }
    } else if (cli_opt(&a, "--seed")) {
      int64_t s;
      if (a.missing || !cli_parse_int64(a.val, &s)) {
        return cli_usage(cmd, "--seed %s: give an integer >= 0", a.missing ? "" : a.val);
      }
      def.seed = (uint64_t)s;
    } else if (cli_opt(&a, "--fraction")) {
      if (a.missing || !cli_parse_double(a.val, &def.fraction) || !(def.fraction > 0) ||
          !(def.fraction < 1)) {
        return cli_usage(cmd, "--fraction %s: give a number in (0, 1)", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--diameter")) {
      if (a.missing || !cli_parse_double(a.val, &def.diameter) || !(def.diameter > 0)) {
        return cli_usage(cmd, "--diameter %s: give a finite number > 0", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--size-ratio")) {
      if (a.missing || !cli_parse_double(a.val, &def.size_ratio) || !(def.size_ratio >= 1)) {
        return cli_usage(cmd, "--size-ratio %s: give a finite number >= 1", a.missing ? "" : a.val);
      }
    } else if (cli_opt(&a, "--offset")) {
      if (a.missing || !cli_parse_double(a.val, &def.offset)) {
        return cli_usage(cmd, "--offset %s: give a finite number", a.missing ? "" : a.val);
      }
    } else if (cli_flag(&a, "--sorted", NULL)) {
      def.sorted = 1;
    } else if (cli_opt(&a, "--output") || cli_opt(&a, "-o")) {
      if (a.missing) return cli_usage(cmd, "%s needs a file name", arg);
      output = a.val;
    } else if (cli_opt(&a, "--format")) {
      int f = a.missing ? -1 : cli_format_from_name(a.val);
      if (f <= 0) return cli_usage(cmd, "--format %s: use csv, f64, dump, vtk or vtp", a.missing ? "" : a.val);
      format = (cli_format)f;
    } else if (cli_opt(&a, "--vtp-encoding")) {
      if (a.missing) return cli_usage(cmd, "--vtp-encoding needs appended, base64 or ascii");
      if (strcmp(a.val, "appended") == 0) vo.encoding = CLI_VTP_APPENDED;
      else if (strcmp(a.val, "base64") == 0) vo.encoding = CLI_VTP_BASE64;
      else if (strcmp(a.val, "ascii") == 0) vo.encoding = CLI_VTP_ASCII;
      else return cli_usage(cmd, "--vtp-encoding %s: use appended, base64 or ascii", a.val);
    } else if (cli_flag(&a, "--no-compress", NULL)) {
      vo.compress = false;
    } else if (cli_flag(&a, "--quiet", "-q")) {
      cli_quiet = true;
    } else if (arg[0] == '-' && arg[1] != '\0') {
      return cli_usage(cmd, "unknown option '%s'", arg);
    } else if (!name) {
      name = arg;
    } else {
      return cli_usage(cmd, "unexpected argument '%s'", arg);
    }
  }
  if (!name) return cli_usage(cmd, "which scene? (uniform, lattice, clustered, sparse, wide, ...)");
  int kind = scene_kind_from_name(name);
  if (kind < 0) {
    return cli_usage(cmd, "unknown scene '%s': use uniform, lattice, clustered, sparse, wide, "
                          "faces, identical, far, huge or slab", name);
  }
  def.kind = (scene_kind)kind;
  scene s;
  char err[256];
  if (scene_generate(&def, &s, err, sizeof err) != 0) {
    return cli_fail(strstr(err, "memory") ? CLI_RESOURCE : CLI_USAGE, "generate %s: %s", name, err);
  }
  cli_elements e = {s.dim, s.n, s.coords, s.radii, s.diameter};
  int code = cli_write_elements(output ? output : "-", cli_output_format(output, format), &vo, &e);
  scene_free(&s);
  return code;
}
