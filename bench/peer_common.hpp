// Shared by the C++ peer drivers: reading a scene file, the clock, resident memory and
// the output line. Every driver prints one line of key=value fields (bench/README.md):
//   tool=NAME status=ok seconds=S ns_per_element=E pairs=P rss_extra_bytes=B
//   rss_peak_bytes=H repeats=K n=N dim=D
// seconds is the minimum over the repeats of one full detection (index built from the
// coordinates, then all pairs i<j with |xi-xj|^2 <= d^2 counted); rss_extra_bytes is the
// peak resident memory above the resident memory once the coordinates were read.
#ifndef NBS_BENCH_PEER_COMMON_HPP
#define NBS_BENCH_PEER_COMMON_HPP

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace peer {

struct Args {
  std::string file;
  int dim = 3;
  double diameter = 1.0;
  int repeats = 3;
};

inline void usage(const char *tool) {
  std::fprintf(stderr,
               "usage: %s --file PATH [--dim 2|3] [--diameter D] [--repeats K]\n"
               "  PATH holds raw little-endian f64 coordinates, DIM per element.\n",
               tool);
}

inline Args parse(int argc, char **argv, const char *tool) {
  Args a;
  for (int k = 1; k < argc; k++) {
    std::string s = argv[k];
    if (k + 1 >= argc) {
      usage(tool);
      std::exit(2);
    }
    const char *v = argv[++k];
    if (s == "--file") a.file = v;
    else if (s == "--dim") a.dim = std::atoi(v);
    else if (s == "--diameter") a.diameter = std::strtod(v, nullptr);
    else if (s == "--repeats") a.repeats = std::atoi(v);
    else {
      usage(tool);
      std::exit(2);
    }
  }
  if (a.file.empty() || (a.dim != 2 && a.dim != 3) || !(a.diameter > 0)) {
    usage(tool);
    std::exit(2);
  }
  if (a.repeats < 1) a.repeats = 1;
  return a;
}

inline std::vector<double> read_coords(const Args &a) {
  std::ifstream f(a.file, std::ios::binary | std::ios::ate);
  if (!f) throw std::runtime_error("cannot open " + a.file);
  std::streamoff size = f.tellg();
  if (size < 0 || size % (std::streamoff)(a.dim * sizeof(double)) != 0)
    throw std::runtime_error(a.file + ": size is not a multiple of dim doubles");
  std::vector<double> c((size_t)size / sizeof(double));
  f.seekg(0);
  f.read(reinterpret_cast<char *>(c.data()), size);
  if (!f) throw std::runtime_error("cannot read " + a.file);
  return c;
}

inline double now() {
  using namespace std::chrono;
  return duration<double>(steady_clock::now().time_since_epoch()).count();
}

// A field of /proc/self/status in bytes ("VmHWM:", "VmRSS:"), 0 where there is none.
inline long long status_bytes(const char *field) {
  FILE *f = std::fopen("/proc/self/status", "r");
  if (!f) return 0;
  char line[256];
  long long kb = 0;
  size_t len = std::strlen(field);
  while (std::fgets(line, sizeof line, f)) {
    if (std::strncmp(line, field, len) == 0) {
      kb = std::strtoll(line + len, nullptr, 10);
      break;
    }
  }
  std::fclose(f);
  return kb * 1024;
}

// Resets VmHWM to the current resident size (Linux >= 4.0).
inline void reset_peak() {
  if (FILE *f = std::fopen("/proc/self/clear_refs", "w")) {
    std::fputs("5", f);
    std::fclose(f);
  }
}

inline void report(const char *tool, double seconds, unsigned long long pairs,
                   long long rss_base, int repeats, long long n, int dim) {
  long long hwm = status_bytes("VmHWM:");
  std::printf("tool=%s status=ok seconds=%.9g ns_per_element=%.6g pairs=%llu "
              "rss_extra_bytes=%lld rss_peak_bytes=%lld repeats=%d n=%lld dim=%d\n",
              tool, seconds, n > 0 ? 1e9 * seconds / (double)n : 0.0, pairs, hwm - rss_base,
              hwm, repeats, n, dim);
  std::fflush(stdout);
}

}  // namespace peer

#endif
