// nanoflann peer: a KD-tree over the centres (leaf size 10, nanoflann's default), then one
// radius search per element, counting the pairs i<j with |xi-xj|^2 <= d^2.
//
// nanoflann's L2 adaptors work in squared distance: the search radius is d^2, not d. Its
// result sets keep `dist < radius` (strict), while nbs's contract counts touching pairs
// (<=): the search runs with the next double above d^2 and the count then keeps
// dist <= d^2 exactly. The count goes to a result set that stores nothing (the pairs are
// not materialised), which is the fastest way to use the library for this question.
// Timed: building the tree and all the searches, minimum over the repeats.
#include <nanoflann.hpp>

#include <cmath>
#include <cstdint>
#include <memory>

#include "peer_common.hpp"

namespace {

template <int DIM>
struct Cloud {
  const double *c;
  size_t n;
  size_t kdtree_get_point_count() const { return n; }
  double kdtree_get_pt(size_t i, size_t a) const { return c[i * DIM + a]; }
  template <class BBOX>
  bool kdtree_get_bbox(BBOX &) const { return false; }
};

// Counts the neighbours with a larger index within d^2; stores nothing.
struct CountAbove {
  using DistanceType = double;
  using IndexType = uint32_t;
  double search_radius;  // next double above d^2, so that nanoflann's `<` admits d^2
  double d2;
  uint32_t self;
  unsigned long long count = 0;
  void init() {}
  void clear() {}
  size_t size() const { return 0; }
  bool full() const { return true; }
  bool addPoint(double dist, uint32_t index) {
    if (index > self && dist <= d2) count++;
    return true;
  }
  double worstDist() const { return search_radius; }
};

template <int DIM>
int run(const peer::Args &a) {
  std::vector<double> c = peer::read_coords(a);
  const size_t n = c.size() / DIM;
  long long base = peer::status_bytes("VmRSS:");
  peer::reset_peak();
  using Tree = nanoflann::KDTreeSingleIndexAdaptor<
      nanoflann::L2_Simple_Adaptor<double, Cloud<DIM>>, Cloud<DIM>, DIM, uint32_t>;
  Cloud<DIM> cloud{c.data(), n};
  const double d2 = a.diameter * a.diameter;
  double best = -1;
  unsigned long long pairs = 0;
  for (int r = 0; r < a.repeats; r++) {
    double t0 = peer::now();
    auto tree = std::make_unique<Tree>(DIM, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(10));
    tree->buildIndex();
    CountAbove set;
    set.search_radius = std::nextafter(d2, INFINITY);
    set.d2 = d2;
    nanoflann::SearchParams params;
    params.sorted = false;
    for (size_t i = 0; i < n; i++) {
      set.self = (uint32_t)i;
      tree->findNeighbors(set, &c[i * DIM], params);
    }
    double t = peer::now() - t0;
    if (best < 0 || t < best) best = t;
    pairs = set.count;
  }
  peer::report("nanoflann", best, pairs, base, a.repeats, (long long)n, DIM);
  return 0;
}

}  // namespace

int main(int argc, char **argv) {
  peer::Args a = peer::parse(argc, argv, "nanoflann_pairs");
  try {
    return a.dim == 2 ? run<2>(a) : run<3>(a);
  } catch (const std::exception &e) {
    std::fprintf(stderr, "nanoflann_pairs: %s\n", e.what());
    return 2;
  }
}
