#include "pectus/patient/solid_grid.h"

#include "pectus/union_find.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace pectus::patient {

namespace {
using Vec3 = Eigen::Vector3d;
using CrossMap = std::unordered_map<std::uint64_t, std::array<float, 2>>;

constexpr std::uint8_t kReached = 8;  // bits 0-2: the edge to the +axis neighbour is crossed by the surface

// The grid edges the faces cross: each face is projected along each axis, and each grid line through the box
// that meets the projection (an inclusive test, with a tolerance, so that a line through a shared edge or
// vertex meets at least one of its faces) gives the crossing's position along the line.
void rasterise(const Soup& s, const Grid& g, const Box3i& box, CrossMap& cross) {
  auto record = [&](int a, int b, int c, int axis, float t) {
    std::array<int, 3> q{a, b, c};
    if (q[std::size_t(axis)] < 0 || q[std::size_t(axis)] + 1 >= box.n[std::size_t(axis)]) return;
    auto [it, fresh] = cross.try_emplace(3 * box.index(q[0], q[1], q[2]) + std::uint64_t(axis), std::array<float, 2>{t, t});
    if (!fresh) it->second = {std::min(it->second[0], t), std::max(it->second[1], t)};
  };
  const Vec3 lo = g.origin + g.h * Vec3(box.lo[0], box.lo[1], box.lo[2]);
  for (const auto& f : s.F) {
    std::array<Vec3, 3> P;
    for (int q = 0; q < 3; ++q) P[std::size_t(q)] = (s.V[std::size_t(f[std::size_t(q)])] - lo) / g.h;
    for (int axis = 0; axis < 3; ++axis) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      const double x0 = P[0][u], y0 = P[0][w], x1 = P[1][u], y1 = P[1][w], x2 = P[2][u], y2 = P[2][w];
      const double d = (x1 - x0) * (y2 - y0) - (x2 - x0) * (y1 - y0);
      if (std::abs(d) < 1e-12) continue;  // parallel to the axis: its neighbours cross the lines
      constexpr double kTol = 1e-9;
      const int ju0 = std::max(0, int(std::ceil(std::min({x0, x1, x2}) - 1e-7)));
      const int ju1 = std::min(box.n[std::size_t(u)] - 1, int(std::floor(std::max({x0, x1, x2}) + 1e-7)));
      const int jw0 = std::max(0, int(std::ceil(std::min({y0, y1, y2}) - 1e-7)));
      const int jw1 = std::min(box.n[std::size_t(w)] - 1, int(std::floor(std::max({y0, y1, y2}) + 1e-7)));
      for (int jw = jw0; jw <= jw1; ++jw)
        for (int ju = ju0; ju <= ju1; ++ju) {
          const double l1 = ((ju - x0) * (y2 - y0) - (x2 - x0) * (jw - y0)) / d;
          const double l2 = ((x1 - x0) * (jw - y0) - (ju - x0) * (y1 - y0)) / d;
          const double l0 = 1 - l1 - l2;
          if (l0 < -kTol || l1 < -kTol || l2 < -kTol) continue;
          const double t = l0 * P[0][axis] + l1 * P[1][axis] + l2 * P[2][axis];
          const int i = int(std::floor(t));
          const double frac = t - i;
          std::array<int, 3> q{};
          q[std::size_t(u)] = ju, q[std::size_t(w)] = jw;
          auto at = [&](int k, float share) {
            q[std::size_t(axis)] = k;
            record(q[0], q[1], q[2], axis, share);
          };
          at(i, float(frac));
          // through a grid point: the edges on both sides of it are crossed
          if (frac < 1e-6) at(i - 1, 1.0f);
          if (frac > 1 - 1e-6) at(i + 1, 0.0f);
        }
    }
  }
}

// floods the box from its border points; blocked(p, axis): the edge from local point p to its +axis neighbour
// cannot be passed; sets kReached in state
template <class Blocked>
void flood(const Box3i& box, std::vector<std::uint8_t>& state, const Blocked& blocked) {
  const std::array<int, 3>& n = box.n;
  const std::array<std::size_t, 3> stride{1, std::size_t(n[0]), std::size_t(n[0]) * std::size_t(n[1])};
  std::vector<std::size_t> stack;
  for (int c = 0; c < n[2]; ++c)
    for (int b = 0; b < n[1]; ++b)
      for (int a = 0; a < n[0]; ++a)
        if (a == 0 || b == 0 || c == 0 || a + 1 == n[0] || b + 1 == n[1] || c + 1 == n[2]) {
          const std::size_t p = box.index(a, b, c);
          if (!(state[p] & kReached)) state[p] |= kReached, stack.push_back(p);
        }
  while (!stack.empty()) {
    const std::size_t p = stack.back();
    stack.pop_back();
    std::array<int, 3> q{int(p % stride[1]), int((p / stride[1]) % std::size_t(n[1])), int(p / stride[2])};
    for (int axis = 0; axis < 3; ++axis) {
      if (q[std::size_t(axis)] + 1 < n[std::size_t(axis)] && !blocked(p, axis)) {
        const std::size_t r = p + stride[std::size_t(axis)];
        if (!(state[r] & kReached)) state[r] |= kReached, stack.push_back(r);
      }
      if (q[std::size_t(axis)] > 0) {
        const std::size_t r = p - stride[std::size_t(axis)];
        if (!blocked(r, axis) && !(state[r] & kReached)) state[r] |= kReached, stack.push_back(r);
      }
    }
  }
}

// the grid points around the soup's faces, two steps wider on each side: the border points are outside
Box3i boxOf(const Soup& s, const Grid& g) {
  Eigen::AlignedBox3d b;
  for (const auto& f : s.F)
    for (int v : f) b.extend(s.V[std::size_t(v)]);
  Box3i box;
  for (int a = 0; a < 3; ++a) {
    const int lo = int(std::floor((b.min()[a] - g.origin[a]) / g.h)) - 2;
    const int hi = int(std::ceil((b.max()[a] - g.origin[a]) / g.h)) + 2;
    box.lo[std::size_t(a)] = lo;
    box.n[std::size_t(a)] = hi - lo + 1;
  }
  return box;
}

// Caps every hole: the edges in an odd number of faces (a hole's rim; a fin's or a sliver's edges), grouped by
// the vertices they share, each group spanned by a fan of triangles from its centre. However the rim winds, the
// fan spans it, so no path passes through the hole without crossing a face; the fan may cross the surface, which
// the flood does not mind. The fans' faces are appended to s.F, their centres to s.V; returns the number of fans.
int capHoles(Soup& s) {
  const Topology top(s);
  UnionFind sets(s.V.size());
  std::vector<std::pair<int, int>> rim;
  for (const auto& e : top.edges)
    if (e.faces % 2 == 1) {
      rim.push_back({e.a, e.b});
      sets.unite(e.a, e.b);
    }
  if (rim.empty()) return 0;
  std::vector<Vec3> sum(s.V.size(), Vec3::Zero());
  std::vector<int> n(s.V.size(), 0), centre(s.V.size(), -1);
  for (const auto& [a, b] : rim)
    for (int v : {a, b}) sum[std::size_t(sets.find(v))] += s.V[std::size_t(v)], ++n[std::size_t(sets.find(v))];
  int groups = 0;
  for (const auto& [a, b] : rim) {
    const int root = sets.find(a);
    if (centre[std::size_t(root)] < 0) {
      s.V.push_back(sum[std::size_t(root)] / n[std::size_t(root)]);
      centre[std::size_t(root)] = int(s.V.size()) - 1;
      ++groups;
    }
    s.F.push_back({a, b, centre[std::size_t(root)]});
  }
  return groups;
}

}  // namespace

std::size_t Solid::count() const { return std::size_t(std::count(in.begin(), in.end(), std::uint8_t(1))); }

double Solid::exit(int i, int j, int k, int axis, bool insideAtStart) const {
  const auto it = box.contains(i, j, k) ? cross.find(3 * box.index(i - box.lo[0], j - box.lo[1], k - box.lo[2]) + std::uint64_t(axis))
                                        : cross.end();
  if (it == cross.end()) return 0.5;
  // kept off the grid points, so that no face of the surface collapses
  return std::clamp(double(insideAtStart ? it->second[1] : it->second[0]), 0.05, 0.95);
}

Solid solidify(const Soup& input, const Grid& g) {
  Solid so;
  if (input.F.empty()) return so;
  Soup s = input;
  so.duplicates = removeDuplicateFaces(s);  // a face written twice would make its edges look like a rim
  so.capped = capHoles(s);
  so.box = boxOf(s, g);
  rasterise(s, g, so.box, so.cross);
  std::vector<std::uint8_t> state(so.box.size(), 0);
  for (const auto& [key, t] : so.cross) state[std::size_t(key / 3)] |= std::uint8_t(1u << (key % 3));
  flood(so.box, state, [&](std::size_t p, int axis) { return (state[p] & (1u << axis)) != 0; });
  so.in.resize(so.box.size());
  for (std::size_t p = 0; p < state.size(); ++p) so.in[p] = (state[p] & kReached) ? 0 : 1;
  return so;
}

std::vector<std::size_t> components6(const std::array<int, 3>& n, const std::vector<std::uint8_t>& mask,
                                     std::vector<std::int32_t>& comp) {
  const std::array<std::size_t, 3> stride{1, std::size_t(n[0]), std::size_t(n[0]) * std::size_t(n[1])};
  comp.assign(mask.size(), 0);
  std::vector<std::size_t> count, stack;
  for (std::size_t s = 0; s < mask.size(); ++s) {
    if (!mask[s] || comp[s]) continue;
    count.push_back(0);
    const std::int32_t id = std::int32_t(count.size());
    comp[s] = id;
    stack.push_back(s);
    while (!stack.empty()) {
      const std::size_t p = stack.back();
      stack.pop_back();
      ++count.back();
      const std::array<int, 3> q{int(p % stride[1]), int((p / stride[1]) % std::size_t(n[1])), int(p / stride[2])};
      for (int axis = 0; axis < 3; ++axis) {
        if (q[std::size_t(axis)] + 1 < n[std::size_t(axis)]) {
          const std::size_t r = p + stride[std::size_t(axis)];
          if (mask[r] && !comp[r]) comp[r] = id, stack.push_back(r);
        }
        if (q[std::size_t(axis)] > 0) {
          const std::size_t r = p - stride[std::size_t(axis)];
          if (mask[r] && !comp[r]) comp[r] = id, stack.push_back(r);
        }
      }
    }
  }
  return count;
}

// Felzenszwalb and Huttenlocher's lower envelope of parabolas, along each axis in turn
std::vector<float> squaredDistance(const std::array<int, 3>& n, const std::vector<std::uint8_t>& set) {
  constexpr double kFar = 1e20;
  std::vector<float> d(set.size());
  for (std::size_t p = 0; p < set.size(); ++p) d[p] = set[p] ? 0.f : float(kFar);
  const std::array<std::size_t, 3> stride{1, std::size_t(n[0]), std::size_t(n[0]) * std::size_t(n[1])};
  const int longest = std::max({n[0], n[1], n[2]});
  std::vector<double> f(std::size_t(longest) + 1), z(std::size_t(longest) + 1);
  std::vector<int> v(std::size_t(longest) + 1);
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, w = (axis + 2) % 3, m = n[std::size_t(axis)];
    for (int jw = 0; jw < n[std::size_t(w)]; ++jw)
      for (int ju = 0; ju < n[std::size_t(u)]; ++ju) {
        const std::size_t base = std::size_t(ju) * stride[std::size_t(u)] + std::size_t(jw) * stride[std::size_t(w)];
        const std::size_t step = stride[std::size_t(axis)];
        int k = -1;  // the envelope of the finite parabolas only
        for (int q = 0; q < m; ++q) {
          f[std::size_t(q)] = d[base + std::size_t(q) * step];
          if (f[std::size_t(q)] >= kFar) continue;
          double s = -1e300;
          while (k >= 0) {
            const int p = v[std::size_t(k)];
            s = ((f[std::size_t(q)] + double(q) * q) - (f[std::size_t(p)] + double(p) * p)) / (2.0 * (q - p));
            if (s > z[std::size_t(k)]) break;
            --k;
          }
          ++k;
          v[std::size_t(k)] = q;
          z[std::size_t(k)] = k == 0 ? -1e300 : s;
        }
        if (k < 0) continue;
        int e = 0;
        for (int q = 0; q < m; ++q) {
          while (e < k && z[std::size_t(e + 1)] < q) ++e;
          const int p = v[std::size_t(e)];
          d[base + std::size_t(q) * step] = float(double(q - p) * (q - p) + f[std::size_t(p)]);
        }
      }
  }
  return d;
}

}  // namespace pectus::patient
