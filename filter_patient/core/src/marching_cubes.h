// Internal to the patient core: marching cubes on a grid of inside/outside points, with a closed, 2-manifold,
// outward-oriented result for every mask (inside points are taken 6-connected: points meeting at a cube's edge or
// corner only stay apart). Used for the labels of a NIfTI file and for the solids of 'Pectus: Prepare Patient Rib Cage'.
#pragma once
#include <array>
#include <cstdint>
#include <vector>

#include <Eigen/Dense>

namespace pectus::patient {

// Cube corner c = x + 2y + 4z (x, y, z in {0, 1}); edge e joins corners eA[e] and eB[e] = eA[e] + 2^axis.
struct McTable {
  std::array<int, 12> eA{}, eB{}, eAxis{};
  std::array<std::vector<std::array<std::int8_t, 3>>, 256> tris;

  std::array<std::array<int, 4>, 6> faces{};

  static Eigen::Vector3d pos(int c) { return Eigen::Vector3d(c & 1, (c >> 1) & 1, (c >> 2) & 1); }
  Eigen::Vector3d mid(int edge) const { return 0.5 * (pos(eA[std::size_t(edge)]) + pos(eB[std::size_t(edge)])); }
  bool shareFace(int e0, int e1) const {
    for (const auto& f : faces) {
      int n = 0;
      for (int k = 0; k < 4; ++k) {
        const int a = f[std::size_t(k)], b = f[std::size_t((k + 1) % 4)];
        const int x = std::min(a, b), y = std::max(a, b);
        if ((eA[std::size_t(e0)] == x && eB[std::size_t(e0)] == y) || (eA[std::size_t(e1)] == x && eB[std::size_t(e1)] == y)) ++n;
      }
      if (n == 2) return true;
    }
    return false;
  }

  // Triangulates one loop (polygon of edge midpoints) without a diagonal lying in a cube face: the cube on
  // the other side of that face could make the same triangle or diagonal (a duplicate face, an edge with
  // four faces). Among those triangulations, the one whose smallest triangle is largest (dynamic programming).
  void triangulate(const std::vector<int>& loop, int cs) {
    const int m = int(loop.size());
    auto area = [&](int i, int j, int k) {
      return (mid(loop[std::size_t(j)]) - mid(loop[std::size_t(i)])).cross(mid(loop[std::size_t(k)]) - mid(loop[std::size_t(i)])).norm();
    };
    auto diagonalOk = [&](int i, int j) { return j == i + 1 || (i == 0 && j == m - 1) || !shareFace(loop[std::size_t(i)], loop[std::size_t(j)]); };
    std::vector<std::vector<double>> best(std::size_t(m), std::vector<double>(std::size_t(m), -1));
    std::vector<std::vector<int>> split(std::size_t(m), std::vector<int>(std::size_t(m), -1));
    for (int i = 0; i + 1 < m; ++i) best[std::size_t(i)][std::size_t(i + 1)] = 1e30;
    for (int len = 2; len < m; ++len)
      for (int i = 0; i + len < m; ++i) {
        const int j = i + len;
        if (!diagonalOk(i, j)) continue;
        for (int k = i + 1; k < j; ++k) {
          const double a = best[std::size_t(i)][std::size_t(k)], b = best[std::size_t(k)][std::size_t(j)];
          if (a < 0 || b < 0) continue;
          const double v = std::min({a, b, area(i, k, j)});
          if (v > best[std::size_t(i)][std::size_t(j)] + 1e-9) { best[std::size_t(i)][std::size_t(j)] = v; split[std::size_t(i)][std::size_t(j)] = k; }
        }
      }
    std::vector<std::pair<int, int>> stack{{0, m - 1}};
    while (!stack.empty()) {
      const auto [i, j] = stack.back();
      stack.pop_back();
      if (j - i < 2) continue;
      int k = split[std::size_t(i)][std::size_t(j)];
      if (k < 0) k = i + 1;  // not reached: every loop of the 256 cases has such a triangulation
      tris[std::size_t(cs)].push_back({std::int8_t(loop[std::size_t(i)]), std::int8_t(loop[std::size_t(k)]), std::int8_t(loop[std::size_t(j)])});
      stack.push_back({i, k});
      stack.push_back({k, j});
    }
  }

  McTable() {
    int e = 0;
    int edgeOf[8][8];
    for (auto& r : edgeOf) for (int& x : r) x = -1;
    for (int a = 0; a < 3; ++a)
      for (int c = 0; c < 8; ++c)
        if (!(c & (1 << a))) {
          eA[std::size_t(e)] = c;
          eB[std::size_t(e)] = c | (1 << a);
          eAxis[std::size_t(e)] = a;
          edgeOf[c][c | (1 << a)] = edgeOf[c | (1 << a)][c] = e;
          ++e;
        }
    // the six faces, corners counter-clockwise seen from outside the cube
    for (int a = 0; a < 3; ++a)
      for (int s = 0; s < 2; ++s) {
        const int u = (a + 1) % 3, w = (a + 2) % 3;
        // (0,0) (1,0) (1,1) (0,1) in the (u, w) plane is counter-clockwise about +axis
        std::array<int, 4> f{};
        const int uv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        for (int k = 0; k < 4; ++k) f[std::size_t(k)] = (s << a) | (uv[k][0] << u) | (uv[k][1] << w);
        if (s == 0) std::reverse(f.begin(), f.end());
        faces[std::size_t(2 * a + s)] = f;
      }
    for (int cs = 0; cs < 256; ++cs) {
      auto in = [&](int c) { return (cs >> c) & 1; };
      // On every face, each run of consecutive inside corners is cut off by one segment from the edge where
      // the run starts to the edge where it ends: inside corners on a face diagonal stay separated, outside
      // ones connect. Both cubes sharing a face decide alike, so the surface is closed and 2-manifold.
      std::array<int, 12> next;
      next.fill(-1);
      for (const auto& f : faces) {
        for (int j = 0; j < 4; ++j) {
          const int c0 = f[std::size_t(j)], c1 = f[std::size_t((j + 1) % 4)];
          if (in(c0) || !in(c1)) continue;  // edge j enters the run
          for (int k = 1; k < 4; ++k) {
            const int d0 = f[std::size_t((j + k) % 4)], d1 = f[std::size_t((j + k + 1) % 4)];
            if (in(d0) && !in(d1)) {
              next[std::size_t(edgeOf[c0][c1])] = edgeOf[d0][d1];
              break;
            }
          }
        }
      }
      std::array<bool, 12> used{};
      for (int s = 0; s < 12; ++s) {
        if (next[std::size_t(s)] < 0 || used[std::size_t(s)]) continue;
        std::vector<int> loop;
        for (int p = s; !used[std::size_t(p)]; p = next[std::size_t(p)]) {
          used[std::size_t(p)] = true;
          loop.push_back(p);
        }
        triangulate(loop, cs);
      }
    }
    // orientation: the one-corner case must point away from its inside corner
    const auto& t = tris[1][0];
    const Eigen::Vector3d n = (mid(t[1]) - mid(t[0])).cross(mid(t[2]) - mid(t[0]));
    if (n.dot(mid(t[0]) - pos(0)) < 0)
      for (auto& list : tris)
        for (auto& tri : list) std::swap(tri[1], tri[2]);
  }
};

inline const McTable& mcTable() {
  static const McTable t;
  return t;
}


/// Marching cubes over the points (0..gx-1, 0..gy-1, 0..gz-1); the caller pads the grid so that its border points
/// are outside. inside(a, b, c) -> bool; vertex(a, b, c, axis) -> the position (Eigen::Vector3d) of the vertex on
/// the grid edge from point (a, b, c) to its +axis neighbour (asked once per edge the surface crosses); face(a, b,
/// c, tri) receives each triangle (indices into V) with the cube (a, b, c) it lies in. Triangles face outward in
/// the grid's index frame.
template <class Inside, class Vertex, class Face>
void marchCubes(int gx, int gy, int gz, const Inside& inside, const Vertex& vertex, std::vector<Eigen::Vector3d>& V,
                const Face& face) {
  const McTable& T = mcTable();
  // vertex ids of the grid edges: x/y edges of the two grid layers of the current cube layer, z edges between them
  std::array<std::vector<int>, 2> layer{std::vector<int>(std::size_t(gx) * gy * 2, -1), std::vector<int>(std::size_t(gx) * gy * 2, -1)};
  std::vector<int> zed(std::size_t(gx) * gy, -1);
  auto vertexOf = [&](int a, int b, int c, int axis, int cubeLayer) -> int {
    int* slot;
    if (axis == 2) slot = &zed[std::size_t(a) + std::size_t(gx) * std::size_t(b)];
    else slot = &layer[std::size_t(c - cubeLayer)][(std::size_t(a) + std::size_t(gx) * std::size_t(b)) * 2 + std::size_t(axis)];
    if (*slot < 0) {
      V.push_back(vertex(a, b, c, axis));
      *slot = int(V.size()) - 1;
    }
    return *slot;
  };
  for (int c = 0; c + 1 < gz; ++c) {
    if (c > 0) {
      std::swap(layer[0], layer[1]);
      std::fill(layer[1].begin(), layer[1].end(), -1);
      std::fill(zed.begin(), zed.end(), -1);
    }
    for (int b = 0; b + 1 < gy; ++b)
      for (int a = 0; a + 1 < gx; ++a) {
        int cs = 0;
        for (int corner = 0; corner < 8; ++corner)
          if (inside(a + (corner & 1), b + ((corner >> 1) & 1), c + ((corner >> 2) & 1))) cs |= 1 << corner;
        if (cs == 0 || cs == 255) continue;
        for (const auto& t : T.tris[std::size_t(cs)]) {
          std::array<int, 3> f{};
          for (int q = 0; q < 3; ++q) {
            const int e = t[std::size_t(q)], c0 = T.eA[std::size_t(e)];
            f[std::size_t(q)] = vertexOf(a + (c0 & 1), b + ((c0 >> 1) & 1), c + ((c0 >> 2) & 1), T.eAxis[std::size_t(e)], c);
          }
          face(a, b, c, f);
        }
      }
  }
}

}  // namespace pectus::patient
