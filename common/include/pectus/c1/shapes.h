// Icosphere-based ellipsoid meshes for the C1 tests and benchmark (closed, consistently oriented).
#pragma once
#include <map>
#include <utility>

#include "pectus/c1/surface.h"

namespace pectus::c1 {

/// The icosahedron subdivided `level` times (20 * 4^level faces), projected onto the unit sphere and
/// scaled by `axes` into an ellipsoid with those semi-axes.
inline TriMesh icoEllipsoid(int level, const Vec3& axes = Vec3(1, 1, 1)) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  TriMesh m;
  m.V = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  m.F = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
         {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (auto& v : m.V) v.normalize();
  for (int l = 0; l < level; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int i, int j) {
      auto key = std::minmax(i, j);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      m.V.push_back((m.V[i] + m.V[j]).normalized());
      return mid[key] = int(m.V.size()) - 1;
    };
    std::vector<std::array<int, 3>> F;
    for (const auto& f : m.F) {
      const int x = midpoint(f[0], f[1]), y = midpoint(f[1], f[2]), z = midpoint(f[2], f[0]);
      F.push_back({f[0], x, z}); F.push_back({f[1], y, x}); F.push_back({f[2], z, y}); F.push_back({x, y, z});
    }
    m.F = F;
  }
  for (auto& v : m.V) v = v.cwiseProduct(axes);
  return m;
}

}  // namespace pectus::c1
