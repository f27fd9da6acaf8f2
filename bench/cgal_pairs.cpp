// CGAL peer: CGAL::box_self_intersection_d over axis-aligned boxes of half-size d/2 around
// the centres (closed boxes, so touching boxes intersect), then the exact test
// |xi-xj|^2 <= d^2 in double on every intersecting pair, counted.
// Timed: making the boxes, the self-intersection with its callback, minimum over the
// repeats (box_self_intersection_d copies and sorts the boxes inside that time).
#include <CGAL/Box_intersection_d/Box_with_info_d.h>
#include <CGAL/box_intersection_d.h>

#include <cstdint>

#include "peer_common.hpp"

namespace {

template <int DIM>
int run(const peer::Args &a) {
  std::vector<double> c = peer::read_coords(a);
  const size_t n = c.size() / DIM;
  long long base = peer::status_bytes("VmRSS:");
  peer::reset_peak();
  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, DIM, uint32_t,
                                                        CGAL::Box_intersection_d::ID_EXPLICIT>;
  const double r = 0.5 * a.diameter, d2 = a.diameter * a.diameter;
  double best = -1;
  unsigned long long pairs = 0;
  for (int rep = 0; rep < a.repeats; rep++) {
    double t0 = peer::now();
    std::vector<Box> boxes;
    boxes.reserve(n);
    for (size_t i = 0; i < n; i++) {
      double lo[DIM], hi[DIM];
      for (int k = 0; k < DIM; k++) {
        lo[k] = c[i * DIM + k] - r;
        hi[k] = c[i * DIM + k] + r;
      }
      boxes.emplace_back(lo, hi, (uint32_t)i);
    }
    unsigned long long count = 0;
    const double *x = c.data();
    CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), [&](const Box &p, const Box &q) {
      const double *u = x + (size_t)p.info() * DIM, *v = x + (size_t)q.info() * DIM;
      double s = 0;
      for (int k = 0; k < DIM; k++) s += (u[k] - v[k]) * (u[k] - v[k]);
      if (s <= d2) count++;
    });
    double t = peer::now() - t0;
    if (best < 0 || t < best) best = t;
    pairs = count;
  }
  peer::report("cgal", best, pairs, base, a.repeats, (long long)n, DIM);
  return 0;
}

}  // namespace

int main(int argc, char **argv) {
  peer::Args a = peer::parse(argc, argv, "cgal_pairs");
  try {
    return a.dim == 2 ? run<2>(a) : run<3>(a);
  } catch (const std::exception &e) {
    std::fprintf(stderr, "cgal_pairs: %s\n", e.what());
    return 2;
  }
}
